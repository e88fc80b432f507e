"""A generated clip: frames rendered on demand plus exact ground truth for every frame."""

from __future__ import annotations

from collections.abc import Callable, Iterator
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from vtrack.frame import BgrFrame
from vtrack.geometry import Box
from vtrack.scenes.render import Compositor, Measured


@dataclass(frozen=True)
class Scene:
    """A deterministic synthetic clip with exact ground truth.

    Ground truth, per frame (0-based):

    - ``boxes[i]``: the target's (track id 1) exact bounding box, sub-pixel, *not* clipped to
      the frame; ``None`` only when the target lies entirely outside the frame. While the target
      is fully hidden behind a foreground object the box is its true (hidden) position, and
      ``visibility`` is 0: "where is it" and "can it be seen" are separate questions.
    - ``visibility[i]``: fraction (0..1) of the target's area that is drawn and not covered:
      1 fully visible, 0 fully occluded or out of the frame.
    - ``tracks[i]``: ``[(track_id, box), ...]`` for every tracked object at least partly inside
      the frame (also while occluded), sorted by id; single-target scenes have only id 1.
    - ``track_visibility[i]``: ``{track_id: fraction}`` for the objects of ``tracks[i]``, as
      ``visibility`` is for the target: the fraction of its area inside the frame and not
      covered by an object in front of it (MOTChallenge's visibility ratio).
    - ``events``: the scenario's key frames (see :data:`vtrack.scenes.SCENARIOS`).

    Frames are rendered when asked for (``frame(i)``, ``frames()``) and are bit-identical for the
    same scenario, seed, size, frame count and fps.
    """

    name: str
    width: int
    height: int
    fps: float
    seed: int
    boxes: list[Box | None]
    visibility: list[float]
    tracks: list[list[tuple[int, Box]]]
    track_visibility: list[dict[int, float]]
    events: dict[str, Any]
    compositor: Compositor = field(repr=False)

    def __len__(self) -> int:
        return len(self.boxes)

    def frame(self, index: int) -> np.ndarray:
        """Frame ``index`` (0-based) as a uint8 BGR array of shape (height, width, 3)."""
        if not 0 <= index < len(self):
            raise IndexError(f"frame {index} outside 0..{len(self) - 1}")
        return self.compositor.render(index)

    def frames(self) -> Iterator[np.ndarray]:
        """All frames in order, as uint8 BGR arrays of shape (height, width, 3)."""
        for index in range(len(self)):
            yield self.compositor.render(index)

    def as_frames(self) -> Iterator[BgrFrame]:
        """All frames as :class:`~vtrack.frame.BgrFrame` (time ``i / fps``): a pipeline can run
        on a scene directly, without writing a file."""
        for index, bgr in enumerate(self.frames()):
            yield BgrFrame(index, index / self.fps, bgr)


#: Per track id, per frame (0-based; only those of its span for a track drawn on some frames
#: only, see :class:`~vtrack.scenes.render.Sprite`): (box, in-frame fraction, visible fraction).
Truth = dict[int, dict[int, Measured]]


@dataclass(frozen=True)
class SceneSpec:
    """What was asked for: scenario name, seed, frame size, frame count and frame rate."""

    name: str
    seed: int
    width: int
    height: int
    frames: int
    fps: float

    def rng(self, stream: int) -> np.random.Generator:
        """Generator for one independent stream of randomness (0 motion, 1 looks)."""
        return np.random.default_rng([self.seed, stream])


def assemble(
    spec: SceneSpec,
    compositor: Compositor,
    events_of: Callable[[Truth], dict[str, Any]] | None = None,
) -> Scene:
    """Measure the ground truth of ``compositor`` and wrap everything in a :class:`Scene`.

    ``events_of`` derives the scenario's events from the measurement (spans of full occlusion,
    frames out of view, ...), so events always agree with the boxes and visibility.
    """
    truth = compositor.measure(spec.width, spec.height, spec.frames)
    target = [truth[1].get(i, (None, 0.0, 0.0)) for i in range(spec.frames)]
    in_view: list[list[int]] = [[] for _ in range(spec.frames)]
    for tid, rows in sorted(truth.items()):
        for i, (_, in_frame, _) in rows.items():
            if in_frame > 0.0:
                in_view[i].append(tid)
    return Scene(
        name=spec.name,
        width=spec.width,
        height=spec.height,
        fps=spec.fps,
        seed=spec.seed,
        boxes=[box if in_frame > 0.0 else None for box, in_frame, _ in target],
        visibility=[visible for _, _, visible in target],
        tracks=[[(tid, truth[tid][i][0]) for tid in ids] for i, ids in enumerate(in_view)],
        track_visibility=[{tid: truth[tid][i][2] for tid in ids} for i, ids in enumerate(in_view)],
        events=events_of(truth) if events_of else {},
        compositor=compositor,
    )
