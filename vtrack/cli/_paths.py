"""Path and name options and arguments shared by the commands."""

from __future__ import annotations

import os
from pathlib import Path
from typing import Any

import click

from vtrack.configs import CONFIG_HINT

#: The longest file or folder name the common file systems take (bytes).
NAME_MAX = 255
#: The longest path a command takes (bytes): Linux takes 4096 (PATH_MAX), and vtrack adds
#: names below an ``--out`` (a batch's ``<input>/<config>/`` and a temporary file name).
PATH_BYTES = 3584


class NonEmptyPath(click.Path):
    """A ``click.Path`` that refuses an empty value: ``--out ""`` would otherwise mean the
    current folder and replace the outputs an earlier run left there (and ``vtrack batch ""``
    track every input in it). ``hint`` says what to give instead."""

    def __init__(self, *args: Any,
                 hint: str = "a folder or file name ('.' for the current folder)",
                 **kwargs: Any) -> None:
        super().__init__(*args, **kwargs)
        self.hint = hint

    def convert(self, value: Any, param: click.Parameter | None,
                ctx: click.Context | None) -> Any:
        if isinstance(value, str) and not value.strip():
            self.fail(f"empty; give {self.hint}", param, ctx)
        problem = length_problem(value) if isinstance(value, str) else None
        if problem:
            self.fail(problem, param, ctx)
        return super().convert(value, param, ctx)


def length_problem(path: str) -> str | None:
    """Why ``path`` is too long for a file system to take (None: it is not): a name in it
    longer than :data:`NAME_MAX` bytes, or the whole longer than :data:`PATH_BYTES`."""
    if any(len(os.fsencode(part)) > NAME_MAX for part in Path(path).parts):
        return f"a name in it is longer than {NAME_MAX} bytes, more than a file system takes"
    if len(os.fsencode(path)) > PATH_BYTES:
        return (f"longer than {PATH_BYTES} bytes (a path takes at most 4096, and vtrack adds "
                "names below it)")
    return None


#: The type of every ``--out`` option and path argument.
PATH = NonEmptyPath(path_type=Path)
#: The type of ``vtrack frame --out``: an image file, no folder.
IMAGE_PATH = NonEmptyPath(path_type=Path, hint="an image file name ending in .png or .jpg")
#: The type of ``vtrack run --gt``: a ground-truth file, no folder.
GT_PATH = NonEmptyPath(path_type=Path, hint="a ground-truth file name (OTB, VOT or "
                       "MOTChallenge boxes)")
#: The type of ``vtrack scene``'s OUT: a clip's name (``.`` is no video file name).
CLIP_PATH = NonEmptyPath(path_type=Path, hint="the clip's name: clip.mp4 (or .mkv, .avi, .mov), "
                         "a folder for --format images, a file for --format raw")


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


class FileOrDash(NonEmptyText):
    """A file name or ``-`` (stdout), neither empty nor longer than a file system takes."""

    name = "FILE|-"

    def __init__(self) -> None:
        super().__init__("a file or - (stdout)")

    def convert(self, value: Any, param: click.Parameter | None,
                ctx: click.Context | None) -> Any:
        value = super().convert(value, param, ctx)
        problem = length_problem(value) if isinstance(value, str) else None
        if problem:
            self.fail(problem, param, ctx)
        return value


#: An input argument (``vtrack run``, ``frame``, ``select``, ``vectors``).
INPUT = NonEmptyText("a video file, an image folder, a URL or - (stdin)")
#: A ``--config`` value.
CONFIG = NonEmptyText(CONFIG_HINT)
