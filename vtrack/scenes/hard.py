"""Scenes that defeat a plain colour tracker, with looks and motion RANDOMISED per seed.

The older scenarios fix the target's colours (red/orange), size and speed; a tracker tuned on them
may work on nothing else. Each scenario here draws its parameters from declared ranges
(:data:`RANGES`): target size, colour (any hue), texture of the background, speed, brightness
range, occluder width and grey level. Same seed -> same parameters and bit-identical frames; the
parameters drawn are in ``scene.events["params"]``. The property each scene shows (channels that
clip, >= 1.2 widths a frame, size x3, >= 15 frames fully hidden, ...) holds for every seed.

These are the scenes of issue 14's "must show" list: ``clip_ramp``, ``fast``, ``grow``,
``shrink``, ``crossing``, ``slab``, ``exit_return`` and ``grey``. They register themselves in
:data:`vtrack.scenes.SCENARIOS` (imported by the package).
"""

from __future__ import annotations

import math
from typing import Any

import cv2
import numpy as np

from vtrack.errors import ConfigError
from vtrack.scenes.render import (
    PAPER,
    BackgroundStyle,
    Compositor,
    Ellipse,
    Pillar,
    SensorNoise,
    StaticBackground,
    SurfacePaint,
    make_background,
    pillar_texture,
    target_paint,
)
from vtrack.scenes.scenarios import (
    NOISE_SIGMA,
    SCENARIOS,
    Scenario,
    _axes,
    _first_run,
    _fractions,
    _full,
    _lissajous,
    _phase,
    _target,
)
from vtrack.scenes.scene import Scene, SceneSpec, Truth, assemble

#: Declared ranges of the randomised parameters (uniform draws). Sizes are relative to the
#: standard target (a 4:3 ellipse ~17% of the frame's short side wide); speeds in target widths
#: per frame unless said otherwise; grey levels 0..255.
RANGES: dict[str, tuple[float, float]] = {
    "size": (0.6, 1.0),
    "hue": (0.0, 180.0),  # OpenCV hue of the target's first colour
    "hue_spread": (6.0, 16.0),  # hue difference of its second colour
    "saturation": (170.0, 255.0),
    "value": (205.0, 245.0),  # bright enough that a gain >= 1.3 clips its channels
    "background_mean": (120.0, 190.0),
    "texture": (0.6, 1.6),  # amplitude multiplier of the background's texture
    "gain_low": (0.42, 0.55),  # clip_ramp: darkest gain
    "gain_high": (1.3, 1.45),  # clip_ramp: brightest gain
    "fast_size": (0.5, 0.75),
    "fast_speed": (1.2, 1.6),  # fast: widths per frame (between consecutive frames, at least)
    "scale_factor": (3.0, 3.6),  # grow / shrink: final/initial (or initial/final) size
    "gap": (0.1, 0.5),  # crossing: gap between the two objects, in target heights
    "twin_size": (0.9, 1.1),  # crossing: distractor size relative to the target
    "hidden": (15.0, 22.0),  # slab: frames fully hidden (at least; integer)
    "slab_grey": (70.0, 170.0),
    "exit_speed": (0.15, 0.4),  # exit_return: widths per frame (at least)
    "out_frames": (15.0, 25.0),  # exit_return: frames fully out of view (integer)
    "grey_contrast": (40.0, 75.0),  # grey: target level minus background level (either sign)
}


def _draw(rng: np.random.Generator, name: str) -> float:
    low, high = RANGES[name]
    return float(rng.uniform(low, high))


# ------------------------------------------------------------------------------------ looks


def _hsv_to_bgr(hue: float, sat: float, val: float) -> tuple[float, float, float]:
    """An OpenCV HSV colour (hue 0..180, S and V 0..255) as float BGR 0..255."""
    hsv = np.array([[[2.0 * (hue % 180.0), sat / 255.0, val / 255.0]]], np.float32)
    b, g, r = cv2.cvtColor(hsv, cv2.COLOR_HSV2BGR)[0, 0] * 255.0
    return float(b), float(g), float(r)


def random_paint(looks: np.random.Generator, params: dict[str, Any]) -> SurfacePaint:
    """A saturated two-colour textured paint of any hue (recorded in ``params``)."""
    hue, spread = _draw(looks, "hue"), _draw(looks, "hue_spread")
    sats = [_draw(looks, "saturation") for _ in range(2)]
    vals = [_draw(looks, "value") for _ in range(2)]
    first = _hsv_to_bgr(hue, sats[0], vals[0])
    second = _hsv_to_bgr(hue + spread, sats[1], vals[1])
    paint = target_paint(looks, first, second)
    params.update(hue=hue, hue_spread=spread, first=first, second=second)
    return paint


def random_background(
    spec: SceneSpec, looks: np.random.Generator, params: dict[str, Any], grey: bool = False
) -> StaticBackground:
    """A PAPER-like textured background with random mean level, texture strength and tint."""
    mean, texture = _draw(looks, "background_mean"), _draw(looks, "texture")
    tint = tuple(float(t) for t in looks.uniform(-6.0, 6.0, 3))
    style = BackgroundStyle(
        mean=mean,
        octaves=tuple((size, amp * texture) for size, amp in PAPER.octaves),
        fine=PAPER.fine * texture,
        shapes=PAPER.shapes,
        shape_contrast=PAPER.shape_contrast * texture,
        tint=(0.0, 0.0, 0.0) if grey else tint,  # type: ignore[arg-type]
        chroma=0.0 if grey else PAPER.chroma,
        grey=grey,
    )
    params.update(background_mean=mean, texture=texture)
    return StaticBackground(make_background(looks, spec.height, spec.width, style))


def _sized(spec: SceneSpec, looks: np.random.Generator, params: dict[str, Any],
           name: str = "size") -> tuple[float, float]:
    size = _draw(looks, name)
    params[name] = size
    return _axes(spec, size)


def _compose(spec: SceneSpec, background: StaticBackground, sprites: list,
             gain: np.ndarray | None = None) -> Compositor:
    return Compositor(background, sprites, SensorNoise(NOISE_SIGMA), spec.seed, gain)


def _with_params(params: dict[str, Any], **events: Any) -> dict[str, Any]:
    return {**events, "params": params}


# -------------------------------------------------------------------------------- scenarios


def _clip_ramp(spec: SceneSpec) -> Scene:
    motion, looks = spec.rng(0), spec.rng(1)
    params: dict[str, Any] = {}
    ax, ay = _sized(spec, looks, params)
    cx, cy = _lissajous(spec, motion, ax, ay, reach=float(motion.uniform(0.4, 0.8)))
    low, high = _draw(looks, "gain_low"), _draw(looks, "gain_high")
    knee = float(motion.uniform(0.3, 0.45))
    # A global gain ramp 1 -> low -> high: dark (hue noisy, masks drop pixels), then so bright
    # that the target's brightest channel saturates at 255 (its hue and value shift).
    gain = np.interp(_phase(spec), [0.0, knee, 1.0], [1.0, low, high])
    params.update(gain_low=low, gain_high=high, knee=knee)
    background = random_background(spec, looks, params)
    target = _target(spec, looks, cx, cy, ax, ay, random_paint(looks, params))
    compositor = _compose(spec, background, [target], gain)
    darkest = int(np.argmin(gain))
    return assemble(spec, compositor, lambda truth: _with_params(
        params, gain=(0, darkest, spec.frames - 1, low, high)))


def _constant_speed_loop(spec: SceneSpec, motion: np.random.Generator, ax: float, ay: float,
                         step: float) -> tuple[np.ndarray, np.ndarray]:
    """Centres at constant speed along an ellipse inside the frame, consecutive centres at least
    ``step`` px apart (a chord is shorter than its arc, so the arc step is raised until so)."""
    w, h = spec.width, spec.height
    rx = (w / 2 - ax - 0.04 * w) * float(motion.uniform(0.8, 1.0))
    ry = (h / 2 - ay - 0.04 * h) * float(motion.uniform(0.8, 1.0))
    theta = np.linspace(0.0, 2 * math.pi, 4097)
    px, py = w / 2 + rx * np.cos(theta), h / 2 + ry * np.sin(theta)
    arc = np.concatenate([[0.0], np.cumsum(np.hypot(np.diff(px), np.diff(py)))])
    perimeter = float(arc[-1])
    start = float(motion.uniform(0.0, perimeter))
    sign = 1.0 if motion.random() < 0.5 else -1.0
    arc_step = step
    for _ in range(20):
        s = np.mod(start + sign * arc_step * np.arange(spec.frames), perimeter)
        cx, cy = np.interp(s, arc, px), np.interp(s, arc, py)
        shortest = float(np.hypot(np.diff(cx), np.diff(cy)).min()) if spec.frames > 1 else step
        if shortest >= step:
            return cx, cy
        arc_step *= step / shortest * 1.001
    raise ConfigError(f"scenario 'fast' at {w}x{h}: the frame is too small for the target's speed")


def _fast(spec: SceneSpec) -> Scene:
    motion, looks = spec.rng(0), spec.rng(1)
    params: dict[str, Any] = {}
    ax, ay = _sized(spec, looks, params, "fast_size")
    speed = _draw(motion, "fast_speed")
    params["fast_speed"] = speed
    # Smooth motion (constant speed round an ellipse) of >= `speed` target widths a frame: the
    # target never overlaps its own previous position.
    cx, cy = _constant_speed_loop(spec, motion, ax, ay, speed * 2 * ax)
    background = random_background(spec, looks, params)
    target = _target(spec, looks, cx, cy, ax, ay, random_paint(looks, params))
    return assemble(spec, _compose(spec, background, [target]),
                    lambda truth: _with_params(params, speed=speed))


def _scaling(spec: SceneSpec, grow: bool) -> Scene:
    motion, looks = spec.rng(0), spec.rng(1)
    params: dict[str, Any] = {}
    factor = _draw(looks, "scale_factor")
    small = float(looks.uniform(0.4, 0.5))
    params.update(scale_factor=factor, small=small)
    # Exponential growth (constant relative rate) over the clip, x factor from end to end.
    t = _phase(spec) if grow else 1.0 - _phase(spec)
    size = small * factor**t
    ax0, ay0 = _axes(spec, small)
    cx, cy = _lissajous(spec, motion, ax0 * factor, ay0 * factor,
                        reach=float(motion.uniform(0.3, 0.7)), cycles=(0.5, 0.75))
    background = random_background(spec, looks, params)
    target = Ellipse(cx, cy, ax0 / small * size, ay0 / small * size,
                     random_paint(looks, params), 1)
    return assemble(spec, _compose(spec, background, [target]),
                    lambda truth: _with_params(params, scale=(0, spec.frames - 1, factor)))


def _grow(spec: SceneSpec) -> Scene:
    return _scaling(spec, grow=True)


def _shrink(spec: SceneSpec) -> Scene:
    return _scaling(spec, grow=False)


def _crossing(spec: SceneSpec) -> Scene:
    motion, looks = spec.rng(0), spec.rng(1)
    params: dict[str, Any] = {}
    w, h = spec.width, spec.height
    ax, ay = _sized(spec, looks, params)
    twin_size, gap = _draw(looks, "twin_size"), _draw(motion, "gap")
    tx, ty = ax * twin_size, ay * twin_size
    separation = ay + ty + max(2.0, gap * 2 * ay)
    below = motion.random() < 0.5
    params.update(twin_size=twin_size, gap=gap, below=below)
    # Target across the frame; a same-coloured twin the other way on a parallel path, passing
    # closest (a gap of `gap` target heights, never touching) at frame `closest`.
    t = _phase(spec)
    x_from, x_to = 0.08 * w + ax, 0.92 * w - ax
    cx = x_from + (x_to - x_from) * t
    if motion.random() < 0.5:
        cx = cx[::-1].copy()
    lo = 0.05 * h + ay + (0.0 if below else separation)
    hi = 0.95 * h - ay - (separation if below else 0.0)
    base = float(motion.uniform(lo, max(lo, hi)))
    cy = base + 0.03 * h * np.sin(2 * math.pi * t + float(motion.uniform(0, 2 * math.pi)))
    closest = int(round(float(motion.uniform(0.4, 0.6)) * (spec.frames - 1)))
    twin_cx = 2 * cx[closest] - cx
    twin_cy = cy + (separation if below else -separation)
    paint = random_paint(looks, params)
    twin_paint = target_paint(looks, paint.first, paint.second)
    twin = Ellipse(twin_cx, twin_cy, _full(spec, tx), _full(spec, ty), twin_paint, None)
    target = _target(spec, looks, cx, cy, ax, ay, paint)
    background = random_background(spec, looks, params)

    def events(truth: Truth) -> dict[str, Any]:
        distance = np.hypot(cx - twin_cx, cy - twin_cy)
        return _with_params(params, closest=closest,
                            distractor=_first_run(distance < 2 * (2 * ax)))

    return assemble(spec, _compose(spec, background, [twin, target]), events)


def _slab(spec: SceneSpec) -> Scene:
    motion, looks = spec.rng(0), spec.rng(1)
    params: dict[str, Any] = {}
    w, h, n = spec.width, spec.height, spec.frames
    ax, ay = _sized(spec, looks, params)
    hidden = int(round(_draw(motion, "hidden")))
    middle = int(round(float(motion.uniform(0.45, 0.55)) * (n - 1)))
    # Constant velocity v: fully visible at both ends of the clip, fully hidden for >= `hidden`
    # frames behind a slab of width 2 ax + 2 + v (hidden + 1), partly hidden on either side.
    near = min(middle, n - 1 - middle)
    lowest = (2 * ax + 4) / max(near - (hidden + 1) / 2, 1e-9)
    highest = (w / 2 - ax - 0.06 * w) / max(middle, n - 1 - middle)
    if near <= (hidden + 1) / 2 or lowest > highest:
        raise ConfigError(f"scenario 'slab' at {w}x{h}: {n} frames are too few for its occlusion")
    speed = float(motion.uniform(lowest, highest))
    slab = math.ceil(2 * ax + 2 + speed * (hidden + 1))
    x0 = round(w / 2 - slab / 2 + float(motion.uniform(-0.03, 0.03)) * w)
    direction = 1.0 if motion.random() < 0.5 else -1.0
    cx = x0 + slab / 2 + direction * speed * (np.arange(n) - middle)
    y0, y1 = motion.uniform(0.35, 0.65, 2) * h
    cy = y0 + (y1 - y0) * _phase(spec)
    grey = _draw(looks, "slab_grey")
    params.update(hidden=hidden, speed_px=speed, slab_width=slab, slab_grey=grey)
    background = random_background(spec, looks, params)
    sprites = [
        _target(spec, looks, cx, cy, ax, ay, random_paint(looks, params)),
        Pillar(x0, pillar_texture(looks, h, slab, grey)),
    ]

    def events(truth: Truth) -> dict[str, Any]:
        in_frame, visible = _fractions(truth, 1)
        return _with_params(params, occluded=_first_run((visible == 0.0) & (in_frame > 0.0)))

    return assemble(spec, _compose(spec, background, sprites), events)


def _outside(side: int, along: float, spec: SceneSpec, ax: float, ay: float) -> np.ndarray:
    """A centre just fully outside ``side`` (0 left, 1 right, 2 top, 3 bottom) of the frame, at
    fraction ``along`` of that side."""
    w, h = spec.width, spec.height
    return np.array([
        (-ax - 1.5, along * h), (w + ax + 1.5, along * h),
        (along * w, -ay - 1.5), (along * w, h + ay + 1.5),
    ][side])


def _exit_return(spec: SceneSpec) -> Scene:
    motion, looks = spec.rng(0), spec.rng(1)
    params: dict[str, Any] = {}
    w, h, n = spec.width, spec.height, spec.frames
    ax, ay = _sized(spec, looks, params)
    out_frames = int(round(_draw(motion, "out_frames")))
    exit_side, entry_side = (int(s) for s in motion.integers(0, 4, 2))
    start = np.array([w, h]) * motion.uniform(0.35, 0.65, 2)
    gone = _outside(exit_side, float(motion.uniform(0.25, 0.75)), spec, ax, ay)
    enter = _outside(entry_side, float(motion.uniform(0.25, 0.75)), spec, ax, ay)
    end = np.array([w, h]) * motion.uniform(0.35, 0.65, 2)
    # Straight out at constant speed, `out_frames` frames fully out (it comes back elsewhere,
    # maybe through another side), straight back in at the same speed, then a slow drift.
    # The speed is raised if needed to leave >= 20 frames after it is fully back.
    d_out, d_in = float(np.linalg.norm(gone - start)), float(np.linalg.norm(end - enter))
    speed = _draw(motion, "exit_speed") * 2 * ax
    speed = max(speed, (d_out + d_in) / max(n - out_frames - 20, 1))
    k_out = math.ceil(d_out / speed)
    k_in = min(math.ceil(d_in / speed), n - k_out - out_frames - 1)
    if k_in < 1:
        raise ConfigError(f"scenario 'exit_return': {n} frames are too few")
    path = np.empty((n, 2))
    path[: k_out + 1] = start + (gone - start) * (np.arange(k_out + 1) / k_out)[:, None]
    back = k_out + out_frames  # first frame on the way back (still fully outside)
    path[k_out + 1 : back] = gone
    path[back : back + k_in + 1] = enter + (end - enter) * (np.arange(k_in + 1) / k_in)[:, None]
    rest = n - (back + k_in + 1)
    if rest > 0:  # a slow sway about `end`, on the line it came in along (stays in view)
        sway = 0.1 * min(w, h)
        angle = np.sin(0.25 * speed / sway * np.arange(1, rest + 1))[:, None]
        path[back + k_in + 1 :] = end + (end - enter) / max(d_in, 1e-9) * sway * angle
    params.update(out_frames=out_frames, exit_side=exit_side, entry_side=entry_side,
                  speed_px=speed)
    background = random_background(spec, looks, params)
    target = _target(spec, looks, path[:, 0].copy(), path[:, 1].copy(), ax, ay,
                     random_paint(looks, params))

    def events(truth: Truth) -> dict[str, Any]:
        in_frame, _ = _fractions(truth, 1)
        leave = _first_run(in_frame == 0.0)
        assert leave is not None
        full = np.flatnonzero(in_frame[leave[1]:] == 1.0)
        return _with_params(params, leave=leave,
                            back=leave[1] + int(full[0]) if full.size else None)

    return assemble(spec, _compose(spec, background, [target]), events)


def _grey(spec: SceneSpec) -> Scene:
    motion, looks = spec.rng(0), spec.rng(1)
    params: dict[str, Any] = {}
    ax, ay = _sized(spec, looks, params)
    cx, cy = _lissajous(spec, motion, ax, ay, reach=float(motion.uniform(0.4, 0.8)))
    background = random_background(spec, looks, params, grey=True)
    # A textured grey target on grey texture: brighter or darker than the background by
    # `grey_contrast`, no colour at all (R = G = B before sensor noise).
    contrast = _draw(looks, "grey_contrast") * (1 if looks.random() < 0.5 else -1)
    level = float(np.clip(params["background_mean"] + contrast, 30.0, 235.0))
    other = float(np.clip(level + looks.uniform(-30.0, 30.0), 20.0, 245.0))
    paint = target_paint(looks, (level,) * 3, (other,) * 3)
    params.update(grey_contrast=contrast, level=level, other=other)
    target = _target(spec, looks, cx, cy, ax, ay, paint)
    return assemble(spec, _compose(spec, background, [target]),
                    lambda truth: _with_params(params))


#: The randomised scenarios, in the order of issue 14's list.
HARD_SCENARIOS: tuple[Scenario, ...] = (
    Scenario("clip_ramp", "random looks; gain 1 -> x0.42..0.55 -> x1.3..1.45: target channels clip",
             '"gain": (first, darkest, last frame, low, high gain)', _clip_ramp),
    Scenario("fast", "random looks; smooth loop at 1.2..1.6 target widths per frame",
             '"speed": widths per frame (at least)', _fast),
    Scenario("grow", "random looks; target grows x3..3.6 over the clip",
             '"scale": (first frame, last frame, factor)', _grow),
    Scenario("shrink", "random looks; target shrinks x3..3.6 over the clip",
             '"scale": (first frame, last frame, factor)', _shrink),
    Scenario("crossing", "random looks; a same-coloured twin passes the other way close by",
             '"closest": frame; "distractor": (start, end) centres < 2 widths apart', _crossing,
             min_frames=30),
    Scenario("slab", "random looks; behind a grey slab >= 15 frames, partly hidden around it",
             '"occluded": (start, end) frames fully hidden (>= 15)', _slab, min_frames=60),
    Scenario("exit_return", "random looks; leaves the frame >= 15 frames, re-enters anywhere",
             '"leave": (first frame fully out, first frame back in part); "back": first frame '
             "fully in view again", _exit_return, min_frames=60),
    Scenario("grey", "random looks; a textured grey target on grey texture",
             "none", _grey),
)

SCENARIOS.update((s.name, s) for s in HARD_SCENARIOS)
