"""Fuzz every stage's numeric parameters within and just outside their declared ranges.

For each registered stage, the shipped configs that contain it are run with ``--set``-style
overrides on a few tiny in-memory frames. A value outside the declared range (or not finite) must
be refused by :meth:`Config.with_overrides` with one line naming the stage, the parameter and
the range; a value inside must run with no exception other than vtrack's own errors, within the
per-frame bounds that docs/stages.md ("Limits") states. Examples are derandomized (the same on
every run) and few, so the whole file takes seconds.
"""

from __future__ import annotations

import math
import re
import tracemalloc
from functools import cache

import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from vtrack.config import Config, load_config, shipped_configs
from vtrack.errors import ConfigError, VtrackError
from vtrack.frame import BgrFrame
from vtrack.geometry import Box
from vtrack.params import Param
from vtrack.pipeline import Pipeline
from vtrack.scenes import make_scene
from vtrack.stages.base import all_stages
from vtrack.stages.robust_model import REGIONS_PER_FRAME

WIDTH, HEIGHT, FRAMES = 64, 48, 5
PIXELS = WIDTH * HEIGHT
#: docs/stages.md "Limits": beyond the frames themselves, a few frame-sized buffers (~32 bytes a
#: pixel) plus the particle filter's histograms (4 x 1024 particles x 256 bins x 8 bytes).
#: Python's own bookkeeping (particle windows, hypotheses) gets a fixed allowance of 4 MiB.
#: The robust tracker's search patches are bounded by its declared working size, whatever the
#: frame (~40 bytes a working pixel for features, spectra and colour maps), one patch a frame
#: plus the re-detection regions while lost, on top of the frame-sized buffers.
_AREA = next(p.max for p in all_stages()["robust_model"].params if p.name == "working_area")
ROBUST_PIXELS = int(_AREA) ** 2 * (1 + REGIONS_PER_FRAME)
MEMORY_BOUND = 32 * PIXELS + 4 * 1024 * 256 * 8 + 4 * 2**20


def _numeric(cls: type) -> list[Param]:
    return [p for p in cls.params if p.type in (int, float) and p.choices is None]


def _chain_for(stage: str) -> str:
    """A shipped config running ``stage`` (the first by name)."""
    for name in sorted(shipped_configs()):
        if any(s == stage for s, _ in load_config(name).stages):
            return name
    raise AssertionError(f"no shipped config runs stage {stage!r}")


FUZZED = sorted(name for name, cls in all_stages().items()
                if _numeric(cls) and name != "mot_detections")


@cache
def _frames(multi: bool) -> tuple[list[BgrFrame], tuple[float, ...] | None]:
    scene = make_scene("multi" if multi else "smooth", 0, WIDTH, HEIGHT, 60, 30.0)
    frames = [BgrFrame(i, i / scene.fps, scene.frame(i)) for i in range(FRAMES)]
    return frames, None if multi else tuple(scene.boxes[0])


def _inside(param: Param) -> st.SearchStrategy[str]:
    if param.type is int:
        return st.integers(int(param.min), int(param.max)).map(str)
    return st.floats(param.min, param.max, allow_nan=False).map(repr)


def _outside(param: Param) -> st.SearchStrategy[str]:
    """Values just outside the range, far outside it (2**31, 2**63, 1e308), and not finite."""
    low, high = param.min, param.max
    if param.type is int:
        above = st.sampled_from([high + 1, 2**31, 2**63]) | st.integers(high + 1, 2**70)
        below = st.sampled_from([low - 1, -(2**63)]) | st.integers(-(2**70), low - 1)
        return (above | below).map(str)
    above = st.sampled_from([math.nextafter(high, math.inf), high + 1, 1e308]) | st.floats(
        high, 1e308, exclude_min=True)
    below = st.sampled_from([math.nextafter(low, -math.inf), -1e308]) | st.floats(
        -1e308, low, exclude_max=True)
    return (above | below).map(repr) | st.sampled_from(["nan", "inf", "-inf"])


def _value(param: Param) -> st.SearchStrategy[tuple[str, bool]]:
    """(text, inside the range): mostly inside, so that most examples run the tracker."""
    return st.one_of(
        _inside(param).map(lambda t: (t, True)),
        _inside(param).map(lambda t: (t, True)),
        _outside(param).map(lambda t: (t, False)),
    )


def _run_bounded(config: Config, multi: bool) -> None:
    """Track the tiny clip; per frame, traced memory within the documented bound (work per frame
    is bounded by the declared parameter ranges; no timing threshold in a unit test)."""
    frames, init = _frames(multi)
    pipeline = Pipeline(config.build(), seed=0)
    bound = MEMORY_BOUND
    if any(stage == "robust_model" for stage, _ in config.stages):
        bound += 40 * ROBUST_PIXELS
    results = pipeline.track(iter(frames), Box(*init) if init else None)
    tracemalloc.start()
    try:
        while True:
            base = tracemalloc.get_traced_memory()[0]
            tracemalloc.reset_peak()
            try:
                result = next(results)
            except StopIteration:
                break
            peak = tracemalloc.get_traced_memory()[1] - base
            assert peak <= bound, f"frame {result.index}: {peak} bytes traced"
    except VtrackError:
        pass  # the project's own errors (e.g. a target the model cannot describe) are allowed
    finally:
        tracemalloc.stop()


@pytest.mark.parametrize("stage", FUZZED)
def test_stage_parameters_in_and_out_of_range(stage: str) -> None:
    cls = all_stages()[stage]
    params = _numeric(cls)
    base = load_config(_chain_for(stage))
    multi = any(all_stages()[s].multi_target for s, _ in base.stages)

    # The corners first: every parameter at its largest, then at its smallest (the most work).
    for corner in (lambda p: p.max, lambda p: p.min):
        values = [f"{stage}.{p.name}={corner(p)!r}" for p in params]
        _run_bounded(base.with_overrides(values), multi)

    @settings(max_examples=40, deadline=None, derandomize=True, database=None,
              suppress_health_check=list(HealthCheck))
    @given(st.fixed_dictionaries({}, optional={p.name: _value(p) for p in params}))
    def check(values: dict[str, tuple[str, bool]]) -> None:
        assignments = [f"{stage}.{name}={text}" for name, (text, _) in values.items()]
        bad = [name for name, (_, inside) in values.items() if not inside]
        if bad:
            with pytest.raises(ConfigError) as refused:
                base.with_overrides(assignments)
            message = str(refused.value)
            assert "\n" not in message
            assert f"stage '{stage}'" in message and " range " in message
            assert any(f"parameter '{name}'" in message for name in bad)
            return
        given = {p.name: p.default for p in cls.params} | dict(dict(base.stages)[stage]) | {
            p.name: p.parse(values[p.name][0], stage) for p in params if p.name in values}
        problem = cls.values_problem(given)  # a pair contradicting each other, each in range
        if problem:
            with pytest.raises(ConfigError, match=f"stage '{stage}': {re.escape(problem)}$"):
                base.with_overrides(assignments)
            return
        _run_bounded(base.with_overrides(assignments), multi)

    check()


def test_every_numeric_parameter_declares_a_range() -> None:
    """A numeric Param without min and max cannot even be declared."""
    with pytest.raises(TypeError, match="min and max"):
        Param("n", int, 1, "a count", min=1)
    for cls in all_stages().values():
        for param in _numeric(cls):
            assert param.min is not None and param.max is not None
            assert param.min <= param.default <= param.max, (cls.name, param.name)


@settings(max_examples=200, derandomize=True, deadline=None,
          suppress_health_check=[HealthCheck.function_scoped_fixture])
@given(name=st.text(max_size=40))
def test_any_config_name_plans_one_folder_inside_the_results(tmp_path, name: str) -> None:
    """Issue 21 item 5: whatever a config's ``name`` holds (``/``, ``..``, NUL, nothing), the
    batch plans its results one folder below the input's, inside ``--out``; a blank one is
    refused as the Config is made, as a config file's is."""
    from dataclasses import replace

    from vtrack.batch import BatchInput, plan
    from vtrack.request import RunRequest

    if not name.strip():
        with pytest.raises(ConfigError, match="^s4: name is empty: a config's name names its "):
            replace(load_config("s4"), name=name)
        return
    config = replace(load_config("s4"), name=name)
    out = tmp_path / "out"
    item = BatchInput(name="clip", path=tmp_path / "clip.mp4")
    settings_ = RunRequest(input=str(tmp_path), out_dir=out, config=config)
    batch = plan([item], {name: config}, out, settings_)
    (job,) = batch.jobs
    folder = job.request.out_dir
    assert folder.parent == out.resolve() / "clip"
    assert folder.name not in ("", ".", "..") and "/" not in folder.name
    assert "\x00" not in folder.name
