"""vtrack: classic real-time video object tracking (library and ``vtrack`` command).

The library in one call::

    import vtrack
    for result in vtrack.track("clip.mp4", "s0", vtrack.Box(120, 80, 40, 30)):
        print(result.index, result.state, result.box)
"""

from __future__ import annotations

from collections.abc import Iterable, Iterator

__version__ = "0.1.0"

from vtrack.config import Config, load_config  # noqa: E402
from vtrack.frame import Frame  # noqa: E402
from vtrack.geometry import Box  # noqa: E402
from vtrack.io import open_source  # noqa: E402
from vtrack.pipeline import FrameResult, Pipeline  # noqa: E402


def track(frames: str | Iterable[Frame], config: str | Config = "s0",
          init_box: Box | None = None, seed: int = 0) -> Iterator[FrameResult]:
    """Yield one :class:`FrameResult` per frame of ``frames``.

    ``frames`` is an input path (video file or image folder, opened with
    :func:`vtrack.io.open_source`) or any iterable of :class:`Frame`; ``config`` a shipped
    config name, a TOML path or a :class:`Config`; ``init_box`` the target's first box (not
    needed by the detecting trackers s3/s4).
    """
    chain = config if isinstance(config, Config) else load_config(config)
    pipeline = Pipeline(chain.build(), seed=seed)
    if isinstance(frames, str):
        with open_source(frames) as source:
            yield from pipeline.track(source, init_box)
    else:
        yield from pipeline.track(frames, init_box)


__all__ = ["Box", "Config", "Frame", "FrameResult", "Pipeline", "load_config", "open_source",
           "track", "__version__"]
