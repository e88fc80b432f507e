"""Config files as users write them, hostile ones too: each problem is one line naming the file
(and the stage and parameter when there is one), exit 2, no traceback, whichever command reads
the config (``run``, ``batch``, ``stages``)."""

from __future__ import annotations

from pathlib import Path

import pytest
from click.testing import CliRunner, Result
from conftest import one_error_line

from vtrack.cli import main

CHAIN_TAIL = '[[stage]]\nname = "backproject"\n[[stage]]\nname = "meanshift"\n'


def vtrack(*args: str) -> Result:
    return CliRunner().invoke(main, list(args))


def refusals(config: Path, tmp_path: Path) -> list[str]:
    """The error line of each command given ``config``: run, batch and stages."""
    folder = tmp_path / "inputs"
    folder.mkdir(exist_ok=True)
    return [one_error_line(vtrack(*args)) for args in (
        ("run", "in.mp4", "-c", str(config), "--init", "1,1,9,9", "--out", str(tmp_path / "o")),
        ("batch", str(folder), "-c", str(config), "--out", str(tmp_path / "b")),
        ("stages", str(config)),
    )]


@pytest.mark.parametrize(("text", "said"), [
    ('name = "x"\nk = ' + "[" * 5000 + "]" * 5000 + "\n",
     "arrays or tables nested too deeply to read (a config's values are numbers, text and "
     "true/false)"),
    ('name = "x"\nk = ' + "{a = " * 3000 + "}" * 3000 + "\n", "nested too deeply to read"),
    ("name = " + "1" * 5000 + "\n", "an integer of more than 4300 digits, too long to read"),
], ids=["arrays", "inline-tables", "5000-digits"])
def test_a_config_toml_cannot_turn_into_values_is_one_line(text: str, said: str,
                                                          tmp_path: Path) -> None:
    """A 50 kB config of 5000 nested arrays (or 3000 nested inline tables) ended `vtrack run`,
    `batch` and `stages` with a traceback: 'RecursionError: maximum recursion depth exceeded';
    `name = 111...` (5000 digits) with 'ValueError: Exceeds the limit (4300 digits) for integer
    string conversion ... use sys.set_int_max_str_digits()'."""
    config = tmp_path / "deep.toml"
    config.write_text(text)
    for line in refusals(config, tmp_path):
        assert line.startswith(f"vtrack: error: {config}: ") and said in line, line
