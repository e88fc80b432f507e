"""``vtrack report``: an overlap report from result folders (``vtrack run`` or ``vtrack batch``).

:func:`build_report` finds every ``run.json`` below the given folders and writes into the report
folder ``index.html`` (opens from disk: PNG plots in ``plots/`` referenced relatively),
``summary.md`` and ``summary.csv``:

- per input: overlap over time for each configuration with occluded / lost frames shaded (without
  ground truth: the tracker's own score and state over time), the OTB success plot (AUC in the
  legend) beside the precision plot (value at 20 px), and the frames where the trackers lost
  the target, every configuration side by side (:mod:`.failures`);
- over all inputs: the success and precision plots averaged over inputs;
- sortable tables of AUC / precision@20 / success rates at 0.5 and 0.75 / normalised
  precision / mean IoU / fps / lost frames per input and configuration and averaged per
  configuration, best per column highlighted; multi-target runs get a table of the
  metrics their ``run.json`` records (MOTA, MOTP, IDF1, ID switches ...);
- batch rows that failed without results, from the batch's ``summary.csv``.

Scores follow the OTB definitions of :mod:`vtrack.evaluate.metrics` (see :mod:`.runs`).
"""

from __future__ import annotations

from typing import Any

#: The names :mod:`.build` defines that this package gives (``from vtrack.report import
#: build_report``); importing the package loads none of it (nor matplotlib, which the plots
#: need): ``vtrack batch`` writes its ``summary.csv`` with :mod:`.rows` and :mod:`.runs` only.
_BUILD = ("ALL_INPUTS", "DEFAULT_TITLE", "PLOT_KINDS", "Report", "build_report", "_slugs")


__all__ = ["ALL_INPUTS", "DEFAULT_TITLE", "PLOT_KINDS", "Report", "build_report"]


def __getattr__(name: str) -> Any:
    if name in _BUILD:
        from vtrack.report import build

        return getattr(build, name)
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")


def __dir__() -> list[str]:
    """The package's names with those :mod:`.build` gives (``dir()``, ``help()``, completion
    see ``build_report`` before it is loaded)."""
    return sorted({*globals(), *_BUILD})
