"""Golden models: S0 and S2 in the hardware's own arithmetic, and the test vectors of an HDL bench.

- :mod:`.s0`: Liu et al. 2022 as the FPGA computes it: exact
  integer hue (eq. 1), integer histogram and back-projection (eq. 2-4), integer window sums and
  step (eq. 6-7), the Kalman filter in IEEE float32 operation by operation (eq. 10-17).
- :mod:`.s2`: Di & Zhu 2008, sec. 3, the integer-only DSP loop.
- :mod:`.record`: the typed record the fixed stages share through ``TrackContext.fixed``.
- :mod:`.vectors`: ``$readmemh`` files and a trace per frame; the comparison of a simulator dump.

Everything here is NumPy integer (or float32) arithmetic; nothing depends on OpenCV's rounding.
"""
