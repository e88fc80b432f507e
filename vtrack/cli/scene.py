"""``vtrack scene``: write a synthetic clip with exact ground truth beside it."""

from __future__ import annotations

import re
from pathlib import Path

import click

from vtrack.cli._messages import echo_summary
from vtrack.cli._options import (
    FRAME_RATE,
    NumberWord,
    VtrackCommand,
    WholeNumber,
    stats_period_option,
)
from vtrack.cli._paths import CLIP_PATH
from vtrack.cli._progress import StepProgress
from vtrack.cli._signals import stopping_as_interrupted
from vtrack.errors import ConfigError, quoted_or_cut, shell_word
from vtrack.geometry import MIN_BOX_SIDE
from vtrack.io.raw import MAX_FPS, MIN_FPS
from vtrack.params import MAX_CRF, MAX_SEED
from vtrack.scenes import CLIP_FORMATS, SCENARIOS, X264_PRESETS, make_scene, write_clip
from vtrack.scenes.scenarios import MAX_FRAMES, MAX_HEIGHT, MAX_WIDTH, MIN_HEIGHT, MIN_WIDTH

#: The options a scene's settings come from, for make_scene's errors to name.
_OPTION_NAMES = {"seed": "--seed", "size": "--size", "frames": "--frames", "fps": "--fps"}
_SIZE = re.compile(r"^\s*(\d+)\s*[xX]\s*(\d+)\s*$")


def _parse_size(size: str | None) -> tuple[int | None, int | None]:
    if size is None:
        return None, None
    match = _SIZE.match(size)
    if match is None:
        raise ConfigError(f"--size {quoted_or_cut(size)}: expected WIDTHxHEIGHT, e.g. 320x240")
    return int(match.group(1)), int(match.group(2))


def _refuse_replacing(out: Path, fmt: str) -> None:
    """OutputError when a file that writing a ``fmt`` clip to ``out`` replaces or removes (the
    clip, its OTB and MOTChallenge ground truth, an image folder's seqinfo.ini) holds something,
    or an image folder's ``img/`` holds a file: a clip of the user's own at OUT (``vtrack scene
    occlusion footage.mp4``) is not replaced without ``--overwrite``, as ``vtrack frame`` and
    ``vtrack run`` replace nothing without it."""
    from vtrack.errors import COMMAND_NAMES, OutputError
    from vtrack.io.files import refuse_replacing_file
    from vtrack.scenes.writers import clip_paths

    clip, gt, mot, rate = clip_paths(out, fmt)
    if fmt == "images":
        if clip.is_dir() and any(clip.iterdir()):
            raise OutputError(f"{clip}: holds files already; {COMMAND_NAMES.overwrite} "
                              "replaces the folder")
        files = [gt, mot, *rate]
    else:
        files = [clip, gt, mot]
    for file in files:
        refuse_replacing_file(file, str(file), COMMAND_NAMES.overwrite)


def _scenario_list() -> str:
    width = max(len(name) for name in SCENARIOS)
    lines = [f"  {name:<{width}}  {s.summary}" for name, s in SCENARIOS.items()]
    return "Scenarios:\n\n\b\n" + "\n".join(lines)


@click.command("scene", cls=VtrackCommand, epilog=_scenario_list())
@click.argument("name")
@click.argument("out", type=CLIP_PATH)
@click.option("--frames", type=NumberWord(int, "a whole number of frames"),
              help=f"Number of frames, at most {MAX_FRAMES} (a scenario needs at least a few: "
                   "its message says how many) [scenario default, mostly 150].")
@click.option("--size", metavar="WxH",
              help=f"Frame size, from {MIN_WIDTH}x{MIN_HEIGHT} to {MAX_WIDTH}x{MAX_HEIGHT} "
                   "[scenario default, mostly 320x240].")
@click.option("--fps", type=FRAME_RATE,
              help=f"Frame rate, from {MIN_FPS:g} to {MAX_FPS:g} [scenario default, mostly 30].")
@click.option("--seed", type=WholeNumber(0, MAX_SEED), default=0, show_default=True,
              help="Random seed.")
@click.option(
    "--format",
    "fmt",
    type=click.Choice(CLIP_FORMATS),
    default="mp4",
    show_default=True,
    help="H.264 video file, OTB image folder (OUT/img/0001.jpg) or raw frames.",
)
@click.option(
    "--pix-fmt",
    help="mp4: encoder pixel format, a colour one (H.264: yuv420p, yuv422p, yuv444p, "
         "their 10-bit forms; no grey) [yuv420p]; yuv444p and yuv422p write profiles (High "
         "4:4:4, High 4:2:2) many players refuse. raw: bgr24, rgb24, yuv420p or gray [bgr24].",
)
@click.option("--crf", type=WholeNumber(0, MAX_CRF), default=23, show_default=True,
              help="x264 quality of mp4 output (lower is better and larger; 0 is lossless, in "
                   "a profile (High 4:4:4) many players refuse).")
@click.option("--preset", type=click.Choice(X264_PRESETS), default="medium", show_default=True,
              help="x264 preset of mp4 output.")
@click.option("--overwrite", "-y", is_flag=True,
              help="Replace a clip or ground-truth file already where OUT's files go (as "
                   "vtrack frame -y replaces its image); without it, one line and nothing "
                   "written.")
@stats_period_option()
def command(
    name: str,
    out: Path,
    frames: int | None,
    size: str | None,
    fps: float | None,
    seed: int,
    fmt: str,
    pix_fmt: str | None,
    crf: int,
    preset: str,
    overwrite: bool,
    stats_period: float,
) -> None:
    """Write scenario NAME to OUT with its exact ground truth beside it.

    OUT.mp4 gets OUT.gt.txt (OTB: x,y,w,h per frame; 0,0,0,0 while the target is out of the
    frame) and, for the scenarios with several targets (multi, pedestrians, vehicles,
    street), OUT.mot.txt
    (MOTChallenge). An image folder holds
    its groundtruth_rect.txt (and groundtruth_mot.txt) and seqinfo.ini (its frame rate, which vtrack
    reads it at). Same arguments, same files, byte for byte.
    Progress: a bar in a terminal, else a line every --stats-period seconds.
    """
    if str(out) == "-":  # elsewhere "-" is standard input or output; here it would be a file
        raise ConfigError("OUT -: vtrack scene writes files (the clip and its ground truth "
                          "beside it): name one, e.g. clip.mp4 or clip.raw --format raw")
    if name not in SCENARIOS and str(out) in SCENARIOS:  # `vtrack scene clip.mp4 occlusion`
        raise ConfigError(f"unknown scenario {quoted_or_cut(name)}: NAME comes before OUT "
                          f"(vtrack scene {out} {shell_word(name)})")
    width, height = _parse_size(size)
    if pix_fmt is not None and fmt == "images":
        raise ConfigError("--pix-fmt applies to mp4 and raw output, not to images")
    # NumPy loads numpy.random at its first use: loaded before the stop handlers are set, no
    # signal lands inside that import, whose machinery swallowed the handler's exception (the
    # scene then ran to the end and exited 0); here, not at the module's top, so that `vtrack
    # --help` (which imports every command's module) does not pay for it
    import numpy.random  # noqa: F401

    # SIGTERM as Ctrl-C from here on, while the scene is made too (a long clip's takes
    # seconds): a word said, and no temporary clip left behind
    with stopping_as_interrupted() as settled:
        scene = make_scene(name, seed=seed, width=width, height=height, frames=frames, fps=fps,
                           names=_OPTION_NAMES)
        first = scene.boxes[0] if scene.boxes else None
        if first is not None and 0 < min(first.w, first.h) < MIN_BOX_SIDE:  # run would refuse
            raise ConfigError(f"scene {name} at {scene.width}x{scene.height}: its target "
                              f"starts {first.w:.1f}x{first.h:.1f} pixels, under the "
                              f"{MIN_BOX_SIDE:g}x{MIN_BOX_SIDE:g} a tracker starts from: give "
                              "a larger --size")
        if not overwrite:  # (after the arguments' own refusals: a mistyped NAME says so)
            _refuse_replacing(out, fmt)
        progress = StepProgress(False, out.name, "frames", stats_period)
        try:
            files = write_clip(scene, out, fmt=fmt, pix_fmt=pix_fmt, crf=crf, preset=preset,
                               progress=progress, settled=settled)
        finally:
            progress.close()
    extra = f" and {files.mot}" if files.mot else ""
    layout = f", {pix_fmt or 'bgr24'}" if fmt == "raw" else ""
    echo_summary(f"wrote {files.clip} ({len(scene)} frames, {scene.width}x{scene.height}"
                 f"{layout}, {scene.fps:g} fps) with ground truth {files.groundtruth}{extra}")
