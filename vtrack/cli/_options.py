"""Options several commands share, declared once so they read and behave the same."""

from __future__ import annotations

import math
import os
import sys
from collections.abc import Callable
from decimal import Decimal
from typing import Any

import click
from click.core import ParameterSource

from vtrack.cli._messages import WordsCut, echo_result
from vtrack.cli._progress import STATS_PERIOD
from vtrack.errors import cut, number_text, quoted_or_cut, shell_word
from vtrack.params import MAX_FRAME_NUMBER, MAX_SECONDS, shown


class Seconds(click.FloatRange):
    """A duration in seconds from ``min`` to ``max`` (both finite): click's FloatRange lets
    ``nan`` through every bound (it compares false), and ``inf`` through an open one. A value
    that is no number, or one out of the range, is refused in one wording naming the value as
    given (``'1e-400' is not a number of seconds from 0.1 to 3600``: click named the float it
    made of it, ``0.0 is not in the range 0.1<=x<=3600.0``).
    ``optional``: the option's own flag (``--follow``) may come without a number, so a word
    after it may be the argument that was meant to follow it: its refusal says how to give
    that; not for a value starting with ``-`` (which would be read as an option there), nor
    one attached with ``=`` (``--follow=abc``: :class:`SecondsCommand` notes those in
    ``ctx.meta``)."""

    name = "seconds"

    def __init__(self, *args: Any, optional: str | None = None, **kwargs: Any) -> None:
        super().__init__(*args, **kwargs)
        self.optional = optional

    def convert(self, value: Any, param: click.Parameter | None,
                ctx: click.Context | None) -> Any:
        try:  # (click's own words for a word: "'x' is not a valid seconds.")
            seconds, word = float(value), False
        except (TypeError, ValueError):
            seconds, word = math.nan, True
        if not (math.isfinite(seconds) and self._within(seconds)):
            hint = ""
            attached = ctx.meta.get(_ATTACHED, ()) if ctx is not None else ()
            if (word and self.optional and isinstance(param, click.Option)
                    and not str(value).startswith("-") and value not in attached):
                flag = max(param.opts, key=len)
                hint = (f"; if it is {self.optional}, put it before {flag} or give the "
                        f"seconds ({flag} 5 {cut(value)})")
            self.fail(f"{value!r} is not a number of seconds {self.range_words()}{hint}",
                      param, ctx)
        return seconds

    def _within(self, seconds: float) -> bool:
        """Whether ``seconds`` is in the range (its open bounds excluded)."""
        return ((seconds > self.min if self.min_open else seconds >= self.min)
                and (seconds < self.max if self.max_open else seconds <= self.max))

    def range_words(self) -> str:
        """The range as words, its open bounds said so: ``from 0.1 to 3600``, ``above 0 and
        at most 86400`` (``--follow 0`` is refused: 0 is no number of seconds it takes)."""
        low = f"above {self.min:g}" if self.min_open else f"from {self.min:g}"
        high = f"below {self.max:g}" if self.max_open else f"at most {self.max:g}"
        if not self.min_open and not self.max_open:
            return f"{low} to {self.max:g}"
        return f"{low} and {high}"


def print_help(ctx: click.Context, param: click.Parameter, value: bool) -> None:
    """``--help``'s callback: as click's, but standard output that cannot take the help (``>
    /dev/full``) is one line saying so and exit code 1, not click's traceback
    (:func:`~vtrack.cli._messages.echo_result`); its reader gone (``| head``), nothing."""
    if value and not ctx.resilient_parsing:
        echo_result(ctx.get_help(), "the help")
        ctx.exit()


class HelpPrinted(click.Command):
    """A command (or group: put this class before click's among its bases) whose ``--help``
    is printed by :func:`print_help`: click's writes the help from the option's callback, while
    the arguments are parsed, before any command runs (and so outside its handling of standard
    output)."""

    def get_help_option(self, ctx: click.Context) -> click.Option | None:
        """As click's (None: the command has no ``--help``), with :func:`print_help` as the
        option's callback."""
        option = super().get_help_option(ctx)
        if option is not None:
            option.callback = print_help
        return option


class VtrackCommand(HelpPrinted):
    """A vtrack command: arguments it does not take are refused as click refuses them, "Got
    unexpected extra argument (clip.gt.txt)", each shown as :func:`~vtrack.errors.cut` shows
    it (click echoed a word of any length whole), a :class:`~vtrack.cli._messages.WordsCut`:
    the option hint of :meth:`_option_for` is said whole and shell-quoted. An unknown option
    right after an option's name that another option took as its value (``-o --follow -1``)
    is refused saying so (:func:`_option_taken_as_value`)."""

    def parse_args(self, ctx: click.Context, args: list[str]) -> list[str]:
        refused = not ctx.allow_extra_args
        ctx.allow_extra_args = True  # (to see the extra ones: click names them all, whole)
        words = list(args)  # (click's parser takes the words out of ``args`` as it reads them)
        try:
            extra = super().parse_args(ctx, args)
        except click.NoSuchOption as exc:
            taken = _option_taken_as_value(self, words, exc.option_name)
            if taken is not None:
                flag, value = taken
                raise WordsCut(f"No such option {quoted_or_cut(exc.option_name)}: the "
                               f"{quoted_or_cut(value)} before it was read as {flag}'s value "
                               f"(is {flag}'s value missing?)", ctx=ctx) from None
            raise
        finally:
            ctx.allow_extra_args = not refused
        if extra and refused and not ctx.resilient_parsing:
            words = " ".join(cut(word) for word in extra)
            hint = self._option_for(ctx, extra[-1]) if len(extra) == 1 else ""
            raise WordsCut(f"Got unexpected extra argument{'s' if len(extra) > 1 else ''} "
                           f"({words}){hint}", ctx=ctx)
        return extra

    def _option_for(self, ctx: click.Context, word: str) -> str:
        """``"; if it is the ground truth: --gt clip.gt.txt"``: the option of this command
        that takes a file of ``word``'s kind (:data:`_FILE_KINDS`), for an extra argument
        that may be meant for it; ``""`` when none does, or when that option was given on the
        command line already (``--gt a.gt.txt b.gt.txt``: a second --gt would replace it)."""
        for kind, looks_like, flag in _FILE_KINDS:
            option = next((param for param in self.params if isinstance(param, click.Option)
                           and flag in param.opts and param.metavar == "FILE"), None)
            if (option is not None and option.name is not None
                    and ctx.get_parameter_source(option.name) is not ParameterSource.COMMANDLINE
                    and looks_like(os.path.basename(word).lower())):
                return f"; if it is {kind}: {min(option.opts, key=len)} {shell_word(word)}"
        return ""


def _option_taken_as_value(command: click.Command, args: list[str],
                           unknown: str) -> tuple[str, str] | None:
    """The option (as typed) and the word that click's parser took as its value, when that
    word is the name of an option of ``command`` (``-o --follow -1``: ``-o`` took
    ``--follow``, and ``-1`` was then read as an option, the unknown ``unknown``): the
    option's value is likely missing. None when no word starting with ``unknown`` (before
    ``--``) comes after such a value."""
    names = {name for param in command.params if isinstance(param, click.Option)
             for name in (*param.opts, *param.secondary_opts)}
    takes_value = {name for param in command.params if isinstance(param, click.Option)
                   and not param.is_flag and not param.count and param.nargs == 1
                   and not getattr(param, "_flag_needs_value", False) for name in param.opts}
    words = args[:args.index("--")] if "--" in args else args
    for flag, value, word in zip(words, words[1:], words[2:], strict=False):
        if (word.startswith(unknown) and flag in takes_value
                and value.partition("=")[0] in names):
            return flag, value
    return None


#: The kinds of file an extra argument may be (what it is, whether a name in lower case looks
#: like one, the option that takes it where that option takes a FILE): a ground-truth file
#: (``clip.gt.txt``, ``gt.txt``, ``groundtruth_rect.txt``), an image to write (``frame.png``).
_FILE_KINDS: tuple[tuple[str, Callable[[str], bool], str], ...] = (
    ("the ground truth", lambda name: name.endswith(".txt") and ("gt" in name.split(".")[:-1]
                                                                 or "groundtruth" in name),
     "--gt"),
    ("the image to write", lambda name: name.endswith((".png", ".jpg", ".jpeg")), "--out"),
)


class SecondsCommand(VtrackCommand):
    """A command whose :class:`Seconds` options that may come without a number (``optional``:
    ``--follow [SECONDS]``) are refused, as any value out of their range is, when given a
    value starting with ``-`` that click's parser read as the next option, unknown: "No such
    option '-1'" for ``--follow -1`` or ``--follow=-1`` (the flag taking its default), not
    naming the option it was given to. Only the word click found no option for is looked at:
    a word that is another option's value (``-o --follow=-1``: a folder) is left to click,
    and so is shell completion (which parses leaving out usage errors)."""

    def parse_args(self, ctx: click.Context, args: list[str]) -> list[str]:
        words = list(args)  # (click's parser takes the words out of ``args`` as it reads them)
        optional = _optional_seconds(self)
        ctx.meta[_ATTACHED] = {value for flag, attached, value in
                               (word.partition("=") for word in words)
                               if attached and flag in optional}
        try:
            return super().parse_args(ctx, args)
        except click.NoSuchOption as exc:
            given = _value_read_as_option(optional, words, exc.option_name)
            if given is not None:
                option, value = given
                option.type.convert(value, option, ctx)  # (out of range: its usage error)
            raise


#: ``ctx.meta`` key: the values given attached to an optional :class:`Seconds` option's flag
#: (``--follow=abc``), which cannot be the argument meant to come after it.
_ATTACHED = "vtrack.seconds_attached"


def _optional_seconds(command: click.Command) -> dict[str, click.Option]:
    """The :class:`Seconds` options of ``command`` that may come without a number, by flag."""
    return {name: param for param in command.params
            if isinstance(param, click.Option) and isinstance(param.type, Seconds)
            and param.type.optional for name in param.opts}


def _value_read_as_option(optional: dict[str, click.Option], args: list[str],
                          unknown: str) -> tuple[click.Option, str] | None:
    """The option of ``optional`` (:func:`_optional_seconds`) and the value given to it (attached
    with ``=``, or a number after it: ``--follow -x`` may be an unknown option indeed) that
    click's parser read as the option ``unknown``, which it has not (``-1`` of ``--follow
    -1e3``: a short option's name is its first two characters); None if no such value comes
    before ``--``."""
    words = args[:args.index("--")] if "--" in args else args
    for before, word in zip(["", *words], words, strict=False):
        flag, attached, value = word.partition("=")
        if not attached:
            flag, value = before, (word if _is_number(word) else "")
        option = optional.get(flag)
        if option is not None and len(value) > 1 and value.startswith(unknown):
            return option, value
    return None


def _is_number(word: str) -> bool:
    """Whether ``word`` is a number as ``float()`` reads it (``-1``, ``-1e3``, ``-inf``)."""
    try:
        float(word)
    except ValueError:
        return False
    return True


class WholeNumber(click.IntRange):
    """A whole number in click's ``IntRange`` bounds; a value that is none is refused naming
    the range, as one out of it is (click said "'abc' is not a valid integer range.")."""

    def convert(self, value: Any, param: click.Parameter | None,
                ctx: click.Context | None) -> Any:
        try:
            int(value)
        except (TypeError, ValueError):
            self.fail(f"{value!r} is not a whole number in the range "
                      f"{self._describe_range()}", param, ctx)
        return super().convert(value, param, ctx)


class NumberWord(click.ParamType):
    """A number (``kind``: int or float) whose range the command checks itself, in its own
    words; a value that is no number is refused here saying what the option takes (click said
    "'abc' is not a valid float."), and so is a float's text beyond what a float holds
    (``1e-400``, ``1e400``, ``1e-320``: the command would have named the 0, inf or
    9.99989e-321 it became), as typed."""

    def __init__(self, kind: type[int] | type[float], takes: str) -> None:
        self.kind, self.takes = kind, takes
        self.name = "integer" if kind is int else "float"

    def convert(self, value: Any, param: click.Parameter | None,
                ctx: click.Context | None) -> Any:
        if isinstance(value, self.kind) and not isinstance(value, bool):
            return value
        try:
            number = self.kind(value)
        except (TypeError, ValueError):
            self.fail(f"{value!r} is not {self.takes}", param, ctx)
        if self.kind is float and not _held(number, value):
            self.fail(f"{value!r} is not {self.takes}", param, ctx)
        return number


def _held(number: float, text: Any) -> bool:
    """Whether ``number`` (``float(text)``) is the number ``text`` says: false for text that
    underflowed to 0 or overflowed to inf (``1e-400``, ``-1e400``), or to a subnormal float,
    nonzero and below ``sys.float_info.min``, that a message would print as another number
    (``1e-320`` became 9.99989e-321, :func:`~vtrack.errors.number_text`); a subnormal that
    prints back as typed (``2e-308``) is held."""
    if math.isfinite(number) and abs(number) >= sys.float_info.min:
        return True
    try:
        written = Decimal(str(text).strip().replace("_", ""))
    except ArithmeticError:  # (decimal.InvalidOperation: text float() reads and Decimal not)
        return True
    if number != 0 and math.isfinite(number):
        return Decimal(number_text(number)) == written
    return (written == 0) == (number == 0) and written.is_finite() == math.isfinite(number)


#: ``--fps`` of ``run`` and ``scene`` (the range: :func:`vtrack.io.raw.checked_fps`'s, which
#: checks it; that module loads OpenCV, too slow to import for a command's options).
FRAME_RATE = NumberWord(float, "a frame rate (a number from 0.01 to 10000 frames per second)")


def _origin(ctx: click.Context, param: click.Parameter, value: str) -> int | None:
    return None if value == "auto" else int(value)


def stats_period_option() -> Callable[[Any], Any]:
    """``--stats-period SECONDS`` of ``run``, ``batch``, ``report`` and ``scene``: how often
    a progress line is written when stderr is a log."""
    return click.option(
        "--stats-period", type=Seconds(min=0, max=3600), default=STATS_PERIOD,
        show_default=True, metavar="SECONDS",
        help="When stderr is not a terminal (a log): a progress line this often, instead of "
             "the bar (as ffmpeg's -stats_period).")


def refuse_encoding_without_video(no_video: bool) -> None:
    """With ``--no-video``, refuse ``--preset`` or ``--crf`` given (``run``, ``batch``): they
    set the x264 encoding of the annotated video, and none is written (click.UsageError, one
    line naming the option and its value, exit 2). Their defaults pass."""
    if not no_video:
        return
    ctx = click.get_current_context()
    for name in ("preset", "crf"):
        if ctx.get_parameter_source(name) is not ParameterSource.DEFAULT:
            raise click.UsageError(f"--{name} {ctx.params[name]}: sets the x264 encoding of "
                                   "the annotated video, and --no-video writes none; give "
                                   "one of them")


def gt_origin_option() -> Callable[[Any], Any]:
    """``--gt-origin auto|0|1`` of ``run``, ``batch`` and ``report``: the command receives
    None for auto (:func:`vtrack.evaluate.groundtruth.gt_origin_of` decides per file), else 0
    or 1."""
    return click.option(
        "--gt-origin", type=click.Choice(["auto", "0", "1"]), default="auto",
        show_default=True, callback=_origin,
        help="Origin of single-target ground-truth boxes: 1 for MATLAB-style 1-based boxes "
             "(OTB), 0 for 0-based. auto: 1 for OTB's groundtruth_rect.txt (.N.txt) in a sequence "
             "folder (img/, img1/, color/ or its images beside it: the folders vtrack batch "
             "takes) and groundtruth.txt beside img/ "
             "(UAV123, LaSOT), else 0 (VOT's groundtruth.txt beside its images or color/, "
             "name.gt.txt beside a video). "
             "MOTChallenge ground truth is read as written, as TrackEval reads it.")


def gt_first_option() -> Callable[[Any], Any]:
    """``--gt-first N`` of ``run`` and ``report``: the 0-based frame (as ``--start`` counts
    them) the single-target ground truth's first box belongs to, 0 to
    :data:`~vtrack.params.MAX_FRAME_NUMBER`; default 0."""
    return click.option(
        "--gt-first", "gt_first", type=WholeNumber(0, MAX_FRAME_NUMBER), default=0,
        show_default=True, metavar="N",
        help="The frame single-target ground truth's first box belongs to, 0-based as --start "
             f"counts frames (0 to {MAX_FRAME_NUMBER}; an image folder's frame is its image's "
             "number less the first image's): for files that start later than the images, as "
             "OTB's David (startFrame 300 of img/0001.jpg...: --gt-first 299) and UAV123's "
             "sub-sequences. Frames before it have no ground truth and are not scored. "
             "MOTChallenge ground truth numbers its frames itself.")


def refuse_gt_origin_without_gt(gt_given: bool) -> None:
    """Without ``--gt``, refuse ``--gt-origin 0`` or ``1`` and a ``--gt-first`` other than 0
    (``run``, ``report``): they say how to read ``--gt``'s boxes and would change nothing
    (click.UsageError, one line, exit 2). The defaults pass."""
    params = click.get_current_context().params
    origin, first = params.get("gt_origin"), params.get("gt_first")
    if not gt_given and origin is not None:
        raise click.UsageError(f"--gt-origin {origin}: sets the origin of --gt's boxes, and no "
                               "--gt is given; give both or neither")
    if not gt_given and first:
        raise click.UsageError(f"--gt-first {first}: says which frame --gt's first box is of, "
                               "and no --gt is given; give both or neither")


def _frames_or_seconds(text: str, least: int) -> tuple[int | None, float | None] | str:
    """``"75"`` -> ``(75, None)``, ``"2.5s"`` -> ``(None, 2.5)``: a whole number of frames from
    ``least`` to ``MAX_FRAME_NUMBER``, or a time in seconds (at least 0, or above 0 when
    ``least`` is 1; at most ``MAX_SECONDS``); for anything else what is wrong with it, for a
    message (``is negative``, ``is past the limit``; empty: not such a number at all)."""
    seconds = text.lower().endswith("s")
    try:
        number = float(text[:-1] if seconds else text)
    except ValueError:
        return ""
    if not math.isfinite(number):
        return ""
    if number < 0:
        return "is negative"
    if number > (MAX_SECONDS if seconds else MAX_FRAME_NUMBER):
        return "is past the limit"
    if seconds:
        return (None, number) if number > 0 or not least else ""
    return (int(text), None) if text.isdigit() and int(text) >= least else ""


class _FramesOrSeconds(click.ParamType):
    """A number of frames (at least ``least``) or a time in seconds (``2.5s``); converts to
    ``(frames, seconds)`` with the other None."""

    least: int
    expected: str

    def convert(self, value: Any, param: click.Parameter | None,
                ctx: click.Context | None) -> tuple[int | None, float | None]:
        if isinstance(value, tuple):
            return value
        parsed = _frames_or_seconds(str(value).strip(), self.least)
        if isinstance(parsed, str):
            self.fail(f"{shown(value)}: {parsed + '; ' if parsed else ''}expected "
                      f"{self.expected}", param, ctx)
        return parsed


#: The time forms ``--start``/``--at`` take, for their help: only seconds ending in ``s``.
TIME_FORMS = ("a time T in seconds ending in s (2.5s, 3s; not 00:00:02.5 nor a bare 2.5, "
              "which ffmpeg -ss would take)")


class StartPoint(_FramesOrSeconds):
    """``--start``: a 0-based frame number (``75``) or a time in seconds (``2.5s``, as
    ``ffmpeg -ss``). Converts to ``(frame, seconds)``: ``(75, None)`` or ``(0, 2.5)``."""

    name = "start"
    least = 0
    expected = (f"a frame number (75, at most {MAX_FRAME_NUMBER}) or a time in seconds (2.5s, "
                f"at most {MAX_SECONDS}s)")

    def convert(self, value: Any, param: click.Parameter | None,
                ctx: click.Context | None) -> tuple[int, float | None]:
        frame, seconds = super().convert(value, param, ctx)
        return frame or 0, seconds


class FrameSpan(_FramesOrSeconds):
    """``--frames``: how many frames to track (``300``) or for how long (``10s``, as ``ffmpeg
    -t``). Converts to ``(count, seconds)``: ``(300, None)`` or ``(None, 10.0)``."""

    name = "frames"
    least = 1
    expected = (f"a number of frames (300, from 1 to {MAX_FRAME_NUMBER}) or a duration in "
                f"seconds (10s, above 0 and at most {MAX_SECONDS}s)")
