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
``"appear"``/``"appear_id"`` (first frame walker 4 is in), ``"walkers"`` (N) and ``"params"``.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any

import numpy as np

from vtrack.scenes.render import (
    BackgroundStyle,
    Compositor,
    Ellipse,
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
}
#: Height of a walker (frame heights) with its feet at the top / bottom of the walkway.
FAR_HEIGHT, NEAR_HEIGHT = 0.22, 0.5
#: The walkway: feet between these shares of the frame height.
WALKWAY = (0.5, 0.95)


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


def _uniform(rng: np.random.Generator, name: str) -> float:
    low, high = PEDESTRIAN_RANGES[name]
    return float(rng.uniform(low, high))


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


def _pedestrians(spec: SceneSpec) -> Scene:
    motion, looks = spec.rng(0), spec.rng(1)
    w, h, n, fps = spec.width, spec.height, spec.frames, spec.fps
    t = np.arange(n, dtype=np.float64)
    walkers = round(_uniform(motion, "walkers"))
    ground = _uniform(looks, "ground")
    shadow = _uniform(looks, "shadow")
    drift = _uniform(looks, "drift")
    shadow_side = float(looks.choice((-1.0, 1.0)))
    params: dict[str, Any] = {"walkers": walkers, "ground": ground, "shadow": shadow,
                              "drift": drift}

    def height_at(feet: float) -> float:
        share = (feet / h - WALKWAY[0]) / (WALKWAY[1] - WALKWAY[0])
        return h * (FAR_HEIGHT + (NEAR_HEIGHT - FAR_HEIGHT) * share)

    def speed() -> float:
        return _uniform(motion, "speed") * w / fps

    paths: list[tuple[np.ndarray, float]] = []  # (centre x per frame, feet y)
    # 1 and 2 meet near the middle at mid-clip, at nearly the same depth, walking towards
    # each other; 1 is in view from the first frame.
    meet_x = w * motion.uniform(0.4, 0.6)
    feet = h * motion.uniform(0.62, 0.85)
    v1 = min(speed(), 0.8 * (meet_x - 0.1 * w) / (n / 2))  # 1 starts inside the frame
    paths.append((meet_x + v1 * (t - n / 2), feet))
    paths.append((meet_x - speed() * (t - n / 2), feet + h * motion.uniform(0.02, 0.05)))
    # 3 leaves through the side it walks to before the last quarter; 4 enters at about a third.
    side = float(motion.choice((-1.0, 1.0)))
    v3 = max(speed(), 0.3 * w / (0.6 * n))
    start3 = w / 2 + side * 0.25 * w
    paths.append((start3 + side * v3 * t, h * motion.uniform(*WALKWAY)))
    side = float(motion.choice((-1.0, 1.0)))
    enter = n * motion.uniform(0.25, 0.4)
    feet4 = h * motion.uniform(*WALKWAY)
    half4 = height_at(feet4) / 2.0 / 2.2 + 1.0
    edge = -half4 if side > 0 else w + half4  # just out of view at frame `enter`
    paths.append((edge + side * speed() * (t - enter), feet4))
    for _ in range(walkers - 4):
        direction = float(motion.choice((-1.0, 1.0)))
        paths.append((w * motion.uniform(-0.2, 1.2) + direction * speed() * t,
                      h * motion.uniform(*WALKWAY)))

    shades, people = [], []
    for track_id, (cx, feet) in enumerate(paths, start=1):
        tall = height_at(feet)
        wide = tall / _uniform(looks, "aspect")
        cy = np.full(n, feet - tall / 2)
        ax, ay = np.full(n, wide / 2), np.full(n, tall / 2)
        people.append((feet, Ellipse(cx, cy, ax, ay, _paint(looks, ground), track_id)))
        shades.append(Shade(cx + shadow_side * 0.35 * tall, np.full(n, feet - 0.02 * tall),
                            np.full(n, 0.45 * tall), np.full(n, 0.07 * tall), shadow))
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
            "walkers": walkers,
            "params": params,
        }

    return assemble(spec, compositor, events)


SCENARIOS["pedestrians"] = Scenario(
    "pedestrians",
    "random people walking past a fixed camera: crossing, hiding each other, entering and "
    "leaving, with shadows and a slowly changing brightness",
    '"cross"/"cross_ids", "exit"/"exit_id", "appear"/"appear_id", "walkers", "params"; '
    "see scene.tracks",
    _pedestrians,
    width=640,
    height=480,
    frames=150,
    fps=25.0,
    min_frames=60,
)
