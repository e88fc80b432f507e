"""The docs that are generated from the stages' declarations are up to date, and the README's
commands name things that exist."""

from __future__ import annotations

import re
from pathlib import Path

from vtrack.cli.stages import stages_text
from vtrack.config import shipped_configs

ROOT = Path(__file__).resolve().parent.parent


def test_stage_reference_matches_the_declarations() -> None:
    current = (ROOT / "docs" / "stages.md").read_text()
    assert current.strip() == stages_text(markdown=True).strip(), (
        "docs/stages.md is stale: regenerate it with `vtrack stages --markdown > docs/stages.md`"
    )


def test_readme_configs_exist_and_set_up_commands_come_first() -> None:
    readme = (ROOT / "README.md").read_text()
    table = readme.split("### Trackers", 1)[1].split("\n\n", 1)[0]
    listed = re.findall(r"^\| `([\w-]+)`", table, re.M)
    assert sorted(listed) == sorted(shipped_configs())
    blocks = re.findall(r"```bash\n(.*?)```", readme, re.S)
    assert "pip install ." in blocks[0] and "vtrack run samples/" in blocks[0]
    assert "pytest" in blocks[1]
    ci = (ROOT / ".ci" / "run").read_text()
    assert blocks[1].strip() in ci
    sample = re.search(r"vtrack run (samples/\S+)", blocks[0])
    assert sample and (ROOT / sample.group(1)).is_file()
