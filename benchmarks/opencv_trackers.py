"""OpenCV's own trackers on an image folder, for ``robust_bench.py`` (run in any Python with cv2).

    python benchmarks/opencv_trackers.py FOLDER X,Y,W,H TRACKER [TRACKER ...]

Reads every ``.jpg``/``.png`` of FOLDER (or FOLDER/img) in name order with ``cv2.imread`` (colour),
starts each tracker on the 0-based box X,Y,W,H on the first frame and prints one JSON line per
tracker: ``{"tracker", "boxes": [[x, y, w, h] | null, ...], "ok": [bool, ...], "seconds"}``.
``seconds`` is the tracking work only (init + every update; reading excluded); a tracker whose
update reports failure claims no box on that frame. A tracker this OpenCV lacks prints
``{"tracker", "error"}``.

Trackers: ``MIL``, ``KCF``, ``CSRT`` (``cv2.Tracker*_create``; KCF and CSRT need
``opencv-contrib-python-headless``, which is never a dependency of vtrack: install it in a
separate venv and give that venv's python to ``robust_bench.py``) and ``meanshift``, OpenCV's
meanShift tutorial ("Meanshift and Camshift", OpenCV docs): a 180-bin hue histogram of the
first box over pixels with S >= 60 and V >= 32, normalised to 0..255, back-projected over the
whole frame each frame, ``cv2.meanShift`` with criteria (EPS | COUNT, 10 iterations, 1 px).
"""

from __future__ import annotations

import json
import sys
import time
from pathlib import Path

import cv2
import numpy as np


def read_frames(folder: Path) -> list[np.ndarray]:
    """The folder's images (``img/`` inside it if present) in name order, as BGR arrays."""
    if (folder / "img").is_dir():
        folder = folder / "img"
    paths = sorted((p for p in folder.iterdir() if p.suffix.lower() in (".jpg", ".png")),
                   key=lambda p: (len(p.name), p.name))
    return [cv2.imread(str(p), cv2.IMREAD_COLOR) for p in paths]


class MeanShiftTutorial:
    """OpenCV's meanShift tutorial, step for step."""

    def init(self, frame: np.ndarray, box: tuple[int, int, int, int]) -> None:
        x, y, w, h = box
        hsv_roi = cv2.cvtColor(frame[y : y + h, x : x + w], cv2.COLOR_BGR2HSV)
        mask = cv2.inRange(hsv_roi, np.array((0.0, 60.0, 32.0)), np.array((180.0, 255.0, 255.0)))
        self.hist = cv2.calcHist([hsv_roi], [0], mask, [180], [0, 180])
        cv2.normalize(self.hist, self.hist, 0, 255, cv2.NORM_MINMAX)
        self.window = box
        self.criteria = (cv2.TERM_CRITERIA_EPS | cv2.TERM_CRITERIA_COUNT, 10, 1)

    def update(self, frame: np.ndarray) -> tuple[bool, tuple[int, int, int, int]]:
        hsv = cv2.cvtColor(frame, cv2.COLOR_BGR2HSV)
        dst = cv2.calcBackProject([hsv], [0], self.hist, [0, 180], 1)
        _, self.window = cv2.meanShift(dst, self.window, self.criteria)
        return True, self.window


def make(name: str):
    """A fresh tracker with ``init(frame, box)`` and ``update(frame) -> (ok, box)``."""
    if name == "meanshift":
        return MeanShiftTutorial()
    create = getattr(cv2, f"Tracker{name}_create", None)
    if create is None:
        legacy = getattr(cv2, "legacy", None)
        create = getattr(legacy, f"Tracker{name}_create", None) if legacy else None
    if create is None:
        raise LookupError(f"OpenCV {cv2.__version__} here has no Tracker{name}_create "
                          "(KCF and CSRT need opencv-contrib-python-headless)")
    return create()


def run(name: str, frames: list[np.ndarray], box: tuple[int, int, int, int]) -> dict:
    """One tracker over ``frames``: boxes, ok flags and tracking seconds."""
    tracker = make(name)
    started = time.perf_counter()
    tracker.init(frames[0], box)
    boxes: list[list[float] | None] = [list(map(float, box))]
    oks = [True]
    for frame in frames[1:]:
        ok, found = tracker.update(frame)
        oks.append(bool(ok))
        boxes.append([float(v) for v in found] if ok else None)
    seconds = time.perf_counter() - started
    return {"tracker": name, "boxes": boxes, "ok": oks, "seconds": seconds}


def main(argv: list[str]) -> int:
    if len(argv) < 3:
        print(__doc__, file=sys.stderr)
        return 2
    frames = read_frames(Path(argv[0]))
    x, y, w, h = (float(v) for v in argv[1].split(","))
    box = (round(x), round(y), max(round(w), 1), max(round(h), 1))
    for name in argv[2:]:
        try:
            print(json.dumps(run(name, frames, box)))
        except (LookupError, cv2.error) as exc:
            print(json.dumps({"tracker": name, "error": str(exc)}))
        sys.stdout.flush()
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
