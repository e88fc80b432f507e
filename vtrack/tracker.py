"""``vtrack.Tracker``: one frame in, one result out, as OpenCV's and norfair's trackers work.

``Tracker(config, **params).init(frame, box)`` then ``update(frame)`` for each next frame; frames
are NumPy BGR (``HxWx3``) or grey (``HxW``, ``HxWx1``) uint8 images, :class:`vtrack.Frame`
objects or PyAV ``av.VideoFrame`` objects. The same chain of stages as ``vtrack run`` runs on
them, so a frame gives the same box, state and score here as in ``track.csv``.
"""

from __future__ import annotations

import os
from typing import Any

import numpy as np

from vtrack.config import Config, load_config
from vtrack.configs import DEFAULT_CONFIG
from vtrack.errors import ConfigError, cut
from vtrack.frame import BgrFrame, Frame, GrayFrame, check_pixels
from vtrack.geometry import Box, frame_size_problem
from vtrack.io.raw import checked_fps
from vtrack.params import check_flag, check_seed, shown
from vtrack.pipeline import FrameResult, Pipeline, check_first_track_id

#: A frame as :meth:`Tracker.update` takes it.
FrameLike = Frame | np.ndarray | Any  # Any: an av.VideoFrame (PyAV is imported only if used)


def as_frame(item: FrameLike, index: int, fps: float, time_s: float | None = None) -> Frame:
    """``item`` as a :class:`Frame` numbered ``index``: a Frame as it is; a uint8 ``HxWx3`` BGR
    or ``HxW`` / ``HxWx1`` grey array (a camera's one-channel image) timed ``time_s``
    (``index / fps`` when None); an ``av.VideoFrame`` as ``vtrack run``'s reader takes it (I420
    planes, converted as there) and timed by its own timestamp (``time_s`` if it has none).
    TypeError for anything else: pixels that are not uint8, a 4-channel image (BGRA or RGBA:
    which, and whether the 4th is alpha, the array does not say; the message says how to give
    its colour), a picture FFmpeg cannot convert to BGR (rgb4); ValueError for a size vtrack
    refuses and for an ``av.VideoFrame`` whose ``pts`` has no ``time_base`` (no time)."""
    if isinstance(item, Frame):
        return item
    if time_s is None:
        time_s = index / fps
    if isinstance(item, np.ndarray):
        # checked before a copy is made (a huge or float array is refused, not copied)
        if item.ndim == 3 and item.shape[2] == 1:
            item = item[:, :, 0]  # grey (a view: contiguous when the image is)
        if item.ndim == 2:
            check_pixels(index, item, 2, "HxW grey")
            frame_type: type[BgrFrame | GrayFrame] = GrayFrame
        else:
            if item.ndim == 3 and item.shape[2] == 4:
                raise TypeError(f"frame {index}: a 4-channel image {shape_text(item)} (BGRA?) is "
                                "not read: give its BGR colour, image[:, :, :3] "
                                "(cv2.cvtColor(image, cv2.COLOR_RGBA2BGR) for RGBA)")
            check_pixels(index, item, 3, "HxWx3 BGR or HxW grey")
            frame_type = BgrFrame
        problem = frame_size_problem(item.shape[1], item.shape[0])
        if problem:
            raise ValueError(f"frame {index}: {problem}")
        return frame_type(index, time_s, np.ascontiguousarray(item))
    if type(item).__module__.split(".")[0] == "av":  # PyAV only for a PyAV object
        import av

        if isinstance(item, av.VideoFrame):
            return _decoded(item, index, time_s)
    raise TypeError(f"frame {index}: expected a vtrack.Frame, a NumPy image or an "
                    f"av.VideoFrame, got {type(item).__name__}")


def shape_text(image: np.ndarray) -> str:
    """``image``'s shape as a message writes a picture's: ``120x160x4``."""
    return "x".join(str(n) for n in image.shape)


def _decoded(item: Any, index: int, untimed_s: float) -> Frame:
    """An ``av.VideoFrame`` as ``vtrack run``'s reader takes it (see :func:`as_frame`)."""
    import av

    from vtrack.io.video import decoded_frame

    problem = frame_size_problem(item.width, item.height)
    if problem:
        raise ValueError(f"frame {index}: {problem}")
    if item.pts is not None and item.time_base is None:  # (PyAV's time: NaN)
        raise ValueError(f"frame {index}: an av.VideoFrame with pts {item.pts} but no "
                         "time_base: its time cannot be told (set its time_base, or its pts "
                         "to None to have it timed as a NumPy image is)")
    time_s = untimed_s if item.time is None else float(item.time)
    try:
        return decoded_frame(item, index, time_s)  # as vtrack run reads it
    except av.FFmpegError as exc:
        raise TypeError(f"frame {index}: FFmpeg cannot convert an av.VideoFrame of pixel "
                        f"format {item.format.name} to BGR ({exc.strerror})") from None


def _by_parameter(params: dict[str, Any]) -> dict[str, Any]:
    """``params`` keyed ``"stage.param"`` (``stage__param`` is written so); ConfigError for one
    parameter given twice (``meanshift__iterations=3`` and ``**{"meanshift.iterations": 2}``),
    which would leave one value unused without a word, and for a keyword that names no stage
    parameter (``Tracker("s0", iterations=3)``, a misspelt ``kepp_frames=True``), said as
    the keyword it is."""
    values: dict[str, Any] = {}
    given: dict[str, str] = {}
    for key, value in params.items():
        name = key.replace("__", ".", 1).strip()
        if "." not in name:
            raise ConfigError(f"{cut(key)}={shown(value)}: not an argument of Tracker(); "
                              "a stage's parameter is given as "
                              "stage__param=value (e.g. meanshift__iterations=10)")
        if name in given:
            raise ConfigError(f"{name}: given twice ({given[name]}={shown(params[given[name]])}, "
                              f"{key}={shown(value)}); give it once")
        values[name], given[name] = value, key
    return values


class Tracker:
    """A per-frame tracker over any shipped or own config.

    ``params`` override the config's parameters, keyed ``"stage.param"`` or ``stage__param``
    (``Tracker("s0", meanshift__iterations=10, kalman__model="ca")``), Python (or NumPy)
    values checked as a config file's are; ``config`` None is the default config. Results are
    :class:`FrameResult`: ``box`` (None while lost), ``state``, ``score``, ``extras`` and, for
    the multi-target configs (s3, s4_multi), ``tracks``, numbered from ``first_track_id`` (1 to
    :data:`~vtrack.params.MAX_TRACK_ID`, default 1; a ConfigError for one other than 1 with a
    single-target config, which numbers no tracks). A result keeps its decoded frame only
    with ``keep_frames=True`` (a copy of its pixels: a raw reader's or a camera's buffer
    refilled later leaves it as it was), so memory stays flat over any number of frames.
    """

    def __init__(self, config: str | os.PathLike[str] | Config | None = DEFAULT_CONFIG, *,
                 seed: int = 0, fps: float = 30.0, keep_frames: bool = False,
                 first_track_id: int = 1, **params: Any) -> None:
        chain = config if isinstance(config, Config) else load_config(config)
        if params:
            chain = chain.with_values(_by_parameter(params))
        chain.check_files_named()
        self.config = chain
        self.seed = check_seed(seed)
        self.first_track_id = check_first_track_id(first_track_id, chain.multi_target,
                                                   chain.name)
        self.fps = checked_fps(fps, "fps")
        self.keep_frames = check_flag(keep_frames, "keep_frames")
        self._pipeline: Pipeline | None = None
        self._index = 0
        #: The last frame timed off the ``index / fps`` timeline (its index and time_s), from
        #: which the images after it are timed.
        self._timed_at: tuple[int, float] = (0, 0.0)

    @property
    def multi_target(self) -> bool:
        """True for the configs that detect and return several tracks (no initial box)."""
        return self.config.multi_target

    @property
    def needs_init_box(self) -> bool:
        """True for the configs that start from the target's first box (all but s3, s4, ...)."""
        return any(stage.needs_init_box for stage in self.config.stage_classes())

    def _new_pipeline(self) -> Pipeline:
        return Pipeline(self.config.build(), seed=self.seed, first_track_id=self.first_track_id)

    def init(self, frame: FrameLike, box: Box | Any = None) -> FrameResult:
        """Start tracking at ``frame`` with the target's box ``(x, y, w, h)`` in it (None for
        the detecting configs); returns that frame's result (its box is ``box``).

        A new track: a NumPy image is numbered 0 (``index``, ``time_s`` 0), also when the
        tracker was tracking (give a :class:`vtrack.Frame` to keep a camera's numbering).
        ConfigError for a box the frame cannot start from (as ``vtrack run --init``: not 4
        finite numbers, under 4x4, larger than the frame or outside it); TypeError or
        ValueError for a frame :meth:`update` refuses. After an error the tracker holds no
        target (as :meth:`reset` leaves it): the previous one is forgotten."""
        return self._begin(box, as_frame(frame, 0, self.fps))

    def update(self, frame: FrameLike) -> FrameResult:
        """Track the next frame. Detecting configs may start with ``update`` (no ``init``).

        A NumPy image (or an ``av.VideoFrame`` without a timestamp) is numbered one after the
        previous frame and timed ``index / fps``, or, after a frame timed otherwise (a
        :class:`vtrack.Frame` with a camera's clock), that frame's ``time_s`` plus ``(index -
        its index) / fps``: never back in time. A :class:`vtrack.Frame` keeps its own ``index``
        and ``time_s``, so a frame the camera dropped is told by giving the next one as
        ``vtrack.BgrFrame(n, n / fps, image)`` (``GrayFrame`` for grey), and the images after it
        are numbered on from ``n``. InputError for a frame of another size, or grey
        after colour (the track goes on with the next right one); TypeError for pixels it
        cannot read (not uint8, not ``HxWx3``, ``HxW`` or ``HxWx1``, or 4 channels: see
        :func:`as_frame`); ValueError for an empty frame or
        one over 16384x16384."""
        if self._pipeline is None:
            return self._begin(None, frame)  # ConfigError if the config needs a box
        return self._process(frame)

    def _begin(self, box: Box | Any, frame: FrameLike) -> FrameResult:
        """Fresh stages starting from ``box`` on ``frame``, the sequence's first; when they
        cannot start there (an error), the tracker is left as :meth:`reset` leaves it."""
        self.reset()
        pipeline = self._new_pipeline()
        if box is not None:
            pipeline.refuse_a_first_box(self.config.name, "call init(frame) without a box, or "
                                        "update(frame)")
        if box is None and pipeline.needs_init_box:
            raise ConfigError(f"{self.config.name}: this tracker needs the target's box first: "
                              "call init(frame, (x, y, w, h))")
        pipeline.begin(box)
        self._pipeline = pipeline
        try:
            return self._process(frame)
        except BaseException:
            self.reset()
            raise

    def reset(self) -> None:
        """Forget the target: the next call must be :meth:`init` (or ``update`` for the
        detecting configs), which starts from fresh stages."""
        self._pipeline, self._index, self._timed_at = None, 0, (0, 0.0)

    def _process(self, item: FrameLike) -> FrameResult:
        assert self._pipeline is not None
        # a frame of another size or kind than the first: InputError from the pipeline
        # an image is timed on from the last frame that came with its own time (a camera's
        # clock), one interval a frame: neither back in time after it nor on an older clock
        at, at_s = self._timed_at
        frame = as_frame(item, self._index, self.fps, at_s + (self._index - at) / self.fps)
        if not isinstance(item, np.ndarray):  # (on the index / fps clock: it, exactly)
            on_clock = frame.time_s == frame.index / self.fps
            self._timed_at = (0, 0.0) if on_clock else (frame.index, frame.time_s)
        result = self._pipeline.process(frame)
        # an image after a vtrack.Frame numbered by the caller (a camera's frame after a
        # dropped one) is the frame after that one, not the count of frames given
        self._index = result.index + 1
        # a kept frame's pixels are its own: raw input reads the next frames into a small
        # ring of buffers, and a camera's array may be refilled after update() returns
        result.frame = result.frame.kept() if self.keep_frames and result.frame else None
        return result

