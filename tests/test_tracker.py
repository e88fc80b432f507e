"""``vtrack.Tracker`` (init/update/reset) gives what ``vtrack run`` writes, for every config."""

from __future__ import annotations

import csv
from pathlib import Path

import av
import numpy as np
import pytest

import vtrack
from vtrack.config import shipped_configs
from vtrack.errors import ConfigError
from vtrack.io.csvfile import DECIMALS, format_cell
from vtrack.io.raw import RawFormat
from vtrack.run import run
from vtrack.scenes import make_scene, write_raw


def _cells(columns: list[str], values: list[object]) -> list[str]:
    return [format_cell(v, DECIMALS.get(c, 3)) for c, v in zip(columns, values, strict=True)]


@pytest.mark.parametrize("name", sorted(shipped_configs()))
def test_tracker_results_equal_run_csv(tmp_path: Path, name: str) -> None:
    """Frame by frame through ``Tracker.init``/``update`` on NumPy BGR images, the same box,
    state, score and extras as the CSV that ``vtrack run`` writes for those frames."""
    detecting = name in ("s3", "s4", "s4_multi")
    frames = 60 if detecting else 24  # the multi scene's shortest
    scene = make_scene("multi" if detecting else "smooth", seed=3, width=160, height=120,
                       frames=frames, fps=30)
    raw = write_raw(scene, tmp_path / "clip.bgr")
    config = vtrack.load_config(name)
    tracker = vtrack.Tracker(name)
    init = None if detecting else scene.boxes[0]
    run(vtrack.RunRequest(str(raw), tmp_path / "out", config, init_box=init, video=False,
                          raw=RawFormat(160, 120, "bgr24", 30.0)))
    results = [tracker.init(frame, init) if i == 0 else tracker.update(frame)
               for i, frame in enumerate(scene.frames())]
    assert all(r.frame is None for r in results)  # no decoded frame is kept
    multi = (tmp_path / "out" / "tracks.csv").exists()
    with (tmp_path / "out" / ("tracks.csv" if multi else "track.csv")).open() as f:
        reader = csv.reader(f)
        header = next(reader)
        rows = list(reader)
    mine = []
    for r in results:
        if multi:
            mine += [_cells(header, [r.index + 1, t.id, t.box.x, t.box.y, t.box.w, t.box.h,
                                     t.confidence, -1, -1, -1, t.state])
                     for t in r.tracks if t.state == "confirmed"]
        else:
            geometry = [None] * 6 if r.box is None else [*r.box, r.box.cx, r.box.cy]
            extras = [r.extras.get(c) for c in header[12:]]
            mine.append(_cells(header, [r.index, r.time_s, *geometry, r.state, r.score,
                                        None, None, *extras]))
    assert len(rows) == (len(mine) if multi else frames) and rows
    assert mine == rows


def test_tracker_takes_av_frames_grey_and_resets(tmp_path: Path) -> None:
    """``av.VideoFrame``s give the track their BGR arrays give; ``reset`` then ``init`` starts
    afresh (the same results again); params override the config like ``--set``."""
    scene = make_scene("smooth", seed=5, width=160, height=120, frames=12, fps=30)
    images = list(scene.frames())
    tracker = vtrack.Tracker("s0", meanshift__iterations=3)
    first = [tracker.init(f, scene.boxes[0]) if i == 0 else tracker.update(f)
             for i, f in enumerate(images)]
    tracker.reset()
    av_frames = [av.VideoFrame.from_ndarray(f, format="bgr24") for f in images]
    again = [tracker.init(f, scene.boxes[0]) if i == 0 else tracker.update(f)
             for i, f in enumerate(av_frames)]
    assert [(r.index, r.box, r.state, r.score) for r in first] == \
        [(r.index, r.box, r.state, r.score) for r in again]
    assert first[0].box == vtrack.Box(*scene.boxes[0])
    other = vtrack.Tracker("s0")
    default = [other.init(f, scene.boxes[0]) if i == 0 else other.update(f)
               for i, f in enumerate(images)]
    assert tracker.config.resolved() != other.config.resolved()
    assert len(default) == 12
    kept = vtrack.Tracker("s2", keep_frames=True)
    grey = np.ascontiguousarray(images[0][:, :, 1])
    assert kept.init(grey, scene.boxes[0]).frame is not None
    with pytest.raises(TypeError, match="frame 1"):
        kept.update([1, 2, 3])


def test_tracker_without_a_box_is_refused_for_a_box_config() -> None:
    with pytest.raises(ConfigError, match="initial box"):
        vtrack.Tracker("robust").update(np.zeros((48, 64, 3), np.uint8))
