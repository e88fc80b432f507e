"""vtrack: classic real-time video object tracking (library and ``vtrack`` command).

The library in one call::

    import vtrack
    for result in vtrack.track("clip.mp4", "s0", (120, 80, 40, 30)):
        print(result.index, result.state, result.box)

The names below are loaded on first use (module ``__getattr__``, PEP 562), so ``import vtrack``
and the ``vtrack`` command start without the trackers, readers or plotting they do not use.
"""

from __future__ import annotations

import importlib
from typing import TYPE_CHECKING, Any

__version__ = "0.1.0"

# public name -> module that defines it
_EXPORTS = {
    "track": "vtrack.api",
    "Box": "vtrack.geometry",
    "Config": "vtrack.config",
    "load_config": "vtrack.config",
    "Frame": "vtrack.frame",
    "BgrFrame": "vtrack.frame",
    "GrayFrame": "vtrack.frame",
    "I420Frame": "vtrack.frame",
    "open_source": "vtrack.api",
    "FrameResult": "vtrack.pipeline",
    "Pipeline": "vtrack.pipeline",
    "RunRequest": "vtrack.request",
    "Tracker": "vtrack.tracker",
}

if TYPE_CHECKING:  # for type checkers and IDEs; at run time __getattr__ loads these
    from vtrack.api import open_source, track
    from vtrack.config import Config, load_config
    from vtrack.frame import BgrFrame, Frame, GrayFrame, I420Frame
    from vtrack.geometry import Box
    from vtrack.pipeline import FrameResult, Pipeline
    from vtrack.request import RunRequest
    from vtrack.tracker import Tracker


def __getattr__(name: str) -> Any:
    """Load a public name from its module on first access (PEP 562) and keep it."""
    module = _EXPORTS.get(name)
    if module is None:
        raise AttributeError(f"module 'vtrack' has no attribute {name!r}")
    value = getattr(importlib.import_module(module), name)
    globals()[name] = value
    return value


def __dir__() -> list[str]:
    return sorted(set(globals()) | set(_EXPORTS))


__all__ = ["BgrFrame", "Box", "Config", "Frame", "FrameResult", "GrayFrame", "I420Frame",
           "Pipeline", "RunRequest", "Tracker", "load_config", "open_source", "track",
           "__version__"]
