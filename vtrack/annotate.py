"""Drawing the tracker's output straight into I420 planes, before the frame is encoded.

Every shape is drawn twice: on the Y plane at full resolution with the colour's luma, and on the
half-size U and V planes at half coordinates with its chroma. The frame is never converted to BGR
and back, and only the drawn pixels are touched (~0.1 ms per 1080p frame).

What is drawn: the ground-truth box (if given), the stage overlays (:mod:`vtrack.overlays`:
``SearchWindow`` as a thin rectangle, ``Particles`` as dots sized like the lines; another kind
is a ``TypeError``), the trajectory of the last ``trail`` centres, the tracked box and its centre,
confirmed multi-target tracks (a stable colour and a short trail per id, the id as text on a
black plate above the box, kept inside the frame and clear of the caption), the
state caption: ``TRACKING`` / ``OCCLUDED`` top-left, ``LOST`` top-right (with no box), and
bottom-left the frame number (``track.csv``'s ``frame``, 0-based; for multi-target results
``tracks.csv``'s, 1-based as MOTChallenge numbers frames) above a legend of the colours.
The prediction (where the next search starts, single target) is a thin box. The legend lists
only what this run has drawn so far (a tracker without a search window has no such row; the
``lost`` row appears with the first lost frame), so it differs between trackers.

A multi-target run (``multi_target``) has no single target: its caption counts the tracks shown
(``3 TRACKS``), its legend explains the per-id colours (and the ground truth, thin green boxes
of every object when given), and no single-target box, trail or prediction is drawn.

Line widths, dots and text scale with the frame (1 px lines and the smallest text at 320x240).
The legend is rendered into a small I420 patch when its rows change (at most once per kind of
shape) and copied into each frame; only the frame number is drawn per frame, on the patch's black
top row (luma only: white on black has neutral chroma).
"""

from __future__ import annotations

import math
from collections import deque
from collections.abc import Iterable, Mapping, Sequence
from typing import NamedTuple

import cv2
import numpy as np

from vtrack.geometry import Box
from vtrack.io.planes import i420_planes
from vtrack.overlays import Overlay, Particles, SearchWindow
from vtrack.pipeline import FrameResult
from vtrack.stages.base import Track, TrackState, TrackStatus


class Yuv(NamedTuple):
    """A colour as the Y, U, V values OpenCV's BGR <-> I420 conversion uses (BT.601)."""

    y: int
    u: int
    v: int

    @classmethod
    def from_bgr(cls, b: int, g: int, r: int) -> Yuv:
        i420 = cv2.cvtColor(np.full((2, 2, 3), (b, g, r), np.uint8), cv2.COLOR_BGR2YUV_I420)
        return cls(int(i420[0, 0]), int(i420[2, 0]), int(i420[2, 1]))


# BGR of the colours the legend explains (one definition for the drawing and the legend)
TRACKED_BGR = (0, 255, 255)  # yellow
OCCLUDED_BGR = (0, 165, 255)  # orange
GROUND_TRUTH_BGR = (0, 220, 0)  # green
WINDOW_BGR = (255, 255, 0)  # cyan
PREDICTION_BGR = (255, 128, 64)  # light blue
TRACKED = Yuv.from_bgr(*TRACKED_BGR)
OCCLUDED_BOX = Yuv.from_bgr(*OCCLUDED_BGR)
LOST_BGR = (40, 40, 255)  # red
PARTICLES_BGR = (255, 0, 255)  # magenta
LOST_TEXT = Yuv.from_bgr(*LOST_BGR)
GROUND_TRUTH = Yuv.from_bgr(*GROUND_TRUTH_BGR)
WINDOW = Yuv.from_bgr(*WINDOW_BGR)
PARTICLES = Yuv.from_bgr(*PARTICLES_BGR)
PREDICTION = Yuv.from_bgr(*PREDICTION_BGR)
CAPTION_BACKGROUND = Yuv.from_bgr(0, 0, 0)
#: Track colours, none of them a green that could pass for the ground truth's.
TRACK_PALETTE_BGR = (
    (255, 128, 0), (0, 200, 255), (180, 0, 255), (64, 64, 192), (255, 0, 128),
    (192, 64, 192), (0, 128, 255), (255, 255, 255), (160, 160, 255), (255, 160, 160),
)
TRACK_PALETTE = tuple(Yuv.from_bgr(*bgr) for bgr in TRACK_PALETTE_BGR)
FONT = cv2.FONT_HERSHEY_SIMPLEX
#: Coordinates are clipped to this far outside the frame before drawing (cv2 needs int32).
_MARGIN = 1 << 15


def _point(x: float, y: float) -> tuple[int, int]:
    return (int(min(max(round(x), -_MARGIN), _MARGIN)), int(min(max(round(y), -_MARGIN), _MARGIN)))


def _corners(box: Box) -> tuple[tuple[int, int], tuple[int, int]]:
    """Top-left and bottom-right pixel of a box (inclusive, as cv2.rectangle wants)."""
    return _point(box.x, box.y), _point(box.x + box.w - 1, box.y + box.h - 1)


def _half(p: tuple[int, int]) -> tuple[int, int]:
    return p[0] // 2, p[1] // 2


class Canvas:
    """The Y, U, V planes of one I420 buffer, with shapes drawn in all three."""

    def __init__(self, buffer: np.ndarray) -> None:
        self.height = buffer.shape[0] * 2 // 3
        self.width = buffer.shape[1]
        self.y, self.u, self.v = i420_planes(buffer, self.width, self.height)

    def rectangle(self, p0: tuple[int, int], p1: tuple[int, int], colour: Yuv, thickness: int,
                  ) -> None:
        """Outline (``thickness`` > 0) or fill (``thickness`` = -1) the rectangle p0..p1."""
        cv2.rectangle(self.y, p0, p1, colour.y, thickness)
        half = thickness if thickness < 0 else max(1, thickness // 2)
        cv2.rectangle(self.u, _half(p0), _half(p1), colour.u, half)
        cv2.rectangle(self.v, _half(p0), _half(p1), colour.v, half)

    def circle(self, centre: tuple[int, int], radius: int, colour: Yuv) -> None:
        """A filled disc."""
        cv2.circle(self.y, centre, radius, colour.y, -1)
        cv2.circle(self.u, _half(centre), max(1, radius // 2), colour.u, -1)
        cv2.circle(self.v, _half(centre), max(1, radius // 2), colour.v, -1)

    def polyline(self, points: Sequence[tuple[int, int]], colour: Yuv, thickness: int) -> None:
        if len(points) < 2:
            return
        full = np.array(points, np.int32).reshape(-1, 1, 2)
        cv2.polylines(self.y, [full], False, colour.y, thickness)
        half = full // 2
        cv2.polylines(self.u, [half], False, colour.u, max(1, thickness // 2))
        cv2.polylines(self.v, [half], False, colour.v, max(1, thickness // 2))

    def text(self, origin: tuple[int, int], text: str, colour: Yuv, scale: float,
             thickness: int) -> None:
        """Text with its baseline starting at ``origin`` (chroma drawn at half scale)."""
        cv2.putText(self.y, text, origin, FONT, scale, colour.y, thickness, cv2.LINE_AA)
        half = max(1, thickness // 2)
        cv2.putText(self.u, text, _half(origin), FONT, scale / 2, colour.u, half)
        cv2.putText(self.v, text, _half(origin), FONT, scale / 2, colour.v, half)

    def dots(self, points: np.ndarray, colour: Yuv, size: int = 1) -> None:
        """Square dots of ``2 * size`` pixels a side at ``points`` (an (N, 2) array of x, y),
        each covering whole chroma samples; the parts of dots outside the frame are skipped."""
        if points.size == 0:
            return
        finite = np.isfinite(points).all(axis=1)
        # one chroma sample = a 2x2 luma block; a dot is size x size chroma samples
        cells = (points[finite] // 2).astype(np.int64) - size // 2
        cw, ch = self.width // 2, self.height // 2
        for oy in range(size):
            for ox in range(size):
                cx, cy = cells[:, 0] + ox, cells[:, 1] + oy
                inside = (cx >= 0) & (cx < cw) & (cy >= 0) & (cy < ch)
                cx, cy = cx[inside], cy[inside]
                for dy in (0, 1):
                    for dx in (0, 1):
                        self.y[2 * cy + dy, 2 * cx + dx] = colour.y
                self.u[cy, cx] = colour.u
                self.v[cy, cx] = colour.v


def _shown(track: Track) -> bool:
    """Whether a multi-target track is drawn: confirmed, with a box that can be drawn."""
    return track.state == TrackStatus.CONFIRMED and _drawable(track.box)


def _drawable(box: Box | None) -> bool:
    return box is not None and all(math.isfinite(v) for v in box) and box.w > 0 and box.h > 0


def _draw_overlay(canvas: Canvas, overlay: Overlay, thickness: int) -> str:
    """Draw one stage overlay and return its legend row; a kind this function does not know is
    a TypeError."""
    match overlay:
        case SearchWindow(box):
            canvas.rectangle(*_corners(box), WINDOW, 1)
            return "search window"
        case Particles(centres):
            canvas.dots(centres, PARTICLES, thickness)
            return "particles"
        case _:
            raise TypeError(f"annotate: no drawing for overlay {overlay!r}")


BGR = tuple[int, int, int]
#: Every legend row, in the order they are listed: what each colour means (README, "Outputs").
#: A legend shows the rows of the shapes its run has drawn ("track id": the swatch shows the
#: first colours of the palette).
LEGEND_ROWS: dict[str, tuple[BGR, ...]] = {
    "box": (TRACKED_BGR,),
    "occluded": (OCCLUDED_BGR,),
    "lost (no box)": (LOST_BGR,),
    "track id": TRACK_PALETTE_BGR[:4],
    "prediction": (PREDICTION_BGR,),
    "search window": (WINDOW_BGR,),
    "particles": (PARTICLES_BGR,),
    "ground truth": (GROUND_TRUTH_BGR,),
}
#: The legend is left out (the frame number stays) when it would be taller than this share
#: of the frame: on tiny frames it would hide what it explains.
LEGEND_MAX_SHARE = 0.4


class Legend:
    """The bottom-left block: a row for the frame number, then one row per colour.

    Rendered once (BGR, converted to I420 with OpenCV) into ``y``, ``u``, ``v`` patches;
    :meth:`draw` copies them into a frame's planes and writes the frame number.
    """

    def __init__(self, width: int, height: int, font_scale: float,
                 labels: Iterable[str] = ()) -> None:
        self.scale = max(0.3, font_scale * 0.6)
        shown = set(labels)
        rows = [(label, bgr) for label, bgr in LEGEND_ROWS.items() if label in shown]
        (text_w, text_h), base = cv2.getTextSize("frame 000000", FONT, self.scale, 1)
        for label, _ in rows:
            text_w = max(text_w, cv2.getTextSize(label, FONT, self.scale, 1)[0][0])
        self.row = text_h + base + 3
        self.pad = 3
        swatch = 3 * self.row // 2
        pw = _even(self.pad * 3 + swatch + text_w)
        full = _even(self.pad * 2 + self.row * (len(rows) + 1))
        ph = full if full <= LEGEND_MAX_SHARE * height else _even(self.pad * 2 + self.row)
        rows = rows if ph == full else []
        self.rows = tuple(label for label, _ in rows)
        pw, ph = min(pw, width - width % 2), min(ph, height - height % 2)
        self.y0 = _even(height - ph)  # the left edge: x = 0
        patch = np.zeros((ph, pw, 3), np.uint8)
        for n, (label, colours) in enumerate(rows, start=1):
            mid = self.pad + n * self.row + self.row // 2
            edges = np.linspace(self.pad, self.pad + swatch, len(colours) + 1).round().astype(int)
            for x0, x1, bgr in zip(edges[:-1], edges[1:], colours, strict=True):
                cv2.rectangle(patch, (int(x0), mid - 2), (int(x1), mid + 1), bgr, -1)
            cv2.putText(patch, label, (2 * self.pad + swatch, mid + text_h // 2), FONT,
                        self.scale, colours[0] if len(colours) == 1 else (235, 235, 235), 1,
                        cv2.LINE_AA)
        i420 = cv2.cvtColor(patch, cv2.COLOR_BGR2YUV_I420)
        self.y, self.u, self.v = (p.copy() for p in i420_planes(i420, pw, ph))
        self.text_h = text_h

    def draw(self, canvas: Canvas, index: int) -> None:
        """Copy the legend into the bottom-left corner and write ``frame INDEX`` on top."""
        ph, pw = self.y.shape
        y0 = self.y0
        canvas.y[y0:y0 + ph, :pw] = self.y
        canvas.u[y0 // 2:(y0 + ph) // 2, :pw // 2] = self.u
        canvas.v[y0 // 2:(y0 + ph) // 2, :pw // 2] = self.v
        corner = canvas.y[y0:y0 + self.pad + self.row, :pw]  # a view: drawn in place
        cv2.putText(corner, f"frame {index}", (self.pad, self.pad + self.text_h), FONT,
                    self.scale, 235, 1, cv2.LINE_AA)


def _even(n: int) -> int:
    return n - n % 2


class _Plate(NamedTuple):
    """A caption laid out: its ``text``, its black plate from ``(x0, 0)`` to ``corner`` (right
    edge, bottom) and the text's ``origin`` (baseline-left, as ``cv2.putText`` takes it)."""

    text: str
    x0: int
    corner: tuple[int, int]
    origin: tuple[int, int]


class Annotator:
    """Draws one :class:`~vtrack.pipeline.FrameResult` per frame into an I420 buffer.

    Keeps the trajectory (last ``trail`` centres) and per-track trails between calls, so call
    ``draw`` once per frame, in order. ``gt`` is the ground truth by frame index (None = none).
    ``multi_target``: the results are a multi-target tracker's (caption, legend and drawing as
    the module says); ``gt_tracks`` its ground truth, ``{frame: [(id, box), ...]}``.
    ``width``/``height`` set line widths and text size; the planes' size comes from the buffer.
    """

    def __init__(
        self,
        width: int,
        height: int,
        gt: Sequence[Box | None] | None = None,
        trail: int = 30,
        legend: bool = True,
        multi_target: bool = False,
        gt_tracks: Mapping[int, Sequence[tuple[int, Box]]] | None = None,
    ) -> None:
        scale = max(width, height * 16 / 9) / 1280.0  # 1.0 at 720p, 1.5 at 1080p
        self.thickness = max(1, round(2 * scale))
        self.font_scale = max(0.35, 0.7 * scale)
        self.gt = gt
        self.trail: deque[tuple[int, int] | None] = deque(maxlen=max(trail, 1))
        self.track_trail = max(2, trail // 2)
        self._tracks: dict[int, deque[tuple[int, int]]] = {}
        self._last_seen: dict[int, int] = {}
        self.multi_target = multi_target
        self.gt_tracks = gt_tracks
        self._size = (width, height)
        self._drawn: set[str] = set()  # the legend rows of the shapes drawn so far
        self.legend = Legend(width, height, self.font_scale) if legend else None

    def draw(self, i420_buffer: np.ndarray, result: FrameResult) -> None:
        """Draw ``result`` into ``i420_buffer`` (an ``(h * 3 // 2, w)`` I420 array) in place."""
        canvas = Canvas(i420_buffer)
        drawn = self._draw_multi(canvas, result) if self.multi_target else self._draw_single(
            canvas, result)
        if self.legend is not None:
            if not drawn <= self._drawn:
                self._drawn |= drawn
                self.legend = Legend(*self._size, self.font_scale, self._drawn)
            # the number of the frame's rows in the run's CSV: tracks.csv's are 1-based (MOT)
            self.legend.draw(canvas, result.index + 1 if self.multi_target else result.index)

    def _draw_single(self, canvas: Canvas, result: FrameResult) -> set[str]:
        """A single-target frame; returns the legend rows of what it drew."""
        t = self.thickness
        drawn: set[str] = set()
        if self.gt is not None and result.index < len(self.gt):
            gt_box = self.gt[result.index]
            if _drawable(gt_box):
                canvas.rectangle(*_corners(gt_box), GROUND_TRUTH, t)
                drawn.add("ground truth")
        drawn.update(_draw_overlay(canvas, overlay, t) for overlay in result.overlays)
        if _drawable(result.prediction) and not result.tracks:
            canvas.rectangle(*_corners(result.prediction), PREDICTION, 1)
            drawn.add("prediction")
        box = result.box
        colour = OCCLUDED_BOX if result.state == TrackState.OCCLUDED else TRACKED
        self.trail.append(_point(box.cx, box.cy) if _drawable(box) else None)
        for run in self._runs(self.trail):
            canvas.polyline(run, colour, max(1, t // 2))
        if _drawable(box):
            canvas.rectangle(*_corners(box), colour, t)
            canvas.circle(_point(box.cx, box.cy), t + 1, colour)
            drawn.add("occluded" if result.state == TrackState.OCCLUDED else "box")
        if self._draw_tracks(canvas, result):
            drawn.add("track id")
        colour = {TrackState.LOST: LOST_TEXT, TrackState.OCCLUDED: OCCLUDED_BOX}.get(
            result.state, TRACKED)
        self._caption(canvas, self._caption_plate(canvas, result.state,
                                                  right=result.state == TrackState.LOST), colour)
        if result.state == TrackState.LOST:
            drawn.add("lost (no box)")
        return drawn

    def _draw_multi(self, canvas: Canvas, result: FrameResult) -> set[str]:
        """A multi-target frame: ground truth, the confirmed tracks, their count; returns the
        legend rows of what it drew."""
        drawn: set[str] = set()
        if self.gt_tracks is not None:
            for _, box in self.gt_tracks.get(result.index, ()):
                if _drawable(box):
                    canvas.rectangle(*_corners(box), GROUND_TRUTH, 1)
                    drawn.add("ground truth")
        drawn.update(_draw_overlay(canvas, overlay, self.thickness) for overlay in result.overlays)
        shown = sum(_shown(track) for track in result.tracks)
        caption = f"{shown} track" + ("" if shown == 1 else "s")
        plate = self._caption_plate(canvas, caption)
        if self._draw_tracks(canvas, result, clear_of=plate.corner):
            drawn.add("track id")
        self._caption(canvas, plate, TRACKED)
        return drawn

    @staticmethod
    def _runs(points: Iterable[tuple[int, int] | None]) -> list[list[tuple[int, int]]]:
        """Consecutive stretches of the trail without a gap (frames with no box break it)."""
        runs: list[list[tuple[int, int]]] = [[]]
        for p in points:
            if p is None:
                runs.append([])
            else:
                runs[-1].append(p)
        return [r for r in runs if len(r) > 1]

    def _draw_tracks(self, canvas: Canvas, result: FrameResult,
                     clear_of: tuple[int, int] = (0, 0)) -> int:
        """Draw the confirmed tracks (box, id, trail); returns how many. Their ids keep clear
        of ``clear_of``, the (width, height) of the top-left caption drawn over them."""
        t = self.thickness
        shown = 0
        for track in result.tracks:
            if not _shown(track):
                continue
            colour = TRACK_PALETTE[track.id % len(TRACK_PALETTE)]
            b = track.box
            trail = self._tracks.setdefault(track.id, deque(maxlen=self.track_trail))
            trail.append(_point(b.cx, b.cy))
            self._last_seen[track.id] = result.index
            canvas.polyline(list(trail), colour, max(1, t // 2))
            p0, p1 = _corners(b)
            canvas.rectangle(p0, p1, colour, t)
            self._label(canvas, p0, str(track.id), colour, clear_of)
            shown += 1
        stale = [i for i, seen in self._last_seen.items() if result.index - seen > self.track_trail]
        for track_id in stale:
            del self._tracks[track_id], self._last_seen[track_id]
        return shown

    def _label(self, canvas: Canvas, corner: tuple[int, int], text: str, colour: Yuv,
               clear_of: tuple[int, int]) -> None:
        """A track's id ``text`` in its ``colour`` on a black plate (readable on a target of
        that colour too), above the box's top-left ``corner``, moved into the frame when that
        is outside it (a box cut by the frame's left or top border: the id goes inside the
        box, under its top edge) and below the top-left caption (``clear_of``: its width and
        height), so every drawn track shows its id."""
        t, scale = self.thickness, self.font_scale * 0.8
        (w, h), baseline = cv2.getTextSize(text, FONT, scale, t)
        x = min(max(corner[0], 0), max(canvas.width - w, 0))
        top = clear_of[1] if x < clear_of[0] else 0  # the first row the id may cover
        y = corner[1] - 2 * t
        if y - h < top:  # no room above the box: under its top edge (and the caption)
            y = max(corner[1], top) + 2 * t + h
        y = min(y, canvas.height - 1 - baseline)
        canvas.rectangle((x - t, y - h - t), (x + w + t - 1, y + t), CAPTION_BACKGROUND, -1)
        canvas.text((x, y), text, colour, scale, t)

    def _caption_plate(self, canvas: Canvas, caption: str, right: bool = False) -> _Plate:
        """Where ``caption`` goes, in capitals on a black plate, top-left (``right``:
        top-right): the text measured once for the plate and the text in it."""
        text = caption.upper()
        t = self.thickness
        (w, h), baseline = cv2.getTextSize(text, FONT, self.font_scale, t)
        pad = 2 * t + 2
        x0 = canvas.width - w - 2 * pad if right else 0
        return _Plate(text, x0, (x0 + w + 2 * pad, h + baseline + 2 * pad), (x0 + pad, pad + h))

    def _caption(self, canvas: Canvas, plate: _Plate, colour: Yuv) -> None:
        """Draw the caption ``plate`` (:meth:`_caption_plate`), its text in ``colour``."""
        canvas.rectangle((plate.x0, 0), plate.corner, CAPTION_BACKGROUND, -1)
        canvas.text(plate.origin, plate.text, colour, self.font_scale, self.thickness)
