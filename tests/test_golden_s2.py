"""S2 golden model (configs/s2-fixed.toml): the integer loop against a per-pixel Python
recomputation of the document's step formulas, and the chain end to end (with vectors)."""

from __future__ import annotations

import csv
import itertools
import math
import subprocess
import sys

from vtrack.config import load_config
from vtrack.frame import BgrFrame
from vtrack.geometry import iou
from vtrack.pipeline import Pipeline


def grey_bins(bgr, x: int, y: int) -> int:
    b, g, r = (int(v) for v in bgr[y, x])
    return ((77 * r + 150 * g + 29 * b + 128) >> 8) * 16 >> 8


def histogram(bgr, cx: int, cy: int, hx: int, hy: int, s_t: int) -> tuple[list[int], int]:
    """Step 3 per pixel: K = h_x - |dx| 10000 // s_t + h_y - |dy| 10000 // s_t, both terms >= 0."""
    hist, total = [0] * 16, 0
    height, width = bgr.shape[:2]
    for y in range(height):
        ty = hy - abs(y - cy) * 10000 // s_t
        if ty < 0:
            continue
        for x in range(width):
            tx = hx - abs(x - cx) * 10000 // s_t
            if tx < 0:
                continue
            hist[grey_bins(bgr, x, y)] += tx + ty
            total += tx + ty
    return hist, total


def test_first_iteration_recomputed_pixel_by_pixel(scene_factory) -> None:
    scene = scene_factory("smooth", frames=150)
    images = [bgr.copy() for bgr in itertools.islice(scene.frames(), 2)]
    frames = [BgrFrame(i, i / 30.0, bgr) for i, bgr in enumerate(images)]
    stages = load_config("s2-fixed").build()
    list(Pipeline(stages).track(frames, scene.boxes[0]))
    record = stages[0].record
    box = scene.boxes[0]
    hx, hy = round(box.w) // 2, round(box.h) // 2
    cx, cy = math.floor(box.cx), math.floor(box.cy)
    q, c = histogram(images[0], cx, cy, hx, hy, 10000)  # step 1
    assert list(record.hist) == q and record.trace["c"] == c
    first = record.iterations[0]  # frame 1, scale 10 x 1000 (tried first), iteration 1
    assert (first["frame"], first["s_t"], first["iteration"]) == (1, 10000, 1)
    x, y = first["x"], first["y"]
    p, c_prime = histogram(images[1], x, y, hx, hy, 10000)
    assert first["c_prime"] == c_prime
    table = [(qu << 8) // pu if pu else 0 for qu, pu in zip(q, p, strict=True)]  # step 4
    sw = swx = swy = 0
    for yy in range(y - hy, y + hy + 1):
        for xx in range(x - hx, x + hx + 1):
            w = table[grey_bins(images[1], xx, yy)]
            sw, swx, swy = sw + w, swx + w * (xx - x), swy + w * (yy - y)
    assert (first["sum_w"], first["sum_w_dx"], first["sum_w_dy"]) == (sw, swx, swy)

    def nearest(num: int, den: int) -> int:
        return int(math.copysign((2 * abs(num) + den) // (2 * den), num)) if num else 0

    assert (first["new_x"], first["new_y"]) == (x + nearest(swx, sw), y + nearest(swy, sw))
    # the rows of a scale end with its rho = sum min(q_u, C p_u // C') at the converged pixel
    last = [r for r in record.iterations if r["s_t"] == 10000 and r["search"] == 0][-1]
    p_end, c_end = histogram(images[1], last["new_x"], last["new_y"], hx, hy, 10000)
    assert last["rho"] == sum(min(qu, c * pu // c_end) for qu, pu in zip(q, p_end, strict=True))
    # s_k = (s_t + 90 s) // 100 for the kept scale
    assert record.trace["s"] in (990, 1000, 1010)


def test_s2_fixed_tracks_and_writes_its_iteration_trace(clip_factory, scene_factory,
                                                       tmp_path) -> None:
    clip = clip_factory("smooth", frames=30)
    box = clip.scene.boxes[0]
    out = tmp_path / "v"
    result = subprocess.run(
        [sys.executable, "-m", "vtrack", "vectors", str(clip.path), "--config", "s2-fixed",
         "--init", f"{box.x},{box.y},{box.w},{box.h}", "--frames", "6", "--out", str(out)],
        capture_output=True, text=True, timeout=120, check=False)
    assert result.returncode == 0, result.stderr
    with (out / "iterations.csv").open() as handle:
        rows = list(csv.DictReader(handle))
    assert {int(r["frame"]) for r in rows} == set(range(1, 6))
    assert {int(r["s_t"]) // 1000 for r in rows} >= {9, 10, 11}
    assert (out / "frame_0005" / "gray.hex").is_file()
    with (out / "trace.csv").open() as handle:
        trace = list(csv.DictReader(handle))
    assert len(trace) == 6 and {t["decision"] for t in trace} <= {"accept", "fast_motion",
                                                                   "occlusion"}
    check = subprocess.run([sys.executable, "-m", "vtrack", "vectors", "check", str(out),
                            str(out)], capture_output=True, text=True, timeout=120, check=False)
    assert check.returncode == 0, check.stdout
    scores = []
    scene = scene_factory("smooth", frames=150)  # the scenario's own speed
    stages = load_config("s2-fixed").build()
    images = itertools.islice(scene.frames(), 40)
    frames = [BgrFrame(i, i / 30.0, bgr.copy()) for i, bgr in enumerate(images)]
    tracked = Pipeline(stages).track(frames, scene.boxes[0])
    for res, truth in zip(tracked, scene.boxes, strict=False):
        scores.append(iou(res.box, truth))
    assert sum(scores) / len(scores) > 0.5
