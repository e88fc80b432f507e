#!/usr/bin/env bash
# Prepare ECO-HC (the public Python port StrangerZhang/pyECO) as an optional peer of
# robust_bench.py, in its own venv, outside vtrack's environment (never a dependency of vtrack).
#
#   (PYECO_DIR: a clone of the public GitHub repository StrangerZhang/pyECO; measured at 9179450)
#   bash benchmarks/peers/setup_eco.sh PYECO_DIR VENV_DIR
#   python benchmarks/robust_bench.py --eco-python VENV_DIR/bin/python --eco-dir PYECO_DIR ...
#
# pyECO needs Python 3.11 (python3.11 on PATH, or PYTHON=...) with numpy<2 and scipy<1.13. Two
# small local patches: scipy.signal.hann -> scipy.signal.windows.hann, and the top-level
# `import mxnet` (used only by the deep-feature variant) made optional. Then eco/features'
# C++ gradient extension is built in place.
set -euo pipefail
if [ $# -ne 2 ]; then
    echo "usage: $0 PYECO_DIR VENV_DIR" >&2
    exit 2
fi
eco=$1
venv=$(realpath -m "$2")
if [ ! -f "$eco/eco/tracker.py" ]; then
    echo "$eco: not a pyECO checkout (no eco/tracker.py)" >&2
    exit 2
fi
"${PYTHON:-python3.11}" -m venv "$venv"
"$venv/bin/pip" install -q "numpy<2" "scipy<1.13" "opencv-python-headless<4.11" setuptools
sed -i 's/signal\.hann(/signal.windows.hann(/' "$eco/eco/scale_filter.py"
features="$eco/eco/features/features.py"
if ! grep -q "^try:  # mxnet" "$features"; then
    python3 - "$features" <<'PY'
import sys
path = sys.argv[1]
text = open(path).read()
lines = [l for l in text.splitlines(keepends=True)
         if not (l.startswith("import mxnet") or l.startswith("from mxnet"))]
header = ("try:  # mxnet: only the deep-feature variant needs it\n"
          "    import mxnet as mx\n"
          "    from mxnet.gluon.model_zoo import vision\n"
          "    from mxnet.gluon.nn import AvgPool2D\n"
          "except ImportError:\n"
          "    mx = vision = AvgPool2D = None\n")
open(path, "w").write(header + "".join(lines))
PY
fi
(cd "$eco/eco/features" && "$venv/bin/python" setup.py build_ext --inplace -q)
"$venv/bin/python" -c "import sys; sys.path.insert(0, '$eco'); from eco import ECOTracker; print('pyECO ready')"
