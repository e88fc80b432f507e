"""Accuracy of S0 and of OpenCV's CamShift (the tutorial pipeline) on the real sequences.

    python benchmarks/accuracy.py

For every single-target sequence of ``../shared/data`` (or ``$VTRACK_DATA``): AUC (OTB success,
21 thresholds), precision at 20 px and mean IoU, for the shipped ``s0`` config and the shipped
``camshift`` config (180-bin hue histogram with mask S>=60, V>=32, full-frame back-projection,
``cv2.CamShift`` with criteria (10 iterations, 1 px)), both run by the same code path as
``vtrack run``. Prints a Markdown table with the means. Skips (and says so) when there is no data.
"""

from __future__ import annotations

import statistics
import sys

from common import no_arguments, run_sequence, single_target_sequences

from vtrack.errors import VtrackError

#: (label, shipped config, --set overrides): S0 as shipped, S0 without the saturation/value mask
#: (the paper's literal hue-only model), S0 iterating mean shift to convergence in every frame,
#: and the OpenCV-tutorial CamShift peer.
VARIANTS = (
    ("s0", "s0", []),
    ("s0 no-mask", "s0", ["hue.sat_min=0", "hue.val_min=0"]),
    ("s0 iter10", "s0", ["meanshift.iterations=10"]),
    ("camshift", "camshift", []),
)
CONFIGS = tuple(label for label, _, _ in VARIANTS)


def main() -> None:
    no_arguments(__doc__)
    sequences = single_target_sequences()
    if not sequences:
        print("no benchmark sequences found (../shared/data or $VTRACK_DATA): skipped")
        return
    print("Command: `python benchmarks/accuracy.py`\n")
    header = "| sequence | " + " | ".join(
        f"{c} AUC | {c} P@20 | {c} mIoU" for c in CONFIGS) + " |"
    print(header)
    print("|---|" + "---:|" * (3 * len(CONFIGS)))
    totals: dict[str, list[tuple[float, float, float]]] = {c: [] for c in CONFIGS}
    failures: list[str] = []
    for seq in sequences:
        cells = []
        for config, name, overrides in VARIANTS:
            try:
                summary = run_sequence(seq, name, overrides=overrides)
            except VtrackError as exc:  # e.g. a hue tracker on grey footage: scores 0
                failures.append(f"{seq.name} [{config}]: {exc}")
                totals[config].append((0.0, 0.0, 0.0))
                cells += ["fail"] * 3
                continue
            values = (summary.auc or 0.0, summary.precision20 or 0.0, summary.mean_overlap or 0.0)
            totals[config].append(values)
            cells += [f"{v:.3f}" for v in values]
        print(f"| {seq.name} | " + " | ".join(cells) + " |")
        sys.stdout.flush()
    means = []
    for config in CONFIGS:
        for i in range(3):
            means.append(f"**{statistics.mean(v[i] for v in totals[config]):.3f}**")
    print("| **mean** (a failed run counts 0) | " + " | ".join(means) + " |")
    for failure in failures:
        print(f"\n- fail: {failure}")


if __name__ == "__main__":
    main()
