"""The library entry point ``vtrack.track`` on a real encoded clip and on in-memory frames."""

from __future__ import annotations

from pathlib import Path

import numpy as np

import vtrack
from vtrack.geometry import center_error
from vtrack.scenes import make_scene, write_video


def test_track_a_path_and_frames_follow_the_target_alike(tmp_path: Path) -> None:
    scene = make_scene("smooth", seed=4, width=320, height=240, frames=40, fps=30)
    clip = write_video(scene, tmp_path / "clip.mp4")
    from_file = list(vtrack.track(str(clip), "s0", scene.boxes[0]))
    in_memory = list(vtrack.track(scene.as_frames(), vtrack.load_config("s0"), scene.boxes[0]))
    assert [r.index for r in from_file] == [r.index for r in in_memory] == list(range(40))
    for results in (from_file, in_memory):
        errors = [center_error(r.box, gt) for r, gt in zip(results, scene.boxes, strict=True)]
        assert np.mean(errors) < 10.0 and max(errors) < 25.0
    # a run request gives the same results as the path it names, up to its frame limit
    request = vtrack.RunRequest(str(clip), tmp_path / "unused", vtrack.load_config("s0"),
                                init_box=scene.boxes[0], max_frames=12)
    from_request = list(vtrack.track(request))
    assert [(r.index, r.box) for r in from_request] == [(r.index, r.box) for r in from_file[:12]]
    assert not (tmp_path / "unused").exists()  # nothing is written
    # the decoded clip differs from the rendered frames only by compression
    drift = [center_error(a.box, b.box) for a, b in zip(from_file, in_memory, strict=True)]
    assert np.median(drift) < 3.0
