"""vtrack: classic real-time video object tracking (library and ``vtrack`` command).

The library in one call::

    import vtrack
    for result in vtrack.track("clip.mp4", "s0", vtrack.Box(120, 80, 40, 30)):
        print(result.index, result.state, result.box)
"""

from __future__ import annotations

from collections.abc import Iterable, Iterator
from itertools import islice
from pathlib import Path

__version__ = "0.1.0"

from vtrack.config import Config, load_config  # noqa: E402
from vtrack.frame import Frame  # noqa: E402
from vtrack.geometry import Box  # noqa: E402
from vtrack.io import open_source  # noqa: E402
from vtrack.pipeline import FrameResult, Pipeline  # noqa: E402
from vtrack.request import RunRequest  # noqa: E402


def track(frames: str | RunRequest | Iterable[Frame], config: str | Config = "s0",
          init_box: Box | None = None, seed: int = 0) -> Iterator[FrameResult]:
    """Yield one :class:`FrameResult` per frame of ``frames``.

    ``frames`` is an input path (video file or image folder, opened with
    :func:`vtrack.io.open_source`), a :class:`RunRequest` (its input, raw format, config,
    initial box, seed and frame limit; nothing is written) or any iterable of :class:`Frame`;
    ``config`` a shipped config name, a TOML path or a :class:`Config`; ``init_box`` the
    target's first box (not needed by the detecting trackers s3/s4).
    """
    if isinstance(frames, str):
        chain = config if isinstance(config, Config) else load_config(config)
        frames = RunRequest(frames, Path(), chain, init_box=init_box, seed=seed)
    if isinstance(frames, RunRequest):
        request = frames
        pipeline = Pipeline(request.config.build(), seed=request.seed)
        with open_source(request.input, request.raw) as source:
            yield from pipeline.track(islice(source, request.max_frames), request.init_box)
        return
    chain = config if isinstance(config, Config) else load_config(config)
    yield from Pipeline(chain.build(), seed=seed).track(frames, init_box)


__all__ = ["Box", "Config", "Frame", "FrameResult", "Pipeline", "RunRequest", "load_config",
           "open_source", "track", "__version__"]
