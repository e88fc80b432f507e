"""Refactorings keep outputs byte-identical: every shipped config on generated raw clips gives
the CSV digests recorded in ``benchmarks/identical_outputs.json`` (see that script)."""

from __future__ import annotations

import importlib.util
import sys
from pathlib import Path

SCRIPT = Path(__file__).resolve().parent.parent / "benchmarks" / "identical_outputs.py"


def _script():
    spec = importlib.util.spec_from_file_location("identical_outputs", SCRIPT)
    module = importlib.util.module_from_spec(spec)
    sys.modules[spec.name] = module
    spec.loader.exec_module(module)
    return module


def test_every_shipped_config_writes_the_recorded_csv(tmp_path: Path) -> None:
    script = _script()
    recorded = script.recorded()
    assert {case.config for case in script.CASES} >= {
        "s0", "camshift", "s1", "s2", "s3", "s4", "s4_multi"}
    assert set(recorded) == {case.key for case in script.CASES}
    for case in script.CASES:
        assert script.digest(case, tmp_path) == recorded[case.key], case.key
