"""OpenCV's own trackers on an image folder, for ``robust_bench.py`` (run in any Python with cv2).

    python benchmarks/opencv_trackers.py FOLDER X,Y,W,H TRACKER [TRACKER ...] [--nano-models DIR]

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
``Nano``: NanoTrack v2 through ``cv2.TrackerNano`` (OpenCV >= 4.7), a small Siamese network whose
two ONNX files (``nanotrack_backbone_sim.onnx``, ``nanotrack_head_sim.onnx``, from the
repository HonglinChu/SiamTrackers, folder ``NanoTrack/models/nanotrackv2/``) are read from
``--nano-models DIR``; never a dependency of vtrack either.
"""

from __future__ import annotations

import argparse
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


#: NanoTrack v2's two ONNX files, in ``--nano-models``.
NANO_FILES = ("nanotrack_backbone_sim.onnx", "nanotrack_head_sim.onnx")


def make_nano(models: Path | None):
    """NanoTrack v2 (``cv2.TrackerNano``) from the two ONNX files in ``models``."""
    if not hasattr(cv2, "TrackerNano"):
        raise LookupError(f"OpenCV {cv2.__version__} here has no TrackerNano (needs >= 4.7)")
    if models is None or not all((models / f).is_file() for f in NANO_FILES):
        raise LookupError("NanoTrack v2 needs --nano-models DIR holding "
                          + " and ".join(NANO_FILES))
    params = cv2.TrackerNano_Params()
    params.backbone = str(models / NANO_FILES[0])
    params.neckhead = str(models / NANO_FILES[1])
    return cv2.TrackerNano_create(params)


def make(name: str, nano_models: Path | None = None):
    """A fresh tracker with ``init(frame, box)`` and ``update(frame) -> (ok, box)``."""
    if name == "meanshift":
        return MeanShiftTutorial()
    if name == "Nano":
        return make_nano(nano_models)
    create = getattr(cv2, f"Tracker{name}_create", None)
    if create is None:
        legacy = getattr(cv2, "legacy", None)
        create = getattr(legacy, f"Tracker{name}_create", None) if legacy else None
    if create is None:
        raise LookupError(f"OpenCV {cv2.__version__} here has no Tracker{name}_create "
                          "(KCF and CSRT need opencv-contrib-python-headless)")
    return create()


def run(name: str, frames: list[np.ndarray], box: tuple[int, int, int, int],
        nano_models: Path | None = None) -> dict:
    """One tracker over ``frames``: boxes, ok flags and tracking seconds."""
    tracker = make(name, nano_models)
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
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("folder", type=Path)
    parser.add_argument("box", help="0-based X,Y,W,H on the first frame")
    parser.add_argument("trackers", nargs="+")
    parser.add_argument("--nano-models", type=Path, default=None,
                        help="folder of NanoTrack v2's two ONNX files")
    args = parser.parse_args(argv)
    frames = read_frames(args.folder)
    x, y, w, h = (float(v) for v in args.box.split(","))
    box = (round(x), round(y), max(round(w), 1), max(round(h), 1))
    for name in args.trackers:
        try:
            print(json.dumps(run(name, frames, box, args.nano_models)))
        except (LookupError, cv2.error) as exc:
            print(json.dumps({"tracker": name, "error": str(exc)}))
        sys.stdout.flush()
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
