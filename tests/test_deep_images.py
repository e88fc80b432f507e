"""16-bit grey image sequences (a thermal camera's 12- or 14-bit values in 16-bit files)."""

from __future__ import annotations

import json
import subprocess
import sys
from pathlib import Path

import av
import cv2
import numpy as np
import pytest
from click.testing import CliRunner
from conftest import one_error_line

from vtrack.cli import main
from vtrack.io.images import ImageFolderSource, read_image
from vtrack.io.signatures import float_tiff_problem
from vtrack.io.video import VideoSource

SKY, TARGET, BOX = 0.3, 0.9, 6


def scene(bits: int, i: int) -> np.ndarray:
    """Frame ``i`` of a small bright target crossing a flat sky, values of ``bits`` bits in a
    16-bit image, with two hot pixels at 65535 (the target's top left at ``20 + 4i, 40 + i``)."""
    top = (1 << bits) - 1
    image = np.full((120, 160), round(top * SKY), np.uint16)
    x, y = 20 + 4 * i, 40 + i
    image[y:y + BOX, x:x + BOX] = round(top * TARGET)
    image[5, 5] = image[100, 150] = 65535
    return image


def write_truth(path: Path, frames: int) -> Path:
    """OTB ground truth (1-based) of :func:`scene`'s first ``frames`` frames at ``path``."""
    path.write_text("".join(f"{20 + 4 * i + 1},{40 + i + 1},{BOX},{BOX}\n"
                            for i in range(frames)))
    return path


def write_sequence(folder: Path, bits: int, frames: int = 20, ext: str = ".png") -> Path:
    """:func:`scene`'s frames as 16-bit images in ``folder``; OTB ground truth beside it."""
    folder.mkdir()
    for i in range(frames):
        assert cv2.imwrite(str(folder / f"frame_{i:04d}{ext}"), scene(bits, i))
    write_truth(folder / "groundtruth_rect.txt", frames)
    return folder


@pytest.mark.parametrize(("bits", "ext"), [(12, ".png"), (14, ".tif"), (16, ".png")])
def test_deep_grey_scaled_by_the_bits_used(tmp_path: Path, bits: int, ext: str) -> None:
    folder = write_sequence(tmp_path / "seq", bits, frames=3, ext=ext)
    source = ImageFolderSource(str(folder))
    frames = list(source)
    assert source.info.pix_fmt == "gray16le"
    assert len(frames) == 3
    pixels = frames[2].gray()
    assert pixels.dtype == np.uint8 and pixels.ndim == 2
    top = (1 << bits) - 1
    assert pixels[0, 80] == round(round(top * SKY) * 255 / top)  # ~76, not 4 (12 bits >> 8)
    assert pixels[42, 30] == round(round(top * TARGET) * 255 / top)
    assert pixels[5, 5] == 255  # a hot pixel clips
    assert source.warnings == [
        f"{folder}: 16-bit grey images whose values use {bits} bits (the first image's, hot "
        f"pixels aside): read as 8-bit grey, 0..{top} scaled to 0..255 (a later "
        "image whose values use more bits scales by them from it on, with a warning; isolated "
        "brighter pixels clip at 255)"]
    assert read_image(folder / f"frame_0002{ext}")[0, 80] == pixels[0, 80]


def test_12_bit_sequence_tracked_as_its_8_bit_copy(tmp_path: Path) -> None:
    """s2 (grey levels in 16 bins) lost a 12-bit target read as its top 8 of 16 bits."""
    folder = write_sequence(tmp_path / "thermal", 12)
    out = tmp_path / "out"
    done = CliRunner().invoke(main, ["run", str(folder), "--config", "s2", "--gt",
                                     str(folder / "groundtruth_rect.txt"), "-o", str(out),
                                     "--no-video"])
    assert done.exit_code == 0, done.output
    run = json.loads((out / "run.json").read_text())
    assert run["input"]["pix_fmt"] == "gray16le"
    assert any("use 12 bits" in line for line in run["warnings"])
    rows = (out / "track.csv").read_text().splitlines()[1:]
    assert len(rows) == 20
    overlaps = [float(row.split(",")[10]) for row in rows]
    assert min(overlaps) > 0.5


def write_gray16_video(path: Path, bits: int, frames: int = 20) -> Path:
    """:func:`scene`'s frames as lossless FFV1 ``gray16le`` in Matroska (a thermal camera's
    recording)."""
    with av.open(str(path), "w") as container:
        stream = container.add_stream("ffv1", rate=30)
        stream.width, stream.height, stream.pix_fmt = 160, 120, "gray16le"
        for i in range(frames):
            picture = av.VideoFrame.from_ndarray(scene(bits, i), format="gray16le")
            for packet in stream.encode(picture):
                container.mux(packet)
        for packet in stream.encode():
            container.mux(packet)
    return path


def test_12_bit_video_tracked_as_its_8_bit_copy(tmp_path: Path) -> None:
    """A 16-bit grey video was converted by FFmpeg (its top 8 bits: 0..15): s2 lost it."""
    video = write_gray16_video(tmp_path / "thermal.mkv", 12)
    truth = write_truth(tmp_path / "thermal.txt", 20)
    out = tmp_path / "out"
    done = CliRunner().invoke(main, ["run", str(video), "--config", "s2", "--gt", str(truth),
                                     "--gt-origin", "1", "-o", str(out), "--no-video"])
    assert done.exit_code == 0, done.output
    run = json.loads((out / "run.json").read_text())
    assert run["input"]["pix_fmt"] == "gray16le"
    assert run["warnings"] == [
        f"{video}: 16-bit grey frames whose values use 12 bits (the first frame's, hot pixels "
        "aside): read as 8-bit grey, 0..4095 scaled to 0..255 (a later frame whose values use "
        "more bits scales by them from it on, with a warning; isolated brighter pixels clip at "
        "255)"]
    overlaps = [float(row.split(",")[10]) for row in
                (out / "track.csv").read_text().splitlines()[1:]]
    assert len(overlaps) == 20 and min(overlaps) > 0.5


@pytest.mark.parametrize("given", ["video", "png"])
def test_deep_grey_frames_scaled_by_the_first_frames_bits(tmp_path: Path, given: str) -> None:
    """One scale for the whole stream, the first frame's; a single 16-bit PNG alike."""
    if given == "png":
        path = tmp_path / "one.png"
        assert cv2.imwrite(str(path), scene(14, 2))
    else:
        path = write_gray16_video(tmp_path / "deep.mkv", 14, frames=3)
    with VideoSource(str(path)) as source:
        frames = list(source)
        assert source.warnings[0].startswith(f"{path}: 16-bit grey frames whose values use "
                                             "14 bits")
    pixels = frames[-1].gray()
    assert pixels.dtype == np.uint8
    assert pixels[0, 80] == round(round(16383 * SKY) * 255 / 16383)  # 77, not 19 (>> 8)
    assert pixels[42, 30] == round(round(16383 * TARGET) * 255 / 16383)
    assert pixels[5, 5] == 255


def colour_scene(bits: int, i: int, alpha: bool) -> np.ndarray:
    """:func:`scene` in colour (BGR: blue and red its values, green half of them), with an
    opaque alpha channel when ``alpha`` (a 16-bit PNG's rgba64be, else rgb48be)."""
    grey = scene(bits, i)
    channels = [grey, grey // 2, grey] + ([np.full_like(grey, 65535)] if alpha else [])
    return np.dstack(channels)


@pytest.mark.parametrize("alpha", [False, True])
def test_deep_colour_scaled_by_the_bits_used(tmp_path: Path, alpha: bool) -> None:
    """16-bit colour PNGs were read as their top 8 bits (12-bit sky 1228 -> 4), silently."""
    folder = tmp_path / "seq"
    folder.mkdir()
    for i in range(3):
        assert cv2.imwrite(str(folder / f"{i:04d}.png"), colour_scene(12, i, alpha))
    source = ImageFolderSource(str(folder))
    frames = list(source)
    assert source.info.pix_fmt == "bgr48le"
    assert source.warnings == [
        f"{folder}: 16-bit colour images whose values use 12 bits (the first image's, hot "
        "pixels aside): read as 8-bit colour, 0..4095 scaled to 0..255 (a later "
        "image whose values use more bits scales by them from it on, with a warning; isolated "
        "brighter pixels clip at 255)"]
    sky, target = [76, 38, 76], [230, 115, 230]  # 1228, 614 and 3686, 1843 of 4095
    assert frames[2].bgr()[0, 80].tolist() == sky
    assert frames[2].bgr()[42, 30].tolist() == target
    assert read_image(folder / "0002.png")[42, 30].tolist() == target
    with VideoSource(str(folder / "0002.png")) as alone:  # a PNG given alone
        assert alone.warnings[0].startswith(f"{folder / '0002.png'}: 16-bit colour frames "
                                            "whose values use 12 bits")
        assert next(iter(alone)).bgr()[42, 30].tolist() == target


@pytest.mark.parametrize("first_deep", [False, True])
def test_an_image_of_another_depth_is_warned_of_once(tmp_path: Path, first_deep: bool) -> None:
    """A 16-bit image among 8-bit ones (or the reverse) was read by another scale, silently."""
    folder = tmp_path / "seq"
    folder.mkdir()
    for i in range(4):
        deep_one = first_deep == (i in (0, 3))  # images 1 and 2 of the other depth
        image = scene(12, i)
        assert cv2.imwrite(str(folder / f"{i:04d}.png"),
                           image if deep_one else (image >> 4).clip(0, 255).astype(np.uint8))
    source = ImageFolderSource(str(folder))
    assert len(list(source)) == 4
    other = [line for line in source.warnings if "16-bit grey images" not in line]
    if first_deep:
        assert other == [f"{folder / '0001.png'}: an 8-bit image among 16-bit ones (values of "
                         "12 bits, 0..4095 scaled to 0..255): read as it is, 0..255 (the "
                         "sequence's depth is its first image's; later images of another "
                         "depth are not named)"]
    else:
        assert other == [f"{folder / '0001.png'}: a 16-bit image among 8-bit ones: read as "
                         "16-bit values, 0..65535 scaled to 0..255 (the sequence's depth is "
                         "its first image's; later images of another depth are not named)"]


@pytest.mark.parametrize("alone", [False, True])
def test_a_float_tiff_is_refused_saying_so(tmp_path: Path, alone: bool) -> None:
    """It was "not an image FFmpeg can decode (Invalid data found when processing input)"
    (a folder) or "no frame could be decoded" (given alone)."""
    folder = tmp_path / "seq"
    folder.mkdir()
    image = folder / "0001.tif"
    assert cv2.imwrite(str(image), scene(12, 0).astype(np.float32) / 4095)
    given = image if alone else folder
    done = CliRunner().invoke(main, ["run", str(given), "--config", "s2", "--init",
                                     "20,40,6,6", "-o", str(tmp_path / "out")])
    assert one_error_line(done) == (f"vtrack: error: {image}: 32-bit float TIFF is not "
                                    "supported; save it as 8- or 16-bit")


@pytest.mark.parametrize("order", ["big", "little"])
@pytest.mark.parametrize("channels", [1, 3])
def test_a_float_tiff_whose_tags_are_longs_is_named(tmp_path: Path, order: str,
                                                    channels: int) -> None:
    """BitsPerSample and SampleFormat typed LONG (4 bytes) rather than SHORT: a big-endian
    file's were read as their first 2 bytes (0), and the float TIFF was not named."""
    def number(value: int, size: int) -> bytes:
        return value.to_bytes(size, order)  # type: ignore[arg-type]

    far = 8 + 2 + 2 * 12 + 4  # where values that do not fit in their entry go
    entries, values = b"", b""
    for tag, value in ((258, 32), (339, 3)):  # BitsPerSample, SampleFormat
        if channels == 1:
            entries += number(tag, 2) + number(4, 2) + number(1, 4) + number(value, 4)
        else:
            entries += (number(tag, 2) + number(4, 2) + number(channels, 4)
                        + number(far + len(values), 4))
            values += number(value, 4) * channels
    image = tmp_path / "float.tif"
    image.write_bytes((b"MM\x00*" if order == "big" else b"II*\x00") + number(8, 4)
                      + number(2, 2) + entries + number(0, 4) + values)
    assert float_tiff_problem(image) == ("32-bit float TIFF is not supported; save it as 8- "
                                         "or 16-bit")


def test_a_12_bit_format_is_read_by_ffmpegs_conversion(tmp_path: Path) -> None:
    """A ``gray12le`` FFV1 declares its depth: FFmpeg's 8-bit conversion is right for it. It
    was taken for a 16-bit one, warned of as "12-bit grey frames whose values use 16 bits"
    (FFmpeg widens 12-bit values to 16 bits) and scaled as such."""
    path = tmp_path / "g12.mkv"
    image = scene(12, 0)
    image[5, 5] = image[100, 150] = 4095  # the hot pixels, at a 12-bit top
    with av.open(str(path), "w") as container:
        stream = container.add_stream("ffv1", rate=30)
        stream.width, stream.height, stream.pix_fmt = 160, 120, "gray12le"
        for _ in range(3):
            picture = av.VideoFrame.from_ndarray(image << 4, format="gray16le")
            for packet in stream.encode(picture.reformat(format="gray12le")):
                container.mux(packet)
        for packet in stream.encode():
            container.mux(packet)
    with VideoSource(str(path)) as source:
        assert source.info.pix_fmt == "gray12le"
        frames = list(source)
        assert source.warnings == []
    pixels = frames[-1].gray()
    assert pixels.dtype == np.uint8
    assert abs(int(pixels[0, 80]) - round(4095 * SKY) * 255 / 4095) <= 1  # 76 or 77
    assert abs(int(pixels[42, 22]) - round(4095 * TARGET) * 255 / 4095) <= 1


def test_an_8_bit_frame_in_a_deep_stream_is_read_as_the_first(tmp_path: Path) -> None:
    """PNGs on stdin (``--format image2pipe``), a 12-bit one in 16 bits then an 8-bit grey
    one: the second was converted by FFmpeg to colour and the run refused it ("frame 1:
    160x120 colour, the first frame was 160x120 grey"). It is read as it is, grey as the first,
    with one warning."""
    deep_png, grey_png = tmp_path / "deep.png", tmp_path / "grey.png"
    assert cv2.imwrite(str(deep_png), scene(12, 0))
    assert cv2.imwrite(str(grey_png), (scene(12, 1) >> 4).astype(np.uint8))
    stream = tmp_path / "frames.pngs"
    stream.write_bytes(deep_png.read_bytes() + grey_png.read_bytes() + deep_png.read_bytes())
    with VideoSource(str(stream)) as source:
        frames = list(source)
        warnings = source.warnings
    assert [type(frame).__name__ for frame in frames] == ["GrayFrame"] * 3
    assert frames[1].gray()[0, 80] == round(4095 * SKY) >> 4
    assert frames[2].gray()[0, 80] == round(round(4095 * SKY) * 255 / 4095)
    mixed = (f"{stream}: frame 1: an 8-bit frame among 16-bit ones (values of 12 bits, "
             "0..4095 scaled to 0..255): read as it is, 0..255 (the sequence's depth is its "
             "first frame's; later frames of another depth are not named)")
    assert warnings[1:] == [mixed]
    out = tmp_path / "out"
    with open(stream, "rb") as feed:
        done = subprocess.run([sys.executable, "-m", "vtrack", "run", "-", "--format",
                               "image2pipe", "--init", "20,40,6,6", "-c", "s2", "-q",
                               "--no-video", "-o", str(out)], stdin=feed, capture_output=True,
                              text=True, timeout=120, check=False)
    assert done.returncode == 0, done.stderr
    run = json.loads((out / "run.json").read_text())
    assert run["frames"] == 3
    assert run["warnings"][1] == mixed.replace(str(stream), "-")


@pytest.mark.parametrize("given", ["folder", "video"])
def test_a_dark_first_frame_does_not_white_out_the_rest(tmp_path: Path, given: str) -> None:
    """A black first frame (a lens cap, a shutter frame) then 12-bit frames, then 14-bit ones:
    the scale was the first frame's 8-bit floor, every later value clipped at 255 (a white
    picture) and the warning said "0..255 scaled to 0..255". It rises with the bits a later
    frame uses, one warning per rise, and never falls."""
    pictures = [np.zeros((120, 160), np.uint16), scene(12, 1), scene(12, 2), scene(14, 3),
                scene(12, 4)]
    if given == "folder":
        path = tmp_path / "seq"
        path.mkdir()
        for i, picture in enumerate(pictures):
            assert cv2.imwrite(str(path / f"{i:04d}.png"), picture)
        source: ImageFolderSource | VideoSource = ImageFolderSource(str(path))
        what, rise = "image", [f"{path / '0001.png'}: frame 1", f"{path / '0003.png'}: frame 3"]
    else:
        path = tmp_path / "dark.mkv"
        with av.open(str(path), "w") as container:
            stream = container.add_stream("ffv1", rate=30)
            stream.width, stream.height, stream.pix_fmt = 160, 120, "gray16le"
            for picture in pictures:
                for packet in stream.encode(av.VideoFrame.from_ndarray(picture,
                                                                       format="gray16le")):
                    container.mux(packet)
            for packet in stream.encode():
                container.mux(packet)
        source = VideoSource(str(path))
        what, rise = "frame", [f"{path}: frame 1", f"{path}: frame 3"]
    with source:
        frames = [frame.gray() for frame in source]
        warnings = source.warnings
    assert warnings == [
        f"{path}: 16-bit grey {what}s whose values use 8 bits or fewer (the first {what}'s, hot "
        f"pixels aside): read as 8-bit grey, 0..255 as they are (a later {what} whose values "
        "use more bits scales by them from it on, with a warning; isolated brighter pixels "
        "clip at 255)",
        f"{rise[0]}'s values use 12 bits, more than before: scaled 0..4095 to 0..255 from this "
        f"{what} on",
        f"{rise[1]}'s values use 14 bits, more than before: scaled 0..16383 to 0..255 from "
        f"this {what} on"]
    assert frames[0].max() == 0
    sky12, sky14 = round(4095 * SKY), round(16383 * SKY)
    assert frames[2][0, 80] == round(sky12 * 255 / 4095)  # 76, not 255
    assert frames[3][0, 80] == round(sky14 * 255 / 16383)
    assert frames[4][0, 80] == round(sky12 * 255 / 16383)  # the scale does not fall back


@pytest.mark.parametrize("shape", [(2, 8), (1, 8), (2, 8, 3), (16, 16), (16, 16, 3)])
def test_a_later_picture_using_more_bits_raises_the_scale_whatever_its_size(
        shape: tuple[int, ...]) -> None:
    """A value of 12 bits in a later picture of a 10-bit sequence raises the scale to 12 bits
    with a warning. A picture under 3 pixels high or wide (no 3x3 median: its plain largest
    value) clipped it instead, silently, once a shortcut skipped the median for fewer than two
    values above the scale; a picture with two such values side by side still raises it, and a
    lone stuck pixel (the median sets it aside) does not."""
    from vtrack.io.depth import DepthScale
    first = np.full(shape, 1000, np.uint16)
    scale = DepthScale("seq", first)
    assert scale.bits == 10
    later = first.copy()
    if min(shape[:2]) < 3:
        later[0, 0] = 4000
    else:
        later[4:7, 4:7] = 4000  # a patch the 3x3 median keeps
        later[0, 15] = 65535  # and a stuck pixel it sets aside
    out = scale.frame(later, 1)
    assert scale.bits == 12
    spot = (0, 0) if min(shape[:2]) < 3 else (5, 5)
    assert int(np.max(out[spot])) == round(4000 * 255 / 4095)  # not clipped at 255
    assert any("frame 1's values use 12 bits" in text for _, text in scale.news())
    stuck = first.copy()
    stuck[0, 0] = 65535
    if min(shape[:2]) >= 3:
        scale.frame(stuck, 2)
        assert scale.bits == 12  # (the median sets a lone stuck pixel aside)
