"""Media as cameras, phones and tools write them: photos with an orientation tag, audio files
with cover art, recordings cut before they were finished, containers given as raw frames."""

from __future__ import annotations

import csv
import json
import os
import re
import struct
import subprocess
import sys
import threading
import zlib
from fractions import Fraction
from pathlib import Path

import av
import cv2
import numpy as np
import pytest
from click.testing import CliRunner
from conftest import one_error_line
from PIL import Image, ImageOps

from vtrack.batch import BATCH_SUFFIXES, find_inputs, nested_inputs
from vtrack.cli import main
from vtrack.io import open_source
from vtrack.io.signatures import photo_mirrored

#: EXIF Orientation 6: the stored picture is shown turned 90 degrees clockwise (a phone held
#: upright).
EXIF_ORIENTATION, UPRIGHT_FROM_LANDSCAPE = 0x0112, 6


def _phone_photo(path: Path, marker_x: int, orientation: int = UPRIGHT_FROM_LANDSCAPE) -> Path:
    """A 64x48 stored picture tagged to be shown upright (48x64; or with another EXIF
    ``orientation``, 1: as stored), a bright marker at its top-left corner shifted right by
    ``marker_x``."""
    pixels = np.full((48, 64, 3), 60, np.uint8)
    pixels[:12, marker_x:marker_x + 12] = 250
    exif = Image.Exif()
    exif[EXIF_ORIENTATION] = orientation
    Image.fromarray(pixels).save(path, exif=exif.tobytes(), quality=95)
    return path


def test_an_image_folder_is_turned_by_each_photos_orientation_as_one_image_is(tmp_path):
    """A folder of phone photos was tracked as stored (64x48, on its side) while vtrack run
    of one of them alone (and any phone video) turned it upright: the folder's frames are now
    those of its images read alone."""
    folder = tmp_path / "walk" / "img"
    folder.mkdir(parents=True)
    photos = [_phone_photo(folder / f"{i + 1:04d}.jpg", 4 * i) for i in range(3)]
    with open_source(str(folder.parent)) as source:
        assert (source.info.width, source.info.height) == (48, 64)
        frames = [frame.bgr() for frame in source]
    for frame, photo in zip(frames, photos, strict=True):
        with open_source(str(photo)) as alone:
            expected = next(iter(alone)).bgr()
        assert frame.shape == expected.shape == (64, 48, 3)
        assert np.abs(frame.astype(int) - expected).mean() < 2
    # Turned clockwise: the stored top-left marker is at the top-right of the upright frame.
    assert frames[0][:10, -10:].mean() > 200 and frames[0][:10, :10].mean() < 100


def test_a_folder_whose_photos_are_tagged_apart_is_turned_as_its_first(tmp_path):
    """Photos of one stored size whose orientation tags differ (a tag lost in an edit) stopped
    the run at the first one turned otherwise ('image is 48x64, the sequence is 64x48'), where
    they were tracked whole, as stored, before photos were turned: a sequence has one
    orientation, the first image's, and a warning names the first image tagged otherwise."""
    folder = tmp_path / "mixed"
    folder.mkdir()
    for i in range(6):
        _phone_photo(folder / f"{i + 1:04d}.jpg", 4 * i, UPRIGHT_FROM_LANDSCAPE if i < 3 else 1)
    with open_source(str(folder)) as source:
        frames = [frame.bgr() for frame in source]
        warnings = list(source.warnings)
    assert [frame.shape for frame in frames] == [(64, 48, 3)] * 6
    # each turned as the first: the stored top rows (the marker's) are the upright right side
    assert all(frame[:, -10:].max() > 200 and frame[:, :10].max() < 100 for frame in frames)
    assert warnings == [f"{folder / '0004.jpg'}: turned 0 degrees as its orientation tag says, "
                        "it would not be the sequence's size: turned as the first image (270 "
                        "degrees)"], warnings


def test_a_folder_of_photos_turned_by_an_editor_and_tagged_photos_is_read_whole(tmp_path):
    """Photos an editor turned upright (pixels turned, tag 1) among a phone's tagged photos
    (stored on their side, tag 6) are each upright by their own tag: all are tracked, without
    a warning (turning every image as the first stopped at the first edited one)."""
    folder = tmp_path / "mixed"
    folder.mkdir()
    for i in range(6):
        photo = _phone_photo(folder / f"{i + 1:04d}.jpg", 4 * i)
        if i >= 3:  # edited: the pixels turned upright, the tag saying so
            upright = np.rot90(np.asarray(Image.open(photo)), -1)
            exif = Image.Exif()
            exif[EXIF_ORIENTATION] = 1
            Image.fromarray(np.ascontiguousarray(upright)).save(photo, exif=exif.tobytes(),
                                                                quality=95)
    with open_source(str(folder)) as source:
        frames = [frame.bgr() for frame in source]
        assert source.warnings == []
    assert [frame.shape for frame in frames] == [(64, 48, 3)] * 6
    assert all(frame[:, -10:].max() > 200 and frame[:, :10].max() < 100 for frame in frames)


def _tagged_photos(folder: Path, suffix: str, orientation: int) -> tuple[list[Path], np.ndarray]:
    """Two photos ``FOLDER/0001SUFFIX`` and ``0002SUFFIX`` (made) of a picture marked in its
    top left corner, saved by Pillow with the EXIF ``orientation``, and the picture upright
    as Pillow's exif_transpose (and any viewer) shows it, RGB."""
    folder.mkdir()
    pixels = np.full((48, 64, 3), 60, np.uint8)
    pixels[:12, :12] = 250
    pixels[:12, 20:30] = (250, 0, 0)
    exif = Image.Exif()
    exif[EXIF_ORIENTATION] = orientation
    photos = [folder / f"{i + 1:04d}{suffix}" for i in range(2)]
    for photo in photos:
        Image.fromarray(pixels).save(photo, exif=exif.tobytes(), quality=95, lossless=True)
    return photos, np.asarray(ImageOps.exif_transpose(Image.open(photos[0])).convert("RGB"))


def _assert_upright(frames: list[np.ndarray], upright: np.ndarray) -> None:
    """Each of ``frames`` (BGR) is the picture ``upright`` (RGB)."""
    for frame in frames:
        assert frame.shape == upright.shape
        assert np.abs(frame[..., ::-1].astype(int) - upright).mean() < 3


@pytest.mark.parametrize("suffix", [".jpg", ".png", ".tiff", ".webp"])
@pytest.mark.parametrize("orientation", range(1, 9))
def test_a_photo_is_upright_by_each_orientation_mirrored_ones_too(tmp_path, orientation, suffix):
    """The orientations that mirror a photo (2, 4, 5, 7: a front camera's) were read as
    FFmpeg's quarter turn alone: 2 turned 180 degrees (upside down), 4 not at all, 5 and 7
    turned but mirrored. A photo alone and in a folder are now upright as EXIF says (as
    Pillow's exif_transpose turns it); the others as before."""
    photos, upright = _tagged_photos(tmp_path / "seq", suffix, orientation)
    with open_source(str(photos[0])) as source:
        frames = [next(iter(source)).bgr()]
    if suffix != ".webp":  # no image of a sequence, read alone only
        with open_source(str(photos[0].parent)) as source:
            frames.append(next(iter(source)).bgr())
    _assert_upright(frames, upright)


def _exif_after_image_data(png: Path) -> None:
    """Move the eXIf chunk of ``png`` after its image data (IDAT), just before IEND: where
    the PNG specification allows it, and FFmpeg and Pillow read it."""
    data = png.read_bytes()
    chunks, at = [], 8
    while at < len(data):
        length = int.from_bytes(data[at:at + 4], "big")
        chunks.append(data[at:at + 12 + length])
        at += 12 + length
    exif = next(chunk for chunk in chunks if chunk[4:8] == b"eXIf")
    chunks.remove(exif)
    chunks.insert(len(chunks) - 1, exif)
    png.write_bytes(data[:8] + b"".join(chunks))


@pytest.mark.parametrize("orientation", [2, 5])
def test_a_png_whose_exif_follows_its_image_data_is_upright(tmp_path, orientation):
    """A PNG's eXIf chunk after its image data (IDAT) was not looked for (the chunks were read
    up to IDAT, in the first 128 KiB): FFmpeg turned it as the tag's quarter turn, and the
    picture was left mirrored (2: upside down). Now upright, alone and in a folder."""
    photos, upright = _tagged_photos(tmp_path / "seq", ".png", orientation)
    for photo in photos:
        _exif_after_image_data(photo)
    moved = ImageOps.exif_transpose(Image.open(photos[0])).convert("RGB")  # Pillow reads it
    assert np.array_equal(np.asarray(moved), upright)
    frames = []
    for given in (photos[0], photos[0].parent):
        with open_source(str(given)) as source:
            frames.append(next(iter(source)).bgr())
    _assert_upright(frames, upright)


def _read_calls() -> int:
    """How many read system calls this process has made (Linux: /proc/self/io's syscr)."""
    for line in Path("/proc/self/io").read_text().splitlines():
        if line.startswith("syscr:"):
            return int(line.split()[1])
    raise AssertionError("no syscr in /proc/self/io")


@pytest.mark.skipif(not Path("/proc/self/io").exists(), reason="counts reads by /proc/self/io")
def test_a_png_of_many_small_chunks_is_read_in_few_calls(tmp_path):
    """A PNG's chunks were walked unbuffered, two system calls a chunk (a read of its 8-byte
    header, a seek over its data): a valid PNG of ~200,000 one-byte IDAT chunks took over
    100,000 reads to check for its orientation (173 ms where decoding it took 70). Its chunk
    headers now come from a buffer: a few hundred reads, and an eXIf after them still found."""
    photos, upright = _tagged_photos(tmp_path / "seq", ".png", 2)
    _exif_after_image_data(photos[0])
    data = photos[0].read_bytes()
    chunks, at, image = [], 8, b""
    while at < len(data):  # its image data stored uncompressed, in one-byte IDAT chunks
        length = int.from_bytes(data[at:at + 4], "big")
        kind, body = data[at + 4:at + 8], data[at + 8:at + 8 + length]
        at += 12 + length
        if kind == b"IDAT":
            image += body
            if data[at + 4:at + 8] == b"IDAT":
                continue
            stored = zlib.compress(zlib.decompress(image), 0)
        parts = [stored[i:i + 1] for i in range(len(stored))] if kind == b"IDAT" else [body]
        chunks += [struct.pack(">I", len(part)) + kind + part
                   + struct.pack(">I", zlib.crc32(kind + part)) for part in parts]
    png = tmp_path / "small_chunks.png"
    png.write_bytes(data[:8] + b"".join(chunks))
    assert len(chunks) > 1000
    before = _read_calls()
    assert photo_mirrored(png)
    assert _read_calls() - before < len(chunks) // 10
    with open_source(str(png)) as source:
        _assert_upright([next(iter(source)).bgr()], upright)


@pytest.mark.parametrize(("suffix", "orientation"), [(".jpg", 5), (".png", 2)])
def test_a_mirrored_photo_on_a_pipe_or_a_fifo_is_upright(tmp_path, monkeypatch, suffix,
                                                          orientation):
    """A photo whose orientation mirrors it, read from a pipe on stdin or from a FIFO, was left
    as FFmpeg's quarter turn alone (2 upside down, 5 turned but mirrored): its orientation
    was read only from a regular file. Now from the photo's bytes as they came."""
    photos, upright = _tagged_photos(tmp_path / "seq", suffix, orientation)
    data = photos[0].read_bytes()
    read_fd, write_fd = os.pipe()
    fifo = tmp_path / "feed"
    os.mkfifo(fifo)

    def feed(into: int | Path) -> None:
        with open(into, "wb") as pipe:
            pipe.write(data)

    frames = []
    with open(read_fd, "rb") as stdin:
        monkeypatch.setattr(sys, "stdin", stdin)
        for given, into in (("-", write_fd), (str(fifo), fifo)):
            feeder = threading.Thread(target=feed, args=(into,), daemon=True)
            feeder.start()
            with open_source(given) as source:
                frames.append(next(iter(source)).bgr())
            feeder.join()
    _assert_upright(frames, upright)


def _song_with_cover(path: Path) -> Path:
    """An MP3 of silence whose only picture is its album art (a 32x32 attached picture)."""
    with av.open(str(path), "w") as out:
        audio = out.add_stream("libmp3lame", rate=8000)
        audio.layout = "mono"
        cover = out.add_stream("png")
        cover.width = cover.height = 32
        cover.pix_fmt, cover.disposition = "rgb24", av.stream.Disposition.attached_pic
        picture = av.VideoFrame.from_ndarray(np.zeros((32, 32, 3), np.uint8), format="rgb24")
        for packet in [*cover.encode(picture), *cover.encode()]:
            out.mux(packet)
        for i in range(4):
            sound = av.AudioFrame.from_ndarray(np.zeros((1, 1152), np.int16), format="s16",
                                               layout="mono")
            sound.sample_rate, sound.pts = 8000, i * 1152
            for packet in audio.encode(sound):
                out.mux(packet)
        for packet in audio.encode():
            out.mux(packet)
    return path


def test_an_audio_file_with_cover_art_is_no_video(tmp_path):
    """vtrack run song.mp3 tracked its album art as a one-frame video at 90000 fps and ended
    complete, exit 0; now it is refused as an audio file is, naming the cover picture."""
    song = _song_with_cover(tmp_path / "song.mp3")
    result = CliRunner().invoke(main, ["run", str(song), "--init", "1,1,8,8",
                                       "-o", str(tmp_path / "out")])
    assert one_error_line(result) == (f"vtrack: error: {song}: no video stream "
                                      "(streams: audio, cover picture)")
    assert not (tmp_path / "out").exists()


@pytest.mark.parametrize(("keep", "problem"), [
    (lambda data: data[: len(data) // 2], "no index (moov box)"),
    (lambda data: data[: data.rfind(b"moov") + 60], "its index (moov box) cut short"),
])
def test_an_mp4_cut_before_its_index_was_written_says_so(clip_factory, tmp_path, keep,
                                                         problem):
    """A phone's or camera's MP4 cut off before it was finished (a plain MP4 writes its index
    last; here cut in the middle, or inside the index) was 'not a video FFmpeg can decode
    (Invalid data found ...)' or 'no video stream (streams: none)', as if it were no video at
    all; now the line says what is missing and why."""
    whole = clip_factory("smooth", width=160, height=120, frames=10).path.read_bytes()
    assert whole.rfind(b"moov") > len(whole) // 2  # a plain MP4: its index written last
    cut = tmp_path / "rec.mp4"
    cut.write_bytes(keep(whole))
    result = CliRunner().invoke(main, ["run", str(cut), "--init", "10,10,20,20",
                                       "-o", str(tmp_path / "out")])
    assert one_error_line(result) == (
        f"vtrack: error: {cut}: an MP4 with {problem}: the recording was cut off before it "
        "was finished (a camera or phone stopped, a copy not complete), and its frames cannot "
        "be found without it")


@pytest.mark.parametrize("data", [b"hi\n", b"\x00\x00", b"\x00\x00\x00\x20fty"])
def test_a_file_shorter_than_a_box_header_is_no_cut_mp4(tmp_path, data):
    """A file of 1 to 7 bytes (a text file named clip.avi, a copy that stopped at once) was
    'an MP4 with no index (moov box): the recording was cut off ...', whatever it held; too
    short to be known as an MP4, it is now what FFmpeg says of it."""
    short = tmp_path / "clip.avi"
    short.write_bytes(data)
    result = CliRunner().invoke(main, ["run", str(short), "--init", "10,10,20,20",
                                       "-o", str(tmp_path / "out")])
    assert one_error_line(result) == (f"vtrack: error: {short}: not a video FFmpeg can decode "
                                      "(Invalid data found when processing input)")
    assert not (tmp_path / "out").exists()


def test_an_empty_file_is_called_empty(tmp_path):
    """A 0-byte clip.mp4 (a copy that failed, a recording never begun) was 'not a video FFmpeg
    can decode (Invalid data found when processing input)'."""
    empty = tmp_path / "clip.mp4"
    empty.write_bytes(b"")
    result = CliRunner().invoke(main, ["run", str(empty), "--init", "10,10,20,20",
                                       "-o", str(tmp_path / "out")])
    assert one_error_line(result) == f"vtrack: error: {empty}: an empty file (0 bytes), not a video"


def test_a_container_given_as_raw_frames_is_refused_naming_what_it_is(clip_factory, tmp_path):
    """vtrack run clip.mp4 --raw 160x120 (or an MP4 piped into vtrack run - --raw) tracked the
    container's bytes as pixels: noise frames, then 'raw stream ended with N stray bytes' (exit
    1), or exit 0 when the sizes happened to divide; now one line says what the input is."""
    clip = clip_factory("smooth", width=160, height=120, frames=10).path
    result = CliRunner().invoke(main, ["run", str(clip), "--raw", "160x120", "--pix-fmt", "gray",
                                       "--init", "10,10,20,20", "-o", str(tmp_path / "out")])
    assert one_error_line(result) == (
        f"vtrack: error: {clip}: an MP4/QuickTime file, not raw frames: read it without --raw "
        "(its frames carry their own size and pixel format)")
    assert not (tmp_path / "out").exists()


@pytest.mark.parametrize(("name", "options"), [
    ("c.ts", {}),
    ("c.m2ts", {"mpegts_m2ts_mode": "1"}),  # 192-byte packets: a camcorder's AVCHD .mts
])
@pytest.mark.parametrize("piped", [False, True])
def test_an_mpegts_stream_given_as_raw_frames_is_refused(tmp_path, name, options, piped):
    """cat c.ts | vtrack run - --raw 32x24 tracked the MPEG-TS bytes as pixels: '- (partial):
    41 frames ...', then 'raw stream ended with 1980 stray bytes after 41 whole frames' (its
    signature, a 0x47 sync byte every 188 bytes, was not looked for). Now it is refused as the
    other containers are, from a pipe or a file; a grey raw frame of 0x47 bytes is still one."""
    clip = _red_target_clip(tmp_path / name, "mpegts", "libx264", frames=30, rate=30,
                            options=options, codec_options={"preset": "ultrafast"})
    command = [sys.executable, "-m", "vtrack", "run", "-" if piped else str(clip),
               "--raw", "32x24", "--init", "1,1,8,8", "--no-video", "-o", str(tmp_path / "out")]
    with clip.open("rb") as stdin:
        done = subprocess.run(command, stdin=stdin, capture_output=True, timeout=120)
    label = "-" if piped else str(clip)
    assert (done.returncode, done.stderr.decode()) == (2, (
        f"vtrack: error: {label}: an MPEG-TS stream, not raw frames: read it without --raw "
        "(its frames carry their own size and pixel format)\n"))
    assert not (tmp_path / "out").exists()
    grey = tmp_path / "grey.raw"
    grey.write_bytes(b"\x47" * 32 * 24 * 3 * 2)  # two flat frames: sync bytes everywhere
    command[4] = str(grey)
    assert subprocess.run(command[:-2] + ["-o", str(tmp_path / "grey")], capture_output=True,
                          timeout=120).returncode == 0


def test_an_mpegts_stream_given_as_frames_smaller_than_its_signature_is_refused(tmp_path):
    """`cat c.ts | vtrack run - --raw 8x8 --pix-fmt gray --init 1,1,4,4 --no-video` tracked the
    MPEG-TS bytes as pixels (exit 0): only the first frame's bytes, 64 of the 392 that show
    three packet headers, were looked at (and a first read shorter than the signature looked
    at what the frame's buffer held before). The first 392 bytes are gathered across the
    frames before any is tracked now."""
    clip = _red_target_clip(tmp_path / "c.ts", "mpegts", "libx264", frames=10, rate=30,
                            codec_options={"preset": "ultrafast"})
    options = ["--raw", "8x8", "--pix-fmt", "gray", "--init", "1,1,4,4", "--no-video", "-o"]
    done = subprocess.run([sys.executable, "-m", "vtrack", "run", "-", *options,
                           str(tmp_path / "out")], input=clip.read_bytes(),
                          capture_output=True, timeout=120)
    assert (done.returncode, done.stderr.decode()) == (2, (
        "vtrack: error: -: an MPEG-TS stream, not raw frames: read it without --raw (its "
        "frames carry their own size and pixel format)\n"))
    assert not (tmp_path / "out").exists()
    frames = tmp_path / "frames.gray"
    frames.write_bytes(bytes(range(64)) * 3 + b"\x07" * 10)  # 3 frames, then stray bytes
    result = CliRunner().invoke(main, ["run", str(frames), *options, str(tmp_path / "frames")])
    assert result.exit_code == 1, result.output  # tracked as far as it goes
    assert len((tmp_path / "frames" / "track.csv").read_text().splitlines()) == 1 + 3


def test_raw_rows_repeating_every_188_bytes_are_pixels_and_null_packets_a_stream(tmp_path):
    """`vtrack run ramp.gray --raw 188x8 --pix-fmt gray ...`, a grey ramp 0x47, 0x4a, 0x4d, ...
    on each row, was refused as 'an MPEG-TS stream': its rows put three byte-identical
    packet headers (47 4a 4d 50) 188 bytes apart. A stream's headers differ (each PID's
    continuity counter advances: c.ts begins 47401110, 47400010, 47500010), but for null
    packets (PID 0x1FFF): the ramp tracks, a stream of null packets is still refused."""
    ramp = np.array([(0x47 + 3 * x) % 256 for x in range(188)], np.uint8)
    frames = tmp_path / "ramp.gray"
    frames.write_bytes(np.tile(ramp, (8 * 3, 1)).tobytes())  # three 188x8 frames
    nulls = tmp_path / "nulls.gray"
    nulls.write_bytes((b"\x47\x1f\xff\x10" + b"\xff" * 184) * 24)  # 3 frames' bytes
    command = ["run", "--raw", "188x8", "--pix-fmt", "gray", "--init", "1,1,4,4", "--no-video"]
    done = CliRunner().invoke(main, [*command, str(frames), "-o", str(tmp_path / "ramp")])
    assert done.exit_code == 0, done.output
    rows = (tmp_path / "ramp" / "track.csv").read_text().splitlines()
    assert len(rows) == 1 + 3
    done = CliRunner().invoke(main, [*command, str(nulls), "-o", str(tmp_path / "nulls")])
    assert one_error_line(done) == (f"vtrack: error: {nulls}: an MPEG-TS stream, not raw "
                                    "frames: read it without --raw (its frames carry their own "
                                    "size and pixel format)")
    assert not (tmp_path / "nulls").exists()



@pytest.mark.parametrize(("width", "top"), [(188, 71), (192, 111)])  # M2TS: sync byte at 4
def test_raw_rows_whose_repeating_headers_carry_no_payload_are_pixels(tmp_path, width, top):
    """A 188x8 grey frame whose every row is the falling ramp clip(71 - 10 x) was refused
    as 'an MPEG-TS stream, not raw frames': its rows put three byte-identical headers
    (47 3d 33 29) 188 bytes apart, whose 4th byte reads 'adaptation field only' (no
    payload), so the continuity counter rightly stayed; 192 bytes apart (M2TS, from byte 4)
    alike. Byte-identical headers (but null packets') are no stream now: both ramps track
    (a real .ts or .m2ts is still refused:
    test_an_mpegts_stream_given_as_raw_frames_is_refused)."""
    ramp = np.clip(top - 10 * np.arange(width), 0, 255).astype(np.uint8)
    assert ramp[width - 188: width - 184].tolist() == [0x47, 0x3D, 0x33, 0x29]
    frames = tmp_path / "ramp.gray"
    frames.write_bytes(np.tile(ramp, (8 * 3, 1)).tobytes())  # three frames
    done = CliRunner().invoke(main, ["run", "--raw", f"{width}x8", "--pix-fmt", "gray",
                                     "--init", "1,1,4,4", "--no-video", str(frames), "-o",
                                     str(tmp_path / "ramp")])
    assert done.exit_code == 0, done.output
    assert len((tmp_path / "ramp" / "track.csv").read_text().splitlines()) == 1 + 3

def test_a_batch_takes_an_animated_gif_or_apng_as_vtrack_run_does(tmp_path):
    """`vtrack batch odd2` skipped odd2/c.gif without a word (no inputs, when alone) while
    `vtrack run odd2/c.gif` tracks it: an animation FFmpeg decodes (GIF, APNG) is now one of
    a batch's videos."""
    clip = _red_target_clip(tmp_path / "c.mp4", None, "libx264", frames=3, rate=25)
    folder = tmp_path / "odd2"
    folder.mkdir()
    for name, options in (("c.gif", []), ("d.apng", ["-f", "apng"])):
        subprocess.run(["ffmpeg", "-v", "error", "-i", str(clip), *options,
                        str(folder / name)], check=True, timeout=60)
        (folder / f"{Path(name).stem}.init.txt").write_text("5,10,20,20\n")
    result, rows = _batch_s0(folder, tmp_path / "out")
    assert rows == [("c", "complete", "3"), ("d", "complete", "3")], result.output


def test_a_gif_thumbnail_beside_a_sequences_frames_leaves_it_a_sequence(tmp_path):
    """`vtrack batch seq` of 0001.jpg..0005.jpg, groundtruth.txt and a one-frame thumb.gif
    tried thumb.gif ('no ground truth or initial box') and dropped the sequence: an animation
    made the folder no sequence, as a video does. It is one input again, in a folder of
    inputs and below one; a folder of GIFs alone still yields each."""
    top = tmp_path / "in"
    seq = top / "seq"
    seq.mkdir(parents=True)
    for i in range(1, 6):
        frame = np.full((48, 64, 3), 40, np.uint8)
        frame[10 + i:26 + i, 10 + i:26 + i] = (0, 0, 255)
        cv2.imwrite(str(seq / f"{i:04d}.jpg"), frame)
    (seq / "groundtruth.txt").write_text("".join(f"{10 + i},{10 + i},16,16\n"
                                                 for i in range(1, 6)))
    subprocess.run(["ffmpeg", "-v", "error", "-i", str(seq / "0001.jpg"),
                    str(seq / "thumb.gif")], check=True, timeout=60)
    result, rows = _batch_s0(seq, tmp_path / "out")
    assert rows == [("seq", "complete", "5")], result.output
    gifs = top / "gifs"
    gifs.mkdir()
    for name in ("a.gif", "b.gif"):
        (gifs / name).write_bytes((seq / "thumb.gif").read_bytes())
    assert [item.name for item in find_inputs(top)] == ["seq"]
    assert [item.name for item in find_inputs(gifs)] == ["a", "b"]
    assert nested_inputs(top).found == [gifs / "a.gif", gifs / "b.gif"]
    group = tmp_path / "group"
    group.mkdir()
    seq.rename(group / "seq")
    assert nested_inputs(tmp_path).found == [group / "seq", gifs / "a.gif", gifs / "b.gif"]


def test_a_batch_takes_a_broadcast_cameras_mxf_and_the_readme_lists_what_it_takes(tmp_path):
    """vtrack batch of a folder of a camera's .MXF clips said 'no inputs (video files or
    sequence folders ...)' though vtrack run tracks them and --help said inputs are the video
    files in FOLDER; the README lists every name a batch takes, and only those."""
    folder = tmp_path / "shoot"
    folder.mkdir()
    _red_target_clip(folder / "A001.MXF", "mxf", "mpeg2video", frames=3, rate=25)
    (folder / "A001.init.txt").write_text("5,10,20,20\n")
    result, rows = _batch_s0(folder, tmp_path / "out")
    assert rows == [("A001", "complete", "3")], result.output
    readme = (Path(__file__).parents[1] / "README.md").read_text(encoding="utf-8")
    listed = re.search(r"Video files are known by their names.*?: (`\.[^(]*)\(", readme, re.S)
    assert listed and set(re.findall(r"`(\.\w+)`", listed[1])) == set(BATCH_SUFFIXES)


def _batch_s0(folder: Path, out: Path) -> tuple[object, list[tuple[str, str, str]]]:
    """``vtrack batch FOLDER -c s0`` into ``out``: click's result and each summary row's input,
    status and frame count."""
    result = CliRunner().invoke(main, ["batch", str(folder), "-c", "s0", "--no-video", "-j", "1",
                                       "-o", str(out)], catch_exceptions=False)
    assert result.exit_code == 0, result.output
    with (out / "summary.csv").open(newline="") as handle:
        return result, [(row["input"], row["status"], row["frames"])
                        for row in csv.DictReader(handle)]


def _red_target_clip(path: Path, fmt: str | None, codec: str, *, frames: int, rate: int,
                     options: dict[str, str] | None = None,
                     codec_options: dict[str, str] | None = None, first_pts: int = 0,
                     rotation: int = 0) -> Path:
    """A 64x48 clip of ``frames`` frames of a red 20x20 target moving right a pixel a frame from
    (5, 10), written as ``fmt`` (None: as the name says; muxer ``options``) by ``codec``
    (``codec_options``), its first frame at ``first_pts`` (in frames), its display matrix
    turning it ``rotation`` degrees."""
    with av.open(str(path), "w", format=fmt, options=options or {}) as out:
        stream = out.add_stream(codec, rate=rate)
        stream.width, stream.height, stream.pix_fmt = 64, 48, "yuv420p"
        stream.options = codec_options or {}
        if rotation:
            stream.set_display_rotation(rotation)
        for i in range(frames):
            pixels = np.full((48, 64, 3), 90, np.uint8)
            pixels[10:30, 5 + i:25 + i] = (40, 60, 210)
            picture = av.VideoFrame.from_ndarray(pixels, format="bgr24")
            picture.pts = first_pts + i
            for packet in stream.encode(picture):
                out.mux(packet)
        for packet in stream.encode():
            out.mux(packet)
    return path


def _recording(path: Path, fmt: str, options: dict[str, str]) -> Path:
    """A recording as it is written while it goes (OBS, a phone): ``fmt`` with muxer
    ``options`` (fragmented MP4: an empty index first, a fragment from each key frame; live
    Matroska: no duration, clusters of unknown size), a key frame every 5 of 30 frames."""
    return _red_target_clip(path, fmt, "libx264", frames=30, rate=30, options=options,
                            codec_options={"preset": "ultrafast",
                                           "x264-params": "keyint=5:min-keyint=5"})


def _inside_a_late_mdat(data: bytes) -> int:
    """An offset 16 bytes into the next-to-last ``mdat`` box of ``data``, an MP4 (its top-level
    boxes walked by their sizes): a cut there ends the file inside an ``mdat`` whatever size
    the encoder gave the boxes."""
    offsets, at = [], 0
    while at + 8 <= len(data):
        if data[at + 4:at + 8] == b"mdat":
            offsets.append(at)
        at += int.from_bytes(data[at:at + 4], "big")
    return offsets[-2] + 16


@pytest.mark.parametrize(("name", "fmt", "options", "cut_inside"), [
    ("rec.mp4", "mp4", {"movflags": "frag_keyframe+empty_moov"}, "its last mdat box"),
    # the first fragment in the index (moov lists its frames only)
    ("first-in-moov.mp4", "mp4", {"movflags": "frag_keyframe"}, "its last mdat box"),
    ("rec.mkv", "matroska", {"live": "1"}, "its last cluster"),
])
def test_a_recording_cut_inside_a_fragment_is_partial(tmp_path, name, fmt, options, cut_inside):
    """A fragmented MP4 or a live-written Matroska file cut part way (the recorder crashed, a
    copy stopped) has no frame count or duration to fall short of, and FFmpeg reads its whole
    fragments or blocks without a word: vtrack run ended complete, exit 0, with 2/3 of the
    frames. Now it ends partial (exit 1) naming the cut; the whole file is still complete."""
    whole = _recording(tmp_path / name, fmt, options)
    cut = tmp_path / f"cut-{name}"
    data = whole.read_bytes()
    cut.write_bytes(data[:_inside_a_late_mdat(data) if fmt == "mp4" else len(data) * 2 // 3])
    runs = {}
    for clip in (whole, cut):
        out = tmp_path / f"out-{clip.name}"
        result = CliRunner().invoke(main, ["run", str(clip), "--init", "5,10,20,20",
                                           "--no-video", "-o", str(out)])
        record = json.loads((out / "run.json").read_text())
        runs[clip] = (result.exit_code, record["status"], record["frames"], record["error"])
    assert runs[whole] == (0, "complete", 30, None)
    code, status, frames, error = runs[cut]
    assert (code, status) == (1, "partial") and 0 < frames < 30
    assert error == (f"{cut}: decoding stopped at frame {frames} (the file ends inside "
                     f"{cut_inside}; truncated file?)")


@pytest.mark.parametrize("trailer", [b"\n", b"\0\0\0\0", b"SEFT trailer of a phone"])
def test_a_whole_file_with_bytes_after_its_end_is_complete(tmp_path, trailer):
    """Bytes appended after a file's last box or element (a phone's trailer, a stray newline)
    made every whole MP4 and Matroska file 'partial' ('the file ends inside its last box;
    truncated file?', exit 1) with all its frames read (review of the cut-recording check):
    a file that states its frame count or duration is judged by them, a recording that states
    neither by its last whole box, and bytes that are no box are no cut."""
    clips = [_recording(tmp_path / "rec.mp4", "mp4", {"movflags": "frag_keyframe+empty_moov"}),
             _red_target_clip(tmp_path / "plain.mp4", "mp4", "libx264", frames=30, rate=30),
             _red_target_clip(tmp_path / "plain.mkv", "matroska", "libx264", frames=30,
                              rate=30)]
    for clip in clips:
        clip.write_bytes(clip.read_bytes() + trailer)
        out = tmp_path / f"out-{clip.name}"
        result = CliRunner().invoke(main, ["run", str(clip), "--init", "5,10,20,20",
                                           "--no-video", "-o", str(out)])
        record = json.loads((out / "run.json").read_text())
        assert (result.exit_code, record["status"], record["frames"]) == (0, "complete", 30), \
            (clip.name, record["error"])


def test_a_jpeg_cut_short_in_a_folder_is_skipped_with_a_warning(tmp_path):
    """A sequence image cut short (a card copy or a camera's write that stopped) decodes in
    FFmpeg without an error, its missing part grey: it was tracked as a whole frame without a
    word. Now it is skipped as an unreadable image is, with a warning naming it; a phone's
    motion photo (a video appended after the picture's end marker) is a whole image."""
    folder = tmp_path / "seq" / "img"
    folder.mkdir(parents=True)
    rng = np.random.default_rng(0)
    for i in range(3):
        cv2.imwrite(str(folder / f"{i + 1:04d}.jpg"),
                    rng.integers(0, 256, (48, 64, 3), np.uint8))
    second, third = folder / "0002.jpg", folder / "0003.jpg"
    second.write_bytes(second.read_bytes()[: second.stat().st_size // 2])
    third.write_bytes(third.read_bytes() + b"\x00\x00\x00\x18ftypmp42" + bytes(100))
    with open_source(str(folder.parent)) as source:
        indices = [frame.index for frame in source]
    assert indices == [0, 2] and source.frames_skipped == 1
    assert source.warnings == [f"{second}: a JPEG cut short (no end-of-image marker after its "
                               "image data): part of the picture is missing; frame 1 skipped"]


def test_an_empty_file_followed_says_it_stayed_empty(tmp_path):
    """`vtrack run rec.ts --follow 1` on a file nothing was written to said 'an empty file (0
    bytes), not a video', as if it had not been waited for; it now says it stayed empty for
    --follow's wait."""
    empty = tmp_path / "rec.ts"
    empty.write_bytes(b"")
    result = CliRunner().invoke(main, ["run", str(empty), "--follow", "0.2", "--init",
                                       "10,10,20,20", "-o", str(tmp_path / "out")])
    assert one_error_line(result) == (f"vtrack: error: {empty}: stayed empty (0 bytes) for "
                                      "--follow's wait of 0.2 s: nothing was written to it (a "
                                      "writer that starts later, or holds its first bytes "
                                      "longer, needs a longer --follow)")


@pytest.mark.parametrize(("name", "fmt", "options"), [
    ("rec.ts", "mpegts", {}),
    ("rec.mkv", "matroska", {"live": "1"}),
    ("rec.mp4", "mp4", {"movflags": "frag_keyframe+empty_moov"}),
])
def test_a_followed_recording_that_stops_growing_mid_frame_says_to_wait_longer(
        tmp_path, name, fmt, options):
    """A recorder that pauses longer than --follow's wait, its file ending inside a packet,
    fragment or block: an MPEG-TS run ended partial saying '...; truncated file?', blaming the
    file, not the wait, and saying nothing of what to do; a fragmented MP4 or live Matroska
    one ended complete (exit 0), its torn end unchecked when followed, though the same file
    read without --follow is partial. Each now ends partial saying the file is cut or its
    writer paused longer than the wait, and that a writer pausing longer needs a longer
    --follow."""
    data = _recording(tmp_path / name, fmt, options).read_bytes()
    cut = tmp_path / f"cut-{name}"
    ends = {"mpegts": len(data) * 2 // 3 // 188 * 188 + 100,  # inside a transport packet
            "matroska": len(data) * 2 // 3}
    cut.write_bytes(data[:ends.get(fmt) or _inside_a_late_mdat(data)])
    out = tmp_path / "out"
    result = CliRunner().invoke(main, ["run", str(cut), "--follow", "0.2", "--init",
                                       "5,10,20,20", "--no-video", "-o", str(out)])
    record = json.loads((out / "run.json").read_text())
    assert (result.exit_code, record["status"]) == (1, "partial"), result.output
    assert record["error"].startswith(f"{cut}: decoding stopped at frame {record['frames']} ")
    assert record["error"].endswith("; truncated, or its writer paused longer than --follow's "
                                    "0.2 s: give a longer --follow if it was still being "
                                    "written)"), record["error"]


def test_an_animated_webp_is_named_as_what_ffmpeg_cannot_decode(tmp_path):
    """An animated WebP (FFmpeg bundled with PyAV decodes only still ones) said only 'no frame
    could be decoded'; it now names what the file is and that it cannot be decoded."""
    path = tmp_path / "anim.webp"
    with av.open(str(path), "w", format="webp") as out:
        stream = out.add_stream("libwebp_anim", rate=10)
        stream.width, stream.height, stream.pix_fmt = 64, 48, "yuv420p"
        for value in (0, 120, 240):
            picture = np.full((48, 64, 3), value, np.uint8)
            out.mux(stream.encode(av.VideoFrame.from_ndarray(picture, format="bgr24")))
        out.mux(stream.encode())
    result = CliRunner().invoke(main, ["run", str(path), "--init", "1,1,8,8",
                                       "-o", str(tmp_path / "out")])
    assert one_error_line(result).startswith(
        f"vtrack: error: {path}: an animated WebP, which the FFmpeg vtrack reads with cannot "
        "decode (it decodes still WebP only)")


def test_a_yuv4mpeg2_header_larger_than_its_file_says_the_size_does_not_fit(tmp_path):
    """A .y4m whose header declares 16000x16000 frames (within vtrack's limit) in a 1 kB file
    said 'no frame could be decoded'; it now says the header's size does not fit the data."""
    y4m = tmp_path / "big.y4m"
    y4m.write_bytes(b"YUV4MPEG2 W16000 H16000 F30:1 Ip A1:1 C420jpeg\nFRAME\n" + bytes(1000))
    result = CliRunner().invoke(main, ["run", str(y4m), "--init", "1,1,8,8",
                                       "-o", str(tmp_path / "out")])
    assert one_error_line(result) == (
        f"vtrack: error: {y4m}: its YUV4MPEG2 header declares 16000x16000 frames, whose luma "
        f"alone (256000000 bytes) is more than the whole file holds ({y4m.stat().st_size} "
        "bytes): the header's frame size does not fit the data")


def _png_declaring(path: Path, width: int, height: int) -> Path:
    """A small PNG file whose header declares a ``width`` x ``height`` grey picture (its data
    holds one row)."""
    def chunk(kind: bytes, data: bytes) -> bytes:
        return struct.pack(">I", len(data)) + kind + data + struct.pack(
            ">I", zlib.crc32(kind + data))
    header = struct.pack(">IIBBBBB", width, height, 8, 0, 0, 0, 0)
    path.write_bytes(b"\x89PNG\r\n\x1a\n" + chunk(b"IHDR", header)
                     + chunk(b"IDAT", zlib.compress(bytes(width + 1))) + chunk(b"IEND", b""))
    return path


def test_a_picture_size_declared_too_large_is_named(tmp_path):
    """Headers declaring pictures over FFmpeg's limit (2^28 pixels) were 'not a video FFmpeg
    can decode (Device or resource busy)' (a YUV4MPEG2 stream), 'no frame could be decoded' (a
    PNG) or 'not an image FFmpeg can decode (Invalid data ...)' (a PNG in a folder): now each
    names the size and vtrack's limit, as a video stream's size is."""
    y4m = tmp_path / "huge.y4m"
    y4m.write_bytes(b"YUV4MPEG2 W50000 H50000 F30:1 Ip A1:1 C420jpeg\nFRAME\n" + bytes(1000))
    png = _png_declaring(tmp_path / "pano.png", 40000, 40000)
    folder = tmp_path / "seq" / "img"
    folder.mkdir(parents=True)
    _png_declaring(folder / "0001.png", 40000, 40000)
    for given, named, size in ((y4m, y4m, "50000x50000"), (png, png, "40000x40000"),
                               (folder.parent, folder / "0001.png", "40000x40000")):
        result = CliRunner().invoke(main, ["run", str(given), "--init", "1,1,8,8",
                                           "-o", str(tmp_path / "out")])
        assert one_error_line(result) == (f"vtrack: error: {named}: the frames are {size}; "
                                          "vtrack accepts at most 16384x16384")


def test_a_display_matrix_that_is_no_quarter_turn_is_warned_of(tmp_path):
    """A clip whose display matrix turns it 45 degrees (an editor's tilt) was read as stored
    and recorded rotation 0 without a word (ffmpeg shows it tilted); now a warning says how it
    is read. Quarter turns are applied without one."""
    clips = {}
    for degrees in (45, 90):
        clips[degrees] = _red_target_clip(tmp_path / f"tilt{degrees}.mp4", None, "libx264",
                                          frames=1, rate=30, rotation=degrees)
    with open_source(str(clips[45])) as tilted, open_source(str(clips[90])) as turned:
        assert (tilted.info.rotation, turned.info.rotation) == (0, 90)
        assert tilted.warnings == [f"{clips[45]}: its display matrix turns the picture 45 "
                                   "degrees, not a quarter turn; it is read turned 0 degrees "
                                   "(the nearest quarter turn)"]
        assert turned.warnings == []


def test_a_box_refused_by_a_turned_frame_size_says_the_rotation_turned_it(tmp_path):
    """`ffmpeg -i clip.mp4 -c copy -metadata:s:v rotate=90 c_rot.mp4; vtrack run c_rot.mp4
    --init 262,71,40,31` said "the box ... lies outside the 240x320 frame" of a clip every
    other reader shows as 320x240, without a word of the rotation: now it says the input's
    rotation metadata turned it. A frame no rotation turned is refused as before."""
    turned = _red_target_clip(tmp_path / "turned.mp4", None, "libx264", frames=1, rate=30,
                              rotation=90)
    plain = _red_target_clip(tmp_path / "plain.mp4", None, "libx264", frames=1, rate=30)
    note = " (the input's rotation metadata turned it 90 degrees, from 64x48)"
    for clip, box, problem, size, said in (
            (turned, "50,10,10,10", "lies outside", "48x64", note),
            (turned, "2,2,60,10", "is larger than", "48x64", note),
            (plain, "2,2,60,60", "is larger than", "64x48", "")):
        result = CliRunner().invoke(main, ["run", str(clip), "--init", box,
                                           "-o", str(tmp_path / "out")])
        assert one_error_line(result) == (f"vtrack: error: --init: the box {box} {problem} "
                                          f"the {size} frame{said}")


def test_a_file_with_two_video_streams_warns_which_it_tracks(clip_factory, tmp_path):
    """`ffmpeg -i a.mp4 -i b.mp4 -map 0:v -map 1:v -c copy two.mkv`: vtrack run tracked the
    first stream without a word that there was another; now one warning line says so, on
    stderr and in run.json."""
    first = clip_factory("smooth", width=160, height=120, frames=10)
    second = clip_factory("smooth", seed=1, width=160, height=120, frames=10)
    two = tmp_path / "two.mkv"
    subprocess.run(["ffmpeg", "-v", "error", "-i", str(first.path), "-i", str(second.path),
                    "-map", "0:v", "-map", "1:v", "-c", "copy", str(two)], check=True,
                   timeout=60)
    done = subprocess.run([sys.executable, "-m", "vtrack", "run", str(two), "--gt",
                           str(first.gt), "-c", "s0", "--no-video", "-q", "-o",
                           str(tmp_path / "out")], capture_output=True, text=True, timeout=120)
    warning = f"{two}: 2 video streams; tracking the first (#0)"
    assert (done.returncode, done.stderr) == (0, f"vtrack: warning: {warning}\n")
    record = json.loads((tmp_path / "out" / "run.json").read_text())
    assert (record["status"], record["warnings"]) == ("complete", [warning])


def test_time_s_counts_from_the_first_frame_as_the_readme_says(tmp_path):
    """A recording whose timestamps start at 5 s (an MPEG-TS starts at 1.4 s, a later part of
    a recording hours in) has time_s 0 at frame 0: the README said only 'time_s comes from each
    frame's timestamp', and a user comparing with ffprobe's pts_time found it 5 s off."""
    clip = _red_target_clip(tmp_path / "part2.mp4", None, "libx264", frames=3, rate=30,
                            first_pts=150)
    with av.open(str(clip)) as container:
        assert next(container.decode(video=0)).time == pytest.approx(5.0)
    out = tmp_path / "out"
    result = CliRunner().invoke(main, ["run", str(clip), "--init", "5,10,20,20", "--no-video",
                                       "-o", str(out)])
    assert result.exit_code == 0, result.output
    with (out / "track.csv").open(newline="") as handle:
        times = [float(row["time_s"]) for row in csv.DictReader(handle)]
    assert times == pytest.approx([0, 1 / 30, 2 / 30], abs=1e-4)
    readme = " ".join((Path(__file__).parents[1] / "README.md").read_text().split())
    assert "`time_s` comes from each frame's timestamp, counted from the first frame's (frame " \
           "0 is at 0 s, whatever time the container starts at" in readme


def _restamped_mkv(path: Path, stamps_ms: list[int]) -> Path:
    """A Matroska file of ``len(stamps_ms)`` frames (FFV1: each frame its own, nothing
    reordered) of the red target moving right, each packet stamped ``stamps_ms`` (ms) as a
    re-stamping tool leaves them, repeats included."""
    with av.open(str(path), "w") as out:
        stream = out.add_stream("ffv1", rate=30)
        stream.width, stream.height, stream.pix_fmt = 64, 48, "yuv420p"
        stamps = iter(stamps_ms)
        for i in [*range(len(stamps_ms)), None]:
            picture = None
            if i is not None:
                pixels = np.full((48, 64, 3), 90, np.uint8)
                pixels[10:30, 5 + i % 30:25 + i % 30] = (40, 60, 210)
                picture = av.VideoFrame.from_ndarray(pixels, format="bgr24")
                picture.pts = i
            for packet in stream.encode(picture):
                packet.time_base = Fraction(1, 1000)
                packet.pts = packet.dts = next(stamps)
                out.mux(packet)
    return path


def test_frames_repeating_a_timestamp_are_one_warning_as_a_jump_back_is(tmp_path):
    """An MKV whose frames 19..25 all carry 0.633 s passed without a word, while timestamps
    that go back are warned of: track.csv held one time_s for seven frames. One warning now,
    in run.json and on stderr, counting the frames and naming the first."""
    stamps = [round(i * 1000 / 30) for i in range(40)]
    stamps[19:26] = [633] * 7
    clip = _restamped_mkv(tmp_path / "restamped.mkv", stamps)
    out = tmp_path / "out"
    done = subprocess.run([sys.executable, "-m", "vtrack", "run", str(clip), "--init",
                           "5,10,20,20", "--no-video", "-o", str(out)],
                          capture_output=True, text=True, timeout=120, check=False)
    assert done.returncode == 0, done.stderr
    with (out / "track.csv").open(newline="") as handle:
        times = [row["time_s"] for row in csv.DictReader(handle)]
    assert times[19:26] == ["0.633"] * 7 and len(times) == 40
    repeated = [w for w in json.loads((out / "run.json").read_text())["warnings"]
                if "repeated the timestamp" in w]
    assert repeated == [f"{clip}: 6 frames repeated the timestamp of the frame before (first "
                        "at frame 20: 0.6330 s again; a damaged or re-stamped file?): "
                        "track.csv's time_s is the same for those frames while frame numbers "
                        "carry on"]
    assert done.stderr.count("repeated the timestamp") == 1
