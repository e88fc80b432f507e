"""Start-up: a command loads only what it uses (issue 12 item 1).

Checked by behaviour, not by timing: a real ``python -m vtrack ...`` process reports which
modules it ended up with, and the heavy ones (matplotlib through the report, Dask) must be
absent from commands that do not use them.
"""

from __future__ import annotations

import json
import subprocess
import sys

import pytest

HEAVY = ("matplotlib", "dask", "distributed", "vtrack.report")

# runs the vtrack command in-process, then prints the loaded module names as JSON on stderr
PROBE = """
import json, runpy, sys
sys.argv = ["vtrack", *sys.argv[1:]]
try:
    runpy.run_module("vtrack", run_name="__main__", alter_sys=True)
except SystemExit:
    pass
finally:
    sys.stderr.write("\\nMODULES " + json.dumps(sorted(sys.modules)) + "\\n")
"""


def loaded_modules(*args: str) -> tuple[set[str], str]:
    done = subprocess.run([sys.executable, "-c", PROBE, *args], capture_output=True, text=True,
                          timeout=60, check=False)
    line = next(x for x in done.stderr.splitlines() if x.startswith("MODULES "))
    return set(json.loads(line.removeprefix("MODULES "))), done.stdout


def heavy(modules: set[str]) -> list[str]:
    return sorted(m for m in modules if any(m == h or m.startswith(h + ".") for h in HEAVY))


@pytest.mark.parametrize("args", [["--version"], ["--help"], ["run", "--help"],
                                  ["batch", "--help"], ["stages"], ["scene", "--help"],
                                  ["select", "--help"], ["frame", "--help"]])
def test_commands_that_do_not_plot_load_no_plotting_and_no_dask(args: list[str]) -> None:
    modules, stdout = loaded_modules(*args)
    assert stdout.strip(), "the command printed nothing: the probe did not run it"
    assert heavy(modules) == []


def test_run_help_loads_neither_the_pipeline_nor_the_scene_generator() -> None:
    modules, stdout = loaded_modules("run", "--help")
    assert "--init" in stdout
    assert not {"vtrack.run", "vtrack.scenes", "vtrack.batch", "vtrack.stages.base"} & modules


def test_version_loads_no_video_or_image_library() -> None:
    modules, stdout = loaded_modules("--version")
    assert "0." in stdout
    assert not {"av", "cv2", "numpy"} & modules


def test_report_help_shows_the_reports_own_default_title() -> None:
    from vtrack.report import DEFAULT_TITLE

    modules, stdout = loaded_modules("report", "--help")
    assert DEFAULT_TITLE in stdout and "matplotlib" not in modules


def test_import_vtrack_is_lazy_and_its_names_still_resolve() -> None:
    probe = ("import sys, vtrack; before = 'vtrack.config' in sys.modules; "
             "box = vtrack.Box(1, 2, 3, 4); "
             "print(before, 'vtrack.config' in sys.modules, box.w, "
             "sorted(n for n in vtrack.__all__ if not hasattr(vtrack, n)))")
    done = subprocess.run([sys.executable, "-c", probe], capture_output=True, text=True,
                          timeout=60, check=True)
    assert done.stdout.split() == ["False", "False", "3", "[]"]
