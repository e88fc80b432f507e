"""CSV output (``track.csv``, ``tracks.csv``): compact numbers, rows on disk as they are written.

Rows go to a temporary name (:func:`~vtrack.io.files.temp_path`) and reach the file one by one
(unbuffered), so an interrupted run leaves whole rows, and a full disk cuts the file back to its
last whole row; ``close()`` renames the file to its final name (``finish()`` closes it first
and keeps the temporary name, for a caller that renames it only once its record is ready).
"""

from __future__ import annotations

import contextlib
import csv
import io
import math
import os
from collections.abc import Mapping, Sequence
from pathlib import Path
from typing import Any

import numpy as np

from vtrack.errors import OutputError
from vtrack.geometry import Box
from vtrack.io.files import Closing, os_reason, remove_quietly, temp_path

#: Decimals of float columns: pixels to a thousandth, times/scores to 4 places, overlaps to 6
#: (so a success plot's thresholds, multiples of 0.05, meet a rounded tie only when the overlap
#: is within 5e-7 of one; run.json's metrics are computed from the overlaps as written).
DECIMALS: Mapping[str, int] = {"time_s": 4, "score": 4, "overlap": 6, "conf": 4}
DEFAULT_DECIMALS = 3


def format_cell(value: Any, decimals: int = DEFAULT_DECIMALS) -> str:
    """One CSV cell: None and non-finite floats -> empty, floats rounded without trailing zeros."""
    if value is None:
        return ""
    # plain float first: most cells are floats (np.float64 is one), ints and strings are not
    if isinstance(value, float) or isinstance(value, np.floating):  # noqa: SIM101
        if not math.isfinite(value):
            return ""
        text = f"{value:.{decimals}f}".rstrip("0").rstrip(".")
        return "0" if text in ("-0", "") else text
    return str(value)


def as_written(value: float | None, column: str) -> float | None:
    """``value`` as a reader of ``column``'s cell gets it back (rounded to its decimals);
    None and non-finite values are returned as they are (their cell is empty)."""
    if value is None or not math.isfinite(value):
        return value
    return float(format_cell(float(value), DECIMALS.get(column, DEFAULT_DECIMALS)))


def box_as_written(box: Box) -> Box:
    """``box`` as ``track.csv``'s and ``tracks.csv``'s cells give it back (pixels to
    :data:`DEFAULT_DECIMALS`), its width and height never under the least positive size they
    hold: a box's sizes are positive (MOTChallenge's too), and a tiny one (a ``det.txt``'s box
    of 0.0001 pixels) was written as 0. A non-finite value is kept as it is (its cell is
    empty), as :func:`as_written` keeps it."""
    least = 10.0 ** -DEFAULT_DECIMALS
    x, y, w, h = (as_written(float(v), "x") for v in box)
    return Box(x, y, max(w, least), max(h, least))  # (max keeps a NaN: it compares False)


def scores_as_written(overlap: float | None, error: float | None
                      ) -> tuple[float | None, float | None]:
    """A frame's (overlap, centre error) as ``track.csv``'s cells give them back: what
    ``run.json`` and the report score, so a reader's rescoring gives the same."""
    return as_written(overlap, "overlap"), as_written(error, "center_error")


class CsvWriter(Closing):
    """Write a header and rows to ``path``; each row (or each frame's rows, :meth:`write_rows`)
    reaches the file as it is written.

    A write that fails (a full disk) raises OutputError and leaves the file cut back to its last
    whole row, so the file always holds whole rows: :attr:`rows` of them after the header.
    """

    def __init__(
        self, path: Path | str, columns: Sequence[str], decimals: Mapping[str, int] = DECIMALS
    ) -> None:
        self.path = Path(path)
        self.columns = tuple(columns)
        self._temp = temp_path(self.path)
        self._decimals = [decimals.get(c, DEFAULT_DECIMALS) for c in self.columns]
        #: Rows on disk (header not counted).
        self.rows = 0
        self._size = 0  # bytes of whole rows on disk
        self._closed = False
        self._published: Path | None = None  # the final name, once renamed to it
        self._aborted = False
        try:
            self._fd = os.open(self._temp, os.O_WRONLY | os.O_CREAT | os.O_TRUNC | os.O_CLOEXEC,
                               0o644)
        except OSError as exc:
            raise OutputError(f"{self.path}: cannot write ({os_reason(exc)})") from None
        self._text = io.StringIO()
        self._writer = csv.writer(self._text, lineterminator="\n")
        try:
            self._append([self.columns])
        except OutputError:  # no room even for the header (a full disk): leave nothing
            self.abort()
            raise
        self.rows = 0

    def _append(self, rows: Sequence[Sequence[str]]) -> None:
        """Write ``rows`` whole or not at all (cut back on failure)."""
        self._text.seek(0)
        self._text.truncate()
        self._writer.writerows(rows)
        data = memoryview(self._text.getvalue().encode("utf-8"))
        done = 0
        try:
            while done < len(data):
                done += os.write(self._fd, data[done:])
        except OSError as exc:
            with contextlib.suppress(OSError):
                os.ftruncate(self._fd, self._size)
                os.lseek(self._fd, self._size, os.SEEK_SET)
            raise OutputError(f"{self.path}: cannot write ({os_reason(exc)})") from None
        self._size += len(data)
        self.rows += len(rows)

    def _cells(self, row: Sequence[Any]) -> list[str]:
        if len(row) != len(self.columns):
            raise ValueError(f"{self.path}: row has {len(row)} values for {len(self.columns)} "
                             "columns")
        return [format_cell(v, d) for v, d in zip(row, self._decimals, strict=True)]

    def write(self, row: Sequence[Any]) -> None:
        """Append one row (one value per column) to the file."""
        self._append([self._cells(row)])

    def write_rows(self, rows: Sequence[Sequence[Any]]) -> None:
        """Append several rows (one frame's) together: all of them reach the file or none."""
        if rows:
            self._append([self._cells(row) for row in rows])

    @property
    def on_disk(self) -> Path:
        """Where the rows are now: the temporary name until :meth:`close` renamed it."""
        return self._temp if self._published is None else self._published

    def finish(self) -> None:
        """Close the file, keeping its temporary name (:attr:`on_disk`): no more rows come,
        and nothing under the final name claims to be complete yet. Safe to call twice."""
        if self._closed:
            return
        self._closed = True
        try:
            os.close(self._fd)
        except OSError as exc:
            self._aborted = True  # no file left: close() renames nothing
            remove_quietly(self._temp)
            raise OutputError(f"{self.path}: cannot write ({os_reason(exc)})") from None

    def close(self) -> None:
        """Close the file (:meth:`finish`) and give it its final name. Safe to call twice."""
        self.finish()
        if self._published is not None or self._aborted:
            return
        try:
            os.replace(self._temp, self.path)
        except OSError as exc:
            remove_quietly(self._temp)
            raise OutputError(f"{self.path}: cannot write ({os_reason(exc)})") from None
        self._published = self.path

    def abort(self) -> None:
        """Close without a file: the temporary file is removed."""
        self._aborted = True
        if not self._closed:
            self._closed = True
            with contextlib.suppress(OSError):
                os.close(self._fd)
        remove_quietly(self._temp)
