"""Issue 14: the `robust` config on the randomised hard scenes (parameters drawn per seed).

Mean IoU >= 0.7 on each scene over several seeds, at two frame sizes and lengths (the speeds,
sizes and occluder widths follow from them as well as from the seed), and on `exit_return`:
`lost` while the target is out of view, `tracking` on the target within 10 frames of its being
fully back.
"""

from __future__ import annotations

import functools
from pathlib import Path

import numpy as np
import pytest

import vtrack.configs
from vtrack.evaluate import frame_scores, mean_overlap

if not (Path(vtrack.configs.__file__).parent / "robust.toml").is_file():
    pytest.skip("robust config not merged yet", allow_module_level=True)

from vtrack import track  # noqa: E402
from vtrack.config import load_config  # noqa: E402
from vtrack.scenes import hard as hard_scenes  # noqa: E402
from vtrack.scenes import make_scene  # noqa: E402

SEEDS = (0, 1, 2)
FRAMES = 120
#: Frames the tracker may take to notice that the target has left, and to be back on it.
GRACE = 10


def run_robust(name: str, seed: int, frames: int = FRAMES, size: tuple[int, int] | None = None,
               overrides: tuple[str, ...] = ()):
    """The scene (320x240 unless ``size``) and robust's (with ``overrides``) per-frame (box,
    state) on it, in memory; computed once per arguments and scene ranges (a test may widen
    them)."""
    return _run_robust(name, seed, frames, size, overrides,
                       tuple(sorted(hard_scenes.RANGES.items())))


@functools.cache
def _run_robust(name: str, seed: int, frames: int, size: tuple[int, int] | None,
                overrides: tuple[str, ...], _ranges: tuple):
    width, height = size or (None, None)
    scene = make_scene(name, seed=seed, frames=frames, width=width, height=height)
    config = load_config("robust").with_overrides(list(overrides))
    results = list(track(scene.as_frames(), config, scene.boxes[0]))
    return scene, [r.box for r in results], [r.state for r in results]


HARD = ["clip_ramp", "fast", "grow", "shrink", "crossing", "slab", "exit_return", "grey"]
#: The slab's mean IoU spreads over 0.46-0.88 from seed to seed (the other hard scenes' over
#: 0.92-0.99), so its bar at the default size is a mean over the benchmark tables' seeds 0-8:
#: over three, seed 0 alone (an occluder coloured like the target, learnt while it hides the
#: target: 0.66 -> 0.46 once occluded frames whose colours agree are learnt) moves it by 0.07
#: (seeds 0-8 0.751 -> 0.726, held-out seeds 100-111 0.723 -> 0.722; benchmarks/RESULTS.md
#: section 8, eighth round).
SLAB_SEEDS = tuple(range(9))
GEOMETRIES = {
    "320x240x120": (SEEDS, FRAMES, None),
    "480x360x90": ((3, 4, 5), 90, (480, 360)),  # larger and shorter: faster motion, a wider slab
}


def seed_means(name: str, seeds, frames: int = FRAMES, size: tuple[int, int] | None = None,
               overrides: tuple[str, ...] = ()) -> list[float]:
    """robust's (with ``overrides``) mean IoU on the scene ``name`` drawn with each seed."""
    means = []
    for seed in seeds:
        scene, boxes, _ = run_robust(name, seed, frames, size, overrides)
        means.append(mean_overlap(frame_scores(boxes, scene.boxes)[0]))
    return means


def test_a_target_faster_than_its_region_is_found_again_across_the_frame():
    """``fast`` leaves the search region on the first frame; the filter, which learnt the
    static background around it as context, keeps a sharp peak there, but the colours at that
    peak are not the target's. With ``redetect_on_colour`` the next frame searches the whole
    frame with the merged response and the target is found again (seeds 0-2: 0.04 -> 0.93
    mean IoU; the shipped runs are the hard-scene test's)."""
    shipped = np.mean(seed_means("fast", SEEDS))
    off = np.mean(seed_means("fast", SEEDS, overrides=("robust_failure.redetect_on_colour=false",)))
    assert shipped >= 0.7 and shipped >= off + 0.3, (shipped, off)


def test_a_target_faster_than_the_scenes_declared_speeds_is_followed(monkeypatch):
    """Drawn at 1.6-2.0 widths a frame (beyond ``fast``'s declared 1.2-1.6), the target is
    found far away again and again: a frame whose target the frame-wide search found far away
    is followed by the same search (seeds 0-2; 0.60 at seeds 100-105 while only a frame whose
    colours disagree was)."""
    monkeypatch.setitem(hard_scenes.RANGES, "fast_speed", (1.6, 2.0))
    means = seed_means("fast", SEEDS)
    assert np.mean(means) >= 0.7, [round(m, 3) for m in means]


@pytest.mark.parametrize("seed", SEEDS)
def test_a_target_given_entering_the_view_is_followed_in(seed):
    """``leave_return`` from frame 77, the target coming back with 28% of its box in view: the
    first box is legal, but robust called the target lost on the very next frame (a box
    mostly outside the frame was taken for a target leaving the view) and only took it back
    3-5 frames later; a 200x150 target entering slowly from a corner was never taken back. It
    is followed in now: on frames 1-8 not lost, IoU 0.5 or more (0.63-0.77 on seeds 0-7)."""
    scene = make_scene("leave_return", seed=seed, frames=FRAMES)
    start = 77
    first = scene.boxes[start]
    assert first is not None
    window = first.window(scene.width, scene.height)
    assert window is not None and window.width * window.height < 0.3 * first.area
    frames = [scene.frame(i) for i in range(start, start + 9)]
    results = list(track(frames, "robust", first))
    scores, _ = frame_scores([r.box for r in results], scene.boxes[start:start + 9])
    assert all(r.state != "lost" for r in results), [r.state for r in results]
    assert min(scores) >= 0.5, scores


@pytest.mark.parametrize("seed", SEEDS)
def test_a_target_given_entering_the_view_is_lost_when_it_leaves_again(seed):
    """The share of a box that counts as "mostly outside" was fixed by a first box entering the
    view (28% inside: 14%), so the same target leaving again later by that edge was followed
    as `tracking` with 34-41% of its box inside, where a run started inside calls it lost. The
    limit rises as the target comes in: a `tracking` box is at least half inside."""
    scene = make_scene("leave_return", seed=seed, frames=FRAMES)
    order = [*range(77, FRAMES), *range(FRAMES - 1, 29, -1)]  # in, then back out by its edge
    first = scene.boxes[77]
    assert first is not None

    def inside(box):
        window = None if box is None else box.window(scene.width, scene.height)
        return 0.0 if window is None else window.width * window.height / box.area

    came_in = left = False
    for i, result in zip(order, track([scene.frame(i) for i in order], "robust", first),
                         strict=True):
        came_in = came_in or (result.state == "tracking" and inside(result.box) >= 1.0)
        left = left or (came_in and inside(scene.boxes[i]) < 0.5)
        if came_in and result.state == "tracking":  # (coming in, less may be inside)
            assert inside(result.box) >= 0.5, result
    assert came_in and left  # the clip shows what the test is about


@pytest.mark.parametrize("name, seeds, frames, size", [
    pytest.param(name, *geometry, id=f"{name}-{key}")
    for key, geometry in GEOMETRIES.items() for name in HARD])
def test_robust_follows_each_hard_scene(name, seeds, frames, size):
    if name == "slab" and size is None:
        seeds = SLAB_SEEDS
    means = seed_means(name, seeds, frames, size)
    assert np.mean(means) >= 0.7, [round(m, 3) for m in means]


#: Behind the slab at 200 frames the target is slower: partly covered for ~40% of the clip.
#: Seeds 0-8, as above (seed 0: 0.73 -> 0.51 once occluded frames are learnt; seeds 0-11
#: 0.785 -> 0.767, held-out seeds 100-111 0.744 -> 0.742).
SLOW_SLAB = dict(seeds=SLAB_SEEDS, frames=200)


def test_robust_follows_the_slow_slab():
    means = seed_means("slab", SLOW_SLAB["seeds"], SLOW_SLAB["frames"])
    assert np.mean(means) >= 0.7, [round(m, 3) for m in means]


@pytest.mark.parametrize("seed", range(6))
def test_robust_is_lost_while_out_and_back_within_10_frames(seed):
    """Out of view through an edge for 15-25 frames: `lost` from 10 frames after it left, and
    back on the target within 10 frames of its return. (Seeds 1 and 4 stayed `occluded` while
    a doubtful peak on the border they left by was followed, until such a peak was no longer
    taken when its box lies mostly outside the frame.)"""
    scene, boxes, states = run_robust("exit_return", seed)
    gone, back_in = scene.events["leave"]
    full = scene.events["back"]
    out = states[gone + GRACE : back_in] if back_in - gone > GRACE else []
    assert out and all(s == "lost" for s in out), states[gone:back_in]
    overlaps, _ = frame_scores(boxes, scene.boxes)
    found = [i for i in range(full, min(full + GRACE + 1, len(scene)))
             if states[i] == "tracking" and overlaps[i] is not None and overlaps[i] > 0.5]
    assert found, states[full : full + GRACE + 1]
    assert all(s == "tracking" for s in states[found[0] : found[0] + GRACE])


@pytest.mark.parametrize("seed", SEEDS)
def test_the_filter_over_the_whole_frame_finds_a_target_that_re_enters_elsewhere(seed):
    """Issue 20: while lost, the filter is run over the whole frame; a target that left and came
    back anywhere is followed again, without the rings of regions around where it left."""
    rings_off = ("robust_failure.redetect=false",)
    found = {}
    for wide in ("true", "false"):
        wide_search = (f"robust_model.filter_redetect={wide}",)
        scene, boxes, _ = run_robust("exit_return", seed, overrides=rings_off + wide_search)
        overlaps, _ = frame_scores(boxes[-20:], scene.boxes[-20:])
        found[wide] = mean_overlap(overlaps)
    assert found["true"] >= 0.9
    assert found["false"] < 0.5  # without it the target is not found again


def test_a_target_hidden_behind_the_slab_is_reported_where_its_motion_carries_it():
    """While the slab hides the target, the response peaks on the slab's edge, whose colours are
    not the target's: neither learner sees it, and with ``coast_unseen`` the box reported is the
    motion model's extrapolation from the last frame that saw it (seeds 0-2, mean IoU over the
    fully hidden frames 0.33 -> 0.74; seed 0's slab is coloured like the target, so its colours
    pass the check and its box stays on the edge either way). Only the report changes: every
    frame's state is the same."""
    shipped, off = [], []
    for seed in SEEDS:
        scene, boxes, states = run_robust("slab", seed)
        _, off_boxes, off_states = run_robust("slab", seed,
                                              overrides=("robust_failure.coast_unseen=false",))
        assert states == off_states, seed
        first, last = scene.events["occluded"]
        hidden = slice(first, last + 1)
        for means, reported in ((shipped, boxes), (off, off_boxes)):
            means.append(mean_overlap(frame_scores(reported[hidden], scene.boxes[hidden])[0]))
    assert np.mean(shipped) >= 0.6 and np.mean(shipped) >= np.mean(off) + 0.2, (shipped, off)


def test_a_pale_target_out_of_view_is_not_taken_back_on_background(monkeypatch):
    """Targets paler than the scenes' declared saturation (30-170 instead of 170-255): out of
    view, the filter matched background texture confidently enough (PSR 14, APCE 0.7 of its
    mean) to take it back there, its colours 0.13 of the target's; a hidden target is taken
    back only where the colours agree too (``retake_colour``). Every seed of 200-203 (one fell
    to 0.19 without it)."""
    monkeypatch.setitem(hard_scenes.RANGES, "saturation", (30.0, 170.0))
    means = seed_means("exit_return", range(200, 204))
    assert min(means) >= 0.7, [round(m, 3) for m in means]


@pytest.mark.parametrize(("seed", "size"), [(708, (64, 48)), (703, (176, 144))])
def test_a_hidden_target_is_never_reported_outside_the_frame(seed: int, size: tuple[int, int]
                                                             ) -> None:
    """`fast` in small frames (`vtrack scene fast --size 64x48 --frames 60 --seed 708`, and
    176x144, 150 frames, seed 703): where the target turns at an edge of the view, a frame
    neither learner saw it on reported the constant-velocity extrapolation, which went on past
    the edge: `occluded` with the box wholly outside the frame (64x48, in memory:
    18.1,-5.3,5.9,4.5 on frame 11; the H.264 file: frames 47-51, the target in view), a place
    a hidden target cannot be. Such an extrapolation is no longer reported (the peak's box is,
    which robust_failure found in view): every box called tracking or occluded has at least a
    quarter of it in view."""
    scene, boxes, states = run_robust("fast", seed, 150 if size[0] > 64 else 60, size)
    for index, (box, state) in enumerate(zip(boxes, states, strict=True)):
        if state == "lost":
            continue
        assert box is not None
        window = box.window(*size)
        assert window is not None and window.width * window.height >= 0.25 * box.area, (
            index, state, box)
