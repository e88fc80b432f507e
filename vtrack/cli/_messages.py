"""The lines every command writes about what went wrong: ``vtrack: error: ...`` and ``vtrack:
warning: ...``, and what a command says of its work on stderr (``vtrack select: ...``). Each is
one line whatever names it quotes (a file whose name holds a newline, a tab, an escape): its
control characters are written as their escapes (:func:`~vtrack.errors.printable`)."""

from __future__ import annotations

import click

from vtrack.errors import printable


def error_line(message: str) -> str:
    """``vtrack: error: MESSAGE`` as one line."""
    return f"vtrack: error: {printable(message)}"


def warning_line(message: str) -> str:
    """``vtrack: warning: MESSAGE`` as one line."""
    return f"vtrack: warning: {printable(message)}"


def warn(message: str) -> None:
    """Write :func:`warning_line` of ``message`` on stderr."""
    click.echo(warning_line(message), err=True)


def note(command: str, message: str) -> None:
    """Write ``vtrack COMMAND: MESSAGE`` on stderr as one line: what ``vtrack COMMAND`` says
    of its work (``vtrack select: saved in clip.init.txt ...``)."""
    click.echo(f"vtrack {command}: {printable(message)}", err=True)
