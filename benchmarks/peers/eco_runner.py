"""ECO-HC (the Python port StrangerZhang/pyECO) on an image folder, for ``robust_bench.py``.

    ECO_PYTHON benchmarks/peers/eco_runner.py PYECO_DIR FOLDER X,Y,W,H

Runs in pyECO's own venv (Python 3.11, numpy<2, scipy<1.13; ``setup_eco.sh`` beside this file
prepares it), never in vtrack's. Reads every ``.jpg``/``.png`` of FOLDER (or FOLDER/img) in name
order (``cv2.imread``, handed to pyECO as RGB like its demo's PIL frames; a sequence whose first
frame has three equal channels is handed over as one grey channel, as PIL gives it, so pyECO
uses its grey feature set), starts ECO-HC with its OTB hand-crafted settings (``OTBHCConfig``:
fHOG + colour names, the MATLAB release's) on the 0-based box X,Y,W,H and prints one JSON line
like ``opencv_trackers.py``: ``{"tracker": "ECO-HC", "boxes": [[x, y, w, h], ...], "ok": [...],
"seconds"}``, ``seconds`` the tracking work only (init + every update; reading excluded). ECO
has no failure state: every frame has a box.
"""

from __future__ import annotations

import json
import sys
import time
from pathlib import Path

import cv2
import numpy as np


def read_frames(folder: Path) -> list[np.ndarray]:
    """The folder's images (``img/`` inside it if present) in name order: RGB, or one grey
    channel when the first has three equal channels."""
    if (folder / "img").is_dir():
        folder = folder / "img"
    paths = sorted((p for p in folder.iterdir() if p.suffix.lower() in (".jpg", ".png")),
                   key=lambda p: (len(p.name), p.name))
    frames = [cv2.cvtColor(cv2.imread(str(p), cv2.IMREAD_COLOR), cv2.COLOR_BGR2RGB)
              for p in paths]
    first = frames[0]
    if np.array_equal(first[..., 0], first[..., 1]) and np.array_equal(first[..., 1],
                                                                       first[..., 2]):
        frames = [f[..., :1].copy() for f in frames]
    return frames


def main(argv: list[str]) -> int:
    if len(argv) != 3:
        print(__doc__, file=sys.stderr)
        return 2
    sys.path.insert(0, argv[0])
    from eco import ECOTracker  # pyECO, from its checkout

    frames = read_frames(Path(argv[1]))
    x, y, w, h = (float(v) for v in argv[2].split(","))
    tracker = ECOTracker(frames[0].shape[2] == 3)
    started = time.perf_counter()
    tracker.init(frames[0], (x, y, w, h), total_frame=len(frames))
    boxes: list[list[float]] = [[x, y, w, h]]
    for frame in frames[1:]:
        x0, y0, x1, y1 = (float(v) for v in tracker.update(frame, True, False))
        # pyECO centres a box at x + (w - 1) / 2 and returns centre -/+ size / 2: undo both
        boxes.append([x0 + 0.5, y0 + 0.5, x1 - x0, y1 - y0])
    seconds = time.perf_counter() - started
    print(json.dumps({"tracker": "ECO-HC", "boxes": boxes, "ok": [True] * len(boxes),
                      "seconds": seconds}))
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
