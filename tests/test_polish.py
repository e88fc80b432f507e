"""What a daily user notices (issue 22): help that states the real defaults, one error style,
messages that name the real problem, options that agree between commands."""

from __future__ import annotations

import subprocess
import sys
from pathlib import Path

import pytest

from vtrack.configs import DEFAULT_CONFIG


def vtrack(*args: str, cwd: Path | None = None) -> subprocess.CompletedProcess:
    return subprocess.run([sys.executable, "-m", "vtrack", *args], capture_output=True,
                          text=True, cwd=cwd, timeout=120, check=False)


def one_error_line(result: subprocess.CompletedProcess) -> str:
    """Exit code != 0 and stderr is exactly one ``vtrack: error:`` line."""
    assert result.returncode != 0, result.stderr
    lines = result.stderr.strip().splitlines()
    assert len(lines) == 1 and lines[0].startswith("vtrack: error: "), result.stderr
    return lines[0]


@pytest.mark.parametrize("command", ["run", "batch"])
def test_help_names_the_default_config_the_code_uses(command: str) -> None:
    text = " ".join(vtrack(command, "--help").stdout.split())
    assert f"Default: {DEFAULT_CONFIG}." in text
    assert "Default: s0" not in text


def test_library_defaults_are_the_same_constant() -> None:
    import inspect

    import vtrack

    assert inspect.signature(vtrack.Tracker).parameters["config"].default == DEFAULT_CONFIG
    assert inspect.signature(vtrack.track).parameters["config"].default == DEFAULT_CONFIG
    assert vtrack.Tracker().config.name == DEFAULT_CONFIG


@pytest.mark.parametrize("args", [
    ("run", "clip.mp4", "--bogus"),
    ("run", "clip.mp4", "--crf", "99"),
    ("scene", "smooth", "x.mp4", "--crf", "99"),
    ("scene", "smooth", "x.mp4", "--preset", "speedy"),
    ("nocommand",),
])
def test_usage_errors_are_one_vtrack_error_line(args: tuple[str, ...], tmp_path: Path) -> None:
    line = one_error_line(vtrack(*args, cwd=tmp_path))
    assert "--help" in line
    assert not list(tmp_path.iterdir())


def test_stages_takes_stage_and_config_names() -> None:
    one = vtrack("stages", "robust_model")
    assert one.returncode == 0 and one.stdout.startswith("robust_model: ")
    assert "\nhue:" not in one.stdout
    chain = vtrack("stages", "s0").stdout
    assert [line.split(":")[0] for line in chain.splitlines() if not line.startswith(" ")] == [
        "hue", "backproject", "meanshift", "occlusion", "kalman"]
    assert "not a stage or a shipped config" in one_error_line(vtrack("stages", "nope"))
