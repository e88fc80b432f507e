"""Fingerprints of files, so a record can tell later whether they are still the ones it saw.

``run.json`` records the identity of its input and ground truth (:func:`file_identity`: size
and modification time), the size of each output it verified (:func:`sizes`) and, for an image
sequence, a fingerprint of its images (:func:`images_identity`: what tells two sequences of one
name apart in a report). ``vtrack batch`` reuses a result only when its input, ground truth and
outputs still match (:func:`outputs_intact`), and ``vtrack report`` refuses a ``track.csv``
whose size is not the recorded one.
"""

from __future__ import annotations

import hashlib
import os
from collections.abc import Iterable, Mapping, Sequence
from pathlib import Path
from typing import Any


def file_identity(path: str | Path | None) -> dict[str, int] | None:
    """``{"size", "mtime_ns"}`` of a regular file; for a folder (an image sequence) the number
    of files below it (``files``), their total size and their latest modification time. None
    for anything else: no path, a missing one, stdin (``-``), a URL, a FIFO or a device."""
    if path is None or str(path) == "-":
        return None
    try:
        stat = os.stat(path)
    except (OSError, ValueError):
        return None
    if os.path.isdir(path):
        return _folder_identity(Path(path))
    if not os.path.isfile(path):
        return None
    return {"size": stat.st_size, "mtime_ns": stat.st_mtime_ns}


def _folder_identity(folder: Path) -> dict[str, int]:
    files = size = latest = 0
    for root, _, names in os.walk(folder):
        for name in names:
            try:
                stat = os.stat(os.path.join(root, name))
            except OSError:
                continue
            files, size, latest = files + 1, size + stat.st_size, max(latest, stat.st_mtime_ns)
    return {"files": files, "size": size, "mtime_ns": latest}


def images_identity(paths: Sequence[Path]) -> str | None:
    """A fingerprint of an image sequence's images ``paths`` (in frame order, at least one):
    a hash of their total size and of the first and last images' bytes, each after its size
    (sizes as 8 bytes, little-endian: no two sequences' parts run into each other), which
    tells two sequences of one name, frame count and frame size apart even when every image
    of both has one size (uncompressed BMP, PPM, TIFF). None when an image cannot be looked
    at or read (gone)."""
    digest = hashlib.blake2b(digest_size=16)
    try:
        digest.update(sum(path.stat().st_size for path in paths).to_bytes(8, "little"))
        for path in (paths[0], paths[-1]) if len(paths) > 1 else paths[:1]:
            with path.open("rb") as file:
                digest.update(os.fstat(file.fileno()).st_size.to_bytes(8, "little"))
                while chunk := file.read(1 << 20):
                    digest.update(chunk)
    except OSError:
        return None
    return digest.hexdigest()


def sizes(folder: Path, names: Iterable[str]) -> dict[str, int]:
    """The size in bytes of each file ``names`` in ``folder`` (missing ones are left out)."""
    found = {}
    for name in names:
        try:
            found[name] = (folder / name).stat().st_size
        except OSError:
            continue
    return found


def outputs_intact(folder: Path, record: Mapping[str, Any], required: Iterable[str]) -> bool:
    """Whether every output a ``run.json`` ``record`` lists is still in ``folder`` with the
    size it recorded, and the ``required`` names are among them."""
    outputs = record.get("outputs")
    recorded = record.get("output_bytes")
    if not isinstance(outputs, list) or not isinstance(recorded, dict):
        return False
    if not set(required) <= set(outputs) or set(outputs) - set(recorded):
        return False
    return sizes(folder, outputs) == {name: recorded[name] for name in outputs}
