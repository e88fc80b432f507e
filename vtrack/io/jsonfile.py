"""Atomic, pretty-printed JSON (``run.json``): readers never see a half-written file; and a
``run.json`` read back only when it has the shape vtrack writes."""

from __future__ import annotations

import dataclasses
import json
import math
from pathlib import Path
from typing import Any

import numpy as np

from vtrack.errors import InputError
from vtrack.io.files import write_text_atomic
from vtrack.io.limits import RECORD_BYTES, read_bounded


def to_jsonable(value: Any) -> Any:
    """``value`` as plain JSON types: NaN/inf -> None, NumPy scalars/arrays -> numbers/lists,
    tuples -> lists, paths and other objects -> strings, dataclasses -> dicts."""
    if isinstance(value, dict):
        return {str(k): to_jsonable(v) for k, v in value.items()}
    if isinstance(value, list | tuple):
        return [to_jsonable(v) for v in value]
    if isinstance(value, np.ndarray):
        return to_jsonable(value.tolist())
    if isinstance(value, bool | np.bool_):
        return bool(value)
    if isinstance(value, int | np.integer):
        return int(value)
    if isinstance(value, float | np.floating):
        return float(value) if math.isfinite(value) else None
    if value is None or isinstance(value, str):
        return value
    if dataclasses.is_dataclass(value) and not isinstance(value, type):
        return to_jsonable(dataclasses.asdict(value))
    return str(value)


def write_json(path: Path | str, data: Any) -> None:
    """Write ``data`` to ``path`` atomically (temporary file + ``os.replace``), indented."""
    write_text_atomic(Path(path), json.dumps(to_jsonable(data), indent=2, allow_nan=False) + "\n")


#: The keys every ``run.json`` record holds (a run writes them whatever its end): a JSON object
#: without them is no run's record.
RECORD_KEYS = ("status", "frames")

#: The parts of a ``run.json`` record that are JSON objects when present.
RECORD_OBJECTS = ("request", "summary", "config", "input", "timing", "identity", "output_bytes",
                  "metrics")


def read_run_record(path: Path) -> dict[str, Any]:
    """The ``run.json`` at ``path`` as a dict holding :data:`RECORD_KEYS`, whose
    :data:`RECORD_OBJECTS` are dicts (or absent/null) and whose ``frames`` is a whole number.
    Raises InputError naming the file when it cannot be read, is larger than
    :data:`RECORD_BYTES`, or is not such a record (a file edited by hand: not JSON, nested too
    deep, a part of the wrong type, a JSON object without the keys every record holds, a
    ``frames`` that is not a whole number of 0 or more: null, ``true``, ``-1``, ``2.5``)."""
    data = read_bounded(path, RECORD_BYTES, "run record")
    try:
        record = json.loads(data.decode("utf-8"))
    except (ValueError, RecursionError):
        record = None
    if (not isinstance(record, dict)
            or any(not isinstance(record.get(k), dict | None) for k in RECORD_OBJECTS)):
        raise InputError(f"{path}: not a vtrack run record")
    missing = [key for key in RECORD_KEYS if key not in record]
    if missing:
        raise InputError(f"{path}: not a vtrack run record (it has no "
                         f"{' or '.join(repr(key) for key in missing)})")
    frames = record["frames"]
    if isinstance(frames, bool) or not isinstance(frames, int) or frames < 0:
        raise InputError(f"{path}: not a vtrack run record (its 'frames' is not a whole "
                         "number of 0 or more)")
    return record
