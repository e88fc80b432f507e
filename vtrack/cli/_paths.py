"""Path and name options and arguments shared by the commands."""

from __future__ import annotations

import os
from pathlib import Path
from typing import Any

import click

#: The longest file or folder name the common file systems take (bytes).
NAME_MAX = 255


class NonEmptyPath(click.Path):
    """A ``click.Path`` that refuses an empty value: ``--out ""`` would otherwise mean the
    current folder and replace the outputs an earlier run left there (and ``vtrack batch ""``
    track every input in it)."""

    def convert(self, value: Any, param: click.Parameter | None,
                ctx: click.Context | None) -> Any:
        if isinstance(value, str) and not value.strip():
            self.fail("empty; give a folder or file name ('.' for the current folder)",
                      param, ctx)
        if isinstance(value, str) and any(len(os.fsencode(part)) > NAME_MAX
                                           for part in Path(value).parts):
            self.fail(f"a name in it is longer than {NAME_MAX} bytes, more than a file system "
                      "takes", param, ctx)
        return super().convert(value, param, ctx)


#: The type of every ``--out`` option and path argument.
PATH = NonEmptyPath(path_type=Path)


class NonEmptyText(click.ParamType):
    """A name that refuses an empty value, saying what to give (``hint``): an empty input,
    config or ``--stream`` name would otherwise be read as the current folder or reach a
    message that names nothing (``vtrack: error: : is a folder, not a config file``)."""

    name = "text"

    def __init__(self, hint: str) -> None:
        self.hint = hint

    def convert(self, value: Any, param: click.Parameter | None,
                ctx: click.Context | None) -> Any:
        if isinstance(value, str) and not value.strip():
            self.fail(f"empty; give {self.hint}", param, ctx)
        return value


#: An input argument (``vtrack run``, ``frame``, ``select``, ``vectors``).
INPUT = NonEmptyText("a video file, an image folder, a URL or - (stdin)")
#: A ``--config`` value.
CONFIG = NonEmptyText("a shipped config's name (vtrack stages lists them) or a TOML file")
