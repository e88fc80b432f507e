"""CSV output (``track.csv``, ``tracks.csv``): compact numbers, rows on disk as they are written.

Rows go to a temporary name (:func:`~vtrack.io.files.temp_path`) and are flushed one by one, so an
interrupted run leaves whole rows; ``close()`` renames the file to its final name.
"""

from __future__ import annotations

import csv
import math
import os
from collections.abc import Mapping, Sequence
from pathlib import Path
from typing import Any

import numpy as np

from vtrack.errors import OutputError
from vtrack.io.files import Closing, os_reason, temp_path

#: Decimals of float columns: pixels to a thousandth, times/scores/overlaps to 4 places.
DECIMALS: Mapping[str, int] = {"time_s": 4, "score": 4, "overlap": 4, "conf": 4}
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


class CsvWriter(Closing):
    """Write a header and rows to ``path``; each row is flushed as it is written."""

    def __init__(
        self, path: Path | str, columns: Sequence[str], decimals: Mapping[str, int] = DECIMALS
    ) -> None:
        self.path = Path(path)
        self.columns = tuple(columns)
        self._temp = temp_path(self.path)
        self._decimals = [decimals.get(c, DEFAULT_DECIMALS) for c in self.columns]
        try:
            self._file = open(self._temp, "w", newline="", encoding="utf-8")  # noqa: SIM115
        except OSError as exc:
            raise OutputError(f"{self.path}: cannot write ({os_reason(exc)})") from None
        self._writer = csv.writer(self._file, lineterminator="\n")
        self._write(self.columns)

    def _write(self, cells: Sequence[str]) -> None:
        try:
            self._writer.writerow(cells)
            self._file.flush()
        except OSError as exc:
            raise OutputError(f"{self.path}: cannot write ({os_reason(exc)})") from None

    def write(self, row: Sequence[Any]) -> None:
        """Append one row (one value per column) and flush it to the file."""
        if len(row) != len(self.columns):
            raise ValueError(f"{self.path}: row has {len(row)} values for {len(self.columns)} "
                             "columns")
        self._write([format_cell(v, d) for v, d in zip(row, self._decimals, strict=True)])

    def close(self) -> None:
        """Close the file and give it its final name. Safe to call twice."""
        if self._file.closed:
            return
        self._file.close()
        try:
            os.replace(self._temp, self.path)
        except OSError as exc:
            raise OutputError(f"{self.path}: cannot write ({os_reason(exc)})") from None

