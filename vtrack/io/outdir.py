"""Output folders one run (or one batch) owns at a time.

:class:`OutputFolder` is how ``vtrack run`` and ``vtrack batch`` take a folder: it creates it
(parents too), takes its lock, and on leaving releases the lock and removes the folder again if
the run left nothing in it (an error exit leaves no empty folders behind).

The lock is ``fcntl.flock`` on ``.vtrack.lock`` inside the folder, held on an open file: the
kernel releases it when the process ends however it ends (``kill -9`` included), so a stale lock
never blocks anyone. A second run or batch on a folder in use is refused with one line naming the
process that holds it (its pid and command line are written into the lock file).
"""

from __future__ import annotations

import contextlib
import fcntl
import os
import sys
from collections.abc import Iterable
from pathlib import Path
from typing import Self

from vtrack.errors import (
    COMMAND_NAMES,
    EarlierResultsError,
    FolderInUseError,
    OptionNames,
    OutputError,
)
from vtrack.io.files import (
    NewFolders,
    is_temp_of,
    os_reason,
    prepare_output_dir,
    removing_new_folders,
)

LOCK_NAME = ".vtrack.lock"
#: Files a run writes into its folder; a new run removes these (and only these) first, with
#: stale temporary files of them (``.NAME.tmp-*``) left by a killed run.
RUN_OUTPUTS = ("run.json", "track.csv", "tracks.csv", "annotated.mp4", "error.log")


#: A batch's own file in its results folder, beside its inputs' folders (a report writes one
#: of that name and the same columns beside its ``index.html``).
BATCH_SUMMARY = "summary.csv"
#: The multi-target metrics a run records (``run.json``'s ``metrics``), as ``summary.csv``
#: columns (``frames``, which they also record, is its own column).
MOT_METRICS = ("mota", "motp", "idf1", "idp", "idr", "id_switches", "false_positives",
               "misses", "matches", "mostly_tracked", "partially_tracked", "mostly_lost",
               "gt_ids", "gt_boxes", "track_ids", "track_boxes")
#: The columns of every ``summary.csv``, a batch's and a report's: one row per run, the
#: single-target scores and the multi-target metrics, empty where they do not apply.
BATCH_COLUMNS = ("input", "config", "status", "frames", "frames_evaluated", "auc",
                 "precision20", "success50", "success75", "norm_precision", "mean_overlap",
                 "mean_center_error", "tracking_miss", "miss_flagged", "fps", "frames_occluded",
                 "frames_lost", "frames_skipped", *MOT_METRICS, "ground_truth", "run", "error")
#: The columns of a batch's ``summary.csv`` written by vtrack before it had the report's:
#: still a batch's (its rows are read, and resumed).
EARLIER_BATCH_COLUMNS = ("input", "config", "frames", "fps", "mean_overlap", "auc",
                         "precision20", "frames_lost", "frames_skipped", "status", "error")
#: The page a report writes beside its ``summary.csv``.
REPORT_PAGE = "index.html"
#: How a report's page begins its generator line in its head (``<meta name="generator"
#: content="vtrack 0.1.0">``): what tells a report's folder (its ``summary.csv`` has a batch's
#: header) from a batch's folder holding some other ``index.html`` (the user's own page).
REPORT_GENERATOR = '<meta name="generator" content="vtrack'
#: How much of a page's beginning is read for :data:`REPORT_GENERATOR` (its head).
_PAGE_HEAD = 4096


#: What every report writes beside its page, and a batch never: a report written before its
#: page carried :data:`REPORT_GENERATOR` is told by it.
REPORT_TABLES = "summary.md"


def is_report_folder(folder: Path | str) -> bool:
    """Whether ``folder`` holds a vtrack report: its :data:`REPORT_PAGE`, a regular file (a
    FIFO of that name is never opened), carries :data:`REPORT_GENERATOR` in its head, or sits
    beside :data:`REPORT_TABLES` (an earlier vtrack's report); any other ``index.html`` is not
    a report's."""
    page = Path(folder) / REPORT_PAGE
    try:
        if not page.is_file():
            return False
        if (page.parent / REPORT_TABLES).is_file():
            return True
        with page.open(encoding="utf-8", errors="replace") as handle:
            return REPORT_GENERATOR in handle.read(_PAGE_HEAD)
    except OSError:
        return False


def is_batch_folder(folder: Path | str) -> bool:
    """Whether ``folder`` is a batch's results folder: it holds a ``summary.csv`` whose header
    is a batch's (:data:`BATCH_COLUMNS`, or :data:`EARLIER_BATCH_COLUMNS`), not any file of
    that name, and is no vtrack report's (:func:`is_report_folder`: a report's own
    ``summary.csv`` has the same header)."""
    folder = Path(folder)
    try:
        with (folder / BATCH_SUMMARY).open(encoding="utf-8", errors="replace") as handle:
            header = handle.readline(4096).strip()
    except OSError:
        return False
    return (header in (",".join(BATCH_COLUMNS), ",".join(EARLIER_BATCH_COLUMNS))
            and not is_report_folder(folder))


def refuse_other_results(folder: Path | str, what: str,
                         names: OptionNames = COMMAND_NAMES) -> None:
    """Raise OutputError when ``folder`` holds the other kind's results: a run's
    (``run.json``) for a batch (``what`` ``batch``), whose folder per input would sit among
    them, or a batch's (:func:`is_batch_folder`) for a run (any other ``what``), whose files
    would sit among the batch's: either way a report of it would mix the two. A vtrack
    report's folder (:func:`is_report_folder`) is refused too: to a batch, whose
    ``summary.csv`` would replace the report's, as a report is refused a batch's folder; to a
    run, whose files would sit among the report's pages, unless an earlier run's results are
    already there (``run.json``: what ``--overwrite`` decides on). The message calls the folder
    by ``names`` (``--out``; ``out_dir``)."""
    folder = Path(folder)
    ran = (folder / "run.json").is_file()
    if what == "batch" and ran:
        raise OutputError(f"{folder}: is a run's results folder (run.json); a batch there "
                          f"would mix its inputs' folders with that run: choose another "
                          f"{names.out}")
    if (what == "batch" or not ran) and is_report_folder(folder):
        would = (f"replace the report's {BATCH_SUMMARY}" if what == "batch" else
                 "mix its files with the report's pages")
        raise OutputError(f"{folder}: is a vtrack report's folder ({REPORT_PAGE}); a "
                          f"{'batch' if what == 'batch' else 'run'} there would {would}: "
                          f"choose another {names.out}")
    if what != "batch" and is_batch_folder(folder):
        raise OutputError(f"{folder}: is a batch's results folder ({BATCH_SUMMARY}); a run "
                          f"there would mix its files with the batch's: choose another "
                          f"{names.out} (the batch's own runs are in its <input>/<config>/ "
                          "folders)")


def _holder(path: Path) -> str:
    """Who holds the lock at ``path``, as written into it (``pid N: command``)."""
    try:
        text = path.read_text(encoding="utf-8", errors="replace").strip()
    except OSError:
        text = ""
    return text.splitlines()[0] if text else "another process"


def live_holder(folder: Path | str) -> str | None:
    """Who holds ``folder``'s lock now (``pid N: vtrack ...``, as written into it), or None
    when no process does: no lock file, or a stale one a killed process left behind (the
    kernel released its lock). Told from ``/proc/locks`` without taking the lock (which could
    turn away a run or batch taking it at that moment); where that cannot be read, from
    whether the pid written into the file is running."""
    path = Path(folder) / LOCK_NAME
    try:
        held = os.stat(path)
    except OSError:
        return None
    try:
        with open("/proc/locks", encoding="ascii", errors="replace") as table:
            locks = table.read()
    except OSError:
        holder = _holder(path)
        return holder if _pid_running(holder) else None
    # a line per lock: "1: FLOCK  ADVISORY  WRITE 4242 fe:00:123456 0 EOF" (MAJ:MIN:INODE)
    key = f"{os.major(held.st_dev):02x}:{os.minor(held.st_dev):02x}:{held.st_ino}"
    locked = any("FLOCK" in fields and key in fields
                 for fields in (line.split() for line in locks.splitlines()))
    return _holder(path) if locked else None


def _pid_running(holder: str) -> bool:
    """Whether the ``pid N`` a lock file names is a running process (not this one)."""
    pid = holder.removeprefix("pid ").split(":", 1)[0]
    if not pid.isdigit() or int(pid) == os.getpid():
        return False
    try:
        os.kill(int(pid), 0)
    except ProcessLookupError:
        return False
    except OSError:
        return True  # another user's process
    return True


def earlier_results(folder: Path | str) -> list[str]:
    """The files of :data:`RUN_OUTPUTS` an earlier run left in ``folder`` (none if it is not
    a folder)."""
    folder = Path(folder)
    return [name for name in RUN_OUTPUTS if (folder / name).is_file()]


def refuse_replacing(folder: Path | str, names: OptionNames = COMMAND_NAMES) -> None:
    """Raise EarlierResultsError (an OutputError) when ``folder`` holds an earlier run's
    results (as ffmpeg without ``-y`` will not replace a file): the user says ``--overwrite``
    or picks another ``--out`` (as ``names`` call them: ``overwrite=True``, ``out_dir`` in the
    library)."""
    found = earlier_results(folder)
    if found:
        raise EarlierResultsError(
            f"{folder}: holds the results of an earlier run ({', '.join(found)}); give "
            f"{names.overwrite} to replace them, or another {names.out}")


class OutputFolder:
    """Take ``folder`` for one run or batch: ``with OutputFolder(path) as folder: ...``.

    Entering creates the folder, checks a file can be written in it and takes its lock (or
    raises OutputError: the other kind's results folder, :func:`refuse_other_results`; not
    writable, a file, or in use by another vtrack, naming the holder:
    :class:`~vtrack.errors.FolderInUseError`).
    Leaving releases the lock and removes the folder (and the parents it created) when nothing
    but the lock was left in it.
    """

    def __init__(self, folder: Path | str, what: str = "run",
                 names: OptionNames = COMMAND_NAMES) -> None:
        self.folder = Path(folder)
        self.what = what
        self.names = names  # how a refusal calls the folder (--out; out_dir)
        self._fd: int | None = None
        self._created: NewFolders | None = None  # the folders entering created

    def __enter__(self) -> Self:
        refuse_other_results(self.folder, self.what, self.names)
        with removing_new_folders(self.folder) as created:
            prepare_output_dir(self.folder)
            self._lock()
        self._created = created
        return self

    def _lock(self) -> None:
        path = self.folder / LOCK_NAME
        while True:
            try:
                fd = os.open(path, os.O_RDWR | os.O_CREAT | os.O_CLOEXEC, 0o644)
            except OSError as exc:
                raise OutputError(
                    f"{self.folder}: cannot write output here ({os_reason(exc)})") from None
            try:
                fcntl.flock(fd, fcntl.LOCK_EX | fcntl.LOCK_NB)
            except BlockingIOError:
                os.close(fd)
                raise FolderInUseError(
                    f"{self.folder}: in use by another vtrack ({_holder(path)}); wait for it "
                    f"to finish or choose another {self.names.out}") from None
            # The holder before us may have removed the file between our open and our lock:
            # then we locked a file nobody else will see. Only the file at ``path`` counts.
            try:
                same = os.fstat(fd).st_ino == os.stat(path).st_ino
            except FileNotFoundError:
                same = False
            if same:
                break
            os.close(fd)
        self._fd = fd
        command = " ".join(sys.argv[1:]) if len(sys.argv) > 1 else self.what
        note = f"pid {os.getpid()}: vtrack {command}\n".encode("utf-8", "surrogateescape")
        try:
            os.ftruncate(fd, 0)
            os.write(fd, note)
        except OSError:
            pass  # a full disk: the lock holds anyway, only the note is missing

    def clear(self, names: Iterable[str] = RUN_OUTPUTS, temporaries_only: bool = False) -> None:
        """Remove what an earlier run left here: the files ``names`` (``run.json`` first, so no
        record outlives its outputs) and their stale temporaries, or with ``temporaries_only``
        just those (temporaries of another process: this one's are still being written).
        Nothing else in the folder is touched."""
        names = tuple(names)
        mine = f".tmp-{os.getpid()}-"
        entries = sorted(self.folder.iterdir(), key=lambda e: e.name != "run.json")
        for entry in entries:
            name = entry.name
            temporary = any(is_temp_of(name, n) for n in names) and mine not in name
            stale = temporary or (name in names and not temporaries_only)
            if stale and not entry.is_dir():
                with contextlib.suppress(FileNotFoundError):
                    entry.unlink()

    def refuse_folders(self, names: Iterable[str]) -> None:
        """Raise OutputError when one of the files ``names`` to be written here is a folder."""
        for name in names:
            if (self.folder / name).is_dir():
                raise OutputError(f"{self.folder / name}: is a folder, where vtrack writes a "
                                  f"file; move it away or choose another {self.names.out}")

    def release(self) -> None:
        """Release the lock (remove the lock file first, while it is still held)."""
        if self._fd is None:
            return
        with contextlib.suppress(OSError):
            (self.folder / LOCK_NAME).unlink()
        os.close(self._fd)
        self._fd = None

    def __exit__(self, *exc_info: object) -> None:
        self.release()
        if self._created is not None:
            self._created.remove_empty()
