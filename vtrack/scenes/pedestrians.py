"""``pedestrians``: people walking past a fixed camera, with looks and motion RANDOMISED per seed.

What a multi-target tracker meets on real fixed-camera footage, with exact ground truth:

- 4 to 6 walkers (ids 1..N), each a tall ellipse (height/width 2.2..2.8) painted as a person:
  head, top and trousers, the trousers sometimes within a few grey levels of the ground (so the
  foreground falls apart into torso and legs); sizes follow the perspective of a camera looking
  down a street (lower in the frame = nearer = larger); nearer walkers are drawn in front;
- walkers 1 and 2 walk towards each other at nearly the same depth and **cross** mid-clip,
  one hiding the other; walker 1 is in view on the first frame (the background model must
  learn around it); walker 3 **leaves** through a side, walker 4 **enters** from one; the
  others start anywhere, in or out of view;
- every walker casts a **shadow** on the ground at its feet (60..80% of the ground's
  brightness, same colour, one direction for all);
- the **background changes slowly**: the whole picture's brightness drifts by 5..12% over the
  clip (clouds), plus sensor noise.

The ground truth (``scene.tracks``) holds every walker at least partly inside the frame, also
while hidden by another, as MOTChallenge's does. Events: ``"cross"`` (frame of the closest
approach of 1 and 2), ``"cross_ids"``, ``"exit"``/``"exit_id"`` (first frame walker 3 is out),
``"appear"``/``"appear_id"`` (first frame walker 4 is in), ``"walkers"`` (N, newcomers
included) and ``"params"``.

A clip longer than the default 150 frames (:data:`PLOT_FRAMES`) keeps moving to its end: walker 1
walks at its own speed, turning back at the sides of the frame until it walks to meet 2 at
mid-clip, and from frame 150 on newcomers (ids N+1, ...) enter from a side every 1..3 s and
cross the street. A clip of 150 frames or fewer is as it was, byte for byte.

``vehicles`` is the same street with vehicles instead of people (:data:`VEHICLES`): the same
paths (1 and 2 pass each other in neighbouring lanes, 3 leaves, 4 enters), each target a
rounded box of height/width 0.3..0.8 (a car to a bus from the side; 0.4..0.55 of a walker's
height at the same depth), painted with a body colour, windows and wheels, faster (0.1..0.3
frame widths per second), with a shorter shadow below it. ``street`` mixes both: each target a
person or a vehicle (even odds).
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import dataclass
from typing import Any

import numpy as np

from vtrack.scenes.render import (
    BackgroundStyle,
    Compositor,
    Ellipse,
    RoundedBox,
    SensorNoise,
    Shade,
    StaticBackground,
    make_background,
)
from vtrack.scenes.scenarios import SCENARIOS, Scenario, _centres, _fractions
from vtrack.scenes.scene import Scene, SceneSpec, Truth, assemble

#: Declared ranges of the randomised parameters (uniform draws); speeds in frame widths per
#: second, heights in frame heights, grey levels 0..255.
PEDESTRIAN_RANGES: dict[str, tuple[float, float]] = {
    "walkers": (4, 6),
    "speed": (0.08, 0.2),
    "aspect": (2.2, 2.8),
    "ground": (110.0, 170.0),
    "shadow": (0.6, 0.8),
    "drift": (0.05, 0.12),
    "arrival": (1.0, 3.0),
}
#: ... and for vehicles: the same counts, drift and shadows; wide shapes, faster; ``height``: a
#: vehicle's height as a share of a walker's at the same depth.
VEHICLE_RANGES: dict[str, tuple[float, float]] = {
    **PEDESTRIAN_RANGES,
    "speed": (0.1, 0.3),
    "aspect": (0.3, 0.8),
    "height": (0.4, 0.55),
}
#: Height of a walker (frame heights) with its feet at the top / bottom of the walkway.
FAR_HEIGHT, NEAR_HEIGHT = 0.22, 0.5
#: The walkway: feet between these shares of the frame height.
WALKWAY = (0.5, 0.95)
#: The frames the scene's own events are laid out over, at most (its default length): a clip no
#: longer is as it always was; in a longer one target 1 turns back at the sides of the frame
#: until it walks to meet 2, and new targets keep entering after this frame (``arrival``
#: seconds apart), so that its second half does not empty.
PLOT_FRAMES = 150
#: Target 1 turns back with its centre at these shares of the frame width.
TURNS = (0.1, 0.9)


@dataclass(frozen=True)
class ShadowShape:
    """Where a target's shadow lies, in shares of the target's height: its centre ``offset``
    to the side of the target's (the scene's one side), ``SHADOW_LIFT`` above its feet;
    ``half_width`` (beyond the target's own half-width when ``widened``) and ``half_height``."""

    offset: float
    half_width: float
    half_height: float
    widened: bool


#: A walker's long shadow beside it, and a vehicle's short one under it, as wide as the vehicle
#: and a little more (:func:`_reach` bounds how far either reaches).
WALKER_SHADOW = ShadowShape(offset=0.35, half_width=0.45, half_height=0.07, widened=False)
VEHICLE_SHADOW = ShadowShape(offset=0.15, half_width=0.2, half_height=0.12, widened=True)
#: A shadow's centre lies this share of the target's height above its feet.
SHADOW_LIFT = 0.02


@dataclass(frozen=True)
class PersonPaint:
    """A person seen from the side: a skin-coloured head, a top and trousers (BGR), with folds
    (brightness varying +-25% across the body and down it, moving with the person)."""

    top: tuple[float, float, float]
    trousers: tuple[float, float, float]
    folds: tuple[float, float]  # phases
    skin: tuple[float, float, float] = (120.0, 150.0, 200.0)

    def __call__(self, u: np.ndarray, v: np.ndarray) -> np.ndarray:
        colours = np.empty(u.shape + (3,), np.float32)
        colours[...] = np.asarray(self.trousers, np.float32)
        colours[v < 0.1] = np.asarray(self.top, np.float32)
        colours[v < -0.72] = np.asarray(self.skin, np.float32)
        folds = (1.0 + 0.15 * np.cos(np.pi * (3.0 * u + self.folds[0]))
                 + 0.1 * np.cos(np.pi * (7.0 * v + self.folds[1])))
        return colours * folds.astype(np.float32)[..., None]


@dataclass(frozen=True)
class VehiclePaint:
    """A vehicle from the side: a body colour (BGR), dark windows along its upper part (panes
    ``panes`` wide in shape units, between pillars of the body's colour) and dark wheels at its
    bottom corners, with a highlight along the body and panels across it (moving with it: a
    long plain body would be learnt into the background while it drives across its length)."""

    body: tuple[float, float, float]
    windows: float  # grey level
    panes: float
    phase: float

    def __call__(self, u: np.ndarray, v: np.ndarray) -> np.ndarray:
        colours = np.empty(u.shape + (3,), np.float32)
        colours[...] = np.asarray(self.body, np.float32)
        shade = (1.0 + 0.15 * np.cos(np.pi * (v + 0.3))
                 + 0.12 * np.cos(np.pi * (4.0 * u + self.phase)))
        colours *= shade.astype(np.float32)[..., None]
        pillars = np.abs(((u + 1.0) / self.panes) % 1.0 - 0.5) > 0.42
        glass = (v < -0.25) & (v > -0.85) & (np.abs(u) < 0.75) & ~pillars
        colours[glass] = self.windows
        wheels = (np.hypot((np.abs(u) - 0.6) * 2.5, (v - 0.75) * 2.5) < 0.6)
        colours[wheels] = 25.0
        return colours


def _uniform(rng: np.random.Generator, name: str,
             ranges: Mapping[str, tuple[float, float]] = PEDESTRIAN_RANGES) -> float:
    low, high = ranges[name]
    return float(rng.uniform(low, high))


def _vehicle_paint(looks: np.random.Generator) -> VehiclePaint:
    """Random body: saturated, or a dark or a light grey (off the ground's 110..170: a body
    the ground's grey leaves only windows and wheels, no vehicle); windows dark."""
    hue_bgr = looks.uniform(20.0, 235.0, 3)
    grey = looks.uniform(20.0, 80.0) if looks.random() < 0.5 else looks.uniform(200.0, 240.0)
    body = hue_bgr if looks.random() < 0.6 else np.full(3, grey)
    return VehiclePaint(tuple(float(c) for c in body),  # type: ignore[arg-type]
                        float(looks.uniform(20.0, 60.0)), float(looks.uniform(0.3, 0.6)),
                        float(looks.uniform(0.0, 2.0)))


def _paint(looks: np.random.Generator, ground: float) -> PersonPaint:
    """Random clothes: a saturated or grey top; trousers dark, or close to the ground's grey."""
    hue_bgr = looks.uniform(30.0, 230.0, 3)
    top = tuple(float(c) for c in (hue_bgr if looks.random() < 0.7 else np.full(3, hue_bgr[0])))
    if looks.random() < 0.4:  # the legs hardly differ from the ground
        level = ground + looks.choice((-1.0, 1.0)) * looks.uniform(6.0, 14.0)
    else:
        level = looks.uniform(25.0, 70.0)
    folds = (float(looks.uniform(0.0, 2.0)), float(looks.uniform(0.0, 2.0)))
    return PersonPaint(top, (level,) * 3, folds)  # type: ignore[arg-type]


def _street(spec: SceneSpec, vehicles: float) -> Scene:
    """People and vehicles along a street: each target a vehicle with odds ``vehicles`` (0:
    ``pedestrians``, 1: ``vehicles``), drawn from a stream of its own (2)."""
    motion, looks = spec.rng(0), spec.rng(1)
    w, h, n, fps = spec.width, spec.height, spec.frames, spec.fps
    t = np.arange(n, dtype=np.float64)
    walkers = round(_uniform(motion, "walkers"))
    is_vehicle = [bool(x) for x in spec.rng(2).random(walkers) < vehicles]
    ranges = [VEHICLE_RANGES if v else PEDESTRIAN_RANGES for v in is_vehicle]
    ground = _uniform(looks, "ground")
    shadow = _uniform(looks, "shadow")
    drift = _uniform(looks, "drift")
    shadow_side = float(looks.choice((-1.0, 1.0)))
    params: dict[str, Any] = {"walkers": walkers, "ground": ground, "shadow": shadow,
                              "drift": drift}

    def height_at(feet: float) -> float:
        share = (feet / h - WALKWAY[0]) / (WALKWAY[1] - WALKWAY[0])
        return h * (FAR_HEIGHT + (NEAR_HEIGHT - FAR_HEIGHT) * share)

    def speed(target: int) -> float:
        return _uniform(motion, "speed", ranges[target - 1]) * w / fps

    paths: list[tuple[np.ndarray, float]] = []  # (centre x per frame, feet y)
    # 1 and 2 meet near the middle at mid-clip, at nearly the same depth, walking towards
    # each other; 1 is in view from the first frame.
    meet_x = w * motion.uniform(0.4, 0.6)
    feet = h * motion.uniform(0.62, 0.85)
    # 1 starts inside the frame (turning back at its sides in a long clip)
    v1 = min(speed(1), 0.8 * (meet_x - TURNS[0] * w) / (min(n, PLOT_FRAMES) / 2))
    x1 = meet_x + v1 * (t - n / 2)
    paths.append((np.where(t < n / 2, _pace(x1, TURNS[0] * w, TURNS[1] * w), x1), feet))
    paths.append((meet_x - speed(2) * (t - n / 2), feet + h * motion.uniform(0.02, 0.05)))
    # 3 leaves through the side it walks to before the last quarter; 4 enters at about a third.
    side = float(motion.choice((-1.0, 1.0)))
    v3 = max(speed(3), 0.3 * w / (0.6 * n))
    start3 = w / 2 + side * 0.25 * w
    paths.append((start3 + side * v3 * t, h * motion.uniform(*WALKWAY)))

    def outside(target: int, side: float, feet: float) -> float:
        """The centre x of ``target`` just out of view on ``side`` (-1 left), feet at ``feet``."""
        widest = ranges[target - 1]["height"][1] if is_vehicle[target - 1] else 1.0  # walkers'
        half = height_at(feet) * widest / 2.0 / ranges[target - 1]["aspect"][0] + 1.0  # heights
        return -half if side > 0 else w + half

    side = float(motion.choice((-1.0, 1.0)))
    enter = n * motion.uniform(0.25, 0.4)
    feet4 = h * motion.uniform(*WALKWAY)  # just out of view at frame `enter`
    paths.append((outside(4, side, feet4) + side * speed(4) * (t - enter), feet4))
    for target in range(5, walkers + 1):
        direction = float(motion.choice((-1.0, 1.0)))
        paths.append((w * motion.uniform(-0.2, 1.2) + direction * speed(target) * t,
                      h * motion.uniform(*WALKWAY)))
    # a long clip: newcomers from a stream of their own (3), so the first targets stay as drawn
    # (looks from another, 4), entering just out of view
    # (each kept over the frames it crosses the frame in only: a clip's memory and time grow
    # with its length, not with its length times its newcomers)
    arrivals = spec.rng(3)
    arrive = float(PLOT_FRAMES)
    starts: list[int | None] = [None] * len(paths)  # the first frame of a path's arrays
    while arrive < n:
        is_vehicle.append(bool(arrivals.random() < vehicles))
        ranges.append(VEHICLE_RANGES if is_vehicle[-1] else PEDESTRIAN_RANGES)
        side, depth = float(arrivals.choice((-1.0, 1.0))), h * arrivals.uniform(*WALKWAY)
        pace = _uniform(arrivals, "speed", ranges[-1]) * w / fps
        start = outside(len(ranges), side, depth)
        first, stop = _crossing(start, side * pace, arrive, _reach(height_at(depth)), w, n)
        paths.append((start + side * pace * (t[first:stop] - arrive), depth))
        starts.append(first)
        arrive += _uniform(arrivals, "arrival") * fps
    newcomers = spec.rng(4)

    shades, people = [], []
    for track_id, (cx, feet) in enumerate(paths, start=1):
        vehicle = is_vehicle[track_id - 1]
        drawn = looks if track_id <= walkers else newcomers  # (the background's draws after)
        first, frames = starts[track_id - 1], len(cx)
        tall = height_at(feet)
        if vehicle:
            tall *= _uniform(drawn, "height", VEHICLE_RANGES)
        wide = tall / _uniform(drawn, "aspect", ranges[track_id - 1])
        cy = np.full(frames, feet - tall / 2)
        ax, ay = np.full(frames, wide / 2), np.full(frames, tall / 2)
        if vehicle:
            people.append((feet, RoundedBox(cx, cy, ax, ay, _vehicle_paint(drawn), track_id,
                                            first)))
        else:
            people.append((feet, Ellipse(cx, cy, ax, ay, _paint(drawn, ground), track_id,
                                         first)))
        cast = VEHICLE_SHADOW if vehicle else WALKER_SHADOW
        spread = cast.half_width * tall
        shades.append(Shade(cx + shadow_side * cast.offset * tall,
                            np.full(frames, feet - SHADOW_LIFT * tall),
                            np.full(frames, wide / 2 + spread if cast.widened else spread),
                            np.full(frames, cast.half_height * tall), shadow, first))
    people.sort(key=lambda p: p[0])  # farther (feet higher) first: nearer walkers in front
    style = BackgroundStyle(mean=ground, octaves=((80.0, 10.0), (20.0, 6.0), (4.0, 4.0)),
                            fine=4.0, shapes=2.0, shape_contrast=25.0, tint=(4.0, 0.0, -4.0),
                            chroma=4.0)
    background = StaticBackground(make_background(looks, h, w, style))
    phase = float(looks.uniform(0.0, 2.0 * math.pi))
    gain = 1.0 - drift / 2 + drift / 2 * np.sin(2 * math.pi * t / max(n, 1) + phase)
    compositor = Compositor(background, [*shades, *(p for _, p in people)], SensorNoise(3.0),
                            spec.seed, gain)

    def events(truth: Truth) -> dict[str, Any]:
        gap = np.hypot(*(_centres(truth, 1) - _centres(truth, 2)).T)
        in_3, _ = _fractions(truth, 3)
        in_4, _ = _fractions(truth, 4)
        out = np.flatnonzero(in_3 == 0.0)
        seen = np.flatnonzero(in_4 > 0.0)
        return {
            "cross": int(np.argmin(gap)),
            "cross_ids": (1, 2),
            "exit": int(out[0]) if out.size else None,
            "exit_id": 3,
            "appear": int(seen[0]) if seen.size else None,
            "appear_id": 4,
            "walkers": len(paths),
            "vehicles": [i for i, v in enumerate(is_vehicle, start=1) if v],
            "params": params,
        }

    return assemble(spec, compositor, events)


def _reach(tall: float) -> float:
    """How far from its centre x a target ``tall`` pixels tall (a walker's height at its
    depth, the tallest a target there is) or its shadow touches a pixel, at most: the widest
    vehicle (1/0.3 times as wide as tall, 0.55 of a walker's height) with its shadow, the
    widest walker or a walker's shadow, and the pixel a region adds on each side."""
    vehicle = VEHICLE_RANGES["height"][1] * tall
    widest = max(vehicle / VEHICLE_RANGES["aspect"][0] / 2 + VEHICLE_SHADOW.half_width * vehicle
                 + VEHICLE_SHADOW.offset * vehicle,
                 tall / PEDESTRIAN_RANGES["aspect"][0] / 2,
                 (WALKER_SHADOW.offset + WALKER_SHADOW.half_width) * tall)
    return widest + 2.0


def _crossing(x0: float, velocity: float, arrive: float, reach: float, width: int,
              frames: int) -> tuple[int, int]:
    """The frames ``[first, stop)`` of ``0..frames`` on which something at
    ``x0 + velocity * (t - arrive)`` (``velocity`` not 0) comes within ``reach`` pixels of the
    frame's ``width`` (a frame more on either side, for rounding): the others it is out of view
    on, with its shadow."""
    ends = sorted((arrive + (-reach - x0) / velocity, arrive + (width + reach - x0) / velocity))
    first = min(max(math.floor(ends[0]) - 1, 0), frames)
    return first, min(max(math.ceil(ends[1]) + 2, first), frames)


def _pace(x: np.ndarray, low: float, high: float) -> np.ndarray:
    """``x`` (positions along a straight walk) folded back into ``[low, high]``: walking to and
    fro between them; the positions already inside are ``x``'s, bit for bit."""
    span = high - low
    folded = low + span - np.abs((x - low) % (2.0 * span) - span)
    return np.where((x < low) | (x > high), folded, x)


def _pedestrians(spec: SceneSpec) -> Scene:
    return _street(spec, 0.0)


def _vehicles(spec: SceneSpec) -> Scene:
    return _street(spec, 1.0)


def _mixed(spec: SceneSpec) -> Scene:
    return _street(spec, 0.5)


_EVENTS = ('"cross"/"cross_ids", "exit"/"exit_id", "appear"/"appear_id", "walkers" (targets), '
           '"vehicles" (their ids), "params"; see scene.tracks')
for _name, _summary, _build in (
    ("pedestrians", "random people walking past a fixed camera: crossing, hiding each other, "
     "entering and leaving, with shadows and a slowly changing brightness", _pedestrians),
    ("vehicles", "random vehicles (height/width 0.3-0.8) driving past a fixed camera: passing, "
     "hiding each other, entering and leaving, with shadows and a slowly changing brightness",
     _vehicles),
    ("street", "random people and vehicles (even odds per target) past a fixed camera, as "
     "pedestrians and vehicles", _mixed),
):
    SCENARIOS[_name] = Scenario(_name, _summary, _EVENTS, _build, width=640, height=480,
                                frames=PLOT_FRAMES, fps=25.0, min_frames=60)
