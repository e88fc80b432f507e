"""A detection source that reads a MOTChallenge ``det.txt`` instead of looking at the pixels.

``mot_detections`` puts the boxes a file lists for the current frame into ``ctx.detections``,
so the multi-target trackers (``mht``, ``kalman_tracks``) can be run and scored on a benchmark's
public detections, which separates the tracker's quality from the detector's::

    [[stage]]
    name = "mot_detections"
    path = "MOT_TUD-Campus/det.txt"

    [[stage]]
    name = "mht"
"""

from __future__ import annotations

from pathlib import Path

from vtrack.errors import ConfigError, plural
from vtrack.evaluate.groundtruth import past_end_note, read_mot_detections
from vtrack.params import Param
from vtrack.stages.base import Stage, TrackContext, register
from vtrack.stages.detect import Detection


@register
class MotDetections(Stage):
    """Detections from a MOTChallenge ``det.txt`` (frame ``i`` of the file = 0-based frame
    ``i - 1`` of the input), each with its box centre as centroid, its box area and the file's
    confidence as score; boxes below ``min_score`` are dropped."""

    name = "mot_detections"
    summary = "detections read from a MOTChallenge det.txt (public detections) instead of pixels"
    params = (
        Param(
            "path",
            str,
            "",
            "the det.txt file (frame,id,x,y,w,h,conf,...), relative to the folder vtrack "
            "was started in (a batch's, also on Dask workers)",
        ),
        Param(
            "min_score",
            float,
            0.0,
            "detections with a confidence below this are dropped (DPM scores may be negative: "
            "lower it to keep them)",
            min=-1e9, max=1e9,
        ),
        Param(
            "max_detections",
            int,
            1000,
            "at most this many detections a frame, the highest-scoring (bounds the trackers' "
            "work, as blobs.max_blobs does)",
            min=1, max=1000,
        ),
    )
    provides = frozenset({"detections"})
    #: Parameters naming a file the stage reads: a run's request makes them absolute, and a
    #: batch reuses a result only while the file is the one the run read
    #: (:class:`~vtrack.request.RunRequest`).
    file_params = ("path",)
    needs_init_box = False

    def start(self, ctx: TrackContext) -> None:
        """Read the file (InputError if it cannot be read or parsed), then this frame's boxes."""
        if not self.path:
            raise ConfigError(f"stage '{self.name}': parameter 'path' must name a det.txt file "
                              f"(path = \"det.txt\" in the config's [[stage]] table, or --set "
                              f"{self.name}.path=FILE)")
        self._frames = read_mot_detections(Path(self.path))
        self._outside = 0
        self._crowded = 0  # frames that listed more than max_detections
        self._frame_size = (ctx.frame.width, ctx.frame.height)
        self._first = ctx.frame.index  # the run's first frame (0-based; --start moves it)
        self.step(ctx)

    def step(self, ctx: TrackContext) -> None:
        """This frame's boxes scoring ``min_score`` or more, at most ``max_detections`` of them,
        the highest-scoring (ties in the file's order); those wholly outside the frame are
        dropped (no tracker could follow them there). Both are counted for :meth:`notes`."""
        width, height = ctx.frame.width, ctx.frame.height
        self._end = ctx.frame.index + 1
        found = []
        for box, score in self._frames.get(ctx.frame.index, ()):
            if box.outside(width, height):
                self._outside += 1
            elif score >= self.min_score:
                found.append(Detection(box, box.cx, box.cy, box.area, score=score))
        if len(found) > self.max_detections:
            self._crowded += 1
            found = sorted(found, key=lambda d: -d.score)[: self.max_detections]
        ctx.detections.extend(found)

    def notes(self) -> list[str]:
        """That the file holds no detection (0 bytes or blank lines only: a detector that found
        nothing), how many of its detections lay wholly outside the frame, and how many frames
        listed more than ``max_detections``, if any."""
        notes = []
        if getattr(self, "_frames", None) == {}:
            notes.append(f"{self.path}: the file holds no detection (0 bytes or blank lines "
                         "only): no frame had any to track")
        if getattr(self, "_outside", 0):
            width, height = self._frame_size
            notes.append(f"{self.path}: {plural(self._outside, 'detection')} lay wholly outside "
                         f"the {width}x{height} frame and were ignored (are its boxes in this "
                         "input's pixels?)")
        if getattr(self, "_crowded", 0):
            notes.append(f"{self.path}: {plural(self._crowded, 'frame')} listed more than "
                         f"{self.max_detections} detections; each kept its {self.max_detections} "
                         "highest-scoring (mot_detections.max_detections)")
        return notes

    def past_end_notes(self) -> list[str]:
        """The file's detections in frames after the last one processed, if any: they were not
        used; or, when more than half of the frames the run processed come after the file's
        last detection (a file written for a clip half as long or less), that those frames had
        none. A scene empty for its last few frames is no warning. Either asks whether the file
        is this input's."""
        if not getattr(self, "_frames", None) or not hasattr(self, "_end"):
            return []  # (a file of no detection has its own note)
        note = past_end_note(self.path, "the file has detections", self._frames, self._end,
                             f"they were not used ({_WHOSE})")
        last = max(self._frames) + 1  # 1-based, as the file numbers it
        after = self._end - max(last, self._first)  # the run's frames after the last detection
        if note is None and 2 * after > self._end - self._first:
            note = (f"{self.path}: the file's detections end at frame {last}, before the "
                    f"input's last frame {self._end}; the {plural(after, 'frame')} after it had "
                    f"none ({_WHOSE})")
        return [] if note is None else [note]


#: What a warning of a det.txt's frames that do not fit the input asks.
_WHOSE = "is it this input's det.txt?"
