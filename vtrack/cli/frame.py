"""``vtrack frame INPUT --at N|Ts -o frame.png``: one frame (a number, or a time as ``vtrack run
--start`` takes it) with a pixel grid, to read a box off."""

from __future__ import annotations

import os
from pathlib import Path

import click

from vtrack.cli._messages import echo_summary
from vtrack.cli._options import TIME_FORMS, StartPoint, VtrackCommand, WholeNumber
from vtrack.cli._paths import IMAGE_PATH, INPUT
from vtrack.cli._signals import stopping_as_interrupted
from vtrack.geometry import MAX_FRAME_SIDE


@click.command("frame", cls=VtrackCommand)
@click.argument("input_spec", metavar="INPUT", type=INPUT)
@click.option("--at", "at", type=StartPoint(), default="0", show_default=True,
              metavar="N|Ts", help="The frame: a 0-based frame number N (as track.csv numbers "
              f"them), or {TIME_FORMS}: the first frame whose timestamp is at or after it; as "
              "vtrack run --start takes them.")
@click.option("--out", "-o", "out", type=IMAGE_PATH, metavar="FILE",
              help="Image to write (.png or .jpg). Default: ./<input name>-frame<N>.png. A "
                   "file already there is replaced only with --overwrite; a symbolic link is "
                   "written through (the file it leads to is replaced, the link kept).")
@click.option("--overwrite", "-y", is_flag=True,
              help="Replace the image file already there (as vtrack run -y replaces its "
                   "results).")
@click.option("--step", type=WholeNumber(2, MAX_FRAME_SIDE), default=None, metavar="PX",
              help="Grid spacing in pixels (up to the largest frame side vtrack reads, the "
                   "range shown at the end). Default: a round step giving ~16 lines.")
@click.option("--no-grid", is_flag=True, help="The frame as it is, without grid and scale.")
def command(input_spec: str, at: tuple[int, float | None], out: Path | None,
            overwrite: bool, step: int | None, no_grid: bool) -> None:
    """Write one frame of INPUT (--at: frame N, or the first at time T) as an image with a
    light pixel grid and its scale (x along the top, y down the left), to read the target's box
    x,y,w,h off for --init or NAME.init.txt."""
    from vtrack.errors import ConfigError
    from vtrack.io.files import write_bytes_atomic
    from vtrack.io.images import encode_image
    from vtrack.io.specs import input_name
    from vtrack.picker.frames import read_frame, read_frame_at
    from vtrack.picker.grid import draw_grid

    if no_grid and step is not None:
        raise ConfigError(f"--step {step}: spaces the grid's lines, and --no-grid draws none; "
                          "give one of them")
    if out is not None:  # refused before a frame is decoded
        ext, target = _place(out, f"--out {out}", input_spec, overwrite)
    index, seconds = at
    with stopping_as_interrupted():  # SIGTERM as Ctrl-C: no temporary image left behind
        if seconds is None:
            bgr = read_frame(input_spec, index)
        else:
            index, bgr = read_frame_at(input_spec, seconds)
        if out is None:
            out = Path(f"{input_name(input_spec.rstrip('/')) or 'input'}-frame{index}.png")
            ext, target = _place(out, str(out), input_spec, overwrite)
        image = bgr if no_grid else draw_grid(bgr, step)
        write_bytes_atomic(target, encode_image(image, ext))  # a failed write keeps the old one
    echo_summary(f"wrote {out} (frame {index}, {bgr.shape[1]}x{bgr.shape[0]})")


def _place(out: Path, named: str, input_spec: str, overwrite: bool) -> tuple[str, Path]:
    """The image type ``out`` names and the file written for it (a symbolic link's target),
    once it is checked that it may be written (``named`` as the refusals name it)."""
    from vtrack.io.files import written_file

    ext = _checked_ext(out, input_spec)
    _refuse_replacing(out, named, overwrite)
    return ext, written_file(out, named)


def _checked_ext(out: Path, input_spec: str) -> str:
    """The image type ``out`` names (``.png`` or ``.jpg``); ConfigError when it names neither,
    or is (or is inside) the input."""
    from vtrack.errors import ConfigError

    ext = out.suffix.lower().replace(".jpeg", ".jpg")
    if ext not in (".png", ".jpg"):
        raise ConfigError(f"--out {out}: write a .png or .jpg image")
    source = Path(input_spec)
    if input_spec != "-" and source.exists() and (
            (out.exists() and os.path.samefile(out, source))
            or (source.is_dir() and source.resolve() in out.resolve().parents)):
        raise ConfigError(f"--out {out}: is, or is inside, the input {input_spec} (it would "
                          "replace or add one of its frames); write the image elsewhere")
    return ext


def _refuse_replacing(out: Path, named: str, overwrite: bool) -> None:
    """OutputError when ``out`` holds something already and the user did not say
    ``--overwrite`` (as ``vtrack run`` refuses its earlier results, ffmpeg a file, without
    ``-y``)."""
    from vtrack.errors import COMMAND_NAMES
    from vtrack.io.files import refuse_replacing_file

    if not overwrite:
        refuse_replacing_file(out, named, COMMAND_NAMES.overwrite)
