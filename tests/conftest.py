"""Shared fixtures: synthetic scenes with exact ground truth, in memory or written to files.

``scene_factory(scenario, seed=0, width=320, height=240, frames=90, fps=30.0)`` returns a
(cached) :class:`vtrack.scenes.Scene`.

``clip_factory(scenario, seed=0, width=320, height=240, frames=90, fps=30.0, fmt="mp4",
pix_fmt=None)`` writes the scene once per parameter set (per test session) the way
``vtrack scene`` does and returns a :class:`Clip`: ``clip.path`` (the .mp4, the raw file or the
OTB image folder), ``clip.gt`` (OTB ground truth), ``clip.mot`` (MOTChallenge ground truth,
multi-target scenes only, else None) and ``clip.scene``. Videos use x264 ``veryfast`` at crf 23.
Treat the files as read-only: other tests share them.
"""

from __future__ import annotations

import queue
import signal
import subprocess
import sys
import threading
import time
from collections.abc import Callable, Iterator
from contextlib import contextmanager
from dataclasses import dataclass
from pathlib import Path
from types import CodeType
from typing import IO, TYPE_CHECKING, Any

import pytest

from vtrack.scenes import Scene, make_scene, write_clip

if TYPE_CHECKING:
    from click.testing import Result


@dataclass(frozen=True)
class Clip:
    """A scene written to disk: the clip, its ground-truth files and the scene itself."""

    path: Path
    gt: Path
    mot: Path | None
    scene: Scene


SceneFactory = Callable[..., Scene]
ClipFactory = Callable[..., Clip]


@pytest.fixture(scope="session")
def scene_factory() -> SceneFactory:
    cache: dict[tuple, Scene] = {}

    def make(
        scenario: str,
        seed: int = 0,
        width: int = 320,
        height: int = 240,
        frames: int = 90,
        fps: float = 30.0,
    ) -> Scene:
        key = (scenario, seed, width, height, frames, fps)
        if key not in cache:
            cache[key] = make_scene(scenario, seed, width, height, frames, fps)
        return cache[key]

    return make


@pytest.fixture(scope="session")
def clip_factory(
    tmp_path_factory: pytest.TempPathFactory, scene_factory: SceneFactory
) -> ClipFactory:
    root = tmp_path_factory.mktemp("clips")
    cache: dict[tuple, Clip] = {}
    suffixes = {"mp4": ".mp4", "raw": ".raw", "images": ""}

    def make(
        scenario: str,
        seed: int = 0,
        width: int = 320,
        height: int = 240,
        frames: int = 90,
        fps: float = 30.0,
        fmt: str = "mp4",
        pix_fmt: str | None = None,
    ) -> Clip:
        key = (scenario, seed, width, height, frames, fps, fmt, pix_fmt)
        if key not in cache:
            scene = scene_factory(scenario, seed, width, height, frames, fps)
            name = "_".join(str(part) for part in key if part is not None).replace(".", "p")
            out = root / f"{name}{suffixes[fmt]}"
            files = write_clip(scene, out, fmt=fmt, pix_fmt=pix_fmt, preset="veryfast")
            cache[key] = Clip(files.clip, files.groundtruth, files.mot, scene)
        return cache[key]

    return make


#: How long a test waits at most for a ``python -m vtrack`` (or a batch's worker) it started to
#: get somewhere (its stop handlers in place, a line, a file, rows): a bound against a hang,
#: not a measure. On a host loaded many times over its cores, starting Python, PyAV, OpenCV
#: and NumPy may take minutes; 60 s fell short.
START_BOUND_S = 600


def wait_for_stop_handlers(process: subprocess.Popen,
                           timeout_s: float = START_BOUND_S, ended_ok: bool = False) -> None:
    """Return once ``process`` (a ``python -m vtrack ...``) catches SIGTERM: vtrack's stop
    handlers are in place (Python itself catches only SIGINT), so its start-up is over and a
    signal sent now is vtrack's to handle, however loaded the machine (a fixed sleep was not
    always long enough). Linux: reads ``/proc/PID/status``. ``ended_ok``: return too once it
    has ended (a refusal may hold its handlers for less than a poll's interval)."""
    deadline = time.monotonic() + timeout_s
    while True:
        with open(f"/proc/{process.pid}/status", encoding="ascii") as status:
            caught = next(line for line in status if line.startswith("SigCgt:"))
        if int(caught.split()[1], 16) >> (signal.SIGTERM - 1) & 1:
            return
        if ended_ok and process.poll() is not None:
            return
        assert process.poll() is None, "vtrack ended before it handled signals"
        assert time.monotonic() < deadline, "vtrack did not start within the time"
        time.sleep(0.05)


def run_after_start(args: list[str], after_s: float = 60,
                    **popen: Any) -> subprocess.CompletedProcess:
    """Run ``args`` (a ``python -m vtrack ...`` that ends by itself) to its end, its output
    captured: up to :data:`START_BOUND_S` for its start-up (:func:`wait_for_stop_handlers`),
    then up to ``after_s`` seconds (subprocess.TimeoutExpired after them, the process
    killed): a run that waits for ever fails within a minute of its start-up, however loaded
    the machine."""
    process = subprocess.Popen(args, stdout=subprocess.PIPE, stderr=subprocess.PIPE, **popen)
    try:
        wait_for_stop_handlers(process, ended_ok=True)
        stdout, stderr = process.communicate(timeout=after_s)
    finally:
        if process.poll() is None:
            process.kill()
            process.communicate()
    return subprocess.CompletedProcess(args, process.returncode, stdout, stderr)


@contextmanager
def sigterm_as_called(code: CodeType) -> Iterator[None]:
    """Inside the block, SIGTERM is sent to the main thread as ``code`` (a function's
    ``__code__``) is first called: a signal at that very point, no timing (a trace function
    watches the calls). The SIGINT and SIGTERM handlers are put back after the block."""
    def trace(frame, event, arg):  # noqa: ANN001, ANN202
        if event == "call" and frame.f_code is code:
            sys.settrace(None)
            signal.pthread_kill(threading.main_thread().ident, signal.SIGTERM)
        return None

    previous = {s: signal.getsignal(s) for s in (signal.SIGINT, signal.SIGTERM)}
    sys.settrace(trace)
    try:
        yield
    finally:
        sys.settrace(None)
        for signum, handler in previous.items():
            signal.signal(signum, handler)


def one_error_line(result: Result) -> str:
    """The single ``vtrack: error:`` line of a command the CLI refused (exit 2)."""
    assert result.exit_code == 2, result.output
    lines = [line for line in result.stderr.splitlines() if line.strip()]
    assert len(lines) == 1 and lines[0].startswith("vtrack: error: "), result.stderr
    return lines[0]


class LinesAsTheyCome:
    """The lines of ``stream`` (a subprocess's stdout), each taken by a daemon thread as it
    arrives. Wait for one with :meth:`next`, never with ``select()`` on the stream: a
    ``readline()`` may take several lines into the stream's buffer, where ``select()`` does not
    see them, and then waits for a line the process writes only once it is sent more."""

    def __init__(self, stream: IO[bytes]) -> None:
        self._lines: queue.Queue[bytes] = queue.Queue()
        threading.Thread(target=self._read, args=(stream,), daemon=True).start()

    def _read(self, stream: IO[bytes]) -> None:
        for line in stream:
            self._lines.put(line)
        self._lines.put(b"")

    def next(self, timeout_s: float) -> bytes | None:
        """The next line (``b""`` once the stream has ended); None when none came within
        ``timeout_s`` seconds."""
        try:
            return self._lines.get(timeout=timeout_s)
        except queue.Empty:
            return None
