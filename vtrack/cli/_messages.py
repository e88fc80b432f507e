"""The lines every command writes about what went wrong: ``vtrack: error: ...`` and ``vtrack:
warning: ...``, and what a command says of its work on stderr (``vtrack select: ...``). Each is
one line whatever names it quotes (a file whose name holds a newline, a tab, an escape): its
control characters are written as their escapes (:func:`~vtrack.errors.printable`)."""

from __future__ import annotations

import contextlib
import errno
import os
import sys
from pathlib import Path

import click

from vtrack.errors import (
    close_names,
    guess_text,
    names_a_path,
    printable,
    quoted_or_cut,
    shell_word,
)


class WordsCut(click.UsageError):
    """A usage error in vtrack's own words: each word a user gave is cut already
    (:func:`~vtrack.errors.cut`) and a command to paste is whole and shell-quoted, so the
    message is said as it is (click's own are cut by :func:`~vtrack.errors.cut_quoted`)."""


def error_line(message: str) -> str:
    """``vtrack: error: MESSAGE`` as one line."""
    return f"vtrack: error: {printable(message)}"


def _path_hint(word: str) -> str:
    """The command that takes the file, folder or URL ``word``: for a ``vtrack report``'s
    folder (or a table in it), its page to open; ``vtrack report`` for a results folder (one
    holding run.json or summary.csv), a run.json, or the folder of another .csv or .json
    (vtrack's results); ``-c`` for a .toml config; ``vtrack batch`` for a folder that is no
    image sequence; ``vtrack run`` for anything else (a video, images, a URL, ``-``, a name the
    file system cannot look up)."""
    from vtrack.io.images import holds_images
    from vtrack.io.outdir import REPORT_PAGE, is_report_folder

    if "://" in word:
        return f"; to track it: vtrack run {shell_word(word)}"
    path = Path(word)
    suffix = path.suffix.lower()
    if os.path.isdir(word):  # (False, where Path.is_dir raises, for a name too long)
        if is_report_folder(path):
            return f"; a vtrack report's folder: open {shell_word(path / REPORT_PAGE)}"
        if any(os.path.exists(path / name) for name in ("run.json", "summary.csv")):
            return f"; to report its results: vtrack report {shell_word(word)}"
        if not holds_images(path):
            return f"; to track the inputs in it: vtrack batch {shell_word(word)}"
    elif path.name == "run.json":
        return f"; to report that run: vtrack report {shell_word(word)}"
    elif suffix in (".csv", ".json"):
        if is_report_folder(path.parent):
            return f"; a vtrack report's table: open {shell_word(path.parent / REPORT_PAGE)}"
        return f"; to report results: vtrack report {shell_word(path.parent)}"
    elif suffix == ".toml":
        return f"; a config: vtrack run INPUT -c {shell_word(word)}"
    return f"; to track it: vtrack run {shell_word(word)}"


def no_such_command(ctx: click.Context, word: str,
                    commands: list[str]) -> click.exceptions.NoSuchCommand:
    """The usage error for ``word`` given where ``ctx``'s group takes one of ``commands``:
    "No such command 'rnu'. Did you mean 'run'?" for a near miss (case aside: ``RUN``);
    "No such command 'clip.mp4'; to track it: vtrack run clip.mp4" for a file, folder, URL or
    ``-`` (:func:`~vtrack.errors.names_a_path`: no guess; :func:`_path_hint` names the command
    that takes it: run, batch, report or -c), "No such command 'configs'; vtrack stages
    lists the shipped configs and their stages" for the word a new user types for those; the
    bare "No such command 'x'." otherwise."""
    message = f"No such command {quoted_or_cut(word)}"
    if names_a_path(word):
        message += _path_hint(word)
    elif close := close_names(word, commands):
        message += f". Did you mean {guess_text(close)}?"
    elif word.casefold() in ("config", "configs"):
        message += "; vtrack stages lists the shipped configs and their stages"
    else:
        message += "."
    return click.exceptions.NoSuchCommand(word, message=message, ctx=ctx)


def warning_line(message: str) -> str:
    """``vtrack: warning: MESSAGE`` as one line."""
    return f"vtrack: warning: {printable(message)}"


def warn(message: str) -> None:
    """Write :func:`warning_line` of ``message`` on stderr (:func:`say`: a warning nobody
    reads stops nothing)."""
    say(warning_line(message))


def say(line: str) -> None:
    """``line`` on stderr; nothing when its reader went away (``2>&1 | head``) or it cannot be
    written: what a command says there never stops its work (its exit status, its files and
    records say how it ended)."""
    with contextlib.suppress(OSError, ValueError):
        click.echo(line, err=True)


def note(command: str, message: str) -> None:
    """Write ``vtrack COMMAND: MESSAGE`` on stderr as one line (:func:`say`): what ``vtrack
    COMMAND`` says of its work (``vtrack select: saved in clip.init.txt ...``)."""
    say(f"vtrack {command}: {printable(message)}")


def echo_stdout(line: str, nl: bool = True) -> OSError | ValueError | None:
    """Write ``line`` on standard output. None when it was written; else the error that
    stopped it (BrokenPipeError when its reader went away, ENOSPC for ``> /dev/full``; an
    EBADF OSError "closed before vtrack started" when there was no standard output at all:
    ``>&-``). After a failed write standard output is pointed at the null device, so the
    interpreter's last flush adds nothing; a descriptor closed from the start is left alone
    (it may be another file's now)."""
    if sys.stdout is None:
        return OSError(errno.EBADF, "closed before vtrack started")
    try:
        click.echo(line, nl=nl)
    except (OSError, ValueError) as exc:
        stdout_to_null()
        return exc
    return None


def stdout_failed(failure: OSError | ValueError, what: str) -> str:
    """``standard output: REASON: WHAT``: the error of a command whose line met ``failure`` on
    standard output (:func:`echo_stdout`)."""
    from vtrack.io.files import os_reason

    return f"standard output: {os_reason(failure)}: {what}"


def stdout_problem(failure: OSError | ValueError | None, what: str) -> str | None:
    """:func:`stdout_failed` for a command whose lines met ``failure`` on standard output
    (``> /dev/full``, an I/O error, ``>&-``); None when there was none or its reader went
    away (``| head``: quiet, as a pipe's writer)."""
    if failure is None or isinstance(failure, BrokenPipeError):
        return None
    return stdout_failed(failure, what)


def echo_result(text: str, what: str, nl: bool = True) -> None:
    """``text``, what a command prints of its result, on standard output. Its reader gone
    (``| head``), nothing more is said; stdout unwritable (:func:`stdout_problem`), an
    :class:`~vtrack.errors.OutputBrokenError` (one line, exit code 1) says ``what`` (``the
    summary line``) was not printed there: the command's files are as it made them."""
    from vtrack.errors import OutputBrokenError

    problem = stdout_problem(echo_stdout(text, nl), f"{what} was not printed there")
    if problem:
        raise OutputBrokenError(problem)


def echo_summary(line: str) -> None:
    """A command's summary line (``wrote clip.mp4 (...)``) on standard output as
    :func:`echo_result` prints it, the control characters of the names it holds escaped
    (:func:`~vtrack.errors.printable`): one line, whatever a file or folder is named."""
    echo_result(printable(line), "the summary line")


def stdout_to_null() -> None:
    """Point standard output, whose last write failed, at the null device: what is left in
    its buffer and any later line go nowhere, and the interpreter's last flush adds no error."""
    with contextlib.suppress(OSError, ValueError):
        null = os.open(os.devnull, os.O_WRONLY)
        try:
            os.dup2(null, sys.stdout.fileno())
        finally:
            os.close(null)
