"""Media as cameras, phones and tools write them: photos with an orientation tag, audio files
with cover art, recordings cut before they were finished, containers given as raw frames."""

from __future__ import annotations

from pathlib import Path

import numpy as np
from PIL import Image

from vtrack.io import open_source

#: EXIF Orientation 6: the stored picture is shown turned 90 degrees clockwise (a phone held
#: upright).
EXIF_ORIENTATION, UPRIGHT_FROM_LANDSCAPE = 0x0112, 6


def _phone_photo(path: Path, marker_x: int) -> Path:
    """A 64x48 stored picture tagged to be shown upright (48x64), a bright marker at its
    top-left corner shifted right by ``marker_x``."""
    pixels = np.full((48, 64, 3), 60, np.uint8)
    pixels[:12, marker_x:marker_x + 12] = 250
    exif = Image.Exif()
    exif[EXIF_ORIENTATION] = UPRIGHT_FROM_LANDSCAPE
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
