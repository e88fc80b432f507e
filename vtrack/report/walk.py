"""One walk of each folder given to ``vtrack report``: the folders below it that hold a run's
record, a batch's summary or a running vtrack's lock, the symbolic links to folders it
does not follow (they may lead anywhere, or back up) and the folders it cannot read."""

from __future__ import annotations

import os
from collections.abc import Sequence
from dataclasses import dataclass, field
from pathlib import Path

from vtrack.errors import cut
from vtrack.io.files import os_reason
from vtrack.io.outdir import LOCK_NAME

#: The entries looked for: a run's record, a batch's summary, a running vtrack's lock.
NAMES = ("run.json", "summary.csv", LOCK_NAME)


@dataclass
class Walked:
    """What :func:`walk` found at or below one folder (paths as walked, not resolved):
    ``holding`` the folders that hold an entry of each name of :data:`NAMES`, one that cannot
    be read included (a symbolic link in a loop or to nothing, which ``Path.rglob`` passes
    over as missing: reading it says why it is left out); ``links`` the symbolic links to
    folders, not followed; ``unreadable`` one line per folder that could not be listed (what
    is below it is not looked at), naming it and why."""

    holding: dict[str, list[Path]] = field(default_factory=lambda: {n: [] for n in NAMES})
    links: list[Path] = field(default_factory=list)
    unreadable: list[str] = field(default_factory=list)


def walk(top: Path) -> Walked:
    """The folders at or below ``top`` holding each of :data:`NAMES`, in one pass."""
    found = Walked()

    def unreadable(exc: OSError) -> None:
        found.unreadable.append(f"{cut(str(exc.filename))}: cannot read ({os_reason(exc)}); "
                                "what is in it is not reported")  # (a path past PATH_MAX)

    for folder, folders, files in os.walk(top, onerror=unreadable):
        for name in NAMES:
            if name in files or name in folders:
                found.holding[name].append(Path(folder))
        found.links += [Path(folder, f) for f in folders if os.path.islink(Path(folder, f))]
    return found


def walk_results(paths: Sequence[Path]) -> dict[Path, Walked]:
    """:func:`walk` of each of ``paths`` that is there: a folder itself, a file (a run.json,
    a summary.csv) the folder it is in, resolved (its locks: a running vtrack there)."""
    return {path: walk(path if path.is_dir() else path.resolve().parent)
            for path in paths if path.exists()}
