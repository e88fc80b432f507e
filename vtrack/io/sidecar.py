"""The initial-box sidecar file: where a user leaves the target's first box for an input.

``NAME.init.txt`` beside a video ``NAME.EXT``, ``init.txt`` inside an image-sequence folder
(``SEQ/init.txt`` for an OTB sequence given as ``SEQ/img`` as well as ``SEQ``); one
line ``x,y,w,h`` (top-left corner, width, height) in 0-based pixel coordinates of the first
frame, the same numbers ``--init`` takes. ``vtrack select`` writes it; ``vtrack run`` and
``vtrack batch`` read it when no ``--init`` (and no ground truth) is given.
"""

from __future__ import annotations

import os
from pathlib import Path

from vtrack.errors import InputError
from vtrack.geometry import BOX_FORMS, Box, parse_box_text
from vtrack.io.files import write_text_atomic
from vtrack.io.limits import SIDECAR_BYTES, read_text_bounded
from vtrack.io.specs import is_url

VIDEO_SIDECAR = "{}.init.txt"  # beside NAME.EXT
SEQUENCE_SIDECAR = "init.txt"  # inside the sequence folder
#: The folder of a sequence's images, the first that holds images wins
#: (:func:`~vtrack.io.images.sequence_images`): OTB's SEQ/img, MOTChallenge's SEQ/img1,
#: VOT2017+'s SEQ/color. SEQ/img (img1, color) and SEQ are one input: they share SEQ/init.txt
#: and SEQ's name.
SEQUENCE_IMAGES = ("img", "img1", "color")
#: ... of which these names only sequences use (``color/`` other folders have too).
SEQUENCE_ONLY_IMAGES = SEQUENCE_IMAGES[:2]


def sequence_of(folder: Path) -> Path | None:
    """The sequence folder ``SEQ`` when ``folder`` is its images' folder (``SEQ/img``,
    ``SEQ/img1``, ``SEQ/color``: :data:`SEQUENCE_IMAGES`; ``.`` and ``..`` are resolved
    first, other paths kept as given), else None."""
    named = folder if folder.name not in ("", "..") else folder.resolve()
    return named.parent if named.name in SEQUENCE_IMAGES else None


def sidecar_path(input_spec: str | os.PathLike[str]) -> Path:
    """Where the initial box of ``input_spec`` lives: ``FOLDER/init.txt`` for a folder (for an
    OTB sequence's ``SEQ/img`` too: one box for the sequence given either way, as ``vtrack
    batch`` finds it by ``SEQ``), ``DIR/NAME.init.txt`` for a file ``DIR/NAME.EXT``. The file
    need not exist."""
    path = Path(input_spec)
    if path.is_dir():  # SEQ/img: the sequence's box, which run SEQ reads
        return (sequence_of(path) or path) / SEQUENCE_SIDECAR
    return path.with_name(VIDEO_SIDECAR.format(path.stem))


def has_sidecar(input_spec: str | os.PathLike[str]) -> bool:
    """Whether ``input_spec`` can have a sidecar file: a file or folder, not stdin (``-``), a
    URL, a FIFO or a device (whose box is given with ``--init``)."""
    spec = os.fspath(input_spec)
    if spec == "-" or is_url(spec):
        return False
    return not os.path.exists(spec) or os.path.isfile(spec) or os.path.isdir(spec)


def format_box(box: Box) -> str:
    """``x,y,w,h`` as ``--init`` takes it; whole numbers without a decimal point."""
    return box.text()


def parse_sidecar(text: str, where: str) -> Box:
    """The box of a sidecar file's text: its one line that is not blank or a ``#`` comment,
    4 numbers separated by commas, spaces or tabs (:func:`~vtrack.geometry.parse_box_text`, as
    ``--init``), width and height > 0.

    Raises InputError naming ``where`` otherwise (a second box line too: which box is meant?).
    """
    lines = [x for x in (line.split("#", 1)[0].strip() for line in text.splitlines()) if x]
    if len(lines) > 1:
        raise InputError(f"{where}: holds {len(lines)} lines of values; expected one line "
                         "x,y,w,h (the first frame's box)")
    line = lines[0] if lines else ""
    return parse_box_text(line, where, InputError, f"one line {BOX_FORMS}")


def read_sidecar(input_spec: str | os.PathLike[str]) -> Box | None:
    """The initial box stored for ``input_spec``, or None when it has no sidecar file.

    Raises InputError (naming the sidecar file) when the file exists but is unreadable or
    malformed: a box the user left must not be silently ignored.
    """
    if not has_sidecar(input_spec):
        return None
    path = sidecar_path(input_spec)
    if not path.is_file():
        return None
    return parse_sidecar(read_text_bounded(path, SIDECAR_BYTES, "box file"), str(path))


def write_sidecar(input_spec: str | os.PathLike[str], box: Box) -> Path:
    """Write ``box`` as the initial box of ``input_spec`` (replacing an earlier one, atomically)
    and return the sidecar's path. Raises OutputError when it cannot be written."""
    return write_text_atomic(sidecar_path(input_spec), format_box(box) + "\n")
