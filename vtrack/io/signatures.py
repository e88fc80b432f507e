"""What a file's bytes say it is, where FFmpeg's own message says too little: a container or an
image given as raw frames (``--raw``), an MP4 cut off before its index was written or inside
its last fragment, a Matroska/WebM recording cut inside a block.

Only signatures of four bytes or more are taken, so raw pixels are not mistaken for one
(JPEG's three are not); MPEG-TS, whose signature is one sync byte, is known by three packets'
headers in a row whose continuity counters advance as a stream's do.
"""

from __future__ import annotations

import io
import os
from collections.abc import Iterator
from typing import BinaryIO

from vtrack.geometry import frame_size_problem

#: Top-level boxes an MP4/QuickTime file is read through, at most: a plain file holds a
#: handful, a fragmented recording two a fragment (a day at a fragment a second: 172,800).
_MAX_BOXES = 1_000_000

#: MPEG-TS packets as (offset of the first sync byte, packet size): plain 188-byte packets, and
#: M2TS's 192 (a 4-byte time stamp before each: AVCHD and Blu-ray .m2ts/.mts).
_TS_LAYOUTS = ((0, 188), (4, 192))
#: Packets in a row whose headers make an MPEG-TS stream.
_TS_PACKETS = 3
#: Bytes :func:`container_kind` looks at, at most: three M2TS packet headers.
SIGNATURE_BYTES = 4 + (_TS_PACKETS - 1) * 192 + 4


#: The PID of MPEG-TS null (stuffing) packets: their headers may repeat byte for byte.
_TS_NULL_PID = 0x1FFF


def _mpegts(head: bytes) -> bool:
    """Whether ``head`` begins :data:`_TS_PACKETS` MPEG-TS (or M2TS) packets: each a sync byte
    0x47, no transport error flag, and an adaptation field control that is not the reserved 0
    (so a flat run of 0x47 bytes, a grey raw frame, is none), in an order a stream has
    (:func:`_ts_sequence`: a raw frame whose rows repeat every packet is none)."""
    for first, size in _TS_LAYOUTS:
        starts = range(first, first + _TS_PACKETS * size, size)
        if len(head) >= starts[-1] + 4 and all(
                head[at] == 0x47 and not head[at + 1] & 0x80 and head[at + 3] & 0x30
                for at in starts) and _ts_sequence([head[at + 1:at + 4] for at in starts]):
            return True
    return False


def _ts_pid(header: bytes) -> int:
    """The PID of an MPEG-TS packet header (its three bytes after the sync byte)."""
    return (header[0] & 0x1F) << 8 | header[1]


def _ts_sequence(headers: list[bytes]) -> bool:
    """Whether packet headers (their three bytes after the sync byte) follow one another as in
    a stream: a packet of a PID that carries a payload advances that PID's continuity counter
    by one (mod 16) from its last packet's, one without a payload keeps it. Null packets
    (PID 0x1FFF) count no counter. Byte-identical headers of another PID are none: a raw
    frame's rows repeating every packet (those with a payload break the counter rule; those
    without, an "adaptation field only" 4th byte such as a falling ramp's 0x29, would keep
    it), where a stream starts with tables (PAT, PMT) that carry one."""
    if len(set(headers)) == 1:
        return _ts_pid(headers[0]) == _TS_NULL_PID
    last: dict[int, int] = {}
    for header in headers:
        pid = _ts_pid(header)
        counter = header[2] & 0x0F
        if pid == _TS_NULL_PID:
            continue
        if pid in last:
            step = 1 if header[2] & 0x10 else 0
            if counter != (last[pid] + step) % 16:
                return False
        last[pid] = counter
    return True


def container_kind(head: bytes) -> str | None:
    """What ``head`` (a file's or stream's first :data:`SIGNATURE_BYTES` bytes; an MPEG-TS
    stream is known only from that many, the others from 12) begins, ``"an MP4/QuickTime
    file"`` ... ``"a PNG image"``, when it is a container's or an image's signature; None
    otherwise (raw pixels)."""
    if _mpegts(head):
        return "an MPEG-TS stream"
    if head[4:8] == b"ftyp" and 8 <= int.from_bytes(head[:4], "big") <= 4096:
        return "an MP4/QuickTime file"
    if head[:4] == b"\x1a\x45\xdf\xa3":
        return "a Matroska/WebM file"
    if head[:4] == b"RIFF" and head[8:12] == b"AVI ":
        return "an AVI file"
    if head[:4] == b"FLV\x01":
        return "an FLV file"
    if head[:8] == b"\x89PNG\r\n\x1a\n":
        return "a PNG image"
    if head[:6] in (b"GIF87a", b"GIF89a"):
        return "a GIF image"
    return None


def _box_header(header: bytes, room: int) -> tuple[bytes, int, int] | None:
    """The type, header length and size of the MP4 box whose header (8 bytes or more, 16 for a
    64-bit size) ``header`` begins, ``room`` bytes before its file's end (a size of 0 runs to
    it); None when it is no box as MP4 lays them out (a size under its header's)."""
    size, kind, length = int.from_bytes(header[:4], "big"), header[4:8], 8
    if size == 1 and len(header) >= 16:  # a 64-bit size follows the type
        size, length = int.from_bytes(header[8:16], "big"), 16
    elif size == 0:  # the box runs to the end of the file
        size = room
    return (kind, length, size) if size >= length else None


def _boxes_in(head: bytes, start: int, stop: int) -> Iterator[tuple[bytes, int, int, int]]:
    """The boxes laid out from ``head[start:]`` to ``stop`` (an offset in ``head`` or past its
    end) as (type, offset, header length, size), as far as ``head`` holds their headers."""
    offset = start
    while offset + 8 <= min(stop, len(head)):
        box = _box_header(head[offset:offset + 16], stop - offset)
        if box is None:
            return
        yield box[0], offset, box[1], box[2]
        offset += box[2]


def mp4_head_fragmented(head: bytes) -> bool:
    """Whether ``head``, the first bytes of an MP4/QuickTime file or stream (one read without
    seeking: a pipe), shows it fragmented: a fragment (``moof``) among its top-level boxes, or
    in its index (``moov``) the movie-extends box (``mvex``) that announces fragments (the index
    then lists the first fragment's frames at most, ``-movflags frag_keyframe``). False when it
    shows neither: a plain MP4, or one whose index goes on past ``head``."""
    for kind, offset, header, size in _boxes_in(head, 0, len(head)):
        if kind == b"moof":
            return True
        if kind == b"moov":
            return any(child == b"mvex" for child, *_ in
                       _boxes_in(head, offset + header, offset + size))
    return False


def _top_boxes(path: str | os.PathLike[str]) -> tuple[int, list[tuple[bytes, int, int]]] | None:
    """The size of ``path``, an MP4/QuickTime file (its first box ``ftyp``), and its top-level
    boxes in file order as (type, offset, size), the last one's size as its header says (past
    the file's end when the file was cut inside it; a header cut short after the first box is
    type ``b""``). None when it is no such file, cannot be read, is shorter than a box header
    (8 bytes), is not laid out in boxes, or holds more than
    :data:`_MAX_BOXES`."""
    boxes: list[tuple[bytes, int, int]] = []
    try:
        with open(path, "rb") as handle:
            end = os.fstat(handle.fileno()).st_size
            offset = 0
            while offset < end:
                if len(boxes) == _MAX_BOXES:
                    return None
                handle.seek(offset)
                header = handle.read(16)
                if len(header) < 8:
                    if not boxes:  # too short to say it is an MP4 (3 bytes of text)
                        return None
                    boxes.append((b"", offset, 8))
                    break
                box = _box_header(header, end - offset)
                if box is None or (not boxes and box[0] != b"ftyp"):
                    return None  # not boxes as MP4 lays them out, or no MP4
                kind, _, size = box
                boxes.append((kind, offset, size))
                offset += size
    except OSError:
        return None
    return (end, boxes) if boxes else None


def mp4_index_problem(path: str | os.PathLike[str]) -> str | None:
    """What is wrong with the index (``moov`` box) of ``path``, an MP4/QuickTime file (its
    first box ``ftyp``): ``"no index (moov box)"`` when none of its top-level boxes is one,
    ``"its index (moov box) cut short"`` when the file ends inside it: a recording cut off
    before it was finished (a plain MP4 writes its index last). None when its index is whole,
    when it is no such file or cannot be read."""
    found = _top_boxes(path)
    if found is None:
        return None
    end, boxes = found
    index = next(((offset, size) for kind, offset, size in boxes if kind == b"moov"), None)
    if index is None:
        return "no index (moov box)"
    return "its index (moov box) cut short" if sum(index) > end else None


def _fragmented(boxes: list[tuple[bytes, int, int]]) -> bool:
    """Whether an MP4's top-level ``boxes`` hold a fragment (``moof``)."""
    return any(kind == b"moof" for kind, _, _ in boxes)


def mp4_fragmented(path: str | os.PathLike[str]) -> bool:
    """Whether ``path``, an MP4/QuickTime file, holds fragments (``moof`` boxes): its index
    (``moov``) then lists the frames of its first fragment at most. False when it holds none,
    is no such file or cannot be read."""
    found = _top_boxes(path)
    return found is not None and _fragmented(found[1])


def mp4_torn_box(path: str | os.PathLike[str]) -> str | None:
    """``"the file ends inside its last mdat box"`` (or ``moof`` ...) when ``path``, an
    MP4/QuickTime file, was cut inside its last top-level box: a fragmented recording (a
    phone's, OBS's) stopped part way, whose whole fragments FFmpeg reads without a word. None
    when its last box is whole, when what follows its boxes is no box (bytes appended), when
    it holds no fragment (``moof``: its index lists every frame), or it is no such file."""
    found = _top_boxes(path)
    if found is None or not _fragmented(found[1]):  # not fragmented: its index counts
        return None
    end, boxes = found
    kind, offset, size = boxes[-1]
    if offset + size <= end or not kind.isalnum():  # whole, or bytes after the boxes
        return None
    return f"the file ends inside its last {kind.decode('latin-1')} box"


#: Matroska elements whose children are read one by one when their size is unknown (the Segment
#: and its Clusters, as a live recording leaves them); every other element is passed over by its
#: size.
_MATROSKA_CONTAINERS = frozenset({0x18538067, 0x1F43B675})


def _vint(data: bytes, at: int, keep_marker: bool) -> tuple[int, int] | None:
    """The EBML variable-length integer at ``data[at:]`` and its length (an element ID keeps
    its length marker, a size does not; an all-ones size, unknown, is -1); None when ``data``
    ends inside it or it is not one."""
    if at >= len(data) or data[at] == 0:
        return None
    length = 9 - data[at].bit_length()
    if at + length > len(data):
        return None
    value = int.from_bytes(data[at:at + length], "big")
    if keep_marker:
        return value, length
    value &= (1 << (7 * length)) - 1
    return (-1 if value == (1 << (7 * length)) - 1 else value), length


def matroska_torn_element(path: str | os.PathLike[str]) -> str | None:
    """``"the file ends inside its last cluster"`` (or a block of it) when ``path``, a Matroska/WebM
    file, was cut inside an element (a recording written live, as OBS does, stopped by a crash
    has no duration to fall short of, and FFmpeg reads the whole blocks before the cut without
    a word). None when its last element is whole, it is not such a file or cannot be read."""
    try:
        with open(path, "rb") as handle:
            end = os.fstat(handle.fileno()).st_size
            offset, elements = 0, 0
            while offset < end and elements < _MAX_BOXES:
                handle.seek(offset)
                head = handle.read(12)
                element = _vint(head, 0, keep_marker=True)
                size = element and _vint(head, element[1], keep_marker=False)
                if element is None or size is None:
                    return "the file ends inside an element's header" if elements else None
                if elements == 0 and element[0] != 0x1A45DFA3:  # the EBML header
                    return None
                elements += 1
                offset += element[1] + size[1]
                if element[0] in _MATROSKA_CONTAINERS and size[0] < 0:
                    continue  # of unknown size (written live): read its children
                if size[0] < 0:
                    return None  # an element of unknown size that is no container: give up
                offset += size[0]
                if offset > end:
                    where = ("a block of its last cluster" if element[0] in (0xA3, 0xA0) else
                             "its last cluster" if element[0] == 0x1F43B675 else
                             "its last element")
                    return f"the file ends inside {where}"
    except OSError:
        return None
    return None


#: Bytes at a JPEG's end looked at first for its end-of-image marker (after any padding).
_JPEG_TAIL = 1024


def jpeg_cut_short(path: str | os.PathLike[str]) -> bool:
    """Whether ``path``, a JPEG, ends before its end-of-image marker (FF D9) after its image
    data: a copy or a camera's write cut short, which FFmpeg decodes without an error (the
    missing part grey). Data appended after the marker (a phone's motion photo) is no cut.
    False when it is no JPEG or cannot be read."""
    try:
        with open(path, "rb") as handle:
            end = os.fstat(handle.fileno()).st_size
            handle.seek(max(0, end - _JPEG_TAIL))
            if handle.read().rstrip(b"\x00").endswith(b"\xff\xd9"):
                return False  # the usual end: no need to read the file
            handle.seek(0)
            data = handle.read()
    except OSError:
        return False
    if not data.startswith(b"\xff\xd8"):
        return False
    for at, marker, length in _jpeg_segments(data):  # (EXIF's thumbnail inside one)
        if marker is None:
            return False
        if marker == 0xDA:  # start of scan: entropy-coded data, where FF D9 cannot occur
            return data.find(b"\xff\xd9", at + 2 + length) < 0
    return True  # ends before its first scan


def _jpeg_segments(data: bytes) -> Iterator[tuple[int, int | None, int]]:
    """The marker segments of the JPEG ``data`` (its bytes from its start-of-image marker on,
    as far as they go), each as (its offset, its marker, its length: the bytes after the
    marker), up to its first start of scan (marker 0xDA, the last one given) and fill bytes
    skipped; where a marker should be and none is (no JPEG as written), (its offset, None, 0)
    is the last one. The walk ends where ``data`` does (a segment's length may reach past it)."""
    at = 2
    while at + 4 <= len(data):
        if data[at] != 0xFF:
            yield at, None, 0
            return
        marker = data[at + 1]
        if marker == 0xFF:  # fill byte
            at += 1
            continue
        length = int.from_bytes(data[at + 2:at + 4], "big")
        yield at, marker, length
        if marker == 0xDA:
            return
        at += 2 + length


#: Bytes at a photo's start looked at for its EXIF orientation (JPEG's APP1 segment holding it
#: is at most 64 KiB); a PNG's chunks are walked instead, up to :data:`_PNG_CHUNKS` of them.
_PHOTO_HEAD = 1 << 17
#: Chunks of a PNG looked at for its eXIf chunk, which may come after its image data (IDAT,
#: often in chunks of 4 or 8 KiB): those of a picture of FFmpeg's largest size and more.
_PNG_CHUNKS = 1 << 17
#: EXIF orientations that mirror the picture (2, 4, 5, 7); FFmpeg reads them as the turn alone.
_MIRRORED = frozenset({2, 4, 5, 7})
#: FFmpeg's decoders of the photos :func:`photo_mirrored` reads the orientation of.
PHOTO_CODECS = frozenset({"mjpeg", "png", "tiff", "webp"})


def photo_mirrored(path: str | os.PathLike[str]) -> bool:
    """Whether ``path``, a JPEG, PNG, TIFF or WebP photo, has an EXIF orientation that mirrors
    its picture (2, 4, 5 or 7: a front camera's selfie). FFmpeg reads such a tag as its
    quarter turn alone: 2 as 180 degrees, 4 as none; the picture is upright once flipped top
    to bottom, then turned as FFmpeg says. False when it is none of them, has no such tag or
    cannot be read."""
    try:
        with open(path, "rb") as handle:  # buffered: a PNG's chunk headers, 8 bytes each,
            # come from its buffer, and a seek over a small chunk's data stays within it
            return _exif_orientation(_exif_of(handle)) in _MIRRORED
    except OSError:
        return False


def photo_bytes_mirrored(photo: bytes) -> bool:
    """:func:`photo_mirrored` for a photo given as its bytes (read from what cannot be read
    again: a pipe, a FIFO, a URL)."""
    return _exif_orientation(_exif_of(io.BytesIO(photo))) in _MIRRORED


def _exif_of(photo: BinaryIO) -> bytes:
    """The EXIF data (from its TIFF header on) of the photo ``photo`` reads, from its start: a
    JPEG's APP1 segment, a PNG's eXIf chunk (before or after its image data), a WebP's EXIF
    chunk or a TIFF file itself; b"" when there is none among them."""
    data = photo.read(_PHOTO_HEAD)
    if data[:4] in (b"II*\x00", b"MM\x00*"):
        return data
    if data.startswith(b"\xff\xd8"):
        for at, marker, length in _jpeg_segments(data):  # (none after the start of scan)
            if marker == 0xE1 and data[at + 4:at + 10] == b"Exif\x00\x00":
                return data[at + 10:at + 2 + length]
    elif data.startswith(b"\x89PNG\r\n\x1a\n"):
        return _png_exif(photo)
    elif data[:4] == b"RIFF" and data[8:12] == b"WEBP":
        at = 12
        while at + 8 <= len(data):
            length = int.from_bytes(data[at + 4:at + 8], "little")
            if data[at:at + 4] == b"EXIF":
                exif = data[at + 8:at + 8 + length]
                return exif[6:] if exif.startswith(b"Exif\x00\x00") else exif
            at += 8 + length + length % 2
    return b""


def _png_exif(photo: BinaryIO) -> bytes:
    """The data of the eXIf chunk of the PNG ``photo`` reads (b"" when it has none before
    IEND, or among its first :data:`_PNG_CHUNKS` chunks), its chunks walked by their 8-byte
    headers, each one's data skipped by seeking (``photo`` buffered: a PNG of many small
    chunks costs a read of the file, not two system calls a chunk)."""
    photo.seek(8)
    for _ in range(_PNG_CHUNKS):
        header = photo.read(8)
        if len(header) < 8 or header[4:] == b"IEND":
            break
        length = int.from_bytes(header[:4], "big")
        if header[4:] == b"eXIf":
            return photo.read(min(length, _PHOTO_HEAD))
        photo.seek(length + 4, os.SEEK_CUR)  # its data and CRC
    return b""


def _exif_orientation(tiff: bytes) -> int | None:
    """The Orientation (tag 0x0112) of the first image directory of EXIF data ``tiff`` (its
    TIFF header on); None when it has none or the data is cut short."""
    order = {b"II": "little", b"MM": "big"}.get(tiff[:2])
    if order is None:
        return None

    def number(at: int, size: int) -> int:
        return int.from_bytes(tiff[at:at + size], order)  # type: ignore[arg-type]

    directory = number(4, 4)
    for entry in range(number(directory, 2) if directory + 2 <= len(tiff) else 0):
        at = directory + 2 + 12 * entry
        if at + 12 > len(tiff):
            break
        if number(at, 2) == 0x0112:
            return number(at + 8, 2)
    return None


def declared_size(head: bytes) -> tuple[int, int] | None:
    """The picture size a PNG's header (IHDR) or a YUV4MPEG2 stream's header line declares
    at the start of ``head`` (a file's first 64 bytes or more), as (width, height); None for
    other files. Read before FFmpeg, which refuses a picture over 2^28 pixels with a message
    naming no size ('Device or resource busy', or no frame at all)."""
    if head[:8] == b"\x89PNG\r\n\x1a\n" and head[12:16] == b"IHDR":
        return int.from_bytes(head[16:20], "big"), int.from_bytes(head[20:24], "big")
    if head.startswith(b"YUV4MPEG2 "):
        fields = head.split(b"\n", 1)[0].split()
        sizes = {field[:1]: field[1:] for field in fields[1:] if field[:1] in (b"W", b"H")}
        if sizes.get(b"W", b"").isdigit() and sizes.get(b"H", b"").isdigit():
            return int(sizes[b"W"]), int(sizes[b"H"])
    return None


def _head(path: str | os.PathLike[str]) -> tuple[bytes, int] | None:
    """The first 64 bytes of ``path`` and its size; None when it cannot be read."""
    try:
        with open(path, "rb") as handle:
            return handle.read(64), os.fstat(handle.fileno()).st_size
    except OSError:
        return None


#: TIFF tags of the first image directory: BitsPerSample, SampleFormat (3: floating point).
_TIFF_BITS, _TIFF_SAMPLE_FORMAT, _TIFF_FLOAT = 258, 339, 3
#: The TIFF field type of 4-byte values (LONG); the others these tags take are 2-byte SHORTs.
_TIFF_LONG = 4


def float_tiff_problem(path: str | os.PathLike[str]) -> str | None:
    """``32-bit float TIFF is not supported; ...`` when ``path`` is a TIFF whose first image
    holds floating-point samples (SampleFormat 3: a thermal camera's or a scientific tool's
    export), which the FFmpeg vtrack reads with cannot decode ("Invalid data found"); None
    otherwise, or when it cannot be read."""
    values: dict[int, int] = {}
    try:
        with open(path, "rb") as handle:
            head = handle.read(8)
            order = {b"II*\x00": "little", b"MM\x00*": "big"}.get(head[:4])
            if order is None:
                return None

            def number(data: bytes) -> int:
                return int.from_bytes(data, order)  # type: ignore[arg-type]

            handle.seek(number(head[4:8]))
            entries = handle.read(12 * min(number(handle.read(2)), 4096))
            for at in range(0, len(entries) - 11, 12):
                tag = number(entries[at:at + 2])
                if tag not in (_TIFF_BITS, _TIFF_SAMPLE_FORMAT):
                    continue
                # SHORT (type 3) or LONG (type 4) values, in the entry itself when they fit
                size = 4 if number(entries[at + 2:at + 4]) == _TIFF_LONG else 2
                if number(entries[at + 4:at + 8]) * size <= 4:
                    values[tag] = number(entries[at + 8:at + 8 + size])
                else:  # one per channel, elsewhere: the first
                    handle.seek(number(entries[at + 8:at + 12]))
                    values[tag] = number(handle.read(size))
    except (OSError, ValueError):
        return None
    if values.get(_TIFF_SAMPLE_FORMAT) != _TIFF_FLOAT:
        return None
    return (f"{values.get(_TIFF_BITS, 32)}-bit float TIFF is not supported; save it as 8- or "
            "16-bit")


def declared_size_problem(path: str | os.PathLike[str]) -> str | None:
    """Why the pictures the header of ``path`` declares (:func:`declared_size`) cannot be
    tracked, ``the frames are 50000x50000; vtrack accepts at most ...``; None when they can,
    it declares none, or it cannot be read."""
    read = _head(path)
    size = read and declared_size(read[0])
    return frame_size_problem(*size) if size else None


def header_problem(path: str | os.PathLike[str]) -> str | None:
    """Why FFmpeg cannot track ``path`` that its first bytes tell: frames larger than vtrack
    takes (:func:`declared_size_problem`), an animated WebP (the FFmpeg PyAV bundles decodes
    still WebP only), or a YUV4MPEG2 header declaring frames whose luma alone is more than the
    whole file holds; None otherwise, or when it cannot be read."""
    read = _head(path)
    if read is None:
        return None
    head, size = read
    declared = declared_size(head)
    too_big = declared and frame_size_problem(*declared)
    if too_big:
        return too_big
    if head[:4] in (b"II*\x00", b"MM\x00*"):
        return float_tiff_problem(path)
    if head[:4] == b"RIFF" and head[8:16] == b"WEBPVP8X" and len(head) > 20 and head[20] & 2:
        return ("an animated WebP, which the FFmpeg vtrack reads with cannot decode (it decodes "
                "still WebP only): write its frames as images (an img/ folder) or a video "
                "with another tool first")
    if declared and head.startswith(b"YUV4MPEG2 ") and declared[0] * declared[1] > size:
        width, height = declared
        return (f"its YUV4MPEG2 header declares {width}x{height} frames, whose luma alone "
                f"({width * height} bytes) is more than the whole file holds ({size} bytes): "
                "the header's frame size does not fit the data")
    return None
