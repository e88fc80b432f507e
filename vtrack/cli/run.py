"""``vtrack run INPUT``: track one video, image folder or raw stream."""

from __future__ import annotations

import os
import signal
import sys
import threading
from pathlib import Path
from typing import TYPE_CHECKING, Any

import click

from vtrack.cli._messages import echo_stdout, error_line, say, stdout_problem, warning_line
from vtrack.cli._options import (
    FRAME_RATE,
    TIME_FORMS,
    FrameSpan,
    Seconds,
    SecondsCommand,
    StartPoint,
    WholeNumber,
    gt_first_option,
    gt_origin_option,
    refuse_encoding_without_video,
    refuse_gt_origin_without_gt,
    stats_period_option,
)
from vtrack.cli._paths import CONFIG, GT_PATH, INPUT, PATH, FileOrDash
from vtrack.cli._signals import owns_process
from vtrack.configs import DEFAULT_CONFIG
from vtrack.errors import (
    COMMAND_NAMES,
    STOP_SIGNALS,
    EarlierResultsError,
    Interrupted,
    VtrackError,
    ignore_stop_signals,
    printable,
    quoted,
)
from vtrack.geometry import MAX_FRAME_SIDE
from vtrack.params import (
    MAX_CRF,
    MAX_FRAME_NUMBER,
    MAX_SECONDS,
    MAX_SEED,
    MAX_TIMEOUT_S,
    MAX_TRACK_ID,
    MAX_WAIT_S,
    MIN_TIMEOUT_S,
    X264_PRESETS,
)

if TYPE_CHECKING:
    from vtrack.config import Config
    from vtrack.io import InputInfo
    from vtrack.run import RunSummary

#: ``--follow`` without a number: seconds a growing file may stay the same size before its end.
FOLLOW_S = 5.0


def default_out_dir(input_spec: str, config: str | None = None,
                    target: int | None = None) -> Path:
    """``./vtrack-out/<name>/<config>/``: name is the input's file stem or folder name
    (``stdin`` for -, ``udp-127.0.0.1-5000`` for a URL; ``SEQ-N`` for ``target`` N of an OTB
    sequence of several); config the config's name (a TOML file's stem). Without ``config``,
    ``./vtrack-out/<name>/`` (a batch's results folder)."""
    from vtrack.evaluate.groundtruth import target_input
    from vtrack.io.files import folder_name
    from vtrack.io.specs import input_name

    name = target_input(input_name(input_spec), target)
    folder = Path("vtrack-out") / name
    # a config's own name (``name = "..."`` in its TOML) may hold characters a folder cannot
    return folder / folder_name(config) if config else folder


@click.command("run", cls=SecondsCommand)
@click.argument("input_spec", metavar="INPUT", type=INPUT)
@click.option("--config", "-c", "config_specs", multiple=True, metavar="FILE|NAME", type=CONFIG,
              help="Tracker config: a TOML file or a shipped name (s0, camshift, s1, s2, ...). "
                   f"Default: {DEFAULT_CONFIG}. One per run (vtrack batch runs several).")
@click.option("--init", "init_text", metavar="x,y,w,h",
              help="Initial box (top-left x, y, width, height), as x,y,w,h or \"x y w h\". "
                   "Default: the input's sidecar box "
                   "(NAME.init.txt, written by vtrack select), else the first --gt box. "
                   "Refused by multi-target configs (s3, s4_multi, fixed_camera).")
@click.option("--gt", "gt_path", type=GT_PATH, metavar="FILE",
              help="Ground truth (OTB x,y,w,h lines, VOT polygons; MOTChallenge gt.txt for "
                   "multi-target configs): fills overlap and center_error.")
@gt_origin_option()
@gt_first_option()
@click.option("--out", "-o", "out_dir", type=PATH, metavar="DIR",
              help="Output folder. Default: ./vtrack-out/<input name>/<config name>/. A folder "
                   "holding an earlier run's results is refused unless --overwrite.")
@click.option("--overwrite", "-y", is_flag=True,
              help="Replace the results an earlier run left in the output folder (its "
                   "run.json, track.csv, annotated.mp4 ...; other files are left alone).")
@click.option("--set", "-s", "overrides", multiple=True, metavar="STAGE.PARAM=VALUE",
              help="Override a stage parameter (repeatable). See `vtrack stages`.")
@click.option("--raw", "raw_size", metavar="WxH",
              help=f"Input is raw frames of this size (from -, a FIFO or a file), from 1x1 to "
                   f"{MAX_FRAME_SIDE}x{MAX_FRAME_SIDE} (yuv420p: an even width and height).")
@click.option("--pix-fmt", type=click.Choice(["bgr24", "rgb24", "yuv420p", "gray"]),
              default="bgr24", show_default=True, help="Pixel format of --raw input.")
@click.option("--fps", type=FRAME_RATE, default=None,
              help="Frame rate of --raw input or an image folder, from 0.01 to 10000 (default "
                   "30; a MOTChallenge "
                   "sequence's seqinfo.ini frameRate): time_s = frame index / fps. Refused "
                   "for a video file, whose frames carry their own timestamps.")
@click.option("--format", "-f", "input_format", metavar="NAME", default=None,
              help="FFmpeg input format, for what probing cannot decide (as ffmpeg -f: "
                   "mpegts, h264, mjpeg, rtsp ...).")
@click.option("--input-option", "input_options", multiple=True, metavar="KEY=VALUE",
              help="An FFmpeg demuxer or protocol option (as ffmpeg -KEY VALUE before -i; "
                   "repeatable), e.g. rtsp_transport=tcp (rtsp://), probesize=32, "
                   "fflags=nobuffer (a live stream: less delay; it drops what probing read, "
                   "so it is refused for an input that is not live). One FFmpeg did not use "
                   "opening the input is refused.")
@click.option("--timeout", "timeout_s", type=Seconds(min=MIN_TIMEOUT_S, max=MAX_TIMEOUT_S),
              default=None, metavar="SECONDS",
              help="A network input that does not open, or sends nothing, this long ends the "
                   "run (recorded as partial once frames came); so does a live output "
                   "(--video-out, --stream) whose receiver takes nothing this long. Default: 10.")
@click.option("--live/--no-live", "live", default=None,
              help="Keep up with the source: when a frame arrives while the tracker is busy, "
                   "track the newest and count the skipped ones. Default: on for stream URLs "
                   "(rtsp, rtp, udp, tcp) and capture devices, off for files, stdin and http. "
                   "Refused for --raw frames: a pipe holds their sender back instead.")
@click.option("--follow", "follow_s",
              type=Seconds(min=0, max=MAX_WAIT_S, min_open=True, optional="INPUT"),
              is_flag=False, flag_value=FOLLOW_S, default=None, metavar="[SECONDS]",
              help=f"Read a file that is still being written, until it has not grown for "
                   f"SECONDS (default {FOLLOW_S:g}), as tail -f: the file opened, not one later "
                   "renamed over its name (the run then ends partial). MPEG-TS, Matroska or "
                   "fragmented MP4; a plain MP4 is readable only once finished.")
@click.option("--no-video", is_flag=True, help="Do not write annotated.mp4 (fastest).")
@click.option("--video-out", "video_out", metavar="URL", default=None,
              help="Send the annotated video to this live output instead of annotated.mp4: "
                   "udp://HOST:PORT or tcp://... as MPEG-TS, rtsp://... as RTSP, rtmp://... as "
                   "FLV (watch it with ffplay, mpv or VLC).")
@click.option("--preset", type=click.Choice(X264_PRESETS), default="ultrafast", show_default=True,
              help="x264 preset of annotated.mp4 (ultrafast keeps up with 1080p60 here; slower "
                   "to placebo make a smaller file and a slower run).")
@click.option("--crf", type=WholeNumber(0, MAX_CRF), default=23, show_default=True,
              help="x264 quality of annotated.mp4 (lower is better and larger; 0 is lossless, "
                   "in a profile (High 4:4:4) many players refuse).")
@click.option("--seed", type=WholeNumber(0, MAX_SEED), default=0, show_default=True,
              help="Seed of the stochastic stages (particle filter), recorded in run.json.")
@click.option("--first-id", "first_id", type=WholeNumber(1, MAX_TRACK_ID), default=1,
              show_default=True, metavar="N",
              help=f"Number a multi-target config's tracks (s3, s4_multi, fixed_camera ...) "
                   f"from N (1 to {MAX_TRACK_ID}), so that a run taken up again after an "
                   "interruption (the --first-id its hint gives) uses none of the first run's "
                   "ids. Refused by a single-target config, which numbers no tracks.")
@click.option("--start", "start", type=StartPoint(), default="0", show_default=True,
              metavar="N|Ts", help="First frame to track: a 0-based frame number N "
              f"(as track.csv numbers them; at most {MAX_FRAME_NUMBER}) or {TIME_FORMS}, at "
              f"most {MAX_SECONDS}s: the first frame whose timestamp is at or after it. The "
              "target's box in it: --init's (vtrack run), else the ground truth's box of that "
              "frame (a sidecar box is frame 0's). An MP4 or MOV file of constant frame rate "
              "is read from the key frame at or before it, an image folder from its image; "
              "other videos (MKV, WebM, MPEG-TS, AVI, fragmented MP4, a variable frame rate), "
              "streams and raw frames decode the earlier frames and skip them.")
@click.option("--frames", "max_frames", type=FrameSpan(), default=None, metavar="N|Ts",
              help=f"Stop after N frames (1 to {MAX_FRAME_NUMBER}), or after T seconds of the "
                   f"input (10s, above 0 and at most {MAX_SECONDS}s, like ffmpeg "
                   "-t: the frames whose timestamp is less than T past the first tracked "
                   "one's, so a variable frame rate is followed).")
@click.option("--stream", "stream", metavar="FILE|-", type=FileOrDash(), default=None,
              help="Also write one JSON line per frame (frame, time_s, x, y, w, h, state, "
                   "score, extras; a multi-target config's: frame, time_s and tracks, each "
                   "with its id, x, y, w, h, conf and state), flushed as each frame is done; "
                   "'-' is stdout (the summary line then goes to stderr). A file holding "
                   "anything is replaced only with --overwrite.")
@stats_period_option()
@click.option("--quiet", "-q", is_flag=True, help="No progress and no summary line.")
def command(input_spec: str, config_specs: tuple[str, ...], init_text: str | None,
            gt_path: Path | None, gt_origin: int | None, gt_first: int, out_dir: Path | None,
            overwrite: bool,
            overrides: tuple[str, ...],
            raw_size: str | None, pix_fmt: str, fps: float | None, no_video: bool, preset: str,
            input_format: str | None, input_options: tuple[str, ...], timeout_s: float,
            live: bool | None, follow_s: float | None, video_out: str | None,
            crf: int, seed: int, first_id: int, start: tuple[int, float | None],
            max_frames: tuple[int | None, float | None] | None,
            stream: str | None,
            stats_period: float, quiet: bool) -> None:
    """Track a target through INPUT and write track.csv, annotated.mp4 and run.json.

    INPUT is a video file, an image-sequence folder (img/0001.jpg ...), a container on '-'
    (stdin: vtrack run - < clip.mp4), or raw frames from '-', a FIFO or a file with
    --raw WxH --pix-fmt FMT --fps N.
    """
    # imported here, not at the top: `vtrack --help` and the other commands start without them
    from vtrack.cli._progress import FrameProgress
    from vtrack.config import load_config
    from vtrack.evaluate.groundtruth import gt_origin_of, parse_box, target_of
    from vtrack.io import RawFormat
    from vtrack.io.video import FFmpegInput
    from vtrack.io.videowriter import video_out_problem
    from vtrack.pipeline import check_first_track_id
    from vtrack.run import STATUS_COMPLETE, STATUS_INTERRUPTED, RunRequest, run

    problem = None if video_out is None else \
        "the annotated video cannot go out with --no-video" if no_video else \
        video_out_problem(video_out)
    if problem:
        raise click.UsageError(f"--video-out {video_out}: {problem}")
    refuse_encoding_without_video(no_video)
    refuse_gt_origin_without_gt(gt_path is not None)
    if len(config_specs) > 1:  # click keeps the last of a repeated option without a word
        raise click.UsageError(f"--config given {len(config_specs)} times "
                               f"({', '.join(config_specs)}): a run tracks with one config; "
                               "vtrack batch runs several")
    _refuse_pix_fmt_without_raw(raw_size is not None)
    config_spec = config_specs[0] if config_specs else None
    config = load_config(config_spec).with_overrides(list(overrides))
    check_first_track_id(first_id, config.multi_target, config.name, "--first-id")
    # a bad --fps is refused by RawFormat.parse (raw input) or open_source (image folders)
    raw = RawFormat.parse(raw_size, pix_fmt, 30.0 if fps is None else fps) if raw_size else None
    target = target_of(input_spec, gt_path)  # SEQ --gt SEQ/groundtruth_rect.N.txt: SEQ-N
    request = RunRequest(
        input=input_spec,
        out_dir=out_dir or default_out_dir(input_spec, config.name, target),
        config=config,
        init_box=parse_box(init_text) if init_text is not None else None,
        gt_path=gt_path,
        gt_origin=0 if gt_path is None else gt_origin_of(gt_path, gt_origin),
        gt_first=gt_first,
        raw=raw,
        fps=None if raw else fps,
        video=not no_video,
        preset=preset,
        crf=crf,
        seed=seed,
        first_track_id=first_id,
        max_frames=None if max_frames is None else max_frames[0],
        max_s=None if max_frames is None else max_frames[1],
        start=start[0],
        start_s=start[1],
        stream=stream,
        ffmpeg=FFmpegInput(format=input_format, options=parse_options(input_options),
                           follow_s=follow_s, timeout_option="--timeout",
                           **({} if timeout_s is None else {"timeout_s": timeout_s})),
        live=live,
        video_out=video_out,
        target=target,
    )
    progress = FrameProgress(quiet, request.frames_expected, stats_period)
    with _Ending(whole_process=owns_process()) as ending:

        def opened(info: InputInfo) -> None:
            ending.recording = True
            progress.on_open(info)

        try:
            summary = run(request, on_frame=progress.on_frame, on_open=opened,
                          overwrite=overwrite, names=COMMAND_NAMES)
        except VtrackError as exc:  # recorded (if the outputs had opened): exits as it says
            ending.code = exc.exit_code
            if isinstance(exc, EarlierResultsError) and out_dir is None:
                raise EarlierResultsError(f"{exc}{_named_folder(config_spec, config)}") from None
            raise
        finally:
            progress.close()
        ending.code = _exit_code(summary)
        for warning in summary.warnings:
            say(warning_line(warning))
        if not quiet and stream == "-":
            say(summary.line())
        elif not quiet and not _said_on_stdout(summary.line()):
            ending.code = ending.code or 1
        if summary.interrupted_by == "SIGPIPE":
            pass  # the --stream reader went away (| head): quiet, as a pipe's writer; run.json
        elif summary.status == STATUS_INTERRUPTED:  # says why
            say(error_line(f"{summary.error}; partial results in {summary.out_dir}"))
            if summary.resume is not None:
                say(printable(f"vtrack: {summary.input}: to go on from where it stopped, run "
                               f"the same command with {summary.resume} and another --out"))
        elif summary.status != STATUS_COMPLETE:
            say(error_line(f"{summary.error}; results up to there are in {summary.out_dir}"))
    if ending.code:
        sys.exit(ending.code)


def _named_folder(config_spec: str | None, config: Config) -> str:
    """What the refusal of an earlier run's default folder adds when the config is a file
    whose ``name`` (which names the folder) is not its file's (``vtrack stages robust --toml
    > mine.toml`` keeps ``name = "robust"``): where the folder's name came from; else
    nothing."""
    from vtrack.config import shipped_configs

    if config_spec is None or config_spec in shipped_configs() \
            or config.name == Path(config_spec).stem:
        return ""
    return (f" (the folder is named after the config's name, {quoted(config.name)} in "
            f"{config_spec}: give the config a name of its own)")


def _exit_code(summary: RunSummary) -> int:
    """The exit status ``summary``'s run ends with: 0 complete, 128 + the signal's number
    interrupted (130, 143; 141 when the ``--stream`` reader went away), else 1."""
    from vtrack.run import STATUS_COMPLETE, STATUS_INTERRUPTED

    if summary.status == STATUS_COMPLETE:
        return 0
    if summary.status == STATUS_INTERRUPTED:
        return 128 + signal.Signals[summary.interrupted_by or "SIGINT"].value
    return 1


class _Ending:
    """SIGINT and SIGTERM around :func:`vtrack.run.run`, which handles them itself while it
    works. Before it has opened the outputs a signal interrupts as usual (Interrupted). Once it
    has (``recording``) it writes a record, and when it returns that record is final: a signal
    then cannot make the exit disagree with it (run.json ``complete`` and exit 143). It is
    ignored until the exit status is known (``code``), then it ends the process at once with
    that status. In a process of its own (``whole_process``: vtrack started from the command
    line) the signals are then ignored for the interpreter's teardown after the command (its
    first step puts the default handlers back, which would end the process 130 or 143); else
    (click's test runner) the previous handlers come back after the block."""

    def __init__(self, whole_process: bool) -> None:
        self.whole_process = whole_process
        self.recording = False
        self.code: int | None = None
        self._previous: dict[int, Any] = {}

    def __call__(self, signum: int, frame: object) -> None:
        if not self.recording:
            raise Interrupted(signum)
        if self.code is not None:
            os._exit(self.code)

    def __enter__(self) -> _Ending:
        if threading.current_thread() is threading.main_thread():
            self._previous = {s: signal.signal(s, self) for s in STOP_SIGNALS}
        return self

    def __exit__(self, *exc_info: object) -> None:
        if self.whole_process and self.recording and self._previous:
            ignore_stop_signals()
            return
        for signum, old in self._previous.items():
            signal.signal(signum, old)


def _said_on_stdout(line: str) -> bool:
    """``line`` on stdout. True when it was written, or when its reader went away (``|
    head``: quiet, as a pipe's writer; the run's exit status says how it ended); else (``>
    /dev/full``, an I/O error, stdout closed) False, after one error line naming standard
    output and the problem on stderr."""
    problem = stdout_problem(echo_stdout(line), "the summary line was not printed there")
    if problem is None:
        return True
    say(error_line(problem))
    return False


def _refuse_pix_fmt_without_raw(raw: bool) -> None:
    """--pix-fmt describes --raw input only: given without it, it is refused (--format and
    --input-option, FFmpeg's, are refused for inputs FFmpeg does not read by open_source)."""
    given = click.get_current_context().get_parameter_source("pix_fmt")
    if not raw and given == click.core.ParameterSource.COMMANDLINE:
        raise click.UsageError("--pix-fmt is the pixel format of raw input: give --raw WxH "
                               "too (a video file or image folder says its own)")


def parse_options(pairs: tuple[str, ...]) -> tuple[tuple[str, str], ...]:
    """``--input-option KEY=VALUE`` values as (key, value) pairs; a UsageError naming the one
    without ``=`` or a key."""
    parsed = []
    for pair in pairs:
        key, sep, value = pair.partition("=")
        if not sep or not key.strip():
            raise click.UsageError(f"--input-option {pair!r}: expected KEY=VALUE "
                                   "(e.g. rtsp_transport=tcp)")
        parsed.append((key.strip().lstrip("-"), value))
    return tuple(parsed)
