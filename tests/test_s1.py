"""S1 (the ``particle`` stage, shipped as config ``s1``) against the document's rules.

Exact checks on hand-built frames (centroid, weight, tracked/lost history) and behaviour on
generated scenes (leave and return, smooth motion, determinism), plus parameter validation.
"""

from __future__ import annotations

import math
from functools import cache

import numpy as np
import pytest

from vtrack.config import load_config
from vtrack.errors import ConfigError
from vtrack.frame import BgrFrame
from vtrack.geometry import Box, center_error
from vtrack.overlays import Particles
from vtrack.params import Param
from vtrack.pipeline import FrameResult, Pipeline
from vtrack.scenes import Scene, make_scene
from vtrack.stages.base import TrackState, build_stage
from vtrack.stages.particle import ParticleFilter

FPS = 30.0
RED, BLUE = (0, 0, 255), (255, 0, 0)  # BGR; hue 0 and 240 degrees: no common hue bin

TRACKING, LOST = TrackState.TRACKING, TrackState.LOST


@cache
def _scene(name: str, seed: int, frames: int = 150) -> tuple[Scene, tuple[np.ndarray, ...]]:
    scene = make_scene(name, seed=seed, width=320, height=240, frames=frames, fps=FPS)
    return scene, tuple(scene.frames())


def _track(
    frames: tuple[np.ndarray, ...] | list[np.ndarray],
    init: Box,
    seed: int = 0,
    overrides: tuple[str, ...] = (),
) -> list[FrameResult]:
    config = load_config("s1").with_overrides(list(overrides))
    pipeline = Pipeline(config.build(), seed=seed)
    wrapped = (BgrFrame(i, i / FPS, bgr) for i, bgr in enumerate(frames))
    return list(pipeline.track(wrapped, init))


def _columns(red_columns: int, size: int = 16) -> np.ndarray:
    """A size x size frame: ``red_columns`` red columns on the left, the rest blue."""
    frame = np.empty((size, size, 3), np.uint8)
    frame[:, :red_columns] = RED
    frame[:, red_columns:] = BLUE
    return frame


# With a frame exactly the size of the box, every particle covers the whole frame, so a frame of
# k red columns out of 16 has the known weight sqrt(k / 16) and target centroid x = k / 2.
ONE_PARTICLE = ("particle.particles=1", "particle.spread=0.0")
WHOLE = Box(0.0, 0.0, 16.0, 16.0)


def test_weight_is_the_bhattacharyya_coefficient_and_the_output_the_centroid() -> None:
    frames = [_columns(16), _columns(13)]
    corrected = _track(frames, WHOLE, overrides=ONE_PARTICLE)[1]
    assert corrected.score == pytest.approx(math.sqrt(13 / 16))  # S1 step 6
    assert corrected.box == Box.from_center(6.5, 8.0, 16.0, 16.0)  # S1 step 5: centroid
    assert corrected.extras["particle_cx"] == 8.0
    plain = _track(frames, WHOLE, overrides=(*ONE_PARTICLE, "particle.centroid_correction=false"))
    assert plain[1].box == WHOLE  # the plain filter outputs the best particle's centre


def test_lost_when_the_weight_falls_below_threshold_times_the_weight_ten_frames_ago() -> None:
    # 12 whole-target frames (weight 1), then weights sqrt(13/16) = 0.901, sqrt(12/16) = 0.866,
    # 0, sqrt(15/16) = 0.968, sqrt(14/16) = 0.935, 1.
    red = [16] * 12 + [13, 12, 0, 15, 14, 16]
    results = _track([_columns(k) for k in red], WHOLE, overrides=ONE_PARTICLE)
    states = [r.state for r in results]
    assert states[12] == TRACKING  # 0.901 >= 0.9 x 1
    assert states[13] == LOST and states[14] == LOST  # 0.866 < 0.9 x 1, then 0
    assert results[13].box is None and results[14].box is None  # lost: no box claimed
    # Frozen reference: the weight 10 tracked frames before the loss (frame 3's weight, 1.0),
    # not the last tracked one (0.901).
    assert results[14].extras["reference_weight"] == pytest.approx(1.0)
    assert states[15:] == [TRACKING] * 3  # re-acquired: 0.968 >= 0.9 x 1; the history resumes
    assert results[15].box == Box.from_center(7.5, 8.0, 16.0, 16.0)
    assert results[16].extras["reference_weight"] == pytest.approx(1.0)


def test_start_compares_with_the_oldest_weight_until_the_history_is_full() -> None:
    # Frame 1 (the first tracked frame) is its own reference; frames 2..10 compare with frame 1.
    red = [16, 12, 12, 11]  # weights -, 0.866, 0.866, 0.829 (0.829 / 0.866 = 0.957)
    results = _track([_columns(k) for k in red], WHOLE, overrides=ONE_PARTICLE)
    assert [r.state for r in results] == [TRACKING] * 4
    assert [r.extras.get("reference_weight") for r in results[1:]] == pytest.approx(
        [math.sqrt(12 / 16)] * 3
    )


def test_a_box_outside_the_frame_is_refused_naming_it_as_the_other_stages_do() -> None:
    """The stage's own refusal of a first box outside the frame (the pipeline refuses it
    first, as init_box; the stage started by itself does not) showed it as a Python tuple,
    "stage 'particle': initial box (500.0, 400.0, 20.5, 20.0) is outside the 320x240 frame".
    It names the box as --init takes it, Box.text(), as the other stages' refusals do."""
    from vtrack.errors import FirstFrameError
    from vtrack.stages.base import TrackContext

    frame = BgrFrame(0, 0.0, np.full((240, 320, 3), 90, np.uint8))
    ctx = TrackContext(frame=frame, box=Box(500.0, 400.0, 20.5, 20.0))
    ctx.new_frame(frame)
    stage = build_stage("particle", {}, "test.toml")
    with pytest.raises(FirstFrameError) as refused:
        stage.start(ctx)
    assert str(refused.value) == ("particle: the initial box 500,400,20.5,20 is outside the "
                                  "320x240 frame")


def _leave_return(seed: int, overrides: tuple[str, ...] = ()) -> tuple[Scene, list[FrameResult]]:
    scene, frames = _scene("leave_return", seed)
    assert scene.boxes[0] is not None
    return scene, _track(frames, scene.boxes[0], seed=seed, overrides=overrides)


def _fully_in_view(scene: Scene, since: int) -> int:
    """First frame from ``since`` on where the whole target is inside the frame."""
    return next(
        i for i in range(since, len(scene))
        if (b := scene.boxes[i]) is not None
        and b.x >= 0 and b.y >= 0 and b.x + b.w <= scene.width and b.y + b.h <= scene.height
    )


def _reacquired(scene: Scene, results: list[FrameResult], back: int) -> int:
    """First tracking frame from ``back`` on, checked to be within half a box of the truth."""
    frame = next(i for i in range(back, len(results)) if results[i].state == TRACKING)
    truth, box = scene.boxes[frame], results[frame].box
    assert truth is not None and box is not None
    assert center_error(box, truth) <= truth.w / 2
    return frame


@pytest.mark.parametrize("seed", range(5))
def test_leaving_the_frame_is_reported_lost_and_the_return_reacquired(seed: int) -> None:
    scene, results = _leave_return(seed)
    out, back = scene.events["leave"]
    # S1 step 8: lost within 10 frames after the target is fully out, and while it is out.
    assert [r.state for r in results[out + 10 : back]] == [LOST] * (back - out - 10)
    assert all(r.box is None for r in results if r.state == LOST)
    # Re-acquired once back (not before it is mostly in view), within half a box.
    assert _reacquired(scene, results, back) >= _fully_in_view(scene, back) - 10


#: Particles over the whole frame while lost in the re-acquisition test (not the document's 8):
#: ~1.2% of positions pass on this clip, so a frame finds the target with probability ~54%.
LOST_PARTICLES = 64


@pytest.mark.parametrize("seed", range(5))
def test_more_lost_particles_reacquire_within_10_frames_of_the_target_being_back_in_view(
    seed: int,
) -> None:
    # "Back" as the document's test sees it: the weight must reach 0.9 x the weight before the
    # loss, which a partly visible target cannot (S1 step 8), so count from fully in view.
    scene, results = _leave_return(seed, (f"particle.lost_particles={LOST_PARTICLES}",))
    _, back = scene.events["leave"]
    found = _reacquired(scene, results, back)
    assert found <= _fully_in_view(scene, back) + 10
    assert all(r.state == TRACKING for r in results[found:])  # and it stays found


def test_lost_particles_only_change_the_search_while_lost() -> None:
    overrides = ("particle.draw_particles=true",)
    scene, shipped = _leave_return(0, overrides)
    _, more = _leave_return(0, (*overrides, f"particle.lost_particles={LOST_PARTICLES}"))
    first_lost = next(i for i, r in enumerate(shipped) if r.state == LOST)

    def particle_count(result: FrameResult) -> int:
        return next(len(o.centres) for o in result.overlays if isinstance(o, Particles))

    # Identical up to the loss (same random draws); then every frame after a lost one is
    # searched with 64 whole-frame particles instead of 8.
    assert [(r.box, r.state, r.score) for r in more[: first_lost + 1]] == [
        (r.box, r.state, r.score) for r in shipped[: first_lost + 1]
    ]
    expected = [LOST_PARTICLES if before.state == LOST else 8 for before in more[:-1]]
    assert [particle_count(r) for r in more[1:]] == expected
    assert LOST_PARTICLES in expected and 8 in expected[first_lost + 1 :]  # lost, then found
    assert {particle_count(r) for r in shipped[1:]} == {8}


@pytest.mark.xfail(
    strict=True,
    reason="S1's own search: while lost its 8 particles are scattered uniformly over the frame "
    "and only ~1.2% of positions pass 0.9 x the weight before the loss, so a frame finds the "
    "returned target with probability ~9% (expected wait 11 frames; seeds 3 and 4 wait 33 and "
    "22 frames after it is fully in view; benchmarks/claims_s1_return.py)",
)
def test_document_defaults_reacquire_within_10_frames_of_the_target_being_back_in_view() -> None:
    for seed in range(5):
        scene, results = _leave_return(seed)
        _, back = scene.events["leave"]
        assert _reacquired(scene, results, back) <= _fully_in_view(scene, back) + 10


def test_smooth_motion_is_tracked_with_a_small_centre_error() -> None:
    claimed = frames = 0
    for seed in range(10):
        scene, clip = _scene("smooth", seed)
        truth = scene.boxes
        assert truth[0] is not None
        results = _track(clip, truth[0], seed=seed)
        errors = [center_error(r.box, t) for r, t in zip(results, truth, strict=True)
                  if r.box is not None and t is not None]
        assert np.mean(errors) < 0.1 * truth[0].w  # ~2 px measured on a 41 px wide target
        claimed, frames = claimed + len(errors), frames + len(results)
    # Not every frame: one unlucky frame (best of 6 near particles >10% below the weight 10
    # frames earlier) declares the target lost, and 8 particles then search the whole frame
    # until one lands on it (3 of these 10 clips lose it for 21-47 frames; 94% claimed).
    assert claimed >= 0.9 * frames


def test_the_same_seed_gives_the_same_track_and_another_seed_another() -> None:
    scene, frames = _scene("smooth", 0)
    assert scene.boxes[0] is not None

    def run(seed: int) -> list[tuple[Box | None, str, float]]:
        return [(r.box, r.state, r.score) for r in _track(frames[:40], scene.boxes[0], seed=seed)]

    assert run(7) == run(7)
    assert run(7) != run(8)


def _wrong_value(kind: type) -> object:
    """A value of the wrong type for a parameter of type ``kind``."""
    return {int: 2.5, float: "0.5", bool: 1, str: 3}[kind]


@pytest.mark.parametrize("param", ParticleFilter.params, ids=lambda p: p.name)
def test_every_parameter_rejects_a_wrong_type_naming_stage_and_parameter(param: Param) -> None:
    with pytest.raises(ConfigError) as caught:
        build_stage("particle", {param.name: _wrong_value(param.type)}, "test.toml")
    message = str(caught.value)
    assert "stage 'particle'" in message and f"parameter '{param.name}'" in message


def test_the_shipped_config_holds_the_documents_defaults() -> None:
    (stage,) = load_config("s1").build()
    assert stage.settings() == {p.name: p.default for p in ParticleFilter.params}
    assert stage.settings()["particles"] == 8 and stage.settings()["history"] == 10
