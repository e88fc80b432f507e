"""Image-sequence folders (OTB layout ``seq/img/0001.jpg`` or images directly in the folder).

Images are sorted by name with numbers compared as numbers (``2.png`` before ``10.png``) and
decoded with PyAV in the reader thread, each turned upright by its orientation (a phone
photo's EXIF tag); one that its own tag would not turn to the sequence's size (a tag lost or
added in an edit) is turned as the first image, with a warning. A sequence whose first image
is grey becomes :class:`~vtrack.frame.GrayFrame` s, otherwise :class:`~vtrack.frame.BgrFrame` s
(later images are converted to match); 16-bit images (grey or colour) are scaled to 8 bits by
the bits the first one uses, rising with a later one's (:mod:`vtrack.io.depth`). There are no
timestamps: ``time_s = index / fps``.
An image that cannot be decoded (after the first) is skipped with a warning; the frames after
it keep their indices.
Images numbered alike (``0001.jpg``, ``0002.jpg``, ...: one name but for its last number, of
one count of digits) take their frame index from their number (the first image's is index 0),
so an image missing from the numbering leaves its frame's place empty, counted as skipped with
a warning, and ground truth stays aligned. Both are counted, and warned of, among the frames
handed on (what a run read, not the whole folder nor what the reader went ahead to).
"""

from __future__ import annotations

import bisect
import configparser
import math
import os
import re
from collections.abc import Iterator
from itertools import islice
from pathlib import Path
from typing import NamedTuple

import av
import cv2
import numpy as np

from vtrack.errors import InputError, PartialInputError, plural, quoted
from vtrack.frame import BgrFrame, Frame, GrayFrame
from vtrack.geometry import frame_size_problem
from vtrack.io.depth import DepthScale, as_kind, eight_bit, layout, stored_pixels, used_bits
from vtrack.io.files import ffmpeg_file, os_reason, places_of, real_path
from vtrack.io.identity import images_identity
from vtrack.io.limits import SIDECAR_BYTES, read_text_bounded
from vtrack.io.planes import quarter_turns, turned
from vtrack.io.raw import MAX_FPS, MIN_FPS
from vtrack.io.sidecar import SEQUENCE_IMAGES, sequence_of
from vtrack.io.signatures import (
    PHOTO_CODECS,
    declared_size_problem,
    float_tiff_problem,
    jpeg_cut_short,
    photo_mirrored,
)
from vtrack.io.source import InputInfo, Source

JPEG_SUFFIXES = frozenset({".jpg", ".jpeg"})
IMAGE_SUFFIXES = frozenset({".jpg", ".jpeg", ".png", ".bmp", ".tif", ".tiff", ".pgm", ".ppm"})
#: Frame rate of an image sequence unless told otherwise.
DEFAULT_FPS = 30.0
#: Unreadable images named one warning line each; beyond them, one line gives the count.
_NAMED_SKIPS = 3


class _Note(NamedTuple):
    """A warning of the reader's about frame ``index`` (``unreadable``: an image skipped)."""

    index: int
    line: str
    unreadable: bool = False


def encode_image(bgr: np.ndarray, ext: str = ".jpg", quality: int = 92) -> bytes:
    """``bgr`` encoded as JPEG (``.jpg``) or PNG (``.png``) bytes by OpenCV."""
    params = [cv2.IMWRITE_JPEG_QUALITY, quality] if ext == ".jpg" else []
    ok, data = cv2.imencode(ext, bgr, params)
    if not ok:
        raise InputError(f"cannot encode a {bgr.shape[1]}x{bgr.shape[0]} frame as {ext}")
    return data.tobytes()


def natural_key(name: str) -> tuple[tuple[int, int | str], ...]:
    """Sort key comparing digit runs as numbers: ``img2`` < ``img10``."""
    return tuple(
        (0, int(part)) if part.isdigit() else (1, part.lower())
        for part in re.split(r"(\d+)", name)
        if part
    )


def list_images(folder: Path) -> list[Path]:
    """The images of a sequence folder in frame order (those of its ``img/``, ``img1/`` or
    ``color/`` if it has one, :func:`sequence_images`; hidden files such as macOS
    ``._0001.jpg`` are not images)."""
    return sorted(_image_files(folder), key=lambda p: natural_key(p.name))


def _image_files(folder: Path) -> Iterator[Path]:
    """The images of a sequence folder (:func:`list_images`) as they are listed."""
    where = sequence_images(folder) or folder
    return (p for p in where.iterdir() if _image_name(p.name) and p.is_file())


def _image_name(name: str) -> bool:
    """Whether a file named ``name`` is an image of a sequence: by suffix, not hidden (macOS's
    ``._0001.jpg``)."""
    return Path(name).suffix.lower() in IMAGE_SUFFIXES and not name.startswith(".")


def sequence_images(folder: Path) -> Path | None:
    """The folder of ``folder``'s images when it is a sequence folder: the first of
    :data:`~vtrack.io.sidecar.SEQUENCE_IMAGES` (OTB's ``img/``, MOTChallenge's ``img1/``,
    VOT2017+'s ``color/``) that holds an image, or that cannot be listed (reading it then says
    why); else None (an empty ``img/`` beside images in ``folder`` itself is not theirs)."""
    for name in SEQUENCE_IMAGES:
        where = folder / name
        if not where.is_dir():
            continue
        try:
            with os.scandir(where) as entries:
                if any(_image_name(e.name) and e.is_file() for e in entries):
                    return where
        except OSError:
            return where
    return None


def is_image_of(folder: str | os.PathLike[str], path: Path) -> bool:
    """Whether ``path`` is (or would be) an image of the sequence ``folder`` (a folder: one in
    its images' folder, :func:`sequence_images`, named as :func:`list_images` lists images),
    however either is named (``..``, a symbolic link: either the image it leads to or itself,
    :func:`~vtrack.io.files.places_of`)."""
    root = Path(folder)
    if not root.is_dir():
        return False
    where = real_path(sequence_images(root) or root)
    return any(_image_name(place.name) and place.parent == where for place in places_of(path))


def holds_images(folder: Path, count: int = 1) -> bool:
    """Whether ``folder`` (or its images' folder, :func:`sequence_images`) holds at least
    ``count`` (>= 1) images, as :func:`list_images` lists them; False when it cannot be
    listed."""
    try:
        return len(list(islice(_image_files(folder), count))) == count
    except OSError:
        return False


def images_of(folder: str, first_only: bool = False) -> list[Path]:
    """The images of ``folder`` (:func:`list_images`), or with ``first_only`` only the first
    one listed (a cheap check that it has one, nothing decoded); InputError naming it when it
    cannot be listed or holds no image."""
    try:
        found = (list(islice(_image_files(Path(folder)), 1)) if first_only else
                 list_images(Path(folder)))
    except OSError as exc:
        raise InputError(f"{folder}: cannot list the folder ({os_reason(exc)})") from None
    if not found:
        suffixes = "/".join(sorted(s.lstrip(".") for s in IMAGE_SUFFIXES))
        raise InputError(f"{folder}: no images ({suffixes}) in the folder or its img/ (img1/, "
                         "color/)")
    return found


def frame_places(files: list[Path]) -> list[int]:
    """Each image's frame index: its number less the first image's when every name is one name
    but for its last number, written with one count of digits (``img0001.jpg``,
    ``img0002.jpg``: a sequence's numbering), else its place in the list."""
    numbered = [re.fullmatch(r"(.*?)(\d+)(\D*)", p.name) for p in files]
    if all(numbered):
        parts = [(m[1], len(m[2]), m[3].lower()) for m in numbered if m]
        numbers = [int(m[2]) for m in numbered if m]
        if len(set(parts)) == 1 and all(b > a for a, b in zip(numbers, numbers[1:], strict=False)):
            return [n - numbers[0] for n in numbers]
    return list(range(len(files)))


def read_image(path: Path) -> np.ndarray:
    """Decode one image: ``(h, w)`` uint8 when it is grey, else ``(h, w, 3)`` BGR (a 16-bit one
    scaled by the bits it uses, :func:`~vtrack.io.depth.used_bits`), turned upright by its
    orientation (a phone photo's EXIF tag, as FFmpeg reads it), as ``vtrack run`` turns an
    image given alone (the benchmarks read sequences through it). InputError as
    :func:`read_stored`."""
    stored, turn = read_stored(path)
    return turned(eight_bit(stored, used_bits(stored) if stored.dtype == np.uint16 else 8), turn)


def read_stored(path: Path) -> tuple[np.ndarray, int]:
    """Decode one image as stored (``(h, w)`` when it is grey, else ``(h, w, 3)`` BGR: uint16
    when its values have more than 8 bits (a 16-bit PNG or TIFF), else uint8;
    flipped top to bottom when its orientation mirrors it, :func:`photo_mirrored`) and the
    quarter turn its orientation asks for (0, 90, 180 or 270 degrees counter-clockwise).

    Raises InputError naming the file when it cannot be read (gone, or not readable), FFmpeg
    cannot decode it, or it is a JPEG cut short (which FFmpeg decodes with its missing part
    grey, without an error).
    """
    try:
        with av.open(ffmpeg_file(path)) as container:
            if not container.streams.video:
                raise StopIteration
            codec = container.streams.video[0].codec_context
            # Bounded before the decoder allocates the picture (the size is in the header).
            too_big = codec.width and codec.height and frame_size_problem(codec.width,
                                                                          codec.height)
            if too_big:
                raise InputError(f"{path}: {too_big}")
            picture = next(container.decode(video=0))
            if path.suffix.lower() in JPEG_SUFFIXES and jpeg_cut_short(path):
                raise InputError(f"{path}: a JPEG cut short (no end-of-image marker after its "
                                 "image data): part of the picture is missing")
            pixels = stored_pixels(picture)
            if codec.name in PHOTO_CODECS and photo_mirrored(path):  # FFmpeg: the turn alone
                pixels = cv2.flip(pixels, 0)
            return pixels, quarter_turns(picture.rotation)
    except (av.FFmpegError, OSError, StopIteration) as exc:
        if isinstance(exc, (FileNotFoundError, PermissionError)):  # gone, or not ours to read
            raise InputError(f"{path}: cannot be read ({os_reason(exc)})") from None
        # FFmpeg's message names no size, nor a float TIFF ("Invalid data found ...")
        problem = declared_size_problem(path) or float_tiff_problem(path)
        if problem:
            raise InputError(f"{path}: {problem}") from None
        reason = "no picture" if isinstance(exc, StopIteration) else os_reason(exc)
        raise InputError(f"{path}: not an image FFmpeg can decode ({reason})") from None


#: A MOTChallenge sequence's description, beside its img1/: ``[Sequence]`` ``frameRate=25`` ...
SEQUENCE_INFO = "seqinfo.ini"


def sequence_info(folder: Path) -> Path:
    """Where the :data:`SEQUENCE_INFO` of the sequence folder or its ``img1/`` (``folder``)
    lives (the file need not exist)."""
    return (sequence_of(folder) or folder) / SEQUENCE_INFO


def sequence_fps(folder: Path) -> float | None:
    """The frame rate a MOTChallenge sequence's :data:`SEQUENCE_INFO` gives (its
    ``frameRate``), for the sequence folder or its ``img1/`` (``folder``); None when there is no
    such file or it gives none. InputError naming the file when it cannot be read or its
    ``frameRate`` is not a frame rate ``--fps`` takes (:data:`~vtrack.io.raw.MIN_FPS` to
    :data:`~vtrack.io.raw.MAX_FPS`: past them the annotated video's time base overflows)."""
    path = sequence_info(folder)
    if not path.is_file():
        return None
    parser = configparser.ConfigParser(interpolation=None)
    try:
        parser.read_string(read_text_bounded(path, SIDECAR_BYTES, "sequence description"))
    except configparser.Error as exc:
        first = str(exc).splitlines()[0]
        raise InputError(f"{path}: not a MOTChallenge seqinfo.ini ({first})") from None
    text = parser.get("Sequence", "frameRate", fallback=None)
    if text is None:
        return None
    try:
        fps = float(text)
    except ValueError:
        fps = math.nan
    if not (math.isfinite(fps) and MIN_FPS <= fps <= MAX_FPS):
        raise InputError(f"{path}: frameRate must be a frame rate from {MIN_FPS:g} to "
                         f"{MAX_FPS:g} frames per second, got {quoted(text)} (--fps N gives the "
                         "sequence's frame rate instead)")
    return fps


class ImageFolderSource(Source):
    """The images of a folder as frames, in natural name order."""

    def __init__(self, folder: str, fps: float | None = None) -> None:
        root = Path(folder)
        self._files = images_of(folder)
        self._places = frame_places(self._files)
        self._begin = 0  # the file iteration begins at (start_near)
        #: The run's first place (:meth:`_run_begins`), once its first frame was reached, and
        #: the last frame handed on (or all handed on: ``_ended``): the places between them no
        #: image is numbered for are the run's missing frames (:attr:`frames_missing`), and
        #: the reader's notes of frames up to it the run's (:meth:`_reached`).
        self._run_first: int | None = None
        self._handed: int | None = None
        self._before: int | None = None  # the frame handed on before it (:meth:`not_taken`)
        self._ended = False
        self._notes: list[_Note] = []
        stored, self._turn = read_stored(self._files[0])
        #: How the images are read as 8-bit (the first image's depth and bits).
        self._scale = DepthScale(folder, stored)
        self._first = turned(self._scale.frame(stored, 0), self._turn)
        height, width = self._first.shape[:2]
        fps = fps or sequence_fps(root) or DEFAULT_FPS
        # given the img/ folder itself: named after the sequence
        resolved = root.resolve()
        name = (sequence_of(resolved) or resolved).name
        super().__init__(
            InputInfo(
                path=folder,
                kind="images",
                name=name,
                width=width,
                height=height,
                fps=fps,
                frame_count=self._places[-1] + 1,
                duration_s=(self._places[-1] + 1) / fps,
                codec=self._files[0].suffix.lower().lstrip("."),
                pix_fmt=layout(stored),
            )
        )
        self._note_depth()

    def image_identity(self) -> str | None:
        return images_identity(self._files)

    def _note_depth(self) -> None:
        """Keep the notes :attr:`_scale` added (the sequence's depth, an image of another)."""
        self._notes.extend(_Note(index, text) for index, text in self._scale.news())

    def ends_after(self, index: int) -> bool:
        """Whether ``index`` is the last image's place (its numbering's last)."""
        return index == self._places[-1]

    @property
    def warnings(self) -> list[str]:
        """The warnings of the frames handed on so far (not of those the reader has gone
        ahead to): one line counting the images missing from the numbering
        (:attr:`frames_missing`), if any, then the reader's, in its order (the first
        :data:`_NAMED_SKIPS` unreadable images named, then one line counting them all)."""
        lines = []
        missing = self.frames_missing
        if missing:
            place, at = self._first_gap()
            after = f", after {self._files[at - 1].name}" if at else ""
            lines.append(f"{self.info.path}: {plural(missing, 'image')} missing from the "
                         f"numbering (the first: frame {place}{after}); their frames are "
                         "skipped")
        notes = self._reached()
        unreadable = sum(note.unreadable for note in notes)
        named = [note for note in notes if note.unreadable][:_NAMED_SKIPS]
        lines += [note.line for note in notes if not note.unreadable or note in named]
        if unreadable > _NAMED_SKIPS:
            lines.append(f"{self.info.path}: {unreadable} unreadable images skipped in all "
                         f"(the first {_NAMED_SKIPS} are named above)")
        return lines

    def _reached(self) -> list[_Note]:
        """The reader's notes of the frames handed on so far (all once every frame was)."""
        last = self._handed
        return [note for note in list(self._notes)
                if self._ended or (last is not None and note.index <= last)]

    @property
    def frames_skipped(self) -> int:
        return sum(note.unreadable for note in self._reached()) + self.frames_missing

    @property
    def frames_missing(self) -> int:
        """The places from the run's first frame to the last frame handed on (a run that
        stopped early, ``--frames``, an interrupt: the frames it read) that no image is
        numbered for."""
        first, last = self._run_first, self._handed
        if first is None or last is None or last < first:
            return 0
        numbered = (bisect.bisect_right(self._places, last)
                    - bisect.bisect_left(self._places, first))
        return last + 1 - first - numbered

    def _first_gap(self) -> tuple[int, int]:
        """The run's first place no image is numbered for, and the index in ``self._files``
        of the first image after it (:attr:`frames_missing` is not 0)."""
        assert self._run_first is not None
        place, at = self._run_first, bisect.bisect_left(self._places, self._run_first)
        while at < len(self._places) and self._places[at] == place:
            place, at = place + 1, at + 1
        return place, at

    def __iter__(self) -> Iterator[Frame]:
        resuming = self._resumed is not None  # skip_to's pass: its frames are noted already
        frames = super().__iter__()
        return frames if resuming else self._handing(frames)

    def _handing(self, frames: Iterator[Frame]) -> Iterator[Frame]:
        """``frames``, each noted as handed on as it is (:attr:`frames_missing` counts the
        places up to the last, not those the reader has gone ahead to). An image of another
        size ends them (PartialInputError): the places before it were all read, the images
        missing or unreadable there counted as the run's."""
        try:
            for frame in frames:
                self._before, self._handed = self._handed, frame.index
                yield frame
        except PartialInputError as exc:
            self._handed = max(self._handed if self._handed is not None else -1,
                               exc.frames_done - 1)
            raise
        self._ended = True

    def not_taken(self, frame: Frame) -> None:
        """The last frame handed on was not taken (it ended a ``--frames`` duration): the
        counts and warnings stop at the one before it."""
        if frame.index == self._handed:
            self._handed = self._before

    def absent(self, index: int) -> str:
        """``is missing from the numbering (no image between 0003.jpg and 0007.jpg)`` for a
        place no image is numbered for, else an image that could not be decoded."""
        after = bisect.bisect_left(self._places, index)
        if 0 < after < len(self._places) and self._places[after] != index:
            return (f"is missing from the numbering (no image between "
                    f"{self._files[after - 1].name} and {self._files[after].name})")
        return super().absent(index)

    def start_near(self, index: int) -> int:
        """Begin at the image numbered ``index`` (or the last one numbered before it, when no
        image is): the images before it are not read, and neither they nor the gaps in the
        numbering before ``index`` count as skipped."""
        super().start_near(index)
        if index <= 0 or self._prefetch is not None:
            return 0
        self._begin = bisect.bisect_right(self._places, index) - 1
        return self._places[self._begin]

    def _frames(self) -> Iterator[Frame]:
        fps = self.info.fps or DEFAULT_FPS
        size = self._first.shape[:2]
        first, self._first = self._first, None
        turned_apart = False  # an image's own tag said another turn than the first's
        places, files = self._places[self._begin:], self._files[self._begin:]
        # Skips count from the run's first frame on: a start given as a frame number
        # (start_near) is that frame, decoded or not, as in a whole run; a start by time
        # (skip_to) the first image decoded at or after it. The gaps before it and the images
        # read or undecodable before it are not the run's.
        tracked = next((at for at, place in enumerate(places)
                        if self._tracked(place, place / fps)), len(places))
        by_number = self._from_s is None
        began = False  # the run's first frame was reached
        for at, (index, path) in enumerate(zip(places, files, strict=True)):
            if by_number and not began and at >= tracked:
                began = True
                self._run_first = self._run_begins(index)
            try:
                if index == 0:
                    pixels = first
                else:
                    stored, turn = read_stored(path)
                    stored = self._scale.frame(stored, index, path)
                    self._note_depth()
                    pixels = turned(stored, turn)
                    if pixels.shape[:2] != size and turn != self._turn:
                        pixels = turned(stored, self._turn)  # a tag lost or added in an edit
                        if not turned_apart:
                            turned_apart = True
                            self._notes.append(_Note(index, (
                                f"{path}: turned {turn} degrees as its orientation tag says, it "
                                "would not be the sequence's size: turned as the first image "
                                f"({self._turn} degrees)")))
            except InputError as exc:
                if not began:  # before the first image tracked: not the run's
                    continue
                self._notes.append(_Note(index, f"{exc}; frame {index} skipped", True))
                continue
            if pixels.shape[:2] != size:
                raise PartialInputError(
                    f"{path}: image is {pixels.shape[1]}x{pixels.shape[0]}, the sequence is "
                    f"{size[1]}x{size[0]} (stopped at frame {index})",
                    index,
                )
            if not began and at >= tracked:  # a start by time: its first image decoded
                began = True
                self._run_first = self._run_begins(index)
            time_s = index / fps
            # the first image decides: a sequence is grey or colour
            pixels = as_kind(pixels, self._scale.colour)
            yield (BgrFrame if self._scale.colour else GrayFrame)(index, time_s, pixels)

    def _release(self) -> None:
        """Nothing stays open: each image is opened and closed by :func:`read_stored`."""
