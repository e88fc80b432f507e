"""The ``vtrack`` command. Each module of this package defines one click command as ``command``,
named like the module, a :class:`~vtrack.cli._options.HelpPrinted` (its ``--help`` printed as
a command's result); the group finds them, so a command lives in one file and this file never
changes for it. A command's module is imported only when that command (or the command list of
``vtrack --help``) is asked for, and command modules import their heavy parts inside the command
function: ``vtrack run --help`` never loads the report's plotting, Dask or the scene generator.

User errors (:class:`~vtrack.errors.VtrackError`) and click's usage errors (an unknown option, a
value out of range) become one line on stderr, ``vtrack: error: ...``, and exit code 2 (1 for an
output that broke part way); Ctrl-C exits 130, SIGTERM (where a command handles it: run,
batch, select, report, scene, frame, vectors) 143. A group given no command (``vtrack``, ``vtrack
vectors``) prints its help on stderr, as click does, and exits 2.
"""

from __future__ import annotations

import contextlib
import importlib
import os
import pkgutil
import sys
from typing import Any

import click

from vtrack import __version__
from vtrack.cli._messages import WordsCut, echo_result, error_line, no_such_command
from vtrack.cli._options import HelpPrinted
from vtrack.errors import VtrackError, cut_quoted


class _Group(HelpPrinted, click.Group):
    """A group that loads a command's module on demand and turns user errors into one line and
    a non-zero exit, never a traceback."""

    def list_commands(self, ctx: click.Context) -> list[str]:
        return sorted(m.name for m in pkgutil.iter_modules(__path__) if not m.name.startswith("_"))

    def get_command(self, ctx: click.Context, cmd_name: str) -> click.Command | None:
        if cmd_name not in self.list_commands(ctx):
            return None
        command = getattr(importlib.import_module(f"{__name__}.{cmd_name}"), "command", None)
        return command if isinstance(command, click.Command) else None

    def resolve_command(self, ctx: click.Context,
                        args: list[str]) -> tuple[str | None, click.Command | None, list[str]]:
        """As click's, but a mistyped command is offered the near one, case aside (``vtrack
        rnu``, ``vtrack RUN``: "Did you mean 'run'?"; click looks only in the commands a group
        holds, and this one loads them on demand), a file or folder given as a command is told
        the command that takes it (``vtrack clip.mp4``: "to track it: vtrack run clip.mp4",
        ``vtrack footage/``: "vtrack batch footage/", no guess), and ``vtrack configs`` is told
        where the configs are listed."""
        try:
            return super().resolve_command(ctx, args)
        except click.exceptions.NoSuchCommand as exc:
            raise no_such_command(ctx, exc.command_name, self.list_commands(ctx)) from None

    #: Set when the group runs as the process's own program (the ``vtrack`` command, ``python
    #: -m vtrack``), not called by click's test runner: a command may then leave signal
    #: handlers for the interpreter's teardown after it (``vtrack run``'s final exit status).
    owns_process = False

    def __call__(self, *args: Any, **kwargs: Any) -> Any:
        """Run as the process's own program. When the command ends while FFmpeg still opens a
        URL aside (a signal ended the wait: :func:`~vtrack.io.threads.aside_running`), the
        process ends at once with the command's status, its output flushed: PyAV's open
        timeout calls into Python from that thread, and the interpreter's teardown meanwhile
        could crash the process (a segmentation fault, exit -11, instead of 130 or 143)."""
        self.owns_process = True
        try:
            return self.main(*args, **kwargs)
        except BaseException as exc:  # (also a second Ctrl-C as the first one's line is said)
            # (only a command that read an input imported the threads: --version must not
            # import PyAV, OpenCV and NumPy to learn that nothing runs aside)
            threads = sys.modules.get("vtrack.io.threads")
            if threads is not None and threads.aside_running():
                _exit_now(exc.code if isinstance(exc, SystemExit)
                          else 130 if isinstance(exc, KeyboardInterrupt) else 1)
            raise

    def main(self, *args: Any, standalone_mode: bool = True, **kwargs: Any) -> Any:
        """As click's ``main``, but a usage error is one ``vtrack: error:`` line naming the
        command's ``--help``, like every other error of vtrack."""
        if not standalone_mode:
            return super().main(*args, standalone_mode=False, **kwargs)
        try:
            code = super().main(*args, standalone_mode=False, **kwargs)
        except click.exceptions.NoArgsIsHelpError as exc:  # `vtrack` alone: the help, as click
            click.echo(exc.format_message(), err=True)     # prints it (not an error line)
            sys.exit(exc.exit_code)
        except click.UsageError as exc:
            where = f" (see '{exc.ctx.command_path} --help')" if exc.ctx is not None else ""
            message = exc.format_message()
            if not isinstance(exc, (click.exceptions.NoSuchCommand, WordsCut)):
                # (click's words; no_such_command's and WordsCut's are vtrack's: the words
                # cut already, the command to paste whole and shell-quoted)
                message = cut_quoted(message)
            click.echo(error_line(f"{message}{where}"), err=True)
            sys.exit(exc.exit_code)
        except click.ClickException as exc:
            click.echo(error_line(exc.format_message()), err=True)
            sys.exit(exc.exit_code)
        except VtrackError as exc:  # (--help, --version: standard output could not take it)
            _refuse(exc)
        except click.Abort:
            click.echo("vtrack: interrupted", err=True)
            sys.exit(130)
        sys.exit(code if isinstance(code, int) else 0)

    def invoke(self, ctx: click.Context) -> object:
        try:
            return super().invoke(ctx)
        except VtrackError as exc:
            _refuse(exc)
        except KeyboardInterrupt as exc:  # Ctrl-C; SIGTERM as errors.Interrupted
            click.echo("vtrack: interrupted", err=True)
            sys.exit(getattr(exc, "exit_code", 130))


def _refuse(exc: VtrackError) -> None:
    """End the command for ``exc``: its one ``vtrack: error:`` line (whatever names it quotes: a
    newline in one) and its exit code."""
    click.echo(error_line(str(exc)), err=True)
    sys.exit(exc.exit_code)


def _print_version(ctx: click.Context, param: click.Parameter, value: bool) -> None:
    """``--version``'s callback: ``vtrack, version X`` as click's ``version_option`` says it,
    printed as :func:`~vtrack.cli._options.print_help` prints the help."""
    if value and not ctx.resilient_parsing:
        echo_result(f"vtrack, version {__version__}", "the version")
        ctx.exit()


def _exit_now(code: object) -> None:
    """End the process now with exit status ``code`` (None: 0; not an int: 1), stdout and
    stderr flushed first, without the interpreter's teardown."""
    for stream in (sys.stdout, sys.stderr):
        with contextlib.suppress(OSError, ValueError, AttributeError):  # gone, closed, None
            stream.flush()
    os._exit(code if isinstance(code, int) else 0 if code is None else 1)


@click.group(cls=_Group, context_settings={"help_option_names": ["-h", "--help"]})
@click.option("--version", is_flag=True, expose_value=False, is_eager=True,
              callback=_print_version, help="Show the version and exit.")
def main() -> None:
    """Classic real-time video object tracking: run a tracker over video, image sequences or raw
    streams; batch whole folders; report overlap against ground truth."""
