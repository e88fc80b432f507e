"""Ground-truth readers (OTB, VOT, UAV123/LaSOT, MOTChallenge) and the ``--init`` box parser.

All boxes come back as :class:`~vtrack.geometry.Box` in vtrack's convention: 0-based pixels,
``(x, y)`` the top-left corner. Frames come back 0-based. Anything a file gets wrong raises
:class:`~vtrack.errors.InputError` with one line naming the file, the line and the problem.
"""

from __future__ import annotations

import math
import re
from bisect import bisect_left
from collections import Counter
from collections.abc import Iterable, Iterator, Sequence
from itertools import chain, repeat
from os import PathLike
from pathlib import Path
from typing import NamedTuple, overload

from vtrack.errors import ConfigError, InputError, OptionNames, number_text, plural, quoted
from vtrack.geometry import Box, parse_box_text
from vtrack.io.images import holds_images, sequence_images
from vtrack.io.limits import GROUND_TRUTH_BYTES, read_text_bounded
from vtrack.io.sidecar import SEQUENCE_ONLY_IMAGES, SEQUENCE_SIDECAR, sequence_of
from vtrack.io.specs import VIDEO_SUFFIXES
from vtrack.params import MAX_FRAME_NUMBER

#: OTB files separate numbers by commas, tabs or spaces, sometimes mixed on one line.
_SEPARATORS = re.compile(r"[,\s]+")

#: MOT16/17/20 ``gt.txt`` class id of a walking/standing pedestrian (column 8).
MOT_PEDESTRIAN = 1
#: The classes MOTChallenge's ground truth uses (MOT16/17: 1 pedestrian ... 12 reflection; MOT20
#: adds 13 crowd); TrackEval, the official evaluation kit, refuses a file with any other.
MOT_CLASSES = range(1, 14)
#: The classes whose boxes TrackEval's MOT16/17 preprocessing calls distractors (2 person on
#: vehicle, 7 static person, 8 distractor, 12 reflection): a track box matched to one is taken
#: out before scoring, neither a match nor a false positive. (MOT20 adds 6, non-MOT vehicle; its
#: files do not say they are MOT20's, so 6 is scored as MOT17 scores it: dropped, not a
#: distractor.)
MOT_DISTRACTORS = frozenset({2, 7, 8, 12})

_QUOTE_MAX = 60

#: Single-target ground truth inside a sequence folder, first found wins: OTB's
#: ``groundtruth_rect.txt`` (MATLAB's 1-based boxes) and VOT's ``groundtruth.txt`` (0-based: the
#: VOT toolkit's pixel (0, 0) is the image's top-left pixel).
SEQUENCE_GT = ("groundtruth_rect.txt", "groundtruth.txt")
#: The ground truth ``--gt-origin auto`` reads as 1-based inside a sequence folder: OTB's.
ONE_BASED_GT = SEQUENCE_GT[0]
#: Single-target ground truth beside a video ``name.mp4`` (``{}`` is its stem), first found wins.
VIDEO_GT = ("{}.gt.txt", "{}.txt")


def groundtruth_beside(path: str | PathLike[str]) -> Path | None:
    """The single-target ground truth ``vtrack batch`` takes for input ``path`` (as given): a
    sequence folder's :data:`SEQUENCE_GT` file, else a video's :data:`VIDEO_GT` file beside
    it; None when there is none."""
    return next((c for c in groundtruth_names(path) if c.is_file()), None)


def groundtruth_names(path: str | PathLike[str]) -> list[Path]:
    """Where :func:`groundtruth_beside` looks for input ``path``'s ground truth, in order: a
    folder's :data:`SEQUENCE_GT` files, else a file's :data:`VIDEO_GT` names beside it."""
    path = Path(path)
    if path.is_dir():
        return [path / name for name in SEQUENCE_GT]
    return [path.parent / name.format(path.stem) for name in VIDEO_GT]


def numbered_groundtruth(folder: str | PathLike[str]) -> list[Path]:
    """The ground truth of each target of an OTB sequence with several (``Jogging``,
    ``Skating2``, ``Human4``: ``groundtruth_rect.1.txt``, ``groundtruth_rect.2.txt`` ...), by
    their number; empty for any other folder."""
    found = [(int(m[1]), p) for p in Path(folder).glob("groundtruth_rect.*.txt")
             if (m := _NUMBERED_GT.fullmatch(p.name)) and p.is_file()]
    return [p for _, p in sorted(found)]


#: The most digits of N in one target's ground truth, ``groundtruth_rect.N.txt``.
TARGET_DIGITS = 12
#: The largest target number (a RunRequest's ``target``): the largest N of
#: :data:`TARGET_DIGITS` digits.
MAX_TARGET = 10**TARGET_DIGITS - 1
#: The name of one target's ground truth in an OTB sequence of several (its number captured).
_NUMBERED_GT = re.compile(rf"groundtruth_rect\.(\d{{1,{TARGET_DIGITS}}})\.txt")


def target_number(gt_path: str | PathLike[str]) -> int:
    """The number N of one target's ground truth ``groundtruth_rect.N.txt``
    (:func:`numbered_groundtruth`); ValueError for a file of another name."""
    match = _NUMBERED_GT.fullmatch(Path(gt_path).name)
    if match is None:
        raise ValueError(f"{gt_path}: not one target's groundtruth_rect.N.txt")
    return int(match[1])


def target_of(input_spec: str, gt_path: str | PathLike[str] | None) -> int | None:
    """Which target of an OTB sequence of several a run of ``input_spec`` with ground truth
    ``gt_path`` tracks: N when ``gt_path`` is the sequence's own ``groundtruth_rect.N.txt``
    (:func:`numbered_groundtruth`; ``input_spec`` the sequence folder ``SEQ`` or its images'
    ``SEQ/img``), else None (any other input or ground truth)."""
    match = None if gt_path is None else _NUMBERED_GT.fullmatch(Path(gt_path).name)
    if match is None:
        return None
    folder = Path(input_spec)
    if not folder.is_dir():
        return None
    folder = sequence_of(folder) or folder
    try:
        if not Path(gt_path).parent.resolve().samefile(folder.resolve()):
            return None
    except OSError:
        return None
    return int(match[1])


def target_input(name: str, target: int | None) -> str:
    """The name of the input ``name`` (a sequence's) when its run tracks target ``target``
    (:func:`target_of`): ``NAME-N``, as OTB's toolkit and its published results name these
    sequences (``Jogging-1``, ``Jogging-2``, ``Human4-2``); ``name`` itself for None."""
    return name if target is None else f"{name}-{target}"


def gt_origin_of(path: str | PathLike[str], origin: int | None) -> int:
    """The origin to read ``path``'s boxes with: ``origin`` when given (0 or 1); for None
    (``--gt-origin auto``) 1 for the layouts of the MATLAB toolkits (OTB, UAV123, LaSOT):
    OTB's :data:`ONE_BASED_GT` (or one target's ``groundtruth_rect.N.txt``,
    :func:`numbered_groundtruth`) inside a sequence folder (:func:`is_sequence_folder`, the
    folders ``vtrack batch`` takes: in any of its layouts), and ``groundtruth.txt`` in a
    sequence folder whose images are in ``img/``; else 0: VOT's ``groundtruth.txt`` in VOT's
    own layouts (images beside it, or VOT2017+'s ``color/``: the VOT toolkit's pixel 0 is the
    image's first), ``vtrack scene``'s ``NAME.gt.txt``, any file outside a sequence folder."""
    if origin is not None:
        return origin
    path = Path(path)
    otb = path.name == ONE_BASED_GT or _NUMBERED_GT.fullmatch(path.name) is not None
    if otb:
        return int(is_sequence_folder(path.parent))
    if path.name in SEQUENCE_GT:  # images in img/ make the folder a sequence folder
        images = sequence_images(path.parent)
        return int(images is not None and images.name == "img")
    return 0


def is_sequence_folder(path: str | PathLike[str]) -> bool:
    """Whether ``path`` is an image-sequence folder, one input (``vtrack batch`` takes it as
    one; ``--gt-origin auto`` reads OTB's boxes in it as 1-based, :func:`gt_origin_of`): the
    images ``vtrack run FOLDER`` reads (:func:`~vtrack.io.images.list_images`) are

    - in ``img/`` (OTB) or ``img1/`` (MOTChallenge), names only sequences use (such a folder
      is a sequence even when it holds no image: a download that failed is said so when read,
      not passed over); or
    - in ``color/`` (VOT2017+), a name other folders have too (a colourist's output), beside
      what says which target to track (:func:`_names_a_target`); or
    - directly in the folder (VOT before 2017, GOT-10k, a folder ``vtrack select`` gave a
      box), beside what says which target to track, at least two of them (a folder's
      thumbnail is no sequence) and no video file (a folder of videos: its ground truth is
      theirs).

    A folder of images without any of these files (a report's ``plots/``) is none."""
    path = Path(path)
    if any((path / name).is_dir() for name in SEQUENCE_ONLY_IMAGES):
        return True
    if not _names_a_target(path):  # (cheap: most folders a batch walks stop here)
        return False
    if sequence_images(path) is not None:  # color/
        return holds_images(path)
    return holds_images(path, 2) and not _holds_videos(path)


def _names_a_target(folder: Path) -> bool:
    """Whether ``folder`` holds a sequence's single-target ground truth (:data:`SEQUENCE_GT`,
    :func:`numbered_groundtruth`) or its first box (``init.txt``, what ``vtrack select``
    writes)."""
    return (groundtruth_beside(folder) is not None or bool(numbered_groundtruth(folder))
            or (folder / SEQUENCE_SIDECAR).is_file())


def _holds_videos(folder: Path) -> bool:
    """Whether ``folder`` holds a video file (by suffix, :data:`~vtrack.io.specs.VIDEO_SUFFIXES`)
    directly; False when it cannot be listed."""
    try:
        return any(p.suffix.lower() in VIDEO_SUFFIXES for p in folder.iterdir())
    except OSError:
        return False


def _quote(text: str) -> str:
    """``repr`` of a line for an error message, shortened so the message stays one short line."""
    text = text.strip()
    return repr(text if len(text) <= _QUOTE_MAX else text[:_QUOTE_MAX] + "...")


def _tokens(line: str) -> list[str]:
    return [t for t in _SEPARATORS.split(line) if t]


#: An empty field between two commas (``10,,20,30,40``) or before the first number
#: (``,10,20,30,40``). Searched with the line's trailing separators cut: empty fields after
#: the last number (``10,20,30,40,``, a spreadsheet's padding ``10,20,30,40,,,,``) leave
#: every number where it is.
_EMPTY_FIELD = re.compile(r"^\s*,|,\s*,")


def _check_fields(path: str | PathLike[str], number: int, line: str) -> None:
    """InputError naming ``path`` and line ``number`` when ``line`` has an empty field
    (:data:`_EMPTY_FIELD`): a number left out, which reading the others as they come would
    put the numbers after it in the wrong columns (``10,,20,30,40`` a box at x 10, y 20).
    Empty fields with no number after them (``10,20,30,40,,,``) are taken."""
    if _EMPTY_FIELD.search(line.rstrip(", \t\r\n\f\v")):
        raise InputError(f"{path} line {number}: an empty field in {_quote(line)} (a number "
                         "left out: the numbers after it would be read into the wrong columns)")


#: Characters that separate numbers in files vtrack does not read (a semicolon CSV, as
#: spreadsheets write it where the comma is the decimal mark; bars; slashes).
_OTHER_SEPARATORS = re.compile(r"[;|/]+")


def _separator_hint(line: str) -> str:
    """What to change in ``line`` when a separator vtrack does not take splits it into numbers
    (`` (numbers are separated by commas, tabs or spaces, not ';')`` for ``10;20;30;40``; with
    decimal commas, ``262,20;71,35;...``, that they are to be points: putting commas for the
    semicolons would give twice the numbers); else ``""``."""
    found = _OTHER_SEPARATORS.search(line)
    if found is None:
        return ""
    separator = found.group()[0]
    fields = [t.strip() for t in _OTHER_SEPARATORS.split(line.strip()) if t.strip()]
    decimal = next((f for f in fields if "," in f), None)
    try:
        if decimal is None:
            [float(t) for t in _tokens(_OTHER_SEPARATORS.sub(",", line))]
        else:
            [float(t.replace(",", ".")) for t in fields]
    except ValueError:
        return ""
    rule = f"numbers are separated by commas, tabs or spaces, not {quoted(separator)}"
    if decimal is None:
        return f" ({rule})"
    return _decimal_hint(decimal, rule)


def _decimal_hint(decimal: str, rule: str) -> str:
    """`` (decimal commas: write 262.2, not 262,2; RULE)`` for the field ``decimal``."""
    return f" (decimal commas: write {decimal.replace(',', '.')}, not {decimal}; {rule})"


def _spaced_decimal_commas(line: str) -> str | None:
    """The first field of ``line`` when its 8 numbers are 8 only because each of its 4
    space-separated fields holds one comma (``262,2 71,35 40,8 31,2``: decimal commas, a box,
    or a polygon's points ``x,y`` apart), and each such field is a number with a decimal comma;
    else None."""
    fields = line.split()
    if len(fields) != 4 or any(f.count(",") != 1 for f in fields):
        return None
    try:
        [float(f.replace(",", ".")) for f in fields]
    except ValueError:
        return None
    return fields[0]


def _read_lines(path: str | PathLike[str], what: str, empty_ok: bool = False) -> list[str]:
    """The file's lines without trailing blank lines; InputError if unreadable, larger than
    :data:`~vtrack.io.limits.GROUND_TRUTH_BYTES`, not UTF-8 or, unless ``empty_ok``, empty
    (nothing but blank lines)."""
    text = read_text_bounded(path, GROUND_TRUTH_BYTES, f"{what} file")
    lines = text.splitlines()
    while lines and not lines[-1].strip():
        lines.pop()
    if not lines and not empty_ok:
        raise InputError(f"{path}: {what} file is empty")
    return lines


#: Largest coordinate a ground-truth box may have: frames are at most 16384 pixels a side, so
#: anything near this is a damaged file (and 1e308 would overflow the metrics and the drawing).
MAX_COORDINATE = 1e6
#: Largest frame a single-target file's first box may be given (``--gt-first``): the largest
#: frame number (:data:`vtrack.params.MAX_FRAME_NUMBER`).
MAX_GT_FIRST = MAX_FRAME_NUMBER
#: Largest frame number a MOTChallenge file may give (over a year of 30 fps video): beyond it the
#: file is damaged, and a 300-digit number would be printed whole in the warning of frames past
#: the input.
MAX_MOT_FRAME = 10**9


def _check_coordinates(path: str | PathLike[str], number: int, line: str,
                       values: list[float]) -> None:
    """InputError naming ``path`` and line ``number`` when a finite coordinate of ``values``
    lies beyond +-:data:`MAX_COORDINATE` (one rule for every box file vtrack reads)."""
    if any(abs(v) > MAX_COORDINATE for v in values):
        raise InputError(
            f"{path} line {number}: coordinate beyond +-{MAX_COORDINATE:g} pixels in "
            f"{_quote(line)}"
        )


#: The shipped configs that track many targets and read MOTChallenge ground truth, as a
#: message names them.
MULTI_TARGET_CONFIGS = "fixed_camera, s3 or s4_multi"


class MultiTargetTruthError(InputError):
    """Many targets' ground truth (MOTChallenge) where one target's boxes were expected."""


def _is_mot_row(values: list[float]) -> bool:
    """Whether a line's numbers are a MOTChallenge row (Milan et al. 2016, MOT16 sec. 3.3):
    6 to 10 numbers, the first two (frame, id) whole. 8 numbers are a VOT polygon unless its
    last two are a consider flag (0 or 1) and a MOTChallenge class (frame,id,x,y,w,h,consider,
    class) and the frame is >= 1."""
    if not 6 <= len(values) <= 10 or not all(v.is_integer() for v in values[:2]):
        return False
    if len(values) != 8:
        return True
    return values[0] >= 1 and values[6] in (0, 1) and values[7] in MOT_CLASSES


class FrameBoxes(Sequence[Box | None]):
    """Ground-truth boxes indexed by frame, of a file whose first box is of a later frame than
    0 (``--gt-first``): None for the :attr:`first` frames before the file's first box, then the
    file's own boxes (:attr:`own`), then None for :attr:`after` frames (a reversed slice's).
    The frames of None are not stored (``--gt-first`` may be 10^12): a slice is another
    FrameBoxes, as long as a list's slice would be, and ``in``, :meth:`index`, :meth:`count`
    and ``reversed`` count them without visiting each. Equal to any sequence of the same boxes
    (a list too)."""

    def __init__(self, own: Sequence[Box | None], first: int = 0, after: int = 0) -> None:
        #: The file's own boxes, the first of frame :attr:`first`.
        self.own: list[Box | None] = list(own)
        #: The frame the file's first box belongs to.
        self.first = first
        #: The frames of None after the own boxes.
        self.after = after

    def __len__(self) -> int:
        return self.first + len(self.own) + self.after

    @overload
    def __getitem__(self, index: int) -> Box | None: ...

    @overload
    def __getitem__(self, index: slice) -> FrameBoxes: ...

    def __getitem__(self, index: int | slice) -> Box | None | FrameBoxes:
        if isinstance(index, slice):
            frames = range(len(self))[index]
            before, own, after = self._parts(frames if frames.step > 0 else frames[::-1])
            boxes = [self.own[frame - self.first] for frame in own]
            if frames.step < 0:
                return FrameBoxes(boxes[::-1], len(after), len(before))
            return FrameBoxes(boxes, len(before), len(after))
        frame = index + len(self) if index < 0 else index
        if not 0 <= frame < len(self):
            raise IndexError(f"frame {index} out of range")
        own = frame - self.first
        return self.own[own] if 0 <= own < len(self.own) else None

    def _parts(self, frames: range) -> tuple[range, range, range]:
        """The frames of ``frames`` (ascending) before the own boxes, of them, and after."""
        end = self.first + len(self.own)
        cuts = [bisect_left(frames, frame) for frame in (self.first, end)]
        return frames[:cuts[0]], frames[cuts[0]:cuts[1]], frames[cuts[1]:]

    def __iter__(self) -> Iterator[Box | None]:
        return chain(repeat(None, self.first), self.own, repeat(None, self.after))

    def __reversed__(self) -> Iterator[Box | None]:
        return chain(repeat(None, self.after), reversed(self.own), repeat(None, self.first))

    def __contains__(self, value: object) -> bool:
        return bool(_is_none(value) and (self.first or self.after)) or value in self.own

    def count(self, value: object) -> int:
        """How many frames hold ``value`` (None: also the frames before and after the own
        boxes)."""
        return (self.first + self.after if _is_none(value) else 0) + self.own.count(value)

    def index(self, value: object, start: int = 0, stop: int | None = None) -> int:
        """The first frame from ``start`` to before ``stop`` (as a list's ``index`` takes them)
        that holds ``value``; ValueError if none does."""
        before, own, after = self._parts(range(len(self))[start:stop])
        if _is_none(value) and before:
            return before[0]
        for frame in own:
            box = self.own[frame - self.first]
            if box is value or box == value:
                return frame
        if _is_none(value) and after:
            return after[0]
        raise ValueError(f"{value!r} is not in the ground truth's frames")

    def __eq__(self, other: object) -> bool:
        if isinstance(other, FrameBoxes):
            return (self.first, self.own, self.after) == (other.first, other.own, other.after)
        if not isinstance(other, Sequence) or isinstance(other, str) or len(other) != len(self):
            return False
        return all(a == b for a, b in zip(self, other, strict=True))

    __hash__ = None  # type: ignore[assignment]

    def __repr__(self) -> str:
        after = f", after={self.after}" if self.after else ""
        return f"FrameBoxes({self.own!r}, first={self.first}{after})"


def _is_none(value: object) -> bool:
    """Whether a frame of no box (None) holds ``value``, as a list compares its items."""
    return value is None or value == None  # noqa: E711 (as list.index and list.count compare)


def read_boxes(path: str | PathLike[str], origin: int = 0,
               first: int = 0) -> list[Box | None] | FrameBoxes:
    """Read single-target ground truth: one box per frame, ``None`` where the target is absent
    (:func:`read_truth`'s boxes, the first of frame ``first``): a list when ``first`` is 0, a
    :class:`FrameBoxes` otherwise."""
    return read_truth(path, origin, first).boxes


class SingleTruth(NamedTuple):
    """Single-target ground truth as :func:`read_truth` reads it."""

    #: One box per frame, None where the target is absent (:func:`read_boxes`): a list when
    #: the file's first box is of frame 0; else a :class:`FrameBoxes`, whose ``first`` frames
    #: before the file's first box are None without being stored.
    boxes: list[Box | None] | FrameBoxes
    #: The lines (1-based) whose box has a negative width or height: read as the target
    #: absent, as ``0,0,0,0`` is, though no dataset marks it so (:func:`negative_note`).
    negative: list[int]


def negative_note(path: str | PathLike[str], truth: SingleTruth) -> str | None:
    """The warning for the boxes of ``truth`` (read from ``path``) with a negative width or
    height: how many, the line of the first, and that their frames are not scored; None when
    there are none."""
    if not truth.negative:
        return None
    count = len(truth.negative)
    return (f"{path}: {plural(count, 'box', 'boxes')} with a negative width or height (the "
            f"first on line {truth.negative[0]}) read as the target absent: "
            f"{'its frame is' if count == 1 else 'their frames are'} not scored")


def read_truth(path: str | PathLike[str], origin: int = 0, first: int = 0) -> SingleTruth:
    """Read single-target ground truth: one box per frame, ``None`` where the target is absent,
    and the lines whose box has a negative width or height (:class:`SingleTruth`).

    ``first`` is the 0-based frame the file's first box belongs to (``--gt-first``: OTB's
    ``David`` starts at its image 300, frame 299): the boxes come back indexed by frame, the
    ``first`` frames before it None (no ground truth, not scored; not stored: a
    :class:`FrameBoxes`; with ``first`` 0, the boxes are a list); ConfigError
    for a ``first`` that is not a whole number from 0 to :data:`MAX_GT_FIRST`.

    Each line is ``x,y,w,h`` (OTB, UAV123, LaSOT, VOT rectangles) or an 8-number VOT polygon
    ``x1,y1,...,x4,y4``, which becomes its axis-aligned bounding box. Numbers may be separated
    by commas, tabs or spaces, mixed freely. A line holding NaN, or whose box has ``w <= 0`` or
    ``h <= 0`` (which includes the ``0,0,0,0`` UAV123/LaSOT write for out-of-view), means the
    target is absent in that frame (a negative ``w`` or ``h``, which no dataset writes for it,
    is noted in :attr:`SingleTruth.negative`). ``origin=1`` reads MATLAB 1-based OTB boxes: 1 is
    subtracted from ``x`` and ``y``. Trailing blank lines are ignored; any other blank line, a
    line without 4 or 8 numbers, an empty field (``10,,20,30,40``: a number left out; empty fields
    after the last number are taken), an infinite number or one beyond ``MAX_COORDINATE`` is an
    error, as are a line of 8 numbers only because each of its 4 space-separated fields holds a
    comma (``262,2 71,35 40,8 31,2``: decimal commas, or a polygon's points; said which to
    write), a missing, unreadable or empty file. A file whose first line is a MOTChallenge row
    (:func:`_is_mot_row`) raises :class:`MultiTargetTruthError`; in a file of boxes, a later
    line of 8 numbers is a polygon, also one that could be read as such a row (a polygon
    touching the frame's top-left corner, ``5,2,25,2,25,12,1,12``).
    """
    if origin not in (0, 1):
        raise ConfigError(f"ground-truth origin must be 0 or 1, got {origin!r}")
    if isinstance(first, bool) or not isinstance(first, int) or not 0 <= first <= MAX_GT_FIRST:
        raise ConfigError(f"ground truth's first frame must be a whole number from 0 to "
                          f"{MAX_GT_FIRST}, got {first!r}")
    boxes: list[Box | None] = []
    negative: list[int] = []
    for number, line in enumerate(_read_lines(path, "ground-truth"), start=1):
        _check_fields(path, number, line)
        tokens = _tokens(line)
        try:
            values = [float(t) for t in tokens]
        except ValueError:
            values = []
        if number == 1 and _is_mot_row(values):  # the first line tells the file's kind
            raise MultiTargetTruthError(
                f"{path} line {number}: this is MOTChallenge ground truth (frame,id,x,y,w,h,...), "
                "for many targets; a single-target config reads x,y,w,h per frame: use a "
                f"multi-target config (--config {MULTI_TARGET_CONFIGS})")
        if not line.strip():
            raise InputError(f"{path} line {number}: blank; the file holds one box per frame "
                             "(0,0,0,0 or NaN where the target is out of view)")
        if len(values) not in (4, 8):
            hint = "" if values else _separator_hint(line)
            if not hint and tokens and not values and number == 1:
                hint = " (no header line: the file holds only numbers)"
            raise InputError(f"{path} line {number}: expected 4 or 8 numbers, got "
                             f"{_quote(line)}{hint}")
        decimal = _spaced_decimal_commas(line) if len(values) == 8 else None
        if decimal is not None:
            raise InputError(
                f"{path} line {number}: {_quote(line)} is 8 numbers only if its commas "
                "separate numbers as its spaces do" + _decimal_hint(
                    decimal, "numbers are separated by commas, tabs or spaces; a polygon's "
                    "four x,y points: commas between them too"))
        if any(math.isnan(v) for v in values):
            boxes.append(None)
            continue
        if not all(math.isfinite(v) for v in values):
            raise InputError(f"{path} line {number}: infinite coordinate in {_quote(line)}")
        _check_coordinates(path, number, line, values)
        if len(values) == 8:
            xs, ys = values[0::2], values[1::2]
            box = Box(min(xs), min(ys), max(xs) - min(xs), max(ys) - min(ys))
        else:
            box = Box(*values)
        if box.w < 0 or box.h < 0:
            negative.append(number)
        if box.w <= 0 or box.h <= 0:
            boxes.append(None)
        else:
            boxes.append(box._replace(x=box.x - origin, y=box.y - origin))
    return SingleTruth(FrameBoxes(boxes, first) if first else boxes, negative)


def boxes_for_frames(boxes: int, first: int, frames: int, start: int, its: str = "") -> str:
    """How many ``boxes`` a ground-truth file has (the first frame ``first``'s) for the
    ``frames`` a run tracked from frame ``start`` (``its``: a word before ``frames``), naming
    the boxes' frames when either does not begin at frame 0, so that the counts explain
    themselves: ``15 boxes, frames 0..14, for its 15 frames from frame 5``."""
    held = plural(boxes, "box", "boxes")
    if first or start:
        held += f", frames {first}..{first + boxes - 1}," if boxes else ","
    return f"{held} for {its}{plural(frames, 'frame')}{f' from frame {start}' if start else ''}"


def later_first_hint(boxes: int, frames: int, start: int, first: int,
                     names: OptionNames) -> str:
    """The clause a warning of ground truth with fewer ``boxes`` (the file's, its first of
    frame ``first``) than the ``frames`` a run tracked from frame ``start`` ends with: how a
    file whose first box is of a later frame (OTB's ``David``, UAV123's ``bird1_2``) is aligned
    (``names.gt_first``), with the frame that ends it at the run's last frame: ``; if its first
    box is of a later frame, give --gt-first 5 (its last box then the last frame's)``; empty
    when that frame is no later than ``first``."""
    if start + frames - boxes <= first:
        return ""
    give = names.give(names.gt_first, str(start + frames - boxes))
    return (f"; if its first box is of a later frame, give {give} (its last box then the last "
            "frame's)")


def _mot_rows(path: str | PathLike[str], layout: str) -> Iterator[tuple[int, int, list[float]]]:
    """``(line number, 0-based frame, numbers)`` for each non-blank line of a MOTChallenge file
    (none for an empty one: ground truth of a scene without targets, detections of a detector
    that found nothing).

    ``layout`` names the columns every row must have (``"frame,id,x,y,w,h"``); they must be
    finite numbers, the box's within +-:data:`MAX_COORDINATE` and the frame an integer from 1
    to :data:`MAX_MOT_FRAME`; no field may be empty (``1,1,,20,30,40``: a number left out),
    though empty fields may follow the last number.
    Further columns are passed through unchecked.
    """
    min_columns = layout.count(",") + 1
    for number, line in enumerate(_read_lines(path, "MOT", empty_ok=True), start=1):
        if not line.strip():
            continue
        _check_fields(path, number, line)
        try:
            values = [float(t) for t in _tokens(line)]
        except ValueError:
            values = []
        if len(values) < min_columns:
            raise InputError(
                f"{path} line {number}: expected at least {min_columns} numbers"
                f" ({layout},...), got {_quote(line)}"
            )
        if not all(math.isfinite(v) for v in values[:min_columns]):
            raise InputError(f"{path} line {number}: non-finite number in {_quote(line)}")
        _check_coordinates(path, number, line, values[2:6])
        frame = values[0]
        if not frame.is_integer() or frame < 1:
            raise InputError(
                f"{path} line {number}: frame must be an integer >= 1 (MOTChallenge frames are"
                f" 1-based), got {_quote(line)}"
            )
        if frame > MAX_MOT_FRAME:
            raise InputError(f"{path} line {number}: frame beyond {MAX_MOT_FRAME:,} in "
                             f"{_quote(line)}")
        yield number, int(frame) - 1, values


def read_mot(path: str | PathLike[str]) -> dict[int, list[tuple[int, Box]]]:
    """Read a MOTChallenge ground-truth file (``gt.txt``): ``{0-based frame: [(id, box), ...]}``.

    Rows are ``frame,id,x,y,w,h[,consider,class,visibility]`` (MOT16/17/20) or
    ``frame,id,x,y,w,h,1,-1,-1,-1`` (MOT15 layout, columns 8-10 are world coordinates). Kept
    rows:

    - column 7 (the "consider" flag) equal to 0 drops the row (MOTChallenge: ignore this box);
    - only in the 8- and 9-column MOT16/17/20 layout, column 8 is the class: only pedestrians
      (class 1) are kept; persons on vehicles, static persons, distractors, reflections etc. are
      dropped (track boxes on the distractor classes are taken out of the score by
      :class:`~vtrack.evaluate.mot.MotScore`, given :attr:`MotTruth.distractors`). A class
      that is not one of MOTChallenge's (:data:`MOT_CLASSES`, e.g. the ``-1``
      of a MOT15 row cut to 9 columns) is an error, as in TrackEval. The 10-column layout has
      no class column and is not filtered;
    - a row whose box has ``w <= 0`` or ``h <= 0`` is dropped (:func:`dropped_notes` warns of
      them).

    Frames without kept rows are not keys; keys are ascending, rows keep file order. Frame 1 of
    the file is key 0; boxes are taken as written (MOTChallenge's top-left corner). Blank lines
    are skipped; a file of none but them (or of 0 bytes) is the ground truth of a scene
    without targets, no key (:func:`dropped_notes` warns of it). Two kept rows for one
    (frame, id) are an error: a target is in one place at a time. For ``det.txt`` files use
    :func:`read_mot_detections`; :func:`read_mot_counting` also says which rows were dropped.
    """
    return read_mot_counting(path).boxes


#: The reason a MOTChallenge row with an empty box is dropped, as :class:`Dropped` counts it.
EMPTY_BOX = "w or h <= 0"


class Dropped(Counter[str]):
    """How many MOTChallenge rows were not scored, for each reason, and the line of the first
    dropped for each (``first``)."""

    def __init__(self) -> None:
        super().__init__()
        self.first: dict[str, int] = {}

    def drop(self, reason: str, line: int) -> None:
        """Count a row of ``line`` dropped for ``reason``."""
        self[reason] += 1
        self.first.setdefault(reason, line)


class MotTruth(NamedTuple):
    """MOTChallenge ground truth as :func:`read_mot_counting` reads it."""

    #: The scored boxes, as :func:`read_mot` returns them.
    boxes: dict[int, list[tuple[int, Box]]]
    #: How many rows were not scored, for each reason (``"the consider flag 0 in column 7"``,
    #: ``"class 7 in column 8, not pedestrian 1"``, :data:`EMPTY_BOX`).
    dropped: Dropped
    #: Only for the frames holding a row of a :data:`MOT_DISTRACTORS` class: every row of that
    #: frame with a box, ``(box, is a distractor)``, whatever its consider flag or class (what
    #: TrackEval matches track boxes against before it takes out those on distractors).
    distractors: dict[int, list[tuple[Box, bool]]]


def read_mot_counting(path: str | PathLike[str]) -> MotTruth:
    """:func:`read_mot`, with how many rows it dropped for each reason and the rows that take
    track boxes on distractors out of the score (:class:`MotTruth`)."""
    frames: dict[int, list[tuple[int, Box]]] = {}
    seen: dict[tuple[int, int], int] = {}  # (frame, id) -> line
    dropped = Dropped()
    rows: dict[int, list[tuple[Box, bool]]] = {}  # every row with a box, for the distractors
    for number, frame, values in _mot_rows(path, "frame,id,x,y,w,h"):
        if not values[1].is_integer():
            raise InputError(f"{path} line {number}: id must be an integer, "
                             f"got {number_text(values[1])}")
        kind = values[7] if len(values) in (8, 9) else None  # the class column's, if any
        if kind is not None and kind not in MOT_CLASSES:
            raise InputError(
                f"{path} line {number}: column 8 is {number_text(kind)}, not a MOTChallenge class "
                f"(1-13, 1 pedestrian): {len(values)} columns are "
                "frame,id,x,y,w,h,consider,class[,visibility]; MOT15's rows with world "
                "coordinates have 10 (frame,id,x,y,w,h,conf,x,y,z)")
        box = Box(*values[2:6])
        if kind is not None and box.w > 0 and box.h > 0:
            rows.setdefault(frame, []).append((box, kind in MOT_DISTRACTORS))
        if len(values) >= 7 and values[6] == 0:
            dropped.drop("the consider flag 0 in column 7", number)
            continue
        if kind is not None and kind != MOT_PEDESTRIAN:
            dropped.drop(f"class {number_text(kind)} in column 8, not pedestrian "
                         f"{MOT_PEDESTRIAN}", number)
            continue
        if not (box.w > 0 and box.h > 0):
            dropped.drop(EMPTY_BOX, number)
            continue
        target = int(values[1])
        first = seen.setdefault((frame, target), number)
        if first != number:
            raise InputError(f"{path} line {number}: frame {frame + 1} has a second box for "
                             f"id {target} (the first is on line {first})")
        frames.setdefault(frame, []).append((target, box))
    distractors = {f: r for f, r in sorted(rows.items()) if any(d for _, d in r)}
    return MotTruth(dict(sorted(frames.items())), dropped, distractors)


def dropped_notes(path: str | PathLike[str], truth: MotTruth) -> list[str]:
    """The warnings for the rows of MOTChallenge ground truth :func:`read_mot_counting` did not
    score: when the file has no row (a scene without targets), that each track box is a false
    positive; when it dropped every row, how many and why; else, when rows had an empty box (w
    or h <= 0: no MOTChallenge row has one, the file is wrong there), how many and the line of
    the first. Rows MOTChallenge itself leaves out (consider flag 0, classes other than
    pedestrian) are not warned about when others are scored."""
    dropped = truth.dropped
    if not truth.boxes and not dropped:
        return [f"{path}: no ground-truth rows (a scene without targets): every track box is a "
                "false positive (gt_boxes 0, mota null)"]
    if not truth.boxes and dropped:
        why = "; ".join(f"{count} with {reason}" for reason, count in dropped.most_common())
        return [f"{path}: all {sum(dropped.values())} ground-truth rows are ignored ({why}): "
                "nothing to score against (gt_boxes 0, mota null)"]
    empty = dropped.get(EMPTY_BOX, 0)
    if not empty:
        return []
    return [f"{path}: {plural(empty, 'ground-truth row')} with {EMPTY_BOX} ignored (the first "
            f"on line {dropped.first[EMPTY_BOX]}): not scored, as if the file did not have "
            f"{'it' if empty == 1 else 'them'}"]


def past_end_note(path: object, rows: str, frames: Iterable[int], end: int,
                  fate: str) -> str | None:
    """The warning for a file's rows in 0-based ``frames`` from ``end`` on, past the input's
    ``end`` frames: ``rows`` (what the file has there, e.g. ``ground truth has boxes``), in how
    many frames, up to which (1-based, as the file numbers them), and their ``fate``; None when
    no frame is past the end."""
    past = [f for f in frames if f >= end]
    if not past:
        return None
    return (f"{path}: {rows} in {plural(len(past), 'frame')} past the input's "
            f"{plural(end, 'frame')} (up to frame {max(past) + 1}); {fate}")


def read_mot_detections(path: str | PathLike[str]) -> dict[int, list[tuple[Box, float]]]:
    """Read MOTChallenge detections (``det.txt``): ``{0-based frame: [(box, confidence), ...]}``.

    Rows are ``frame,id,x,y,w,h,conf,...`` (the id, usually -1, and later columns are ignored).
    Every detection is kept whatever its confidence (detector scores may be 0 or negative;
    thresholding is the caller's job). A box with ``w <= 0`` or ``h <= 0`` is an InputError
    naming the file and line, as any malformed row is: a detector gives no empty box, so the
    file is not what it should be there. Keys are ascending, detections keep file order;
    frames without detections are not keys. A file of 0 bytes or blank lines only (a detector
    that found nothing in the scene) has no key.
    """
    frames: dict[int, list[tuple[Box, float]]] = {}
    for number, frame, values in _mot_rows(path, "frame,id,x,y,w,h,conf"):
        box = Box(*values[2:6])
        if not (box.w > 0 and box.h > 0):  # (shown as box_from_parts reads them: -0 as 0)
            raise InputError(f"{path} line {number}: a detection's w and h must be > 0, got "
                             f"w {number_text(box.w + 0.0)}, h {number_text(box.h + 0.0)}")
        frames.setdefault(frame, []).append((box, values[6]))
    return dict(sorted(frames.items()))


def parse_box(text: str) -> Box:
    """Parse the CLI's ``--init x,y,w,h``: 4 finite numbers separated by commas, spaces or
    tabs (the forms a sidecar file takes, :func:`~vtrack.geometry.parse_box_text`), ``w, h >
    0``. Raises ConfigError naming ``--init`` and listing those forms otherwise.
    """
    return parse_box_text(text, "--init", ConfigError)
