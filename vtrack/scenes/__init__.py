"""Deterministic synthetic scenes with exact ground truth, for tests, samples and benchmarks.

Example::

    scene = make_scene("occlusion", seed=0, width=320, height=240, frames=120, fps=30)
    first = next(scene.frames())          # uint8 BGR, shape (240, 320, 3)
    scene.boxes[0], scene.visibility[0]   # exact Box (x, y, w, h) and visible fraction
    scene.events["occluded"]              # (start, end): frames where the target is hidden
    write_clip(scene, "clip.mp4")         # clip.mp4 + clip.gt.txt, as `vtrack scene` does

Same (scenario, seed, size, frames, fps) -> bit-identical frames. Scenarios, their defaults and
events: :data:`SCENARIOS` (the randomised ones, :mod:`.hard`, draw looks and motion from
:data:`RANGES`); ground-truth conventions: :class:`Scene` and :mod:`.writers`.
"""

from vtrack.scenes import pedestrians  # noqa: F401 (registers the pedestrians scenario)
from vtrack.scenes.hard import RANGES  # (importing .hard registers the randomised scenarios)
from vtrack.scenes.scenarios import SCENARIOS, Scenario, make_scene
from vtrack.scenes.scene import Scene
from vtrack.scenes.writers import (
    CLIP_FORMATS,
    RAW_PIX_FMTS,
    X264_PRESETS,
    ClipFiles,
    sidecar,
    write_clip,
    write_groundtruth,
    write_image_sequence,
    write_mot_groundtruth,
    write_raw,
    write_video,
)

__all__ = [
    "CLIP_FORMATS",
    "RANGES",
    "RAW_PIX_FMTS",
    "SCENARIOS",
    "X264_PRESETS",
    "ClipFiles",
    "Scenario",
    "Scene",
    "make_scene",
    "sidecar",
    "write_clip",
    "write_groundtruth",
    "write_image_sequence",
    "write_mot_groundtruth",
    "write_raw",
    "write_video",
]
