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
from conftest import START_BOUND_S

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
                          timeout=START_BOUND_S, check=False)
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
                          timeout=START_BOUND_S, check=True)
    assert done.stdout.split() == ["False", "False", "3", "[]"]


def test_run_loads_only_the_stages_of_its_chain(clip_factory, tmp_path) -> None:
    clip = clip_factory("smooth", frames=10)
    out = tmp_path / "out"
    modules, stdout = loaded_modules("run", str(clip.path), "--config", "s0", "--gt",
                                     str(clip.gt), "--no-video", "--out", str(out), "-q")
    stages = {m.removeprefix("vtrack.stages.") for m in modules if m.startswith("vtrack.stages.")}
    chain = [s["name"] for s in json.loads((out / "run.json").read_text())["config"]["stages"]]
    assert chain == ["hue", "backproject", "meanshift", "occlusion", "kalman"]
    # hue lives in colour.py; every other s0 stage in the module of its own name
    assert stages == {"base", "colour", "backproject", "meanshift", "occlusion", "kalman"}
    assert not {m for m in modules if m.startswith("vtrack.golden")}


def test_an_unknown_stage_still_lists_every_stage() -> None:
    from vtrack.errors import ConfigError
    from vtrack.stages.base import all_stages, stage_class

    with pytest.raises(ConfigError) as caught:
        stage_class("no_such_stage", "test.toml")
    names = all_stages()
    assert {"hue", "kalman", "particle", "hue_bp_fixed"} <= set(names)
    assert f"known stages: {', '.join(names)}" in str(caught.value)
    assert stage_class("hue", "test.toml") is names["hue"]


def test_the_errors_a_caller_catches_are_reached_from_a_bare_import_vtrack() -> None:
    # README's library section names vtrack.errors.ConfigError; after `import vtrack` alone
    # that was an AttributeError (the submodule was loaded only as a side effect of a tracker)
    probe = ("import sys, vtrack; "
             "print(vtrack.errors.InputError.__name__, vtrack.InputError is "
             "vtrack.errors.InputError, issubclass(vtrack.ConfigError, vtrack.VtrackError), "
             "vtrack.OutputError.exit_code, vtrack.evaluate.summarize.__name__, "
             "'vtrack.config' in sys.modules, {'errors', 'InputError'} <= set(dir(vtrack)))")
    done = subprocess.run([sys.executable, "-c", probe], capture_output=True, text=True,
                          timeout=START_BOUND_S, check=False)
    assert done.stdout.split() == ["InputError", "True", "True", "2", "summarize", "False",
                                   "True"], done.stderr


def test_help_of_a_frame_result_says_what_each_of_its_fields_holds() -> None:
    # help(vtrack.FrameResult) said only "What the tracker says about one frame.": the
    # fields' comments (#:) are not docstrings, so a library user could not learn from help()
    # what box None, score NaN or the tracks' states mean
    import dataclasses
    import pydoc

    import vtrack

    shown = pydoc.render_doc(vtrack.FrameResult, renderer=pydoc.plaintext)
    for field in dataclasses.fields(vtrack.FrameResult):
        assert f"``{field.name}``:" in shown, field.name
    for promise in ("None while ``lost``", "NaN", "``confirmed``", "keep_frames=True"):
        assert promise in shown


def test_every_public_method_of_the_exported_classes_says_what_it_promises() -> None:
    # help(vtrack.Pipeline) showed stage_microseconds_per_frame, multi_target and
    # needs_init_box with no word, and Box.cx/cy/area/from_center/is_valid and
    # Frame.full_window too
    import inspect

    import vtrack

    silent = []
    for name in vtrack.__all__:
        exported = getattr(vtrack, name)
        if not inspect.isclass(exported) or issubclass(exported, BaseException):
            continue
        for member_name, member in vars(exported).items():
            if member_name.startswith("_"):
                continue
            function = member.fget if isinstance(member, property) else getattr(
                member, "__func__", member)
            if (isinstance(member, property) or inspect.isfunction(function)) \
                    and not inspect.getdoc(function):
                silent.append(f"{name}.{member_name}")
    assert silent == []
