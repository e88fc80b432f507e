"""Errors a user can cause. The CLI prints them as one line and exits non-zero; no traceback."""

from __future__ import annotations

import math
import os
import re
import shlex
import signal
import threading
import unicodedata
from collections.abc import Callable, Generator, Iterable, Iterator, Sequence
from contextlib import contextmanager
from dataclasses import dataclass, replace
from decimal import Decimal
from numbers import Real
from typing import Any


def plural(count: int, noun: str, nouns: str | None = None) -> str:
    """``1 frame``, ``2 frames``: a count and its noun for a user message (``nouns``: the plural
    when it is not ``noun + "s"``)."""
    return f"{count} {noun}" if count == 1 else f"{count} {nouns or noun + 's'}"


def close_names(given: str, names: Iterable[str]) -> list[str]:
    """The names ``given`` is a near miss of (a typo, a letter's case: ``robst``, ``S0``):
    those of ``names`` nearest to it by difflib's ratio, case aside, at difflib's default cutoff
    0.6; one name when one is nearest, every name tied for nearest otherwise (``fixed``:
    ``s0-fixed`` and ``s2-fixed``), in the order of ``names``; ``[]`` when none is close."""
    import difflib

    folded = {name.casefold(): name for name in names}
    matcher = difflib.SequenceMatcher()
    matcher.set_seq2(given.casefold())
    scores: dict[str, float] = {}
    for key in folded:
        matcher.set_seq1(key)
        scores[key] = matcher.ratio()
    best = max(scores.values(), default=0.0)
    return [folded[key] for key, score in scores.items() if score == best >= 0.6]


def guess_text(names: list[str]) -> str:
    """``'run'``, or ``one of 's0-fixed', 's2-fixed'``: what a "did you mean" names."""
    quoted = ", ".join(f"'{name}'" for name in names)
    return quoted if len(names) == 1 else f"one of {quoted}"


def did_you_mean(given: str, names: Iterable[str]) -> str:
    """``"; did you mean 'robust'?"`` when ``given`` is a near miss of one of ``names``
    (:func:`close_names`), ``"; did you mean one of 's0-fixed', 's2-fixed'?"`` when it is as
    near to several, to end the message that refuses it; ``""`` when none is close."""
    close = close_names(given, names)
    return f"; did you mean {guess_text(close)}?" if close else ""


def names_a_path(word: str) -> bool:
    """Whether ``word``, refused as a name (a command, a scenario), is rather a file, folder or
    URL: one that exists, or holds ``.``, ``/``, ``:`` or ``\\``, which no such name does, or
    ``-`` (standard input, as ``vtrack run -`` reads it). No near name is guessed for it
    (``scene.mp4`` is not a typo of ``scene``)."""
    return word == "-" or any(mark in word for mark in "./:\\") or os.path.lexists(word)


def shell_word(path: str | os.PathLike[str]) -> str:
    """``path`` as one word of a command line a user can paste into a POSIX shell: quoted when
    the shell would split or expand it, and with ``./`` before a name starting with ``-``
    (``./-x.mp4``), which a command would read as an option; ``-`` alone (standard input) is
    kept."""
    text = os.fspath(path)
    return shlex.quote(f"./{text}" if text.startswith("-") and text != "-" else text)


def number_text(value: float) -> str:
    """A number for a user message: ``5``, ``0.25``, ``1e+06`` (six significant digits), or
    Python's shortest exact form (``10.000000000000002``, ``320.0001``, ``1e-300``) when six
    digits would show another number: a value a hair past a limit never reads as the limit.
    Zero is ``0``, never ``-0`` (``-0.0``: the number 0)."""
    if isinstance(value, int):  # exact already (and may be too large for a float)
        return str(value)
    value = value + 0.0  # (-0.0 + 0.0 is 0.0)
    short = f"{value:g}"
    return short if float(short) == value else repr(float(value))


@dataclass(frozen=True)
class OptionNames:
    """How a run's messages name what its caller gave: ``vtrack run``'s options
    (:data:`COMMAND_NAMES`: ``--start 2.5s: ...``, ``give --init x,y,w,h``) or the library's
    (:data:`LIBRARY_NAMES`: the :class:`~vtrack.request.RunRequest` fields and
    :func:`~vtrack.run.run` keywords, ``start_s 2.5: ...``, ``give init_box=(x, y, w, h)``)."""

    init: str
    fps: str
    start: str
    #: The start given as a time (``--start 2.5s``; ``start_s``).
    start_s: str
    gt: str
    #: What says which frame the ground truth's first box is of (``--gt-first``; ``gt_first``).
    gt_first: str
    stream: str
    out: str
    #: How the caller says "replace what is there".
    overwrite: str
    #: What sets how long a run waits on the network and on a stream's reader.
    timeout: str
    #: How the caller says "no annotated video".
    no_video: str
    #: What sends the annotated video to a live output instead of a file.
    video_out: str
    #: What gives raw frames' format (``--raw``; ``raw=``).
    raw: str
    #: What says the input is live (frames passed over to keep up).
    live: str
    #: What reads a file while it is being written.
    follow: str
    #: What names FFmpeg's input format.
    format: str
    #: What hands FFmpeg an input option.
    input_option: str

    @property
    def options(self) -> bool:
        """Whether these are a command's options (``--init``), not the library's names."""
        return self.init.startswith("--")

    def give(self, name: str, value: str) -> str:
        """How ``name`` is given ``value``, for a message's "give ...": ``--gt FILE`` (an
        option), ``gt_path=FILE`` (a library argument)."""
        return f"{name} {value}" if self.options else f"{name}={value}"

    @property
    def give_box(self) -> str:
        """How a first box is given: ``--init x,y,w,h``, ``init_box=(x, y, w, h)``."""
        return self.give(self.init, "x,y,w,h" if self.options else "(x, y, w, h)")

    @property
    def give_raw(self) -> str:
        """How raw frames' format is given: ``--raw WxH``, ``raw=``."""
        return f"{self.raw} WxH" if self.options else self.raw

    def start_given(self, start: int, start_s: float | None) -> str:
        """The first frame as the caller gave it, to begin a message: ``--start 75``,
        ``--start 2.5s``; ``start 75``, ``start_s 2.5``."""
        if start_s is None:
            return f"{self.start} {start}"
        return f"{self.start_s} {start_s:g}{'s' if self.options else ''}"


COMMAND_NAMES = OptionNames(init="--init", fps="--fps", start="--start", start_s="--start",
                            gt="--gt", gt_first="--gt-first", stream="--stream", out="--out",
                            overwrite="--overwrite (-y)", timeout="--timeout",
                            no_video="--no-video", video_out="--video-out", raw="--raw",
                            live="--live", follow="--follow", format="--format",
                            input_option="--input-option")
LIBRARY_NAMES = OptionNames(init="init_box", fps="fps", start="start", start_s="start_s",
                            gt="gt_path", gt_first="gt_first", stream="stream", out="out_dir",
                            overwrite="overwrite=True", timeout="ffmpeg.timeout_s",
                            no_video="video=False", video_out="video_out", raw="raw=",
                            live="live", follow="ffmpeg.follow_s", format="ffmpeg.format",
                            input_option="ffmpeg.options")
#: How a batch's messages name what its runs were given: ``vtrack run``'s options, but for
#: what only ``vtrack run`` takes (a batch's inputs each have their own ground truth).
BATCH_NAMES = replace(COMMAND_NAMES, gt_first="vtrack run --gt-first")


def is_real(value: object) -> bool:
    """Whether ``value`` is a real number a user may give for a number: an int, float,
    ``Fraction``, ``Decimal`` or NumPy number; not a bool (True is not the number 1), a string
    or a complex number."""
    return isinstance(value, Real | Decimal) and not isinstance(value, bool)


def real_or_nan(value: object) -> float:
    """``value`` as a float when it is a real number (:func:`is_real`) that converts to one; NaN
    otherwise (text, a bool, a signalling NaN, a Decimal beyond a float's range), for a range
    check to refuse."""
    if not is_real(value):
        return math.nan
    try:
        return float(value)  # type: ignore[arg-type]
    except (ValueError, OverflowError):
        return math.nan


#: The longest text a user gave that a message quotes whole (:func:`cut`).
LONGEST_SHOWN = 200


def cut(text: str) -> str:
    """``text`` a user gave (a config's name or path, a ``--set`` assignment), for a one-line
    message: whole up to :data:`LONGEST_SHOWN` characters, else its first and last characters
    around ``...`` and its length: ``aaaa...aaaa (100000 characters)``."""
    if len(text) <= LONGEST_SHOWN:
        return text
    return f"{text[:100]}...{text[-30:]} ({len(text)} characters)"


#: A quoted word of click's messages (``'--xxx'``, ``"it's"``: as ``repr`` quotes it).
_QUOTED = re.compile(r"'(?:[^'\\]|\\.)*'|\"(?:[^\"\\]|\\.)*\"")


def cut_quoted(message: str) -> str:
    """``message`` (click's, quoting the words a user gave as ``repr`` does: "No such option
    '--xxx'.", "Invalid value for '--preset': 'xxx' is not one of ...") with each quoted word
    of more than :data:`LONGEST_SHOWN` characters, counted as typed (``\\xff`` and ``\\x01``
    are one character each, not the four of their escape), shown as :func:`cut` shows it,
    unquoted (:func:`printable` escapes its control characters and undecoded bytes; a typed
    backslash is written ``\\\\``, as ``repr`` writes it, so ``\\xff`` typed is not a byte); shorter
    words are left as quoted, but for a byte that is not UTF-8, shown as :func:`quoted` shows
    it (``'\\xff'``, not ``repr``'s ``'\\udcff'``)."""
    return _QUOTED.sub(lambda match: _cut_word(match.group()), message)


def _cut_word(quoted: str) -> str:
    """``quoted``, a word as ``repr`` quotes it, as :func:`quoted_or_cut` shows the word it
    quotes when that is longer than :data:`LONGEST_SHOWN`; else (or not a quoted word) as it
    is."""
    import ast

    try:
        word = ast.literal_eval(quoted)
    except (ValueError, SyntaxError):
        return quoted
    if not isinstance(word, str):
        return quoted
    if len(word) > LONGEST_SHOWN:
        return quoted_or_cut(word)
    return _undecoded_escapes(quoted)


#: In a word as ``repr`` quotes it: a backslash the word holds (``\\\\``, kept as it is) or
#: the escape ``repr`` writes for a byte of a name that is not UTF-8 (``\\udcff``; group 1:
#: the byte's hex digits).
_REPR_UNDECODED = re.compile(r"\\\\|\\udc([89a-f][0-9a-f])")


def _undecoded_escapes(quoted: str) -> str:
    """``quoted``, a word as ``repr`` quotes it, with each byte that is not UTF-8 written as
    :func:`escape_undecoded` writes it (``\\udcff`` as ``\\xff``); a backslash the word holds
    (``\\\\udcff`` in ``repr``, typed as such) is left as it is."""
    return _REPR_UNDECODED.sub(lambda match: f"\\x{match.group(1)}" if match.group(1)
                               else match.group(), quoted)


def quoted(word: str) -> str:
    """``word`` a user gave, quoted for a message as ``repr`` quotes it (``'rnu'``, ``'a\\tb'``),
    but for each byte of a name that is not UTF-8, written as :func:`escape_undecoded` writes
    it (``'\\xff'``, not ``repr``'s ``'\\udcff'``), as vtrack's other messages say it."""
    return _undecoded_escapes(repr(word))


def quoted_or_cut(word: str) -> str:
    """``word`` a user gave, for a one-line message: quoted as :func:`quoted` quotes it up to
    :data:`LONGEST_SHOWN` characters, else as :func:`cut` shows it (its ends and its length,
    unquoted, with each backslash it holds written ``\\\\``, as :func:`quoted` and ``repr``
    write it: a typed ``\\xff`` reads ``\\\\xff``, a byte 0xff ``\\xff``)."""
    if len(word) <= LONGEST_SHOWN:
        return quoted(word)
    return cut(word).replace("\\", "\\\\")


#: A byte of a file name that is not UTF-8, as Python decodes it (``surrogateescape``: byte
#: 0xff is U+DCFF).
_UNDECODED = re.compile("[\udc80-\udcff]")


def escape_undecoded(text: str) -> str:
    """``text`` with each byte of a file name that is not UTF-8 (``c\\xff.mp4`` on disk, which
    Python names ``c\\udcff.mp4``) written as its escape, ``\\xff``: text that can be
    written, printed and drawn, and says which byte it was."""
    return _UNDECODED.sub(lambda match: f"\\x{ord(match.group()) - 0xDC00:02x}", text)


#: A refusal names at most this many of the keys it refuses or guesses (:func:`first_few`).
MOST_LISTED = 5


def first_few(items: Sequence[str], most: int = MOST_LISTED) -> str:
    """``items`` for a one-line message: joined by commas, the first ``most`` and how many more
    (``'a', 'b', 'c', 'd', 'e' and 3 more``); all of them when there are no more."""
    more = len(items) - most
    return ", ".join(items[:most]) + (f" and {more} more" if more > 0 else "")


def printable(text: str) -> str:
    """``text`` with each control character (newline, tab, escape, ...) written as its Python
    escape (``\\n``), and each byte of a name that is not UTF-8 as its own (``\\xff``,
    :func:`escape_undecoded`): a name taken from the file system stays one line of a message,
    a table row or a plot title."""
    return "".join(repr(c)[1:-1] if unicodedata.category(c) == "Cc" else c
                   for c in escape_undecoded(text))


class VtrackError(Exception):
    """A problem with what the user gave us (input, config, options). ``str()`` is the message."""

    exit_code = 2


class InputError(VtrackError):
    """An input that cannot be opened, decoded or understood (video, frames, ground truth)."""


class ConfigError(VtrackError):
    """A configuration or parameter that is unknown, mistyped or impossible."""


class FirstFrameError(InputError):
    """A stage's refusal of the track's first frame or of the box given in it (a box that puts
    no pixel under the stage's window, a target without colour for a hue tracker). The library
    says it as the stage does; ``vtrack run`` (:func:`vtrack.run.run`) names its input and the
    frame first. ``frame_index``: the refused frame's index, once the pipeline knows it."""

    def __init__(self, message: str, frame_index: int | None = None) -> None:
        super().__init__(message)
        self.frame_index = frame_index


class OutputError(VtrackError):
    """An output location that cannot be written."""


class StreamReaderGone(OutputError):
    """The reader of ``--stream`` went away (closed its end of the pipe: ``| head -2``). The
    run stops there as a writer to a closed pipe does (SIGPIPE): it ends ``interrupted`` by
    SIGPIPE (exit 141), its outputs whole, not failed."""


class EarlierResultsError(OutputError):
    """An output folder holding an earlier run's results, refused without ``--overwrite``:
    nothing was written."""


class FolderInUseError(OutputError):
    """An output folder another vtrack process holds (its lock): nothing was written."""


class PartialInputError(InputError):
    """The input broke part way (a file cut short, a pipe that stopped mid-frame): raised
    after every good frame before it was read (tracked and written by a run; its result
    yielded by :func:`vtrack.track`). ``frames_done`` is the number of the frame it stopped at:
    the frames before it were read, but for any the input skipped."""

    def __init__(self, message: str, frames_done: int) -> None:
        super().__init__(message)
        self.frames_done = frames_done


class InputWarning(UserWarning):
    """Damage an input had that reading went past: frames that could not be decoded and were
    skipped (their ``index`` is missing from the results), pictures decoded with errors,
    images missing or unreadable. :func:`vtrack.track` warns with it (``warnings.warn``) as its
    frames end; these are the lines ``vtrack run`` prints as ``vtrack: warning:``.
    ``warnings.simplefilter("error", vtrack.InputWarning)`` makes them errors."""


class OutputBrokenError(OutputError):
    """An output that could not be written part way (a full disk, standard output that cannot
    take a command's line): what is on disk is whole, and says what is there (a run's
    ``run.json``, when it could be written). Exit code 1: the command's work had started."""

    exit_code = 1


class Interrupted(KeyboardInterrupt):
    """SIGINT (Ctrl-C) or SIGTERM (``kill``, ``timeout``, ``docker stop``) while a run or batch
    works: handled like Ctrl-C; the process exits ``128 + signum`` (130, 143)."""

    def __init__(self, signum: int) -> None:
        super().__init__(signum)
        self.signum = signum

    @property
    def exit_code(self) -> int:
        return 128 + self.signum

    @property
    def reason(self) -> str:
        """What stopped the work, as a run's record says it: ``interrupted by the user``
        (SIGINT, Ctrl-C) or ``interrupted by SIGTERM``."""
        if self.signum == signal.SIGINT:
            return "interrupted by the user"
        return f"interrupted by {signal.Signals(self.signum).name}"


@contextmanager
def passing_stop_to(generator: Generator[Any, Any, Any]) -> Iterator[None]:
    """Inside the block (which consumes ``generator``), an :class:`Interrupted` raised outside
    the generator (while its consumer works on what it yielded) is thrown into it at its
    ``yield``, so its clean-up learns the signal; it is raised on either way."""
    try:
        yield
    except Interrupted as exc:
        generator.throw(exc)
        raise


def interrupt(signum: int, frame: object) -> None:
    """A stop-signal handler (:func:`handling_stop_signals`) that stops the work at once: it
    raises :class:`Interrupted`, which the CLI turns into ``vtrack: interrupted`` and exit
    ``128 + signum``."""
    raise Interrupted(signum)


#: The signals a run or batch stops on as it does on Ctrl-C.
STOP_SIGNALS = (signal.SIGINT, signal.SIGTERM)


def ignore_stop_signals() -> None:
    """Ignore SIGINT and SIGTERM from now on (outside the main thread: nothing to do, a handler
    is only ever set there): a vtrack process whose outputs are final."""
    if threading.current_thread() is threading.main_thread():
        for signum in STOP_SIGNALS:
            signal.signal(signum, signal.SIG_IGN)


@contextmanager
def handling_stop_signals(handler: Callable[[int, Any], None],
                          ignored_after: bool = False) -> Iterator[None]:
    """Call ``handler`` on SIGINT and SIGTERM inside the block, then restore the previous
    handlers; with ``ignored_after``, a block that completes leaves the signals ignored
    instead (set in the handler's place: no moment with the default handler, which kills).
    Outside the main thread (where handlers cannot be set) it does nothing."""
    if threading.current_thread() is not threading.main_thread():
        yield
        return
    previous = {s: signal.signal(s, handler) for s in STOP_SIGNALS}
    completed = False
    try:
        yield
        completed = True
    finally:
        for signum, old in previous.items():
            signal.signal(signum, signal.SIG_IGN if completed and ignored_after else old)
