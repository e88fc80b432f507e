"""Speed at 1080p60: vtrack against PyAV decode-only and a PyAV transcode, in one run.

    python benchmarks/speed.py [--frames 600] [--rounds 3]

Generates (once, cached in benchmarks/_work/) a 1920x1080 60 fps H.264 clip of camera-like
footage with the project's scene generator, then measures in alternating rounds:

- PyAV decode only (``thread_type = "AUTO"``, frames not converted);
- ``vtrack run --no-video`` (S0, in-process: reader thread, pipeline, CSV, run.json);
- ``vtrack run`` with annotated video, at the ultrafast and veryfast presets;
- a PyAV transcode (decode + libx264 encode, same encoder settings) at the same presets;
- raw bgr24 1080p frames from a pipe through ``vtrack run - --raw 1920x1080``.

Reports medians and the ratios the targets are stated in, plus S0's per-stage microseconds per
frame, and prints a Markdown table (paste it into benchmarks/RESULTS.md). Machines here are shared
and noisy: only ratios measured in the same run mean much.
"""

from __future__ import annotations

import argparse
import json
import os
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import av

from vtrack.config import load_config
from vtrack.run import RunRequest, run, versions
from vtrack.scenes import make_scene, write_groundtruth, write_video

WORK = Path(__file__).resolve().parent / "_work"


def make_clip(frames: int) -> tuple[Path, Path]:
    """The benchmark clip and its ground truth, generated once per frame count."""
    WORK.mkdir(exist_ok=True)
    clip = WORK / f"bench1080p60_{frames}.mp4"
    gt = WORK / f"bench1080p60_{frames}.gt.txt"
    if not clip.exists() or not gt.exists():
        scene = make_scene("benchmark", seed=0, width=1920, height=1080, frames=frames, fps=60)
        write_video(scene, clip, crf=23, preset="medium")
        write_groundtruth(scene, gt)
    return clip, gt


def decode_only(clip: Path) -> float:
    with av.open(str(clip)) as container:
        stream = container.streams.video[0]
        stream.thread_type = "AUTO"
        started = time.perf_counter()
        n = sum(1 for _ in container.decode(stream))
    return n / (time.perf_counter() - started)


def transcode(clip: Path, preset: str) -> float:
    with tempfile.TemporaryDirectory() as tmp, av.open(str(clip)) as source:
        stream = source.streams.video[0]
        stream.thread_type = "AUTO"
        with av.open(str(Path(tmp) / "out.mp4"), "w") as sink:
            out = sink.add_stream("libx264", rate=stream.average_rate)
            out.width, out.height, out.pix_fmt = stream.width, stream.height, "yuv420p"
            out.options = {"preset": preset, "crf": "23"}
            out.thread_type = "FRAME"
            started = time.perf_counter()
            n = 0
            tick = 1 / stream.average_rate
            for frame in source.decode(stream):
                frame.pts, frame.time_base = n, tick  # restamp as the encoder's 1/fps ticks
                for packet in out.encode(frame):
                    sink.mux(packet)
                n += 1
            for packet in out.encode():
                sink.mux(packet)
            return n / (time.perf_counter() - started)


def vtrack_run(clip: Path, gt: Path, video: bool, preset: str = "ultrafast") -> tuple[float, dict]:
    with tempfile.TemporaryDirectory() as tmp:
        request = RunRequest(input=str(clip), out_dir=Path(tmp), config=load_config("s0"),
                             gt_path=gt, video=video, preset=preset)
        started = time.perf_counter()
        summary = run(request)
        seconds = time.perf_counter() - started
        record = json.loads((Path(tmp) / "run.json").read_text())
    assert summary.status == "complete", summary.error
    return summary.frames / seconds, record


PRODUCER = r"""
import sys, numpy as np
from vtrack.scenes import make_scene
w, h, n = 1920, 1080, int(sys.argv[1])
frames = [f.tobytes() for _, f in zip(range(60), make_scene("benchmark", seed=0, width=w, height=h,
          frames=60, fps=60).frames())]
out = sys.stdout.buffer
for i in range(n):
    out.write(frames[i % len(frames)])
out.flush()
"""


def raw_pipe(frames: int, init: str) -> float:
    """fps of ``vtrack run -`` reading raw bgr24 1080p from a pipe (producer in another process)."""
    with tempfile.TemporaryDirectory() as tmp:
        producer = subprocess.Popen([sys.executable, "-c", PRODUCER, str(frames)],
                                    stdout=subprocess.PIPE)
        consumer = subprocess.run(
            [sys.executable, "-m", "vtrack", "run", "-", "--raw", "1920x1080", "--pix-fmt",
             "bgr24", "--fps", "60", "--init", init, "--no-video", "--out", tmp],
            stdin=producer.stdout, capture_output=True, text=True, check=False)
        producer.wait()
        if consumer.returncode != 0:
            raise RuntimeError(consumer.stderr)
        return json.loads((Path(tmp) / "run.json").read_text())["timing"]["fps"]


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--frames", type=int, default=600)
    parser.add_argument("--rounds", type=int, default=3)
    args = parser.parse_args()
    clip, gt = make_clip(args.frames)
    init = ",".join(f"{v:.1f}" for v in map(float, gt.read_text().splitlines()[0].split(",")))
    size_mb = clip.stat().st_size * 8 / 1e6
    bitrate = size_mb / (args.frames / 60)

    samples: dict[str, list[float]] = {}
    stage_us: dict[str, float] = {}
    for _ in range(args.rounds):
        # Alternate every measurement within a round so drift hits them alike.
        samples.setdefault("decode", []).append(decode_only(clip))
        fps, record = vtrack_run(clip, gt, video=False)
        samples.setdefault("run_novideo", []).append(fps)
        stage_us = record["timing"]["stage_us_per_frame"]
        for preset in ("ultrafast", "veryfast"):
            samples.setdefault(f"transcode_{preset}", []).append(transcode(clip, preset))
            samples.setdefault(f"run_video_{preset}", []).append(
                vtrack_run(clip, gt, video=True, preset=preset)[0])
        samples.setdefault("raw_pipe", []).append(raw_pipe(args.frames, init))
    med = {k: statistics.median(v) for k, v in samples.items()}

    v = versions()
    print(f"Command: `python benchmarks/speed.py --frames {args.frames} --rounds {args.rounds}`  ")
    print(f"Machine: {os.cpu_count()} cores, {v['platform']}; Python {v['python']}, "
          f"PyAV {v['pyav']} (libavcodec {v['ffmpeg']}), OpenCV {v['opencv']}, "
          f"NumPy {v['numpy']}  ")
    print(f"Clip: 1920x1080, 60 fps, {args.frames} frames, H.264 crf 23, {bitrate:.1f} Mb/s; "
          f"median of {args.rounds} alternating rounds\n")
    rows = [
        ("PyAV decode only", med["decode"], "1.00x decode", ""),
        ("vtrack run --no-video (S0)", med["run_novideo"],
         f"{med['run_novideo'] / med['decode']:.2f}x decode", ">= 0.9x and >= 60 fps"),
    ]
    for preset in ("ultrafast", "veryfast"):
        t, r = med[f"transcode_{preset}"], med[f"run_video_{preset}"]
        rows.append((f"PyAV transcode, {preset}", t, f"{t / med['decode']:.2f}x decode", ""))
        target = ">= 0.85x and >= 60 fps" if preset == "ultrafast" else "(report only)"
        rows.append((f"vtrack run with video, {preset}", r, f"{r / t:.2f}x transcode", target))
    rows.append(("vtrack run - --raw 1920x1080 bgr24 (pipe)", med["raw_pipe"], "", ">= 60 fps"))
    print("| measurement | fps (median) | ratio | target |")
    print("|---|---:|---:|---|")
    for name, fps, ratio, target in rows:
        print(f"| {name} | {fps:.1f} | {ratio} | {target} |")
    print("\nS0 per-stage cost (µs per frame, from run.json of the --no-video run):\n")
    print("| stage | µs/frame |")
    print("|---|---:|")
    for name, us in stage_us.items():
        print(f"| {name} | {us:.0f} |")


if __name__ == "__main__":
    main()
