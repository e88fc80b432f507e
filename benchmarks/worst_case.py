"""Worst cases per frame: every shipped config at its default and with its costliest declared
limits at 1280x720, as whole `vtrack run` processes; and memory over 300 and 3,600 frames.

Each case is ``python -m vtrack run - --raw WxH`` fed generated frames on stdin (a scene rendered
once and played back and forth, or noise frames for the detecting configs' worst cases, which
turn every speck into a blob). Time per frame is the run's own frame-loop time (``run.json``
``timing.seconds`` / frames: tracking, CSV; no video); peak memory is the process's maximum
resident set (``/usr/bin/time -f %M``). Ratios are against the config's default in the same run.

    python benchmarks/worst_case.py                       # the worst-case table (1280x720)
    python benchmarks/worst_case.py --memory              # 300 vs 3,600 frames, every config
    python benchmarks/worst_case.py --config s1           # one config (repeatable)
"""

from __future__ import annotations

import argparse
import json
import subprocess
import sys
import tempfile
import threading
from collections.abc import Iterator
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from vtrack.config import shipped_configs
from vtrack.scenes import make_scene

WIDTH, HEIGHT = 1280, 720
WHOLE = f"0,0,{WIDTH},{HEIGHT}"

#: The costliest declared values per config (the issue-21 probe's, and every limit that adds
#: work); "init" replaces the scene's first box (a whole-frame box multiplies per-pixel work).
WORST: dict[str, list[tuple[str, list[str], str | None, bool]]] = {
    # config: [(label, --set overrides, --init or None for the scene's box, noise input)]
    "s0": [("search 16x, 100 iterations, growth 16x",
            ["hue.search_scale=16", "meanshift.iterations=100", "meanshift.epsilon=0",
             "occlusion.max_growth=16", "backproject.bins=256"], None, False)],
    "camshift": [("100 iterations, eps 0", ["meanshift.iterations=100",
                                             "meanshift.epsilon=0"], None, False)],
    "s1": [("1024 particles, whole-frame box",
            ["particle.particles=1024", "particle.lost_particles=1024"], WHOLE, False)],
    "s2": [("100 iterations, eps 0, 256 bins, whole-frame box",
            ["kernel_meanshift.max_iterations=100", "kernel_meanshift.epsilon=0",
             "kernel_meanshift.bins=256"], WHOLE, False),
           ("default, whole-frame box", [], WHOLE, False)],
    "s2-fixed": [("100 iterations, whole-frame box",
                  ["kernel_meanshift_int.max_iterations=100"], WHOLE, False)],
    "s0-fixed": [("search 10x, growth 4x, 40-bit histogram",
                  ["meanshift_fixed.search_permille=10000",
                   "meanshift_fixed.max_growth_permille=10000",
                   "meanshift_fixed.growth_permille=4000", "hue_bp_fixed.hist_bits=40"],
                  None, False)],
    "s3": [("noise, 1000 blobs, 64 hypotheses",
            ["blobs.max_blobs=1000", "mht.max_hypotheses=64"], None, True),
           ("noise, every mht limit at max",
            ["blobs.max_blobs=1000", "mht.max_hypotheses=64", "mht.max_branches=16",
             "mht.gate=100000", "mht.max_coast=100000"], None, True)],
    "s4": [("open 255, close 255", ["background.open=255", "background.close=255"], None,
            False)],
    "s4_multi": [("open/close 255", ["background.open=255", "background.close=255"], None,
                  False),
                 ("noise, 1000 blobs, coast 100000, gate 1e5",
                  ["blobs.max_blobs=1000", "kalman_tracks.max_coast=100000",
                   "kalman_tracks.gate=100000"], None, True)],
    "robust": [("working area 250, cell 3, 33 scales of 2048 px",
                ["robust_model.working_area=250", "robust_model.cell=3",
                 "robust_search.scales=33", "robust_search.scale_area=2048"], None, False)],
    "fixed_camera": [("noise, 1000 blobs, open/close 255",
                      ["blobs.max_blobs=1000", "blobs.min_area=1", "background.open=255",
                       "background.close=255", "background.max_pixels=0"], None, True)],
}


@dataclass
class Measured:
    ms_per_frame: float
    peak_mb: float
    frames: int
    error: str | None = None


def _played(count: int, length: int) -> Iterator[int]:
    """The scene frame shown at each of ``count`` frames: played forward, back, forward ..."""
    cycle = list(range(length)) + list(range(length - 2, 0, -1))
    for n in range(count):
        yield cycle[n % len(cycle)]


def frames_of(kind: str, width: int, height: int, count: int) -> Iterator[bytes]:
    """``count`` BGR frames: a scene played back and forth, or noise (a few frames cycled)."""
    if kind == "noise":
        rng = np.random.default_rng(0)
        pool = [rng.integers(0, 256, (height, width, 3), np.uint8).tobytes() for _ in range(8)]
        for n in range(count):
            yield pool[n % len(pool)]
        return
    scene = make_scene(kind, 0, width, height, 120, 30.0)
    pool = [np.ascontiguousarray(bgr).tobytes() for bgr in scene.frames()]
    for index in _played(count, len(pool)):
        yield pool[index]


def write_mot_truth(path: Path, kind: str, width: int, height: int, count: int) -> Path:
    """MOTChallenge ground truth of :func:`frames_of`'s ``count`` frames of scene ``kind``."""
    scene = make_scene(kind, 0, width, height, 120, 30.0)
    with path.open("w") as handle:
        for n, index in enumerate(_played(count, len(scene))):
            for track_id, box in scene.tracks[index]:
                handle.write(f"{n + 1},{track_id},{box.x:.2f},{box.y:.2f},{box.w:.2f},"
                             f"{box.h:.2f},1,-1,-1,-1\n")
    return path


def first_box(kind: str, width: int, height: int) -> str:
    box = make_scene(kind, 0, width, height, 120, 30.0).boxes[0]
    assert box is not None
    return ",".join(f"{v:.2f}" for v in box)


def run_case(config: str, overrides: list[str], init: str | None, kind: str, width: int,
             height: int, frames: int, gt: Path | None = None) -> Measured:
    """One ``vtrack run`` process on ``frames`` generated frames of ``kind`` (``gt``: its
    ground truth)."""
    with tempfile.TemporaryDirectory() as out:
        # /usr/bin/time -f %M: the peak of vtrack's own process (wait4 on a child forked from
        # this one would count the frames this process holds before the exec)
        command = ["/usr/bin/time", "-f", "maxrss %M", sys.executable, "-m", "vtrack", "run",
                   "-", "--raw", f"{width}x{height}", "--pix-fmt", "bgr24", "--fps", "30",
                   "-c", config, "--no-video", "-q", "-o", out]
        for item in overrides:
            command += ["--set", item]
        if init is not None:
            command += ["--init", init]
        if gt is not None:
            command += ["--gt", str(gt)]
        process = subprocess.Popen(command, stdin=subprocess.PIPE, stderr=subprocess.PIPE)
        errors: list[bytes] = []
        reader = threading.Thread(target=lambda: errors.append(process.stderr.read()))
        reader.start()
        try:
            for data in frames_of(kind, width, height, frames):
                process.stdin.write(data)
        except BrokenPipeError:
            pass
        process.stdin.close()
        process.wait()
        reader.join()
        text = errors[0].decode(errors="replace") if errors else ""
        peaks = [line.split()[1] for line in text.splitlines() if line.startswith("maxrss ")]
        peak = int(peaks[-1]) / 1024 if peaks else float("nan")
        record_path = Path(out) / "run.json"
        if process.returncode != 0 or not record_path.exists():
            message = [line for line in text.splitlines() if line.startswith("vtrack: error")]
            return Measured(float("nan"), peak, 0, message[0] if message else "failed")
        record = json.loads(record_path.read_text())
        done = record["frames"]
        return Measured(1000 * record["timing"]["seconds"] / max(done, 1), peak, done)


def scene_for(config: str) -> str:
    from vtrack.config import load_config
    from vtrack.pipeline import Pipeline

    return "multi" if Pipeline(load_config(config).build()).multi_target else "smooth"


def scene_and_box(config: str, width: int, height: int) -> tuple[str, str | None]:
    """The scene a config is timed on and, for a single-target one, its first box (--init)."""
    kind = scene_for(config)
    return kind, first_box(kind, width, height) if kind == "smooth" else None


def worst_table(frames: int, configs: list[str]) -> None:
    print(f"Per frame at {WIDTH}x{HEIGHT}, {frames} frames, whole `vtrack run --no-video` "
          "processes fed raw bgr24 on stdin; ratios against the config's default in this run.\n")
    print("| config | case | ms/frame | x default | peak MB | note |")
    print("|---|---|---:|---:|---:|---|")
    for config in configs:
        kind, init = scene_and_box(config, WIDTH, HEIGHT)
        base = run_case(config, [], init, kind, WIDTH, HEIGHT, frames)
        print(f"| {config} | default | {base.ms_per_frame:.2f} | 1.0 | {base.peak_mb:.0f} | "
              f"{base.error or ''} |", flush=True)
        for label, overrides, box, noise in WORST.get(config, []):
            measured = run_case(config, overrides, box or init, "noise" if noise else kind,
                                WIDTH, HEIGHT, frames)
            ratio = measured.ms_per_frame / base.ms_per_frame
            print(f"| {config} | {label} | {measured.ms_per_frame:.2f} | {ratio:.1f} | "
                  f"{measured.peak_mb:.0f} | {measured.error or ''} |", flush=True)


def memory_table(width: int, height: int, configs: list[str]) -> None:
    print(f"Peak resident memory of whole `vtrack run --no-video` processes at {width}x{height}, "
          "default parameters; multi-target configs also with MOTChallenge ground truth.\n")
    print("| config | 300 frames MB | 3,600 frames MB | growth MB |")
    print("|---|---:|---:|---:|")
    for config in configs:
        kind, init = scene_and_box(config, width, height)
        short = run_case(config, [], init, kind, width, height, 300)
        long = run_case(config, [], init, kind, width, height, 3600)
        print(f"| {config} | {short.peak_mb:.0f} | {long.peak_mb:.0f} | "
              f"{long.peak_mb - short.peak_mb:+.0f} |", flush=True)
        if kind != "multi":
            continue
        with tempfile.TemporaryDirectory() as folder:
            peaks = [run_case(config, [], None, kind, width, height, count,
                              write_mot_truth(Path(folder) / f"gt{count}.txt", kind, width,
                                              height, count)).peak_mb
                     for count in (300, 3600)]
        print(f"| {config} with ground truth | {peaks[0]:.0f} | {peaks[1]:.0f} | "
              f"{peaks[1] - peaks[0]:+.0f} |", flush=True)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--frames", type=int, default=40, help="frames per timing case")
    parser.add_argument("--memory", action="store_true", help="memory over 300 / 3,600 frames")
    parser.add_argument("--size", default="640x360", help="frame size of --memory")
    parser.add_argument("--config", action="append", choices=sorted(shipped_configs()),
                        help="only this config (repeatable; default: every shipped config)")
    args = parser.parse_args()
    configs = args.config or sorted(shipped_configs())
    if args.memory:
        width, height = map(int, args.size.split("x"))
        memory_table(width, height, configs)
    else:
        worst_table(args.frames, configs)


if __name__ == "__main__":
    main()
