"""vtrack: classic real-time video object tracking (library and ``vtrack`` command).

The library in one call::

    import vtrack
    for result in vtrack.track("clip.mp4", "s0", (120, 80, 40, 30)):
        print(result.index, result.state, result.box)

The names below are loaded on first use (module ``__getattr__``, PEP 562), so ``import vtrack``
and the ``vtrack`` command start without the trackers, readers or plotting they do not use.
What a user can get wrong is a :class:`VtrackError` (``vtrack.ConfigError``, ``InputError``,
``OutputError``, also reached as ``vtrack.errors.InputError``), with a one-line message; an
input that breaks part way is a ``vtrack.PartialInputError`` (an InputError raised after the
good frames' results, its ``frames_done`` the frame it stopped at); damage read past in an
input (frames skipped) is an :class:`InputWarning` (``warnings.warn``).
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
    "VtrackError": "vtrack.errors",
    "ConfigError": "vtrack.errors",
    "InputError": "vtrack.errors",
    "InputWarning": "vtrack.errors",
    "PartialInputError": "vtrack.errors",
    "OutputError": "vtrack.errors",
}

#: Submodules a user names through the package (``vtrack.errors.InputError``,
#: ``vtrack.evaluate.summarize``), loaded on first use as the names above are.
_SUBMODULES = ("errors", "evaluate", "io")

if TYPE_CHECKING:  # for type checkers and IDEs; at run time __getattr__ loads these
    from vtrack import errors as errors  # submodules reached through the package
    from vtrack import evaluate as evaluate
    from vtrack import io as io
    from vtrack.api import open_source, track
    from vtrack.config import Config, load_config
    from vtrack.errors import (
        ConfigError,
        InputError,
        InputWarning,
        OutputError,
        PartialInputError,
        VtrackError,
    )
    from vtrack.frame import BgrFrame, Frame, GrayFrame, I420Frame
    from vtrack.geometry import Box
    from vtrack.pipeline import FrameResult, Pipeline
    from vtrack.request import RunRequest
    from vtrack.tracker import Tracker


def __getattr__(name: str) -> Any:
    """Load a public name from its module, or a submodule (``vtrack.errors``), on first
    access (PEP 562) and keep it."""
    if name in _SUBMODULES:
        value = importlib.import_module(f"vtrack.{name}")
    elif name in _EXPORTS:
        value = getattr(importlib.import_module(_EXPORTS[name]), name)
    else:
        raise AttributeError(f"module 'vtrack' has no attribute {name!r}")
    globals()[name] = value
    return value


def __dir__() -> list[str]:
    return sorted(set(globals()) | set(_EXPORTS) | set(_SUBMODULES))


__all__ = ["BgrFrame", "Box", "Config", "ConfigError", "Frame", "FrameResult", "GrayFrame",
           "I420Frame", "InputError", "InputWarning", "OutputError", "PartialInputError",
           "Pipeline", "RunRequest", "Tracker", "VtrackError", "load_config", "open_source",
           "track", "__version__"]
