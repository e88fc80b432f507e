"""File-system checks and names shared by the readers and writers.

Writers never write the final name directly: they write :func:`temp_path` and rename it when the
file is complete, so a complete-looking file is complete.
"""

from __future__ import annotations

import contextlib
import hashlib
import os
import re
import shutil
import stat
import sys
from collections.abc import Callable, Iterator
from pathlib import Path
from typing import Any, BinaryIO, Generic, Self, TypeVar

from vtrack.errors import InputError, OutputError, escape_undecoded, plural


class Closing:
    """``with`` support for anything with a ``close()``: closes it however the block ends."""

    def __enter__(self) -> Self:
        return self

    def __exit__(self, *exc_info: object) -> None:
        self.close()  # type: ignore[attr-defined]


def os_reason(exc: BaseException) -> str:
    """The short reason of an OS or FFmpeg error (``Permission denied``), without errno noise."""
    return getattr(exc, "strerror", None) or str(exc) or type(exc).__name__


def ffmpeg_file(path: str | Path) -> str:
    """The name that makes FFmpeg open the local file ``path`` as that file, whatever it is
    called: ``file:`` before it. FFmpeg reads a name's start as a protocol (``x:y.mp4``:
    "Protocol not found"; ``file:z.mp4``: the file ``z.mp4``; ``:x.png``, ``subfile,...``),
    and its file protocol takes exactly one ``file:`` off."""
    return f"file:{path}"


def path_text(path: str | bytes | os.PathLike[Any], name: str) -> str:
    """``path`` as text; InputError naming the argument ``name`` for an empty one (it would be
    opened as the current folder, or named in a message as nothing: ``: no such file``)."""
    text = os.fsdecode(path)
    if not text.strip():
        raise InputError(f"{name}: empty; give a video file, an image folder, a URL or a "
                         "capture device")
    return text


def check_input_path(path: str) -> None:
    """Raise InputError when ``path`` does not exist or cannot be read."""
    if not os.path.lexists(path):
        raise InputError(f"{path}: no such file")
    if not os.path.exists(path):
        raise InputError(f"{path}: no such file (broken link)")
    if not os.access(path, os.R_OK):
        raise InputError(f"{path}: cannot be read (permission denied)")


#: The most bytes (UTF-8) of a folder name :func:`folder_name` makes: file systems allow 255,
#: and a run's temporary files add a few dozen to a name inside the folder.
MAX_FOLDER_BYTES = 200


def piped_stdin(what: str) -> BinaryIO:
    """Standard input's bytes, for ``-``: InputError when it is closed (``<&-``) or a terminal
    (``what`` says what to pipe in)."""
    if sys.stdin is None or sys.stdin.closed:
        raise InputError(f"stdin is closed; pipe {what} into vtrack")
    if sys.stdin.isatty():
        raise InputError(f"stdin is a terminal; pipe {what} into vtrack")
    return getattr(sys.stdin, "buffer", sys.stdin)  # a binary stream given as stdin as it is


def folder_name(text: str, fallback: str = "config") -> str:
    """``text`` as one safe folder name: characters other than letters, digits and ``._+-``
    become ``_`` (so ``/``, ``..`` and absolute paths cannot lead anywhere else), leading and
    trailing dots are dropped; ``fallback`` when nothing is left (``.``, ``..``, empty). A
    name longer than :data:`MAX_FOLDER_BYTES` keeps its start and ends with a digest of the
    whole text (distinct texts stay distinct folders)."""
    name = re.sub(r"[^\w.+-]+", "_", text).strip(".") or fallback
    if len(name.encode("utf-8", "surrogateescape")) <= MAX_FOLDER_BYTES:
        return name
    digest = hashlib.sha256(text.encode("utf-8", "surrogateescape")).hexdigest()[:12]
    head = name.encode("utf-8", "surrogateescape")[:MAX_FOLDER_BYTES - 13]
    return f"{head.decode('utf-8', 'ignore')}-{digest}"


T = TypeVar("T")


def folder_key(name: str, fallback: str = "config") -> str:
    """What two names must differ in for their results folders (:func:`folder_name`) to be two
    on any disk: the folder name case-folded (``a`` and ``A`` are one folder on a
    case-insensitive disk: macOS's, Windows')."""
    return folder_name(name, fallback).casefold()


class SharedFolders(Generic[T]):
    """Results folders taken so far (each the :func:`folder_name` of a name, ``fallback`` for a
    name with none), told apart as every disk tells them (:func:`folder_key`), each with what
    took it: which one a new name would share."""

    def __init__(self, fallback: str = "config") -> None:
        self._fallback = fallback
        self._taken: dict[str, tuple[str, T]] = {}

    def take(self, name: str, taker: T) -> None:
        """``name``'s folder taken by ``taker``, unless something took it first."""
        self._taken.setdefault(folder_key(name, self._fallback),
                               (folder_name(name, self._fallback), taker))

    def clash(self, name: str) -> tuple[T, bool] | None:
        """What took ``name``'s folder first, and whether the two are one folder only on a
        case-insensitive disk (their folder names differ in case alone); None when the
        folder is free on every disk."""
        taken = self._taken.get(folder_key(name, self._fallback))
        return (None if taken is None
                else (taken[1], taken[0] != folder_name(name, self._fallback)))


def real_path(path: Path) -> Path:
    """``path`` absolute, its symbolic links followed as far as they lead: as
    ``Path.resolve()``, which on Python 3.11 raises RuntimeError on a link that leads to
    itself, where this stops at the looping link (``os.path.realpath``, not strict)."""
    return Path(os.path.realpath(path))


def written_file(out: Path, named: str) -> Path:
    """The file a writer of ``out`` writes: ``out``, or the file a symbolic link ``out`` leads
    to (written through: the link stays, as ``open()`` would write); OutputError naming
    ``named`` for a link that cannot be followed (a loop) or that leads into a folder that is
    not there (it is not created: the link may be stale)."""
    if not out.is_symlink():
        return out
    try:
        os.stat(out)
    except FileNotFoundError:
        pass  # a link to a file not there yet: that file is written, if its folder is there
    except OSError as exc:
        raise OutputError(f"{named}: {os_reason(exc)}") from None
    target = real_path(out)
    if not target.parent.is_dir():
        raise OutputError(f"{named}: its link leads to {os.readlink(out)}, whose folder does "
                          "not exist")
    return target


def places_of(path: Path) -> set[Path]:
    """The files ``path`` names, whether they exist or not, however its symbolic links are read
    (a loop of links included): the file it leads to (:func:`real_path`) and its own entry in
    its folder (``real_path(path.parent) / path.name``, which a writer renaming over it
    replaces). One place unless ``path`` itself is a symbolic link."""
    return {real_path(path), real_path(path.parent) / path.name}


def same_file(one: Path, other: Path) -> bool:
    """Whether ``one`` and ``other`` name the same file, whether it exists yet or not: a place
    in common (:func:`places_of`), or one existing file both lead to (a hard link)."""
    if places_of(one) & places_of(other):
        return True
    return one.exists() and other.exists() and os.path.samefile(one, other)


def temp_path(path: Path) -> Path:
    """Where a writer writes ``path`` until it is complete: ``dir/.name.tmp-PID-RANDOM.ext``,
    a name no other process (or other writer of this one) uses at the same time.

    The extension is kept so FFmpeg still picks the container format from the name.
    """
    return path.with_name(f".{path.stem}.tmp-{os.getpid()}-{os.urandom(4).hex()}{path.suffix}")


def is_temp_of(name: str, final: str) -> bool:
    """Whether a file called ``name`` is (or was) a :func:`temp_path` of a file ``final``."""
    final_path = Path(final)
    return name.startswith(f".{final_path.stem}.tmp") and name.endswith(final_path.suffix)


def remove_quietly(path: Path) -> None:
    """Delete a temporary file, or folder with what it holds, if it is there (a failure to
    delete is not worth reporting)."""
    if path.is_dir() and not path.is_symlink():
        shutil.rmtree(path, ignore_errors=True)
        return
    with contextlib.suppress(OSError):
        path.unlink(missing_ok=True)


def refuse_replacing_file(path: Path, named: str, overwrite: str) -> None:
    """OutputError when ``path`` is a file that holds something (an earlier output, or
    anything else), to be replaced only when the user says ``overwrite`` (as ffmpeg replaces
    a file only with ``-y``): ``{named}: holds N bytes already; {overwrite} replaces it``.
    Nothing there, a pipe, a device or an empty file passes."""
    try:
        held = os.stat(path)
    except OSError:
        return
    if stat.S_ISREG(held.st_mode) and held.st_size > 0:
        raise OutputError(f"{named}: holds {plural(held.st_size, 'byte')} already; "
                          f"{overwrite} replaces it")


def prepare_output_dir(folder: Path) -> Path:
    """Create ``folder`` (and parents) and return it.

    Raises OutputError naming the folder and the reason (it or a parent is a file, read-only
    file system, permission denied ...). Whether a file can be written in an existing folder is
    for the caller's first write to find (:class:`vtrack.io.outdir.OutputFolder` takes a lock
    file in it).
    """
    try:
        folder.mkdir(parents=True, exist_ok=True)
    except (FileExistsError, NotADirectoryError) as exc:
        blocked = _file_in_the_way(folder)
        if blocked is not None:
            raise file_in_the_way(folder, blocked) from None
        raise OutputError(f"{folder}: cannot write output here ({os_reason(exc)})") from None
    except OSError as exc:
        raise OutputError(f"{folder}: cannot write output here ({os_reason(exc)})") from None
    return folder


def file_in_the_way(folder: Path, blocked: Path) -> OutputError:
    """The error of an output ``folder`` that cannot be made because the file ``blocked`` (at
    its path, or one of its parents) is there: one wording for every command, naming the
    file."""
    reason = "a file, not a folder" if blocked == folder else f"{blocked} is a file, not a folder"
    return OutputError(f"{folder}: cannot write output here ({reason})")


def _file_in_the_way(folder: Path) -> Path | None:
    """The file (not a folder) at ``folder`` or at the deepest of its parents that is there,
    which keeps ``folder`` from being created; None when there is none."""
    for each in (folder, *folder.parents):
        if os.path.lexists(each):
            return None if each.is_dir() else each
    return None


class NewFolders:
    """``folder`` and those of its parents that are not there yet, noted before something may
    create them (deepest first), to be removed again once they are empty."""

    def __init__(self, folder: Path) -> None:
        self.folders: list[Path] = []
        for each in (folder, *folder.parents):
            if os.path.lexists(each):
                break
            self.folders.append(each)

    def remove_empty(self) -> None:
        """Remove those of the folders that are there and empty, deepest first: a folder that
        holds anything (a file, a folder not noted) is left as it is, and so its parents
        are."""
        for each in self.folders:
            with contextlib.suppress(OSError):  # not empty (or gone: its parent may be)
                each.rmdir()


@contextlib.contextmanager
def removing_new_folders(folder: Path) -> Iterator[NewFolders]:
    """For a block that may create ``folder`` and its missing parents: when the block raises
    (an error, Ctrl-C, SIGTERM), those of them that were not there before it and are empty are
    removed, deepest first, so a write that stopped leaves no empty folder behind. A folder that
    was there, or that holds anything, is left as it is. Gives the :class:`NewFolders`, for a
    caller that removes them later too."""
    new = NewFolders(folder)
    try:
        yield new
    except BaseException:
        new.remove_empty()
        raise


class StagedFiles:
    """Files (or folders) written under :func:`temp_path` names and put in place together by
    :meth:`commit`, in the order staged: when one of them cannot be written, none is put in
    place (an earlier set of these files stays whole) and :meth:`discard` removes every
    temporary name. As a ``with`` block: committed when the block completes, discarded however
    it ends. :func:`replacing` and the report's pages and plots both write through it.
    ``settled`` is called as :meth:`commit` starts (a command's ``settled()``: a stop signal
    from then on no longer interrupts, the files are going in place)."""

    def __init__(self, settled: Callable[[], object] | None = None) -> None:
        self._pending: list[tuple[Path, Path]] = []
        self._settled = settled

    def __enter__(self) -> Self:
        return self

    def __exit__(self, exc_type: type[BaseException] | None, *exc_info: object) -> None:
        try:
            if exc_type is None:
                self.commit()
        finally:
            self.discard()

    def temp(self, path: Path) -> Path:
        """A :func:`temp_path` of ``path`` for the caller to write (a file, or a folder it
        creates), renamed over ``path`` by :meth:`commit`."""
        temp = temp_path(path)
        self._pending.append((temp, path))
        return temp

    def write(self, path: Path, write: Callable[[Path], object]) -> Path:
        """Call ``write`` with a temporary path beside ``path`` (put in place by
        :meth:`commit`) and return ``path``. Raises OutputError naming ``path`` when it cannot
        be written (a folder of that name, a full disk, a file size limit, no permission)."""
        if path.is_dir():
            raise OutputError(f"{path}: cannot write (a folder of that name is in the way)")
        try:
            write(self.temp(path))
        except OSError as exc:
            raise OutputError(f"{path}: cannot write ({os_reason(exc)})") from None
        return path

    def commit(self) -> None:
        """Rename every temporary name over its path, in the order staged (a folder replaces
        the folder there, whatever that held). Raises OutputError naming the path that could
        not be (the temporary names not yet renamed are left to :meth:`discard`)."""
        if self._settled is not None:
            self._settled()
        while self._pending:
            temp, path = self._pending[0]
            try:
                _rename_over(temp, path)
            except OSError as exc:
                raise OutputError(f"{path}: cannot write ({os_reason(exc)})") from None
            self._pending.pop(0)

    def discard(self) -> None:
        """Remove the temporary names not put in place (nothing happens after a commit)."""
        for temp, _ in self._pending:
            remove_quietly(temp)
        self._pending.clear()


@contextlib.contextmanager
def replacing(*paths: Path, settled: Callable[[], object] | None = None
              ) -> Iterator[tuple[Path, ...]]:
    """A :func:`temp_path` for each of ``paths``, for the block to write (a file, or a folder
    it creates). When the block completes, each is renamed over its path in turn (a folder
    replaces the folder there, whatever that held); when it raises, every temporary name is
    removed and ``paths`` are left as they were, so a failed write never leaves a file that
    looks complete nor spoils the one that was there. OutputError naming a path whose rename
    fails (:class:`StagedFiles` for files not all known at the start; ``settled`` as
    there)."""
    with StagedFiles(settled) as staged:
        yield tuple(staged.temp(path) for path in paths)


def _rename_over(temp: Path, path: Path) -> None:
    """``os.replace(temp, path)``; a folder ``temp`` first moves an existing folder ``path``
    aside (rename cannot replace a folder that holds something) and removes it after."""
    if not (temp.is_dir() and path.is_dir() and not path.is_symlink()):
        os.replace(temp, path)
        return
    aside = temp_path(path)
    os.replace(path, aside)
    try:
        os.replace(temp, path)
    except OSError:
        os.replace(aside, path)
        raise
    remove_quietly(aside)


def write_bytes_atomic(path: Path, data: bytes) -> Path:
    """Write ``data`` to ``path`` through a temporary file renamed when complete (readers never
    see a half-written file, and a failed write leaves the earlier ``path`` as it was) and
    return ``path``; OutputError naming it if it cannot be."""
    with StagedFiles() as staged:
        staged.write(path, lambda temp: temp.write_bytes(data))
    return path


#: Backslashes a name holds right before text that reads as an escaped byte (``a\xff`` as
#: UTF-8 text) or before such a byte: :func:`name_cell` doubles them.
_BACKSLASHES_BEFORE_ESCAPE = re.compile(r"\\+(?=x[89a-f][0-9a-f]|[\udc80-\udcff])")
#: An escaped byte as :func:`text_bytes` writes it (``\xff``), after the backslashes before it:
#: an odd count is the escape's own and the name's doubled; an even count only the name's.
_WRITTEN_ESCAPE = re.compile(r"(\\+)x([89a-f][0-9a-f])")


def text_bytes(text: str) -> bytes:
    """``text`` in UTF-8, a file name's bytes that are not UTF-8 (``c\xff.mp4`` on disk)
    written as their escapes, ``c\xff.mp4``: a results file naming such an input stays
    UTF-8 text, and says which bytes its name holds (:func:`read_name` reads it back)."""
    return escape_undecoded(text).encode("utf-8", "backslashreplace")


def name_cell(name: str) -> str:
    """``name`` for a cell that :func:`read_name` reads back once :func:`text_bytes` wrote it:
    the backslashes it holds before ``xff`` text or a byte that is not UTF-8 doubled (a UTF-8
    name ``a\xff.mp4`` is then not read back as ``a`` and the byte 0xff)."""
    return _BACKSLASHES_BEFORE_ESCAPE.sub(lambda match: match.group() * 2, name)


def read_name(text: str) -> str:
    """A name as :func:`name_cell` and :func:`text_bytes` wrote it, as Python names that file
    (``c\xff.mp4``, the escape of a byte that is not UTF-8, back to the byte's
    ``surrogateescape`` character; ``a\\xff`` back to the text ``a\xff``)."""
    def read(match: re.Match[str]) -> str:
        count, code = len(match.group(1)), match.group(2)
        return "\\" * (count // 2) + (chr(0xDC00 + int(code, 16)) if count % 2 else f"x{code}")

    return _WRITTEN_ESCAPE.sub(read, text)


def write_text_atomic(path: Path, text: str) -> Path:
    """Write ``text`` to ``path`` (UTF-8, as :func:`text_bytes` makes it) through a temporary
    file renamed when complete (readers never see a half-written file) and return ``path``;
    OutputError naming it if it cannot be."""
    return write_bytes_atomic(path, text_bytes(text))
