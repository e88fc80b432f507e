"""SIGINT and SIGTERM for the commands that write files without a run's record (``vtrack
report``, ``scene``, ``frame``, ``vectors``, ``select``): both stop the work as Ctrl-C does, so
the files staged under temporary names are removed and the command ends ``vtrack:
interrupted`` (exit 130 or 143)."""

from __future__ import annotations

from collections.abc import Callable, Iterator
from contextlib import contextmanager

import click

from vtrack.errors import Interrupted, handling_stop_signals, ignore_stop_signals, interrupt


@contextmanager
def stopping_as_interrupted() -> Iterator[Callable[[], None]]:
    """SIGINT and SIGTERM inside the block raise :class:`~vtrack.errors.Interrupted` (SIGTERM
    killed the process before, leaving its temporary files, with no word) until the block
    calls the function it is given, ``settled()``, as its staged files start to be put in
    place: from then on a signal changes nothing (the work after it, removing files of an
    earlier set, closing an input, ends as it would have). Once the block has returned its
    files are in place and final: in a process of its own (the ``vtrack`` command) the
    signals are then ignored until it exits (a Ctrl-C in the interpreter's teardown raised
    inside a library's finaliser: a traceback, and exit 0 all the same); under click's test
    runner the previous handlers are back after the block.

    An error the block raises after such a signal came is Interrupted too: FFmpeg's C code
    swallows the exception a signal raises while it waits (opening a FIFO no writer opened, a
    read of a pipe or a URL) and fails with EINTR, which read as ``not a video FFmpeg can
    decode (Interrupted system call)``, exit 2."""
    received: list[int] = []

    def stop(signum: int, frame: object) -> None:
        received.append(signum)
        interrupt(signum, frame)

    with handling_stop_signals(stop, ignored_after=owns_process()):
        try:
            yield ignore_stop_signals
        except Exception:
            if received:
                raise Interrupted(received[0]) from None
            raise


def owns_process() -> bool:
    """Whether the running command is the process's own program (the ``vtrack`` command,
    ``python -m vtrack``: the group's ``owns_process``), not called in a host's
    process (click's test runner, a library): only then may it leave SIGINT and SIGTERM
    ignored after its files are final, for the interpreter's teardown."""
    root = click.get_current_context().find_root().command
    return bool(getattr(root, "owns_process", False))

