"""``vtrack.track``: the library in one call, taking plain Python values.

Kept out of ``vtrack/__init__.py`` so that ``import vtrack`` (and every ``vtrack`` command) pays
only for what it uses: this module pulls in the config, the stages and the readers.
"""

from __future__ import annotations

import os
from collections.abc import Iterable, Iterator, Sequence
from itertools import islice

import numpy as np

from vtrack.config import Config, load_config
from vtrack.frame import BgrFrame, Frame, GrayFrame
from vtrack.geometry import Box
from vtrack.io import open_source
from vtrack.pipeline import FrameResult, Pipeline
from vtrack.request import RunRequest

FrameInput = str | os.PathLike[str] | RunRequest | Iterable[Frame] | Iterable[np.ndarray]
BoxInput = Box | Sequence[float]


def as_box(box: BoxInput) -> Box:
    """A :class:`Box` from a ``Box`` or any 4 numbers ``(x, y, w, h)``; ValueError otherwise.

    Width and height must be positive: a box with no area cannot be tracked.
    """
    if isinstance(box, Box):
        values = tuple(box)
    else:
        try:
            values = tuple(float(v) for v in box)
        except (TypeError, ValueError):
            raise ValueError(f"init_box: expected (x, y, w, h) numbers, got {box!r}") from None
    if len(values) != 4:
        raise ValueError(f"init_box: expected 4 numbers (x, y, w, h), got {len(values)}")
    if not (values[2] > 0 and values[3] > 0):
        raise ValueError(f"init_box: width and height must be positive, got {values[2]:g}x"
                         f"{values[3]:g}")
    return Box(*values)


def as_frames(items: Iterable[Frame] | Iterable[np.ndarray], fps: float = 30.0) -> Iterator[Frame]:
    """Frames from :class:`Frame` objects or NumPy images, lazily, in order.

    A ``HxWx3`` uint8 array is a BGR image (OpenCV's order) and a ``HxW`` uint8 array a grey
    image; array frames are numbered from 0 and timed ``index / fps`` seconds.
    """
    for index, item in enumerate(items):
        if isinstance(item, Frame):
            yield item
            continue
        if not isinstance(item, np.ndarray):
            raise TypeError(f"frame {index}: expected a vtrack.Frame or a NumPy image, got "
                            f"{type(item).__name__}")
        if item.dtype != np.uint8:
            raise TypeError(f"frame {index}: expected uint8 pixels, got {item.dtype}")
        time_s = index / fps
        if item.ndim == 3 and item.shape[2] == 3:
            yield BgrFrame(index, time_s, np.ascontiguousarray(item))
        elif item.ndim == 2:
            yield GrayFrame(index, time_s, np.ascontiguousarray(item))
        else:
            raise TypeError(f"frame {index}: expected an HxWx3 BGR or HxW grey image, got shape "
                            f"{item.shape}")


def track(frames: FrameInput, config: str | os.PathLike[str] | Config = "robust",
          init_box: BoxInput | None = None, seed: int = 0, fps: float = 30.0
          ) -> Iterator[FrameResult]:
    """Yield one :class:`FrameResult` per frame of ``frames``.

    ``frames`` is an input path (``str`` or ``pathlib.Path``: a video file or an image folder,
    opened with :func:`vtrack.io.open_source`), a :class:`RunRequest` (its input, raw format,
    frame rate, config, initial box, seed and frame limit; nothing is written), or any iterable
    of :class:`Frame` or of NumPy BGR (``HxWx3``) / grey (``HxW``) uint8 images, those timed at
    ``fps``; ``config`` a shipped config name, a TOML path or a :class:`Config`; ``init_box``
    the target's first box as a
    :class:`Box` or ``(x, y, w, h)`` (not needed by the detecting trackers s3/s4).
    """
    if isinstance(frames, RunRequest):
        request = frames
        pipeline = Pipeline(request.config.build(), seed=request.seed)
        with open_source(request.input, request.raw, fps=request.fps) as source:
            yield from pipeline.track(islice(source, request.max_frames), request.init_box)
        return
    chain = config if isinstance(config, Config) else load_config(os.fspath(config))
    box = None if init_box is None else as_box(init_box)
    pipeline = Pipeline(chain.build(), seed=seed)
    if isinstance(frames, str | os.PathLike):
        with open_source(os.fspath(frames)) as source:
            yield from pipeline.track(source, box)
    else:
        yield from pipeline.track(as_frames(frames, fps), box)
