"""16-bit grey image sequences (a thermal camera's 12- or 14-bit values in 16-bit files)."""

from __future__ import annotations

import json
from pathlib import Path

import cv2
import numpy as np
import pytest
from click.testing import CliRunner

from vtrack.cli import main
from vtrack.io.images import ImageFolderSource, read_image

SKY, TARGET, BOX = 0.3, 0.9, 6


def write_sequence(folder: Path, bits: int, frames: int = 20, ext: str = ".png") -> Path:
    """A small bright target crossing a flat sky, values of ``bits`` bits in 16-bit images,
    with two hot pixels at 65535; OTB ground truth beside it."""
    folder.mkdir()
    top = (1 << bits) - 1
    boxes = []
    for i in range(frames):
        image = np.full((120, 160), round(top * SKY), np.uint16)
        x, y = 20 + 4 * i, 40 + i
        image[y:y + BOX, x:x + BOX] = round(top * TARGET)
        image[5, 5] = image[100, 150] = 65535
        assert cv2.imwrite(str(folder / f"frame_{i:04d}{ext}"), image)
        boxes.append(f"{x + 1},{y + 1},{BOX},{BOX}")
    (folder / "groundtruth_rect.txt").write_text("\n".join(boxes) + "\n")
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
        f"pixels aside): read as 8-bit grey, 0..{top} scaled to 0..255 (a brighter value "
        "clips at 255)"]
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
