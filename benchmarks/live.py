"""A live 1080p60 stream, sent in real time over UDP to ``vtrack run``: does it keep up?

A generated 1080p60 H.264 clip (MPEG-TS, a key frame every second) is sent to
``udp://127.0.0.1:PORT`` at its own pace by ``python -m vtrack.scenes.send`` (as ``ffmpeg -re
-i clip -c copy -f mpegts udp://...``); ``vtrack run udp://...`` receives it (live pacing on)
with each config. Per run: frames tracked, frames passed over because the tracker was busy
(``frames_passed``), latency p50/p99/max from ``run.json`` (frame decoded -> its row written),
and the receiver's resident memory at a quarter, half, three quarters and the end of the
stream (flat = no queue grows). The slow config (s1 with 1024 particles a frame) cannot keep
up, on purpose.

    python benchmarks/live.py [--seconds 10]

Prints a Markdown table (paste it into benchmarks/RESULTS.md).
"""

from __future__ import annotations

import argparse
import json
import os
import socket
import subprocess
import sys
import tempfile
import time
from pathlib import Path

from common import machine, process_env

#: (label, vtrack run arguments after the input)
RUNS = (
    ("robust, --no-video", ["-c", "robust", "--no-video"]),
    ("robust, annotated.mp4", ["-c", "robust"]),
    ("s0, annotated.mp4", ["-c", "s0"]),
    ("slow on purpose: s1, 1024 particles", ["-c", "s1", "--set", "particle.particles=1024",
                                             "--no-video"]),
)


def make_clip(folder: Path, seconds: float) -> tuple[Path, str]:
    """The 1080p60 clip and its first box as --init takes it."""
    from vtrack.scenes import make_scene, write_video

    scene = make_scene("smooth", seed=1, width=1920, height=1080, frames=round(60 * seconds),
                       fps=60)
    clip = write_video(scene, folder / "live1080p60.ts", preset="veryfast", keyint=60)
    return clip, ",".join(f"{v:g}" for v in scene.boxes[0])


def rss_mb(pid: int) -> float | None:
    try:
        with open(f"/proc/{pid}/statm") as f:
            return int(f.read().split()[1]) * os.sysconf("SC_PAGE_SIZE") / 2**20
    except OSError:
        return None


def one_run(clip: Path, box: str, args: list[str], out: Path) -> dict:
    """Receive the clip sent in real time; run.json's figures and the memory samples."""
    with socket.socket(socket.AF_INET, socket.SOCK_DGRAM) as probe:
        probe.bind(("127.0.0.1", 0))
        port = probe.getsockname()[1]
    url = f"udp://127.0.0.1:{port}"
    env = process_env()
    receiver = subprocess.Popen([sys.executable, "-m", "vtrack", "run", url, "--init", box,
                                 "--timeout", "3", "-q", "-o", str(out), "-y", *args], env=env,
                                stderr=subprocess.DEVNULL)  # ends partial: the sender stops
    time.sleep(2.0)  # the receiver is listening (a late start only joins at the next key frame)
    sender = subprocess.Popen([sys.executable, "-m", "vtrack.scenes.send", str(clip), url],
                              env=env)
    samples = []
    while receiver.poll() is None:
        if sender.poll() is None and (rss := rss_mb(receiver.pid)) is not None:
            samples.append(rss)
        time.sleep(0.5)
    sender.wait()
    record = json.loads((out / "run.json").read_text())
    # at a quarter, half, three quarters and the end of the stream
    marks = [samples[min(len(samples) - 1, len(samples) * q // 4)] for q in (1, 2, 3, 4)] \
        if samples else []
    return {
        "frames": record["frames"],
        "passed": record["summary"]["frames_passed"],
        "latency": record["timing"]["latency"],
        "rss": marks,
    }


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--seconds", type=float, default=10.0, help="length of the stream")
    args = parser.parse_args()
    with tempfile.TemporaryDirectory() as tmp:
        folder = Path(tmp)
        clip, box = make_clip(folder, args.seconds)
        sent = round(60 * args.seconds)
        load = os.getloadavg()[0]
        print(machine())
        print()
        print(f"{sent} frames of 1920x1080 at 60 fps sent in real time over UDP (MPEG-TS)")
        print()
        print("| config | frames tracked | passed over (busy) | latency p50 / p99 / max ms | "
              "receiver RSS MB at 1/4, 1/2, 3/4, end of the stream |")
        print("|---|---|---|---|---|")
        for n, (label, run_args) in enumerate(RUNS):
            got = one_run(clip, box, run_args, folder / f"out{n}")
            lat = got["latency"]
            rss = " / ".join(f"{m:.0f}" for m in got["rss"]) or "n/a"
            print(f"| {label} | {got['frames']} | {got['passed']} | {lat['p50_ms']:.1f} / "
                  f"{lat['p99_ms']:.1f} / {lat['max_ms']:.1f} | {rss} |", flush=True)
        print()
        print("Load average (1 min) before and after: "
              f"{load:.1f} / {os.getloadavg()[0]:.1f} (other processes share the cores)")


if __name__ == "__main__":
    main()
