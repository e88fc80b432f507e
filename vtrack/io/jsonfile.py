"""Atomic, pretty-printed JSON (``run.json``): readers never see a half-written file."""

from __future__ import annotations

import dataclasses
import json
import math
from pathlib import Path
from typing import Any

import numpy as np

from vtrack.io.files import write_text_atomic


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
