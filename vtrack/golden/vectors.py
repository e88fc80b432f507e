"""Test vectors of the golden models for an HDL bench, and the comparison of a simulator's dump.

Layout of ``DIR`` (``vtrack vectors INPUT --config s0-fixed|s2-fixed --out DIR``)::

    DIR/manifest.json          formats, widths, roundings, frame size, config, input
    DIR/trace.csv              one row per frame (S0: window, sums, step, Kalman float32 ...)
    DIR/iterations.csv         S2 only: one row per mean-shift iteration
    DIR/frame_0000/rgb.hex     one RRGGBB per pixel, raster order, the whole frame
    DIR/frame_0000/hue.hex     S0: one HH per pixel (8-bit hue of eq. 1)
    DIR/frame_0001/bp.hex      S0, frames >= 1: one HH per pixel (BP of eq. 4, 0 where masked)
    DIR/frame_0000/gray.hex    S2: one HH per pixel (8-bit grey, BT.601 integer weights)

Every ``.hex`` file is lower-case hex, one value per line, no address, no prefix: Verilog
``$readmemh`` loads it as it is. The hex text is built with NumPy from a table of the 256
two-character codes, never a Python loop per pixel.
"""

from __future__ import annotations

import contextlib
import csv
import io
import json
import math
import os
import re
from collections.abc import Callable, Iterator
from pathlib import Path
from typing import Any

import numpy as np

from vtrack.errors import ConfigError, InputError, OutputError, printable, shell_word
from vtrack.golden import s0
from vtrack.golden.record import FixedRecord
from vtrack.golden.s2 import gray8
from vtrack.io.files import (
    StagedFiles,
    file_in_the_way,
    os_reason,
    prepare_output_dir,
    removing_new_folders,
)

#: Largest --frames: a 1080p frame writes ~25 MB of hex text (rgb + hue + bp).
MAX_FRAMES = 300
#: How many differences per file ``check`` names.
SHOWN = 3

_HEX = np.frombuffer(b"".join(f"{i:02x}".encode() for i in range(256)), np.uint8).reshape(256, 2)
_NEWLINE = ord("\n")


def hex_lines(*planes: np.ndarray) -> bytes:
    """The ``$readmemh`` text of one or more uint8 planes of the same shape: per pixel (raster
    order) the planes' two hex digits side by side, then a newline (3 planes: ``RRGGBB``)."""
    count = planes[0].size
    out = np.empty((count, 2 * len(planes) + 1), np.uint8)
    for i, plane in enumerate(planes):
        out[:, 2 * i : 2 * i + 2] = _HEX[plane.reshape(-1)]
    out[:, -1] = _NEWLINE
    return out.tobytes()


def fixed_stage(stages: list[Any], config_name: str) -> Any:
    """The stage of the chain that owns the golden record (``hue_bp_fixed`` or
    ``kernel_meanshift_int``); ConfigError when the config has none."""
    for stage in stages:
        if hasattr(stage, "record"):
            return stage
    raise ConfigError(
        f"--config {config_name}: not a fixed-point config; vectors need s0-fixed or s2-fixed "
        "(or a config with stage hue_bp_fixed or kernel_meanshift_int)"
    )


def _formats(record: FixedRecord, width: int, height: int) -> dict[str, Any]:
    pixel = {"order": "raster: line = y * width + x", "width": width, "height": height,
             "lines": width * height}
    files: dict[str, Any] = {
        "rgb.hex": {**pixel, "format": "RRGGBB, 24 bits, R in bits 23:16", "frames": "all"},
    }
    if record.model == "s0":
        files["hue.hex"] = {**pixel, "format": "HH, 8 bits", "frames": "all",
                            "value": "floor(H_deg * 255 / 360), H_deg the exact rational of eq. "
                                     "1 (max == min -> 0; max ties R, G, B in that order)"}
        files["bp.hex"] = {**pixel, "format": "HH, 8 bits", "frames": ">= 1",
                           "value": "floor(hist[hue] * 255 / max) (eq. 4); 0 where masked"}
    else:
        files["gray.hex"] = {**pixel, "format": "HH, 8 bits", "frames": "all",
                             "value": "(77 R + 150 G + 29 B + 128) >> 8"}
    return files


def frame_files(frame_bgr: np.ndarray, record: FixedRecord, index: int) -> dict[str, bytes]:
    """The frame's ``.hex`` files (see the module docstring), by name: their text."""
    r, g, b = s0.split_rgb(frame_bgr)
    files = {"rgb.hex": hex_lines(*(p.astype(np.uint8) for p in (r, g, b)))}
    if record.model == "s0":
        hue = s0.hue8(r, g, b, record.hue_divider_bits)
        files["hue.hex"] = hex_lines(hue)
        if index >= 1:
            assert record.bp_lut is not None
            mask = s0.optional_mask(r, g, b, record.sat_min, record.val_min)
            bp = s0.back_project(record.bp_lut, hue, mask)
            files["bp.hex"] = hex_lines(bp)
    else:
        files["gray.hex"] = hex_lines(gray8(r, g, b))
    return files


def _stage_frame(staged: StagedFiles, folder: Path, files: dict[str, bytes]) -> list[Path]:
    """Stage ``files`` in ``folder``: as a new folder, or one by one into the folder there
    (which may hold files of the user's own: they stay); their paths. OutputError naming
    ``folder`` when something other than a folder is at its path."""
    paths = [folder / name for name in files]
    if folder.is_dir():
        for path, data in zip(paths, files.values(), strict=True):
            staged.write(path, lambda temp, data=data: temp.write_bytes(data))
        return paths
    if os.path.lexists(folder):
        raise file_in_the_way(folder, folder)
    staged.write(folder, lambda temp: _write_folder(temp, files))
    return paths


def _write_folder(folder: Path, files: dict[str, bytes]) -> None:
    """Make ``folder`` holding ``files`` (name -> bytes)."""
    folder.mkdir()
    for name, data in files.items():
        (folder / name).write_bytes(data)


def _cell(value: Any) -> str:
    if isinstance(value, float):
        return repr(value) if math.isfinite(value) else ""
    return str(value)


class TraceWriter:
    """A CSV whose columns are the first row's keys (every later row has the same keys)."""

    def __init__(self, path: Path) -> None:
        self._file = path.open("w", newline="", encoding="utf-8")
        self._writer = csv.writer(self._file, lineterminator="\n")
        self.columns: list[str] | None = None

    def write(self, row: dict[str, Any]) -> None:
        if self.columns is None:
            self.columns = list(row)
            self._writer.writerow(self.columns)
        self._writer.writerow([_cell(row.get(c, "")) for c in self.columns])

    def close(self) -> None:
        self._file.close()


def manifest(record: FixedRecord, width: int, height: int, stages: list[Any],
             extra: dict[str, Any]) -> dict[str, Any]:
    """What ``manifest.json`` says: files, formats, widths, roundings, the chain's settings."""
    data: dict[str, Any] = {
        "model": record.model,
        "files": _formats(record, width, height),
        "stages": [{"name": s.name, **s.settings()} for s in stages],
        **extra,
    }
    if record.model == "s0":
        assert record.hist is not None
        data["s0"] = {
            "hue": "H8 = floor(17 * (60 * num + off * d) / (24 * d)), integer; eq. 1",
            "histogram": f"256 counters of {stages[0].hist_bits} bits, saturating; "
                         "over the first frame's integer box (eq. 2-3)",
            "histogram_counts": [int(v) for v in record.hist],
            "histogram_max": record.hist_max,
            "bp": "floor(hist * 255 / max), 8 bits (eq. 4)",
            "window": "x = c - w // 2, ref = x + w // 2 (c: centre pixel); the first frame's "
                      "window is the initial box; pixels outside the frame are not summed",
            "sums": "sum_bp, sum_bp_dx = sum bp (x - ref_x), sum_bp_dy: exact signed integers "
                    "(int64 here; bits needed <= 8 + log2(n) + log2(w))",
            "step": "step = sum_bp_dx * 2^f / den, den = sum_bp (weighted) or n * 255 (paper), "
                    "f = step_frac_bits, rounded as meanshift_fixed.rounding; 0 if sum_bp = 0",
            "kalman": "IEEE-754 binary32 per axis, eq. 10-17 in print order, additions left "
                      "to right, round to nearest even, no FMA; columns k<axis>_<name> decimal "
                      "and k<axis>_<name>_hex (bit pattern); l1, l2, pm* = prior (eq. 10-12), "
                      "k1, k2 = gain (eq. 14), x, dx, p* = posterior (eq. 15-17)",
            "prediction": "pred_x = floor(l1 + 0.5) in float32: the next window's centre pixel",
            "box": "box_x, box_y, box_w, box_h: vtrack's box (pixel i covers [i, i+1)), "
                   "centre = measured pixel + 0.5",
        }
    if record.model == "s2":
        assert record.hist is not None
        data["s2"] = _S2_COLUMNS | {
            "histogram_counts": [int(v) for v in record.hist],
            "histogram_max": record.hist_max,
        }
    return data


#: What ``manifest.json`` says of S2's ``trace.csv`` and ``iterations.csv`` (as the ``s0``
#: section does of S0's): each column, its unit and when it is empty.
_S2_COLUMNS: dict[str, str] = {
    "grey": "gray.hex: (77 R + 150 G + 29 B + 128) >> 8; bin b = grey * m >> 8 (m: bins)",
    "histogram": "q_u = sum K [b = u] over the first frame's window about the initial box's "
                 "centre pixel, K = h_x - |dx| + h_y - |dy|, h = round(size) // 2; "
                 "histogram_counts: q_u, C = their sum (trace column c)",
    "trace": "one row per frame: pred_x, pred_y = floor of the Kalman prediction's centre "
             "(empty on frame 0); found_x, found_y = the search's converged pixel; r, r_prime "
             "= |found - pred| summed over both axes (eq. 17) before and after the search "
             "from the prediction (empty when not computed or no bin was seen); decision: "
             "accept, fast_motion or occlusion (sec. 5); x, y = the centre pixel kept; s = "
             "scale x 1000 (s_0 = 1000); rho = sum_u min(q_u, C p_u // C') at found; c = C; "
             "iterations = steps over every scale; box_x, box_y, box_w, box_h: vtrack's box "
             "(centre = x + 0.5, size = initial size * s / 1000)",
    "iterations": "iterations.csv, one row per mean-shift step: search = 0 from the last "
                  "position, 1 from the prediction; s_t = 9, 10 or 11 times s; iteration "
                  "counts from 1 per scale; x, y = the window's centre pixel; c_prime = C' = "
                  "sum K of its in-frame pixels; sum_w, sum_w_dx, sum_w_dy = the step-5 sums "
                  "of w_u = (q_u << F) // p_u (F: weight_frac_bits); new_x, new_y = x, y + the "
                  "step rounded as kernel_meanshift_int.rounding; rho at the scale's last step "
                  "only (empty before)",
}


def generate(frames: Iterator[Any], stages: list[Any], pipeline: Any, init_box: Any,
             out_dir: Path, extra: dict[str, Any],
             settled: Callable[[], object] | None = None) -> int:
    """Run the chain over ``frames`` and write the vectors to ``out_dir``; returns the number of
    frames written. Every file is written under a temporary name and they are put in place
    together, ``manifest.json`` last, once all are complete; then the vector files an earlier
    ``generate`` left there that were not replaced are removed: when the writing stops part
    way (an error, Ctrl-C, SIGTERM) the temporary files are removed, an earlier set of
    vectors stays as it was, and a folder it created for them is removed. A folder at the
    path of one of its files, or something else at a frame folder's, is refused (OutputError)
    before anything is put in place. ``settled()`` is called as they start
    to be put in place (:class:`~vtrack.io.files.StagedFiles`)."""
    owner = fixed_stage(stages, str(extra.get("config")))
    with removing_new_folders(out_dir):
        with StagedFiles(settled) as staged:
            prepare_output_dir(out_dir)  # OutputError naming it: a file, read-only, ...
            for name in _TABLES:  # (refused before a frame is read, and before any rename)
                if (out_dir / name).is_dir():
                    raise OutputError(f"{out_dir / name}: cannot write (a folder of that name "
                                      "is in the way)")
            count, size, record, written = _stage_vectors(
                staged, pipeline.track(frames, init_box), owner, out_dir)
            if record is None:
                raise InputError(f"{extra.get('input')}: no frame decoded")
            data = manifest(record, size[0], size[1], stages, {**extra, "frames": count})
            written.add(staged.write(out_dir / "manifest.json",
                                     lambda temp: temp.write_text(
                                         json.dumps(data, indent=2) + "\n", encoding="utf-8")))
        _remove_earlier_vectors(out_dir, written)  # the staged files are in place now
    return count


def _stage_vectors(staged: StagedFiles, results: Iterator[Any], owner: Any, out_dir: Path
                   ) -> tuple[int, tuple[int, int], FixedRecord | None, set[Path]]:
    """Stage the frame folders, ``trace.csv`` and ``iterations.csv`` of ``results`` in
    ``out_dir``: the frames written, the last frame's size, the last golden record (None:
    no frame) and the paths of the files staged."""
    trace = TraceWriter(staged.temp(out_dir / "trace.csv"))
    written = {out_dir / "trace.csv"}
    iterations: TraceWriter | None = None
    count, size, record = 0, (0, 0), None
    try:
        for result in results:
            record = owner.record
            assert record is not None and result.frame is not None
            frame = result.frame
            size = (frame.width, frame.height)
            # named by the input's frame number, as trace.csv's rows (a skipped frame: a gap)
            folder = out_dir / f"frame_{result.index:04d}"
            written.update(_stage_frame(staged, folder, frame_files(frame.bgr(), record,
                                                                    count)))
            trace.write(record.trace)
            if record.model == "s2":
                if iterations is None:
                    iterations = TraceWriter(staged.temp(out_dir / "iterations.csv"))
                    written.add(out_dir / "iterations.csv")
                for row in record.iterations:
                    iterations.write(row)
            count += 1
    finally:
        trace.close()
        if iterations is not None:
            iterations.close()
    return count, size, record, written


#: The files of a set of vectors beside its frame folders.
_TABLES = ("manifest.json", "trace.csv", "iterations.csv")


def _is_frame_folder(name: str) -> bool:
    """Whether ``name`` is that of a frame folder of vectors: ``frame_`` and a number."""
    return name.startswith("frame_") and name.removeprefix("frame_").isdigit()


def _remove_earlier_vectors(out_dir: Path, written: set[Path]) -> None:
    """Remove the vector files an earlier ``generate`` left in ``out_dir`` that are not among
    those just ``written`` (its frame folders, traces and manifest; nothing else), so that no
    frame of another run is checked against. Best effort: one that cannot be removed stays."""
    folders = [folder for folder in out_dir.glob("frame_*")
               if folder.is_dir() and _is_frame_folder(folder.name)]
    stale = [out_dir / name for name in _TABLES] + [
        vector for folder in folders for vector in folder.glob("*.hex")
        if not vector.name.startswith(".")]  # (not a temporary name)
    for path in stale:
        if path not in written and path.is_file():
            with contextlib.suppress(OSError):
                path.unlink()
    for folder in folders:
        with contextlib.suppress(OSError):  # one holding new vectors or the user's files
            folder.rmdir()


# --- check ---------------------------------------------------------------------------------------


#: Longest value of a dump shown in a difference line (a damaged file may hold a 10 MB line).
_VALUE_SHOWN = 16


def _shown(token: bytes | str) -> str:
    """A value of a dump as text for a message: undecodable bytes escaped, cut short."""
    head = token[:_VALUE_SHOWN]
    text = head.decode("ascii", "backslashreplace") if isinstance(head, bytes) else head
    return text + "..." if len(token) > _VALUE_SHOWN else text


#: ``$readmemh`` comments: ``// ...`` to the end of the line and ``/* ... */``.
_MEMH_COMMENT = re.compile(rb"//[^\n]*|/\*.*?\*/", re.S)


def _memh_value(token: bytes) -> int | bytes:
    """A ``$readmemh`` word as its number; a word that is none (``xx``, ``zz``) as it is."""
    try:
        return int(token, 16)
    except ValueError:
        return token


def memh_values(text: bytes, limit: int) -> tuple[list[int | bytes], int]:
    """What ``$readmemh`` loads from ``text``: the first ``limit`` words in address order
    (comments skipped, ``@addr`` moving the address, a word without leading zeros the same
    number; an address left unwritten ``b"(none)"``) and the number of addresses loaded (the
    highest + 1). Only ``limit`` words are kept, whatever addresses the text names."""
    if b"/" in text:
        text = _MEMH_COMMENT.sub(b" ", text)
    tokens = text.split()
    if b"@" not in text:
        return [_memh_value(t) for t in tokens[:limit]], len(tokens)
    values: list[int | bytes] = [b"(none)"] * limit
    address = count = 0
    for token in tokens:
        if token.startswith(b"@"):
            moved = _memh_value(token[1:])
            if isinstance(moved, int):
                address = moved
                continue
        if address < limit:
            values[address] = _memh_value(token)
        address += 1
        count = max(count, address)
    return values[:count], count


def _shown_word(value: int | bytes, digits: int) -> str:
    """A word ``$readmemh`` loaded, for a message: a number in ``digits`` hex digits (at
    least), else as it is; cut short either way (a damaged dump's word may be 10 MB long)."""
    return _shown(f"{value:0{digits}x}" if isinstance(value, int) else value)


def _hex_differences(name: str, expected: bytes, got: bytes, width: int) -> str | None:
    got = got.lower()
    if expected == got:
        return None
    want = expected.split()
    digits = len(want[0]) if want else 2
    have, count = memh_values(got, len(want))
    lines = []
    n = min(len(want), len(have))
    a = np.array([_memh_value(w) for w in want[:n]], dtype=object)  # (a vector may be xx)
    b = np.array(have[:n], dtype=object)
    bad = np.flatnonzero(a != b)
    for i in bad[:SHOWN]:
        x, y = (int(i) % width, int(i) // width) if width else (0, 0)
        lines.append(f"line {i + 1} (x={x}, y={y}): expected {_shown(want[i])}, "
                     f"got {_shown_word(have[i], digits)}")
    body = _differences(len(bad), lines, _length(count, len(want), "lines"))
    return None if body is None else f"{name}: {body}"


def _length(count: int, expected: int, unit: str) -> str | None:
    """How a dump's length (``count`` lines or rows) differs from the vectors' (None: it
    does not): a shorter one is truncated."""
    if count < expected:
        return f"truncated ({count} of {expected} {unit})"
    return f"{count} {unit}, expected {expected}" if count > expected else None


def _differences(differing: int, shown: list[str], length: str | None) -> str | None:
    """A file's difference line after its name: the number of differing values and the first
    of them (none said when none differs), then how its length differs; None when equal."""
    parts = ([f"{differing} differing value(s)", *shown] if differing else []) + (
        [length] if length is not None else [])
    return "; ".join(parts) if parts else None


def _shown_cell(text: str | None) -> str:
    """A CSV value for a message: an empty or missing one is ``nothing``."""
    return _shown(text) if text else "nothing"


def _cells(row: dict[Any, Any]) -> dict[str | None, str]:
    """A row of :class:`csv.DictReader` as text only: a value missing from a short row is "",
    and the values past the header's columns (DictReader's key None, "" when there are none)
    are one text, joined by commas, under the key None."""
    cells: dict[str | None, str] = {k: v or "" for k, v in row.items() if k is not None}
    cells[None] = ",".join(row.get(None) or [])
    return cells


def _same_cell(a: str, b: str) -> bool:
    if a == b:
        return True
    try:
        return float(a) == float(b)
    except ValueError:
        return a.lower() == b.lower()


#: How many missing column names a difference line lists.
_COLUMNS_SHOWN = 8


def _read_expected_csv(path: Path, ours: bool, frames: int | None
                       ) -> tuple[list[str], list[dict[str, str]]]:
    """The header and rows of a vectors CSV; InputError naming it when it cannot be read, and
    when ``ours`` (one of :data:`_TABLES`, not a file of the user's own) also when a row's
    values do not match the header's columns (a file cut short inside a row) or it holds
    another number of rows than ``frames`` (None: unknown)."""
    try:
        with path.open(newline="", encoding="utf-8-sig") as f:
            text = f.read()
        reader = csv.DictReader(io.StringIO(text, newline=""))
        header = list(reader.fieldnames or [])
        # each row with the line it ends on (blank lines are skipped, a quoted value may span
        # lines: not one line per row)
        numbered = [(row, reader.line_num) for row in reader]
    except (OSError, UnicodeDecodeError, csv.Error) as exc:
        raise InputError(f"{path}: not a vectors CSV file ({os_reason(exc)})") from None
    rows = [row for row, _ in numbered]
    if not ours:
        return header, rows
    if text and not text.endswith("\n"):  # each row of the file ends with one
        raise _damaged(path, f"its last line, {text.count(chr(10)) + 1}, is cut short")
    for row, number in numbered:
        if None in row or None in row.values():  # (DictReader's marks of a ragged row)
            values = sum(v is not None for k, v in row.items() if k is not None) + len(
                row.get(None) or [])
            raise _damaged(path, f"line {number} has {values} values where the header names "
                                 f"{len(header)} columns")
    if frames is not None and len(rows) != frames:
        raise _damaged(path, f"{len(rows)} rows where its manifest.json gives {frames} frames")
    return header, rows


def _damaged(path: Path, problem: str) -> InputError:
    """The error for a file of a vectors folder that is not as ``vtrack vectors`` wrote it
    (cut short, changed): comparing a dump with it would blame the dump."""
    return InputError(f"{path}: not the file vtrack vectors wrote ({problem}); write the "
                      "vectors again")


def _refuse_a_damaged_hex(path: Path, data: bytes, manifest: dict[str, Any]) -> None:
    """InputError (:func:`_damaged`) when ``data``, the ``.hex`` file at ``path`` in a frame
    folder of the vectors (``frame_NNNN/``; the caller's to know), is not as ``vtrack vectors``
    writes it: as many lines as its ``manifest.json`` gives (``files.NAME.lines``), each of 6
    (``rgb.hex``) or 2 hex digits (of either case: values compare as numbers) and its line end
    (``\\n``, or ``\\r\\n`` of a Windows checkout). A file the manifest does not describe
    (one of the user's own) is compared as it is."""
    spec = manifest["files"].get(path.name)
    lines = spec.get("lines") if isinstance(spec, dict) else None
    if isinstance(lines, bool) or not isinstance(lines, int) or lines <= 0:
        return
    digits = 6 if path.name == "rgb.hex" else 2
    word = rb"[0-9a-fA-F]{%d}" % digits
    if re.fullmatch(rb"(?:%s\r?\n)*" % word, data) is None:
        words = re.split(rb"\r?\n", data)
        if words[-1]:  # what follows the last newline: nothing in a whole file
            raise _damaged(path, f"its last line, {len(words)}, is cut short")
        number, bad = next((i, w) for i, w in enumerate(words, 1)
                           if not re.fullmatch(word, w))
        raise _damaged(path, f"line {number} is {_shown(bad) or 'empty'}, not {digits} hex "
                             "digits")
    count = data.count(b"\n")
    if count != lines:
        raise _damaged(path, f"{count} lines where its manifest.json gives {lines}")


def _missing_columns(name: str, want: list[str], have: list[str]) -> str | None:
    """The line naming the columns of the vectors the dump's header lacks (names compare
    exactly, case included) when it cannot be compared: it lacks ``frame``, or every other
    column. None when it can: a bench may dump only the columns its RTL produces, and the
    columns it lacks are not compared."""
    missing = [c for c in want if c not in have]
    if "frame" not in missing and len(missing) < len(want) - 1:
        return None
    shown = ", ".join(missing[:_COLUMNS_SHOWN]) + (", ..." if len(missing) > _COLUMNS_SHOWN
                                                    else "")
    line = f"{name}: missing {len(missing)} column(s) of the vectors: {shown}"
    folded = {c.casefold() for c in have}
    if any(c.casefold() in folded for c in missing):
        line += " (column names are case-sensitive)"
    return line


def _csv_differences(name: str, expected: Path, got: Path, ours: bool, frames: int | None
                     ) -> str | None:
    columns, want = _read_expected_csv(expected, ours, frames)
    try:
        # utf-8-sig: a header saved with a byte-order mark (Excel) names its first column
        with got.open(newline="", encoding="utf-8-sig") as f:
            reader = csv.DictReader(f)
            have = list(reader)
            header = list(reader.fieldnames or [])
    except (UnicodeDecodeError, csv.Error) as exc:
        return f"{name}: unreadable CSV ({exc})"
    except OSError as exc:
        raise InputError(f"{got}: cannot be read ({os_reason(exc)})") from None
    missing = _missing_columns(name, columns, header)
    found: list[str] = []
    total = 0
    for i, (raw_w, raw_h) in enumerate(zip(want, have, strict=False)):
        row_w, row_h = _cells(raw_w), _cells(raw_h)
        for column, value in row_h.items():
            if column not in row_w:
                continue  # a dump may hold extra columns
            if not _same_cell(row_w[column], value):
                total += 1
                if len(found) < SHOWN:
                    frame = row_w.get("frame") or str(i)
                    where = "values past the header" if column is None else f"column {column}"
                    found.append(f"frame {frame} {where}: expected "
                                 f"{_shown_cell(row_w[column])}, got {_shown_cell(value)}")
    body = _differences(total, found, _length(len(have), len(want), "rows"))
    if body is None:
        return missing
    return f"{name}: {body}" if missing is None else f"{missing}; {body}"


def _read_manifest(vectors: Path) -> dict[str, Any]:
    """``manifest.json`` of ``vectors``, whose ``files.rgb.hex.width`` is the frame width;
    InputError naming the manifest when it is missing, not JSON or not a vectors manifest."""
    path = vectors / "manifest.json"
    try:
        info = json.loads(path.read_text(encoding="utf-8"))
    except (OSError, ValueError) as exc:  # UnicodeDecodeError is a ValueError
        raise InputError(f"{vectors}: not a vectors folder (manifest.json: {os_reason(exc)})"
                         ) from None
    files = info.get("files") if isinstance(info, dict) else None
    rgb = files.get("rgb.hex") if isinstance(files, dict) else None
    width = rgb.get("width") if isinstance(rgb, dict) else None
    if isinstance(width, bool) or not isinstance(width, int) or width <= 0:
        raise InputError(f"{path}: not a vectors manifest (no whole positive "
                         "files.rgb.hex.width, the frame width; written by vtrack vectors)")
    return info


def other_version(vectors: Path, version: str) -> str | None:
    """The vtrack version ``vectors``' ``manifest.json`` says wrote them, when it is not
    ``version`` (None when it is, or names none): vectors keep their format across versions,
    but a difference a check finds may be the two versions'. InputError as ``check`` gives
    for a folder that holds no vectors manifest."""
    written = _read_manifest(vectors).get("vtrack")
    return written if isinstance(written, str) and written != version else None


def _frames_of(manifest: dict[str, Any]) -> int | None:
    """The number of frames ``manifest`` gives (trace.csv's rows), None when none."""
    frames = manifest.get("frames")
    return None if isinstance(frames, bool) or not isinstance(frames, int) else frames


def _config_of(folder: Path) -> str | None:
    """The config ``folder``'s ``manifest.json`` names (None: it has none, or names none)."""
    try:
        info = json.loads((folder / "manifest.json").read_text(encoding="utf-8"))
    except (OSError, ValueError):
        return None
    config = info.get("config") if isinstance(info, dict) else None
    return config if isinstance(config, str) else None


def _refuse_another_config(vectors: Path, dump: Path) -> None:
    """InputError when ``dump`` is a vector set (it has a manifest) of another config than
    ``vectors``: its files differ throughout, and for that one reason."""
    ours, theirs = _config_of(vectors), _config_of(dump)
    if ours is not None and theirs is not None and ours != theirs:
        raise InputError(f"{dump}: vectors of {theirs}, {vectors} holds vectors of {ours} "
                         "(their manifest.json): compare vectors of one config")


def _read_bytes(path: Path) -> bytes:
    try:
        return path.read_bytes()
    except OSError as exc:
        raise InputError(f"{path}: cannot be read ({os_reason(exc)})") from None


def check(vectors: Path, dump: Path) -> tuple[list[str], int]:
    """Compare every file of ``dump`` that the vectors also have (any subset of them).

    Returns one line per differing file (naming frame, file, line with pixel x, y or trace
    column, and both values for the first :data:`SHOWN` differences; the dump's names and
    values with their control characters escaped, :func:`~vtrack.errors.printable`, so a
    newline or a terminal escape in them stays text of that one line) and the number of files
    compared. Files of ``dump`` the vectors do not have are reported too. InputError for
    ``vectors`` that are none (saying the order when ``dump`` is the vectors folder), or a
    ``dump`` that is no folder.
    """
    try:
        manifest = _read_manifest(vectors)
    except InputError as exc:
        # given swapped: the first a folder (a dump), the second the vectors
        if vectors.is_dir() and _config_of(dump) is not None and _config_of(vectors) is None:
            raise InputError(f"{exc}; {dump} is one: the vectors come first, then the dump "
                             f"(vtrack vectors check {shell_word(dump)} "
                             f"{shell_word(vectors)})") from None
        raise
    width = manifest["files"]["rgb.hex"]["width"]
    if not dump.is_dir():
        raise InputError(f"{dump}: no such folder")
    _refuse_another_config(vectors, dump)
    lines: list[str] = []
    compared = 0
    for path in sorted(dump.rglob("*")):
        if not path.is_file() or path.suffix not in (".hex", ".csv"):
            continue
        rel = path.relative_to(dump)
        name = rel.as_posix()
        expected = vectors / rel
        if not expected.is_file():
            lines.append(f"{name}: not in the vectors")
            continue
        compared += 1
        if path.suffix == ".hex":
            want = _read_bytes(expected)
            if len(rel.parts) == 2 and _is_frame_folder(rel.parts[0]):  # (not the user's own)
                _refuse_a_damaged_hex(expected, want, manifest)
            diff = _hex_differences(name, want, _read_bytes(path), width)
        else:
            diff = _csv_differences(name, expected, path, name in _TABLES,
                                    _frames_of(manifest) if name == "trace.csv" else None)
        if diff is not None:
            lines.append(diff)
    return [printable(line) for line in lines], compared
