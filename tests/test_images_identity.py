"""The fingerprint run.json records of an image sequence (``input.image_identity``)."""

from __future__ import annotations

from pathlib import Path

from vtrack.io.identity import images_identity


def _sequence(folder: Path, images: list[bytes]) -> list[Path]:
    folder.mkdir()
    paths = [folder / f"{n:04d}.bmp" for n in range(1, len(images) + 1)]
    for path, data in zip(paths, images, strict=True):
        path.write_bytes(data)
    return paths


def test_the_fingerprints_parts_do_not_run_into_each_other(tmp_path: Path) -> None:
    """The total size was hashed as decimal text right before the first image's bytes: a
    sequence of 10 bytes whose first image is b"7abc" and one of 107 bytes whose first image
    is b"abc" (same last image) both hashed "107abc...", one fingerprint for two sequences.
    The total is hashed as 8 bytes now, and so is each hashed image's size before its bytes
    (b"ab" then b"c" ran into b"a" then b"bc" the same way)."""
    one = _sequence(tmp_path / "one", [b"7abc", b"m" * 4, b"zz"])
    other = _sequence(tmp_path / "other", [b"abc", b"m" * 102, b"zz"])
    assert sum(p.stat().st_size for p in one) == 10
    assert sum(p.stat().st_size for p in other) == 107
    assert images_identity(one) != images_identity(other)
    assert images_identity(one) == images_identity(_sequence(tmp_path / "again", [
        b"7abc", b"n" * 4, b"zz"]))  # (the middle images count by their size only)
    assert images_identity(_sequence(tmp_path / "ab", [b"ab", b"m", b"c"])) != images_identity(
        _sequence(tmp_path / "bc", [b"a", b"m", b"bc"]))
