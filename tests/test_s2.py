"""S2 (kernel mean shift, 3 scales, Kalman failure logic): the document's claims, generated scenes.

Every run goes through the shipped config: ``Pipeline(load_config("s2").build()).track(...)``,
i.e. ``kernel_meanshift -> kalman(model="ca")`` with the document's values.

What the document claims and where it is checked here:

- a displacement between two frames larger than the target, which plain mean shift loses, is
  followed by rerunning the search from the Kalman prediction (sec. 5 (2)(1), fig. 1): on the
  ``accelerate`` scene, a target that speeds up until it moves more than its width per frame
  (the motion the constant-acceleration predictor describes). The ``jump`` scene teleports the
  target 2.5 widths with no motion before it: no predictor can point there, so the failure logic
  cannot help on it (see ``benchmarks/claims_s2.py``);
- full occlusion (sec. 5 (2)(2)): the occlusion branch is taken while the window holds nothing
  of the target and the box coasts on the prediction. Riding through 18 hidden frames (the
  document: about 13) on a straight constant-velocity path depends on the unit of the
  predictor's T, which the document gives as the time between frames (with sigma_w^2 = 1):
  with T in seconds (the shipped config) it is reproduced when the target vanishes and
  reappears at once (the ``cover`` scene); with T = 1 frame it is not (strict xfail). Behind a
  slab, where partial occlusion comes first, it is reproduced with neither (strict xfail,
  reasons in the tests);
- the failure logic's threshold D, which the document does not print, is the 20 px of its
  worked 30x20 case (fig. 1(d)) kept in proportion to the box: a curving target's normal lag
  behind the predictor stays inside it, where a fixed 20 px calls it an occlusion;
- scale change (fig. 3(d) shows a zoom out): the box follows a x2 shrink; a x2 growth is not
  followed with the pyramid kernel (strict xfail) but is with the Epanechnikov kernel.
"""

from __future__ import annotations

import math

import numpy as np
import pytest

from vtrack.config import load_config
from vtrack.errors import ConfigError
from vtrack.frame import BgrFrame
from vtrack.geometry import Box, iou
from vtrack.params import Param
from vtrack.pipeline import FrameResult, Pipeline
from vtrack.scenes import Scene, make_scene
from vtrack.scenes.render import (
    PAPER,
    Compositor,
    Ellipse,
    Pillar,
    SensorNoise,
    StaticBackground,
    make_background,
    pillar_texture,
    target_paint,
)
from vtrack.scenes.scene import SceneSpec, Truth, assemble
from vtrack.stages.base import TrackContext, TrackState, build_stage
from vtrack.stages.kernel_meanshift import KernelMeanShift

FPS = 30.0
DECISIONS = {"accept", "fast_motion", "occlusion"}


def track(frames: list[BgrFrame], init_box: Box, *overrides: str) -> list[FrameResult]:
    """Run the shipped S2 config (with ``--set``-style overrides) over ``frames``."""
    config = load_config("s2").with_overrides(list(overrides))
    return list(Pipeline(config.build()).track(frames, init_box))


def overlaps(results: list[FrameResult], boxes: list[Box | None]) -> np.ndarray:
    """Per-frame IoU of the tracker's box with the ground truth."""
    return np.array([iou(r.box, g) if r.box and g else 0.0 for r, g in
                     zip(results, boxes, strict=True)])


def as_frames(images: list[np.ndarray]) -> list[BgrFrame]:
    return [BgrFrame(i, i / FPS, image) for i, image in enumerate(images)]


@pytest.mark.parametrize("seed", [0, 1, 2])
def test_follows_displacements_larger_than_the_target(seed: int) -> None:
    # The shipped `accelerate` scene: the document's 32x20 target speeding up from rest until it
    # moves more than its width between frames (from events["fast"] on), a motion the
    # constant-acceleration predictor describes: a window opened at the last position no longer
    # holds the target (sec. 5: "相邻帧目标位置变化大于目标大小") while the prediction still does.
    scene = make_scene("accelerate", seed=seed)
    frames = list(scene.as_frames())
    s2 = track(frames, scene.boxes[0])
    plain = track(frames, scene.boxes[0], "kernel_meanshift.failure_logic=false")
    s2_iou, plain_iou = overlaps(s2, scene.boxes), overlaps(plain, scene.boxes)
    decisions = [r.extras["decision"] for r in s2]
    assert set(decisions) <= DECISIONS
    k = scene.events["fast"]

    # Without the failure logic the search stays where the target was: lost for good.
    lost = int(np.flatnonzero(plain_iou == 0.0)[0])
    assert plain_iou[-3:].max() == 0.0
    # With it, the two runs are the same computation until the first rejected search, which is
    # the fast-motion branch, at the latest on the frame plain mean shift loses the target ...
    first = next(i for i, d in enumerate(decisions) if d != "accept")
    assert decisions[first] == "fast_motion"
    assert first <= lost
    assert "occlusion" not in decisions
    # ... and the box is on the target on every frame that moved more than the target's width.
    assert s2_iou[k:].min() > 0.5, np.round(s2_iou, 2)
    assert all(r.state == TrackState.TRACKING and 0.0 <= r.score <= 1.0 for r in s2)


def test_full_occlusion_takes_the_occlusion_branch_and_coasts_on_the_prediction() -> None:
    scene = make_scene("cover", seed=0, frames=60)
    start, end = scene.events["occluded"]
    results = track(list(scene.as_frames()), scene.boxes[0])
    assert [r.extras["decision"] for r in results[:start]] == ["accept"] * start
    for previous, current in zip(results[start - 1 : end - 1], results[start:end], strict=True):
        assert current.extras["decision"] == "occlusion"
        assert current.state == TrackState.OCCLUDED
        # S2 sec. 5 (2)(2): the position is the prediction, and the next frame starts there.
        assert previous.prediction is not None and current.box is not None
        assert current.box.cx == pytest.approx(previous.prediction.cx)
        assert current.box.cy == pytest.approx(previous.prediction.cy)


def slab_scene(seed: int, lead: int = 30, hidden: int = 15) -> Scene:
    """A 40x30 target at a constant 4 px/frame (the document's roughly constant-velocity car),
    tracked for ``lead`` frames, then passing behind a full-height slab: partly hidden for 10
    frames, fully hidden for ``hidden`` frames (``events["occluded"]``, half-open), partly for
    10 more, then visible again. The slab's grey (about 40, grey bin 2 of 16) is neither the
    target's (92-139, bins 5-8) nor the background's (about 178, bin 11), so a grey-level model
    finds nothing of itself on it."""
    ax, ay, speed, width, height = 20.0, 15.0, 4.0, 400, 240
    cross = math.ceil(2 * ax / speed)  # frames from touching the slab to fully behind it
    frames = lead + cross + hidden + cross + 12
    spec = SceneSpec("slab", seed, width, height, frames, FPS)
    motion, looks = spec.rng(0), spec.rng(1)
    x_start = ax + 12
    cx = x_start + speed * np.arange(frames, dtype=np.float64)
    slab = math.ceil(2 * ax + 2 + speed * hidden)
    x0 = math.floor(x_start + ax + lead * speed) + 1
    y0, y1 = motion.uniform(0.4, 0.6, 2) * height
    cy = y0 + (y1 - y0) * np.arange(frames) / (frames - 1)
    if motion.random() < 0.5:
        cx, x0 = width - cx, width - x0 - slab
    background = StaticBackground(make_background(looks, height, width, PAPER))
    sprites: list[Ellipse | Pillar] = [
        Ellipse(cx, cy, np.full(frames, ax), np.full(frames, ay), target_paint(looks), 1),
        Pillar(x0, pillar_texture(looks, height, slab, grey=40.0)),
    ]

    def events(truth: Truth) -> dict[str, tuple[int, int]]:
        hidden_frames = np.flatnonzero([visible == 0.0 for _, _, visible in truth[1].values()])
        return {"occluded": (int(hidden_frames[0]), int(hidden_frames[-1]) + 1)}

    compositor = Compositor(background, sprites, SensorNoise(3.0), seed)
    return assemble(spec, compositor, events)


def rides_through(seed: int, occluder: str, *overrides: str) -> tuple[list[str], np.ndarray]:
    """Decisions on the fully hidden frames, and the IoU on the 5 frames after them.

    ``occluder="cover"``: the shipped `cover` scene at 60 frames (a 41x31 target at ~4 px/frame
    tracked for 30 frames, then hidden at once for 18 by a flat panel: no partial occlusion);
    ``"slab"``: :func:`slab_scene`."""
    scene = make_scene("cover", seed=seed, frames=60) if occluder == "cover" else slab_scene(seed)
    start, end = scene.events["occluded"]
    assert end - start >= 15
    results = track(list(scene.as_frames()), scene.boxes[0], *overrides)
    return ([r.extras["decision"] for r in results[start:end]],
            overlaps(results, scene.boxes)[end : end + 5])


#: S2 sec. 5: "T 为帧间时间间隔" (T is the time interval between frames). The shipped config reads
#: it in seconds from the timestamps; the other reading is one frame (see configs/s2.toml).
T_ONE_FRAME = "kalman.timebase=frame"
SEEDS = range(6)


@pytest.mark.parametrize("seed", SEEDS)
def test_rides_through_an_18_frame_sudden_full_occlusion(seed: int) -> None:
    # A straight constant-velocity track, 30 frames tracked (the document's big car: 42), then
    # 18 frames with nothing of the target in any window (the document: about 13): the
    # occlusion branch on every hidden frame, and the box back on the target within 5 frames of
    # its reappearance.
    decisions, back = rides_through(seed, "cover")
    assert set(decisions) == {"occlusion"}
    assert back.max() > 0.5, np.round(back, 2)


def test_the_shipped_predictor_and_threshold_follow_a_curving_target() -> None:
    # The stiff predictor of T in seconds lags a curving target by up to ~25 px, mostly inside
    # the shipped D (0.4 of the box's width + height, 29 px for this 41x31 target): on the
    # curvy `smooth` scene S2 calls at most a few frames an occlusion (measured 0-3 of 150) and
    # recovers. A fixed D of 20 px (the document's 30x20 case applied to every size) calls that
    # lag an occlusion on 19-75 frames and the box drifts off (mean IoU 0.24-0.38 lower).
    fixed_d = ("kernel_meanshift.distance_unit=px", "kernel_meanshift.distance=20")
    for seed in range(3):
        scene = make_scene("smooth", seed=seed, width=320, height=240, fps=FPS)
        frames = list(scene.as_frames())
        shipped = track(frames, scene.boxes[0])
        fixed = track(frames, scene.boxes[0], *fixed_d)
        assert [r.extras["decision"] for r in shipped].count("occlusion") <= 5
        assert [r.extras["decision"] for r in fixed].count("occlusion") >= 15
        assert overlaps(shipped, scene.boxes).mean() > overlaps(fixed, scene.boxes).mean() + 0.15


def kalman_predictions(times: list[float], xs: list[float], *settings: str) -> np.ndarray:
    """Per frame, x of the prediction the shipped S2 kalman stage hands to that frame's search
    (NaN before it predicts), fed the positions ``xs`` at the timestamps ``times``."""
    (_, values), = [(n, v) for n, v in load_config("s2").with_overrides(list(settings)).stages
                    if n == "kalman"]
    kalman = build_stage("kalman", values, "test")
    blank = np.zeros((8, 8, 3), np.uint8)
    ctx = TrackContext(frame=BgrFrame(0, times[0], blank), seed=0)
    predicted = []
    for i, (time_s, x) in enumerate(zip(times, xs, strict=True)):
        ctx.new_frame(BgrFrame(i, time_s, blank))  # the kalman stage's forecast: for time_s
        predicted.append(ctx.prediction.cx if ctx.prediction else math.nan)
        ctx.measurement = Box.from_center(x, 100.0, 10.0, 10.0)
        (kalman.start if i == 0 else kalman.step)(ctx)
    return np.array(predicted)


def test_a_change_of_frame_rate_is_predicted_with_the_new_interval() -> None:
    # A target on a parabola x = 300 t^2 (pixels, seconds) sampled at 25 fps, then at 10 fps,
    # as the document's fig. 1 drops from 5 to 2 frames per second. T from the timestamps
    # follows the change on the frame it happens: with the kinematic T^2/2 the model is exact
    # for a parabola at any step, and every prediction is on the target; with the T^2 printed
    # in eq. 14 the velocity state is a backward difference over the previous T and the
    # predictions are within 2.5 px; with T = 1 frame the change throws them off by > 7 px.
    times = [i / 25 for i in range(12)] + [11 / 25 + j / 10 for j in range(1, 10)]
    xs = np.array([300.0 * t * t for t in times])
    exact = kalman_predictions(times, xs, "kalman.kinematic=true")[3:] - xs[3:]
    printed = kalman_predictions(times, xs)[3:] - xs[3:]
    one_frame = kalman_predictions(times, xs, T_ONE_FRAME)[3:] - xs[3:]
    assert np.abs(exact).max() < 1e-6, np.round(exact, 2)
    assert np.abs(printed).max() < 2.5, np.round(printed, 2)
    assert np.abs(one_frame).max() > 7.0, np.round(one_frame, 2)


@pytest.mark.parametrize("fps", [25.0, 10.0])
def test_t_is_the_time_between_frames_from_their_timestamps(fps: float) -> None:
    # The shipped predictor on a jittery straight track equals the one with a fixed T = 1/fps;
    # it is not the one with T = 1 (S2: "T is the time interval between frames").
    times = [i / fps for i in range(30)]
    xs = [50.0 + 3.0 * i + (-1.0) ** i for i in range(30)]
    shipped = kalman_predictions(times, xs)
    fixed = kalman_predictions(times, xs, T_ONE_FRAME, f"kalman.dt={1 / fps!r}")
    assert shipped[3:] == pytest.approx(fixed[3:], abs=1e-9)
    assert shipped[3:] != pytest.approx(kalman_predictions(times, xs, T_ONE_FRAME)[3:], abs=0.1)


@pytest.mark.xfail(strict=True, reason=(
    "not reproduced with T = 1 frame: with W = diag(0,0,1) in pixels per "
    "frame^2 the acceleration follows the mean-shift jitter of the last frames (R = 1), and 18 "
    "frames of coasting extrapolate it quadratically: on the same straight constant-velocity "
    "path as the previous test, 49 to 319 px off on the last hidden frame, and on no seed back "
    "on the target within 5 frames (T in seconds: 2 to 18 px off, back on every seed)"))
def test_rides_through_an_18_frame_sudden_full_occlusion_with_t_one_frame() -> None:
    for seed in SEEDS:
        decisions, back = rides_through(seed, "cover", T_ONE_FRAME)
        assert set(decisions) == {"occlusion"} and back.max() > 0.5


@pytest.mark.xfail(strict=True, reason=(
    "not reproduced behind a slab, with either reading of T, although the slab's grey is unlike "
    "the target's: for the 10 frames of partial occlusion before the target is fully hidden, "
    "mean shift follows its visible part and, r staying <= D, is accepted and fed to the "
    "predictor (S2 sec. 5 (1); the document has no other test, and does not use rho), which "
    "learns that the target slows down at the slab's edge. With T in seconds the occlusion "
    "branch is taken on 0 to 15 of the 15 hidden frames (never on 2 seeds of 6: the box stays "
    "at the edge, on background of the model) and the box ends 41 to 110 px off; with T = 1 "
    "frame the prediction stops with the visible part (the branch is taken on 0 to 3 frames; "
    "96 to 134 px off). No seed is "
    "back on the target within 5 frames of its reappearance"))
@pytest.mark.parametrize("t", ["kalman.timebase=seconds", T_ONE_FRAME])
def test_rides_through_a_15_frame_full_occlusion_behind_a_slab(t: str) -> None:
    for seed in SEEDS:
        decisions, back = rides_through(seed, "slab", t)
        assert set(decisions) == {"occlusion"} and back.max() > 0.5


def reversed_scale_scene(seed: int) -> tuple[list[BgrFrame], list[Box | None]]:
    """The shipped ``scale`` scene played backwards: the target shrinks to half its size."""
    scene = make_scene("scale", seed=seed, width=320, height=240, fps=FPS)
    return as_frames(list(scene.frames())[::-1]), scene.boxes[::-1]


def size_ratios(results: list[FrameResult], boxes: list[Box | None]) -> np.ndarray:
    """Tracked over true box width, per frame (S2 keeps the initial aspect ratio)."""
    return np.array([r.box.w / g.w for r, g in zip(results, boxes, strict=True)])


@pytest.mark.parametrize("seed", [0, 1])
def test_box_size_follows_a_x2_shrink(seed: int) -> None:
    frames, boxes = reversed_scale_scene(seed)
    assert boxes[0].w == pytest.approx(2 * boxes[-1].w)
    ratios = size_ratios(track(frames, boxes[0]), boxes)
    assert np.abs(ratios - 1.0).max() <= 0.15, np.round(ratios, 2)


def grow(seed: int, *overrides: str) -> np.ndarray:
    scene = make_scene("scale", seed=seed, width=320, height=240, fps=FPS)
    return size_ratios(track(as_frames(list(scene.frames())), scene.boxes[0], *overrides),
                       scene.boxes)


@pytest.mark.xfail(strict=True, reason=(
    "not reproduced with the pyramid kernel: it weighs the box's edges at about half its centre, "
    "so the model holds much background; a window inside a grown target loses that background "
    "at every candidate bandwidth, rho no longer prefers the larger one, and the box shrinks "
    "(ends at 0.57-0.71 of the true size on seeds 0-2, 0.57-0.70 with the Bhattacharyya "
    "coefficient instead of eq. 11); the document shows only a zoom out (fig. 3(d), 60x40 to "
    "48x32), reproduced above; the Epanechnikov kernel follows the growth (next test)"))
def test_box_size_follows_a_x2_growth_with_the_pyramid_kernel() -> None:
    assert np.abs(grow(0) - 1.0).max() <= 0.15


def test_box_size_follows_a_x2_growth_with_the_epanechnikov_kernel() -> None:
    ratios = grow(0, "kernel_meanshift.kernel=epanechnikov")
    assert np.abs(ratios - 1.0).max() <= 0.15, np.round(ratios, 2)


def test_shipped_config_is_the_documented_chain() -> None:
    config = load_config("s2")
    assert [name for name, _ in config.stages] == ["kernel_meanshift", "kalman"]
    meanshift, kalman = config.build()
    assert meanshift.settings() == {
        "feature": "gray16", "bins": 16, "kernel": "pyramid", "weights": "ratio",
        "similarity": "intersection", "max_iterations": 20, "epsilon": 1.0, "scale_step": 0.1,
        "scale_smoothing": 0.1, "failure_logic": True, "distance": 0.4, "distance_unit": "box",
        "occluded_update": "prediction",
    }
    assert kalman.settings()["model"] == "ca"
    assert Pipeline([meanshift, kalman]).columns == ("decision", "scale", "iterations",
                                                     "pred_cx", "pred_cy")


WRONG = {str: 3, int: "3", float: "x", bool: 1}


@pytest.mark.parametrize("param", KernelMeanShift.params, ids=lambda p: p.name)
def test_every_parameter_rejects_a_wrong_type(param: Param) -> None:
    with pytest.raises(ConfigError) as error:
        build_stage("kernel_meanshift", {param.name: WRONG[param.type]}, "s2.toml")
    message = str(error.value)
    assert "s2.toml" in message and "'kernel_meanshift'" in message and param.name in message


@pytest.mark.parametrize(("config", "box"), [("s2-fixed", (319, 239, 4, 4)),
                                           ("s2-fixed", (-3.9, -3.9, 4, 4)),
                                           ("s2", (-3.9, -3.9, 4, 4))])
def test_a_box_s2s_kernel_sees_nothing_of_is_refused_saying_why(config, box) -> None:
    """The box overlaps the frame, so 'is outside the frame' (no stage named) was untrue: S2's
    kernel, centred on the box, weighs no pixel of the frame."""
    from vtrack.errors import InputError
    from vtrack.pipeline import Pipeline

    frames = [BgrFrame(0, 0.0, np.full((240, 320, 3), 90, np.uint8))]
    with pytest.raises(InputError, match=r"kernel_meanshift\w*: the initial box .* puts no frame "
                       r"pixel under S2's kernel \(move it further into the frame\)"):
        list(Pipeline(load_config(config).build()).track(frames, Box(*box)))
