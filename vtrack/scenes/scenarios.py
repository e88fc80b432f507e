"""The scenarios: how objects move and what happens, per scenario, with its events.

Motion is laid out over the clip (a 90-frame and a 600-frame ``smooth`` clip both show the same
path), so every event happens inside the clip whatever its length; each scenario has a minimum
frame count that leaves room for its events (e.g. >= 18 fully hidden frames for ``occlusion``).
Sizes are fractions of the frame's shorter side. Randomness: the seed picks phases, directions,
textures and noise; the structure of each scenario (and its guarantees) never changes.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Mapping
from dataclasses import dataclass
from typing import Any

import numpy as np

from vtrack.errors import (
    ConfigError,
    did_you_mean,
    names_a_path,
    number_text,
    plural,
    quoted_or_cut,
)
from vtrack.geometry import Window
from vtrack.io.raw import MAX_FPS, MIN_FPS
from vtrack.params import shown
from vtrack.scenes.render import (
    CAMERA,
    FLOOR,
    NIGHT,
    PAPER,
    Compositor,
    Ellipse,
    GlowPaint,
    Panel,
    PanningBackground,
    Pillar,
    SensorNoise,
    StaticBackground,
    SurfacePaint,
    make_background,
    pillar_texture,
    target_paint,
)
from vtrack.scenes.scene import Scene, SceneSpec, Truth, assemble

#: Fewest pixels a scene may have across / down.
MIN_WIDTH, MIN_HEIGHT = 64, 48
#: Largest scene (8K UHD): a frame is rendered whole in float32, ~400 MB at this size.
MAX_WIDTH, MAX_HEIGHT = 7680, 4320
#: The longest scene (an hour at 30 fps): its ground truth is computed before any frame.
MAX_FRAMES = 108_000
#: Sensor noise (grey levels, std) of the ordinary scenes.
NOISE_SIGMA = 3.0
#: Fewest frames the target spends fully hidden (occlusion) or fully out of view (leave_return).
HIDDEN_FRAMES = 18


# ---------------------------------------------------------------------------------- helpers


def _axes(spec: SceneSpec, scale: float = 1.0) -> tuple[float, float]:
    """Semi-axes of the standard target (a 4:3 ellipse ~17% of the short side wide)."""
    short = min(spec.width, spec.height)
    return 0.085 * short * scale, 0.065 * short * scale


def _full(spec: SceneSpec, value: float) -> np.ndarray:
    return np.full(spec.frames, value, np.float64)


def _phase(spec: SceneSpec) -> np.ndarray:
    """Clip time 0..1 per frame."""
    return np.arange(spec.frames) / max(spec.frames - 1, 1)


def _lissajous(
    spec: SceneSpec,
    motion: np.random.Generator,
    half_w: float,
    half_h: float,
    reach: float,
    cycles: tuple[float, float] = (1.0, 1.5),
) -> tuple[np.ndarray, np.ndarray]:
    """A smooth curvy path that keeps a ``2 half_w`` x ``2 half_h`` box 5% inside the frame."""
    w, h = spec.width, spec.height
    t = _phase(spec)
    px, py = motion.uniform(0.0, 2.0 * math.pi, 2)
    room_x = max(w / 2 - half_w - 0.05 * w, 0.0)
    room_y = max(h / 2 - half_h - 0.05 * h, 0.0)
    cx = w / 2 + reach * room_x * np.sin(2 * math.pi * cycles[0] * t + px)
    cy = h / 2 + reach * room_y * np.sin(2 * math.pi * cycles[1] * t + py)
    return cx, cy


def _paper(spec: SceneSpec, looks: np.random.Generator) -> StaticBackground:
    return StaticBackground(make_background(looks, spec.height, spec.width, PAPER))


def _target(
    spec: SceneSpec,
    looks: np.random.Generator,
    cx: np.ndarray,
    cy: np.ndarray,
    ax: np.ndarray | float,
    ay: np.ndarray | float,
    paint: SurfacePaint | None = None,
) -> Ellipse:
    """The textured target, track id 1: ``paint``, or the red/orange one drawn from ``looks``."""
    ax_arr = ax if isinstance(ax, np.ndarray) else _full(spec, ax)
    ay_arr = ay if isinstance(ay, np.ndarray) else _full(spec, ay)
    return Ellipse(cx, cy, ax_arr, ay_arr, paint or target_paint(looks), track_id=1)


def _first_run(mask: np.ndarray) -> tuple[int, int] | None:
    """Half-open ``(start, end)`` of the first run of True in ``mask``, or None."""
    hits = np.flatnonzero(mask)
    if hits.size == 0:
        return None
    start = int(hits[0])
    rest = np.flatnonzero(~mask[start:])
    end = start + int(rest[0]) if rest.size else mask.size
    return start, end


def _fractions(truth: Truth, track_id: int) -> tuple[np.ndarray, np.ndarray]:
    """(in-frame, visible) fractions of one track as arrays."""
    rows = truth[track_id].values()
    return np.array([r[1] for r in rows]), np.array([r[2] for r in rows])


def _centres(truth: Truth, track_id: int) -> np.ndarray:
    return np.array([(r[0].cx, r[0].cy) for r in truth[track_id].values()])


# -------------------------------------------------------------------------------- scenarios


def _smooth(spec: SceneSpec) -> Scene:
    motion, looks = spec.rng(0), spec.rng(1)
    ax, ay = _axes(spec)
    cx, cy = _lissajous(spec, motion, ax, ay, reach=0.8)
    background = _paper(spec, looks)
    sprites = [_target(spec, looks, cx, cy, ax, ay)]
    return assemble(spec, Compositor(background, sprites, SensorNoise(NOISE_SIGMA), spec.seed))


def _occlusion(spec: SceneSpec) -> Scene:
    motion, looks = spec.rng(0), spec.rng(1)
    w, h, n = spec.width, spec.height, spec.frames
    ax, ay = _axes(spec)
    # Constant velocity across the frame, behind a slab wide enough to hide the target for
    # HIDDEN_FRAMES (or 20% of the clip) frames: a constant-velocity predictor rides through.
    x_start, x_end = ax + 0.05 * w + 1, w - ax - 0.05 * w - 1
    speed = (x_end - x_start) / (n - 1)
    hidden = max(HIDDEN_FRAMES, round(0.2 * n))
    slab = math.ceil(2 * ax + 2 + speed * hidden)
    x0 = round(w / 2 - slab / 2 + motion.uniform(-0.02, 0.02) * w)
    cx = x_start + speed * np.arange(n)
    if motion.random() < 0.5:
        cx = cx[::-1].copy()
    y0, y1 = motion.uniform(0.35, 0.65, 2) * h
    cy = y0 + (y1 - y0) * _phase(spec)
    background = _paper(spec, looks)
    sprites = [
        _target(spec, looks, cx, cy, ax, ay),
        Pillar(x0, pillar_texture(looks, h, slab)),
    ]

    def events(truth: Truth) -> dict[str, Any]:
        in_frame, visible = _fractions(truth, 1)
        return {"occluded": _first_run((visible == 0.0) & (in_frame > 0.0))}

    compositor = Compositor(background, sprites, SensorNoise(NOISE_SIGMA), spec.seed)
    return assemble(spec, compositor, events)


def _jump(spec: SceneSpec) -> Scene:
    motion, looks = spec.rng(0), spec.rng(1)
    w, h, n = spec.width, spec.height, spec.frames
    ax, ay = _axes(spec)
    t = _phase(spec)
    k = n // 2
    # 2.5 target widths between two consecutive frames, gentle wobble before and after.
    step_x = 2.5 * 2 * ax * (1 if motion.random() < 0.5 else -1)
    step_y = motion.uniform(-0.1, 0.1) * h
    after = (np.arange(n) >= k).astype(np.float64)
    px, py = motion.uniform(0.0, 2.0 * math.pi, 2)
    cx = w / 2 + step_x * (after - 0.5) + 0.08 * w * np.sin(2 * math.pi * t + px)
    cy = h / 2 + step_y * (after - 0.5) + 0.12 * h * np.sin(2 * math.pi * 1.3 * t + py)
    background = _paper(spec, looks)
    sprites = [_target(spec, looks, cx, cy, ax, ay)]
    compositor = Compositor(background, sprites, SensorNoise(NOISE_SIGMA), spec.seed)
    return assemble(spec, compositor, lambda truth: {"jump": k})


def _accelerate(spec: SceneSpec) -> Scene:
    motion, looks = spec.rng(0), spec.rng(1)
    w, h, n = spec.width, spec.height, spec.frames
    short = min(w, h)
    # The document's 32x20 target at 240 px; from rest at a constant acceleration, crossing the
    # frame over the clip, so that its displacement between frames grows by the same amount each
    # frame until it exceeds its width: a motion the constant-acceleration predictor describes.
    ax, ay, margin = short / 15, short / 24, 0.05 * short
    travel = w - 2 * (ax + margin)
    slope = motion.uniform(-0.15, 0.15)
    slope = float(np.clip(slope, -(h / 2 - ay - margin) / travel, (h / 2 - ay - margin) / travel))
    distance = travel * (np.arange(n, dtype=np.float64) / max(n - 1, 1)) ** 2
    direction = 1.0 if motion.random() < 0.5 else -1.0
    start = ax + margin if direction > 0 else w - ax - margin
    cx = start + direction * distance
    cy = h / 2 + slope * distance
    steps = np.hypot(np.diff(cx), np.diff(cy))
    fast = np.flatnonzero(steps > 2 * ax)
    if fast.size == 0:
        longest = max(k for k in range(3, n + 1) if travel * (2 * k - 3) / (k - 1) ** 2 > 2 * ax)
        raise ConfigError(
            f"scenario 'accelerate' at {w}x{h}: in {plural(n, 'frame')} the target never moves "
            f"more than its width between two frames; ask for at most {plural(longest, 'frame')} "
            "or a wider frame"
        )
    background = _paper(spec, looks)
    sprites = [_target(spec, looks, cx, cy, ax, ay)]
    compositor = Compositor(background, sprites, SensorNoise(NOISE_SIGMA), spec.seed)
    return assemble(spec, compositor, lambda truth: {"fast": int(fast[0]) + 1})


def _cover(spec: SceneSpec) -> Scene:
    motion, looks = spec.rng(0), spec.rng(1)
    w, h, n = spec.width, spec.height, spec.frames
    ax, ay = _axes(spec)
    # Constant velocity across the frame; from mid-clip a flat white panel in front hides the
    # target at once for HIDDEN_FRAMES frames, with no partial occlusion before or after.
    x_start, x_end = ax + 0.05 * w + 1, w - ax - 0.05 * w - 1
    cx = x_start + (x_end - x_start) * _phase(spec)
    if motion.random() < 0.5:
        cx = cx[::-1].copy()
    y0, y1 = motion.uniform(0.4, 0.6, 2) * h
    cy = y0 + (y1 - y0) * _phase(spec)
    start = n // 2
    end = start + HIDDEN_FRAMES
    # The panel covers the whole hidden path and two target sizes around it, so no window near
    # the path holds any of the target on those frames.
    left, right = cx[start:end].min() - 4 * ax, cx[start:end].max() + 4 * ax
    top, bottom = cy[start:end].min() - 4 * ay, cy[start:end].max() + 4 * ay
    panel = Window(math.floor(left), math.floor(top), math.ceil(right), math.ceil(bottom))
    sprites = [
        _target(spec, looks, cx, cy, ax, ay),
        Panel(panel, (250, 250, 250), start, end),
    ]

    def events(truth: Truth) -> dict[str, Any]:
        in_frame, visible = _fractions(truth, 1)
        return {"occluded": _first_run((visible == 0.0) & (in_frame > 0.0))}

    compositor = Compositor(_paper(spec, looks), sprites, SensorNoise(NOISE_SIGMA), spec.seed)
    return assemble(spec, compositor, events)


def _scale(spec: SceneSpec) -> Scene:
    motion, looks = spec.rng(0), spec.rng(1)
    ax0, ay0 = _axes(spec, 0.7)
    growth = 2.0 ** _phase(spec)  # x2 over the clip at a constant relative rate
    cx, cy = _lissajous(spec, motion, 2 * ax0, 2 * ay0, reach=0.5, cycles=(0.5, 0.75))
    background = _paper(spec, looks)
    sprites = [_target(spec, looks, cx, cy, ax0 * growth, ay0 * growth)]
    compositor = Compositor(background, sprites, SensorNoise(NOISE_SIGMA), spec.seed)
    return assemble(spec, compositor, lambda truth: {"scale": (0, spec.frames - 1, 2.0)})


def _leave_return(spec: SceneSpec) -> Scene:
    motion, looks = spec.rng(0), spec.rng(1)
    w, h, n = spec.width, spec.height, spec.frames
    ax, ay = _axes(spec)
    # Out through the right side at constant speed, turn round outside, come back the same way.
    hidden = max(HIDDEN_FRAMES, round(0.2 * n))
    middle = (n - 1) / 2
    x_start, gone = 0.7 * w, w + ax + 1
    speed = (gone - x_start) / (middle - (hidden / 2 + 1))
    cx = x_start + speed * (middle - np.abs(np.arange(n) - middle))
    if motion.random() < 0.5:
        cx = w - cx  # out through the left side instead
    cy = h / 2 + 0.2 * h * np.sin(2 * math.pi * _phase(spec) + motion.uniform(0, 2 * math.pi))
    background = _paper(spec, looks)
    sprites = [_target(spec, looks, cx, cy, ax, ay)]

    def events(truth: Truth) -> dict[str, Any]:
        in_frame, _ = _fractions(truth, 1)
        return {"leave": _first_run(in_frame == 0.0)}

    compositor = Compositor(background, sprites, SensorNoise(NOISE_SIGMA), spec.seed)
    return assemble(spec, compositor, events)


def _distractor(spec: SceneSpec) -> Scene:
    motion, looks = spec.rng(0), spec.rng(1)
    w, h = spec.width, spec.height
    ax, ay = _axes(spec)
    t = _phase(spec)
    # Target left to right; an identical object right to left just below it, never touching.
    x_from, x_to = 0.1 * w + ax, 0.9 * w - ax
    cx = x_from + (x_to - x_from) * t
    cy = motion.uniform(0.3, 0.38) * h + 0.04 * h * np.sin(2 * math.pi * t + motion.uniform(0, 6))
    separation = 2 * ay + max(3.0, 0.4 * ay)
    background = _paper(spec, looks)
    target = _target(spec, looks, cx, cy, ax, ay)
    twin = Ellipse(w - cx, cy + separation, _full(spec, ax), _full(spec, ay), target.paint, None)
    sprites = [twin, target]

    def events(truth: Truth) -> dict[str, Any]:
        distance = np.hypot(2 * cx - w, separation)
        return {
            "distractor": _first_run(distance < 2 * (2 * ax)),
            "closest": int(np.argmin(distance)),
        }

    compositor = Compositor(background, sprites, SensorNoise(NOISE_SIGMA), spec.seed)
    return assemble(spec, compositor, events)


def _lighting(spec: SceneSpec) -> Scene:
    motion, looks = spec.rng(0), spec.rng(1)
    ax, ay = _axes(spec)
    cx, cy = _lissajous(spec, motion, ax, ay, reach=0.7)
    gain = 1.0 - 0.4 * _phase(spec)
    background = _paper(spec, looks)
    sprites = [_target(spec, looks, cx, cy, ax, ay)]
    compositor = Compositor(background, sprites, SensorNoise(NOISE_SIGMA), spec.seed, gain)
    return assemble(spec, compositor, lambda truth: {"lighting": (0, spec.frames - 1, 0.6)})


def _multi(spec: SceneSpec) -> Scene:
    motion, looks = spec.rng(0), spec.rng(1)
    w, h, n = spec.width, spec.height, spec.frames
    t = _phase(spec)
    i = np.arange(n, dtype=np.float64)
    radii = motion.uniform(3.0, 6.0, 4)  # 6..12 px across
    peaks = motion.uniform(170.0, 230.0, 4)
    paths = [
        # 1 and 2 cross in the middle of the frame at mid-clip.
        (0.15 * w + 0.7 * w * t, 0.25 * h + 0.5 * h * t),
        (0.15 * w + 0.7 * w * t, 0.75 * h - 0.5 * h * t),
        # 3 leaves through the left side near mid-clip.
        (0.25 * w - (0.25 * w + radii[2] + 1) * i / (0.5 * (n - 1)), 0.5 * h + 0.1 * h * t),
        # 4 comes in through the right side at mid-clip.
        (w + radii[3] + 1 - 0.3 * w * (i - n // 2) / (n / 2), _full(spec, 0.5 * h)),
    ]
    sprites = [
        Ellipse(px, py, _full(spec, r), _full(spec, r), GlowPaint(peak), track_id=tid)
        for tid, ((px, py), r, peak) in enumerate(zip(paths, radii, peaks, strict=True), start=1)
    ]
    background = StaticBackground(make_background(looks, h, w, NIGHT))

    def events(truth: Truth) -> dict[str, Any]:
        gap = np.hypot(*(_centres(truth, 1) - _centres(truth, 2)).T)
        in_3, _ = _fractions(truth, 3)
        in_4, _ = _fractions(truth, 4)
        return {
            "cross": int(np.argmin(gap)),
            "cross_ids": (1, 2),
            "exit": int(np.flatnonzero(in_3 == 0.0)[0]),
            "exit_id": 3,
            "appear": int(np.flatnonzero(in_4 > 0.0)[0]),
            "appear_id": 4,
        }

    compositor = Compositor(background, sprites, SensorNoise(4.0), spec.seed)
    return assemble(spec, compositor, events)


def _bounce(spec: SceneSpec) -> Scene:
    motion, looks = spec.rng(0), spec.rng(1)
    w, h, n, fps = spec.width, spec.height, spec.frames, spec.fps
    radius = 0.05 * min(w, h)
    floor_y = round(0.88 * h)
    rest_y = floor_y - radius  # centre height when touching the floor
    top_y = 0.12 * h + radius
    fall = min(0.6, 0.3 * n / fps)  # seconds of the first drop
    gravity = 2 * (rest_y - top_y) / fall**2
    restitution = 0.8
    # Floor contacts: after the drop, each flight is `restitution` times shorter; once a flight
    # would last under 2 frames the ball rests on the floor (and keeps rolling sideways).
    contacts, up_speeds = [fall], [restitution * gravity * fall]
    while 2 * up_speeds[-1] / gravity > 2.0 / fps and contacts[-1] < n / fps:
        contacts.append(contacts[-1] + 2 * up_speeds[-1] / gravity)
        up_speeds.append(restitution * up_speeds[-1])
    time = np.arange(n) / fps
    cy = np.where(time < fall, top_y + 0.5 * gravity * time**2, rest_y)
    for start, speed in zip(contacts[:-1], up_speeds[:-1], strict=True):
        dt = time - start
        flight = (dt >= 0) & (dt < 2 * speed / gravity)
        cy = np.where(flight, rest_y - speed * dt + 0.5 * gravity * dt**2, cy)
    # Sideways at constant speed, reflected by margins at both sides (not events).
    left, span = radius + 0.05 * w, w - 2 * (radius + 0.05 * w)
    travel = motion.uniform(0.0, span) + 0.3 * w * time
    cx = left + span - np.abs(np.mod(travel, 2 * span) - span)
    image = make_background(looks, h, w, PAPER)
    image[floor_y:] = make_background(looks, h - floor_y, w, FLOOR)
    sprites = [_target(spec, looks, cx, cy, radius, radius)]
    bounces = [math.ceil(c * fps) for c in contacts if math.ceil(c * fps) < n]
    compositor = Compositor(StaticBackground(image), sprites, SensorNoise(NOISE_SIGMA), spec.seed)
    return assemble(spec, compositor, lambda truth: {"bounce": bounces})


def _benchmark(spec: SceneSpec) -> Scene:
    motion, looks = spec.rng(0), spec.rng(1)
    w, h, n, fps = spec.width, spec.height, spec.frames, spec.fps
    ax, ay = _axes(spec, 0.7)
    cx, cy = _lissajous(spec, motion, ax, ay, reach=0.8)
    # A slow sub-pixel pan back and forth over a larger textured world (bounded memory).
    pan_x, pan_y = 0.08 * w, 0.03 * h
    i = np.arange(n)
    px, py = motion.uniform(0.0, 2.0 * math.pi, 2)
    offset_x = 2 + pan_x * (1 + np.sin(2 * math.pi * i / (10 * fps) + px))
    offset_y = 2 + pan_y * (1 + np.sin(2 * math.pi * i / (7 * fps) + py))
    world_h, world_w = math.ceil(h + 2 * pan_y) + 5, math.ceil(w + 2 * pan_x) + 5
    world = make_background(looks, world_h, world_w, CAMERA)
    background = PanningBackground(world, w, h, offset_x, offset_y)
    sprites = [_target(spec, looks, cx, cy, ax, ay)]
    return assemble(spec, Compositor(background, sprites, SensorNoise(3.5), spec.seed))


# --------------------------------------------------------------------------------- registry


@dataclass(frozen=True)
class Scenario:
    """A named scenario: what it shows, its events, its defaults and its minimum length."""

    name: str
    summary: str
    events: str
    build: Callable[[SceneSpec], Scene]
    width: int = 320
    height: int = 240
    frames: int = 150
    fps: float = 30.0
    min_frames: int = 10


SCENARIOS: dict[str, Scenario] = {
    s.name: s
    for s in (
        Scenario("smooth", "smooth curvy motion of a textured red/orange target", "none", _smooth),
        Scenario(
            "occlusion",
            "constant velocity behind a full-height foreground slab",
            '"occluded": (start, end) frames fully hidden (>= 18; box kept, visibility 0)',
            _occlusion,
            min_frames=60,
        ),
        Scenario(
            "jump",
            "a displacement of 2.5 target widths between two frames, smooth otherwise",
            '"jump": first frame after the jump',
            _jump,
        ),
        Scenario(
            "accelerate",
            "speeds up from rest at a constant rate until it moves more than its width a frame",
            '"fast": first frame more than a target width from the previous one',
            _accelerate,
            width=640,
            frames=25,
        ),
        Scenario(
            "cover",
            "constant velocity; a flat panel hides the target at once for 18 frames mid-clip",
            '"occluded": (start, end) frames fully hidden (18; no partial occlusion)',
            _cover,
            min_frames=60,
        ),
        Scenario(
            "scale",
            "target size doubles smoothly over the clip",
            '"scale": (first frame, last frame, size factor 2.0)',
            _scale,
        ),
        Scenario(
            "leave_return",
            "target leaves through a side, stays out >= 18 frames, comes back",
            '"leave": (first frame fully out, first frame back); box None while out',
            _leave_return,
            min_frames=60,
        ),
        Scenario(
            "distractor",
            "an identical object passes just below the target in the other direction",
            '"distractor": (start, end) centres < 2 target widths apart; "closest": frame',
            _distractor,
            min_frames=30,
        ),
        Scenario(
            "lighting",
            "global brightness falls by 40% over the clip",
            '"lighting": (first frame, last frame, final gain 0.6)',
            _lighting,
        ),
        Scenario(
            "multi",
            "4 small bright blobs on a dark noisy background (infrared-like)",
            '"cross"/"cross_ids", "exit"/"exit_id", "appear"/"appear_id"; see scene.tracks',
            _multi,
            min_frames=60,
        ),
        Scenario(
            "bounce",
            "a ball falls and bounces on the floor before a static background",
            '"bounce": first frame at or after each floor contact (the ball rises from there)',
            _bounce,
            min_frames=30,
        ),
        Scenario(
            "benchmark",
            "1080p60 camera-like footage: fine texture, sub-pixel pan, noise, moving target",
            "none",
            _benchmark,
            width=1920,
            height=1080,
            frames=600,
            fps=60.0,
        ),
    )
}


#: What an error of :func:`make_scene` calls each setting (``seed``, ``size``: width and
#: height, ``frames``, ``fps``) by default; ``vtrack scene`` passes its options' names.
SETTING_NAMES = {"seed": "scene seed", "size": "scene size", "frames": "scene frames",
                 "fps": "scene fps"}


def make_scene(
    name: str,
    seed: int = 0,
    width: int | None = None,
    height: int | None = None,
    frames: int | None = None,
    fps: float | None = None,
    *,
    names: Mapping[str, str] = SETTING_NAMES,
) -> Scene:
    """Build scenario ``name``; ``None`` takes the scenario's default size, length or rate.

    The same arguments always give bit-identical frames and identical ground truth. Raises
    :class:`~vtrack.errors.ConfigError` for an unknown name (listing the valid ones), a seed
    below 0, a frame smaller than 64x48 or larger than 7680x4320, too few frames for the
    scenario or more than :data:`MAX_FRAMES`, or a rate outside
    :data:`~vtrack.io.raw.MIN_FPS`..``MAX_FPS``: its message names the setting as ``names``
    calls it (:data:`SETTING_NAMES`'s keys) and gives the valid range.
    """
    # (not text, make_scene(None) or make_scene(['a']): no name, however it hashes)
    scenario = SCENARIOS.get(name) if isinstance(name, str) else None
    if scenario is None:
        text = isinstance(name, str)  # (not text: no text to quote or guess from)
        given = quoted_or_cut(name) if text else shown(name)
        near = did_you_mean(name, SCENARIOS) if text and not names_a_path(name) else ""
        raise ConfigError(f"unknown scenario {given}; choose one of: {', '.join(SCENARIOS)}{near}")
    spec = SceneSpec(
        name=name,
        seed=seed,
        width=scenario.width if width is None else width,
        height=scenario.height if height is None else height,
        frames=scenario.frames if frames is None else frames,
        fps=scenario.fps if fps is None else fps,
    )
    if spec.seed < 0:
        raise ConfigError(f"{names['seed']} {spec.seed}: must be 0 or more")
    if not (MIN_WIDTH <= spec.width <= MAX_WIDTH and MIN_HEIGHT <= spec.height <= MAX_HEIGHT):
        raise ConfigError(
            f"{names['size']} {spec.width}x{spec.height}: must be from {MIN_WIDTH}x{MIN_HEIGHT} to "
            f"{MAX_WIDTH}x{MAX_HEIGHT}"
        )
    if spec.frames < scenario.min_frames:
        raise ConfigError(
            f"{names['frames']} {spec.frames}: must be from {scenario.min_frames} (what "
            f"scenario {name!r} needs) to {MAX_FRAMES}"
        )
    if spec.frames > MAX_FRAMES:
        raise ConfigError(f"{names['frames']} {spec.frames}: at most {MAX_FRAMES} (an hour at "
                          "30 fps)")
    if not (math.isfinite(spec.fps) and MIN_FPS <= spec.fps <= MAX_FPS):
        raise ConfigError(f"{names['fps']} {number_text(spec.fps)}: must be from {MIN_FPS:g} to "
                          f"{MAX_FPS:g}")
    return scenario.build(spec)
