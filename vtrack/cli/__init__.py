"""The ``vtrack`` command. Each module of this package defines one click command as ``command``;
the group collects them, so a command lives in one file and this file never changes for it.

User errors (:class:`~vtrack.errors.VtrackError`) become one line on stderr and exit code 2.
"""

from __future__ import annotations

import importlib
import pkgutil
import sys

import click

from vtrack import __version__
from vtrack.errors import VtrackError


class _Group(click.Group):
    """A group that turns user errors into one line and a non-zero exit, never a traceback."""

    def invoke(self, ctx: click.Context) -> object:
        try:
            return super().invoke(ctx)
        except VtrackError as exc:
            click.echo(f"vtrack: error: {exc}", err=True)
            sys.exit(exc.exit_code)
        except KeyboardInterrupt:
            click.echo("vtrack: interrupted", err=True)
            sys.exit(130)


@click.group(cls=_Group, context_settings={"help_option_names": ["-h", "--help"]})
@click.version_option(__version__, prog_name="vtrack")
def main() -> None:
    """Classic real-time video object tracking: run a tracker over video, image sequences or raw
    streams; batch whole folders; report overlap against ground truth."""


def _add_commands() -> None:
    for module in pkgutil.iter_modules(__path__):
        command = getattr(importlib.import_module(f"{__name__}.{module.name}"), "command", None)
        if isinstance(command, click.Command):
            main.add_command(command)


_add_commands()
