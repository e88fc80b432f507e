"""Inputs FFmpeg opens beyond a file path: a container on stdin, redirected or piped."""

from __future__ import annotations

import functools
import http.server
import os
import socket
import subprocess
import sys
import threading
from pathlib import Path

from vtrack.scenes import make_scene, write_video


def _run(args: list[str], timeout: float = 120, **kwargs: object) -> subprocess.CompletedProcess:
    return subprocess.run([sys.executable, "-m", "vtrack", "run", *args], capture_output=True,
                          timeout=timeout, check=False, **kwargs)  # type: ignore[call-overload]


def test_a_container_on_stdin_gives_the_same_csv_as_its_file(tmp_path: Path) -> None:
    """``vtrack run - < clip.mp4`` (a seekable redirect) and ``cat clip.mp4 | vtrack run -``
    (a pipe, probed as ``ffmpeg -i pipe:`` does) write track.csv bit for bit as the path."""
    scene = make_scene("smooth", seed=6, width=160, height=120, frames=30, fps=30)
    clip = write_video(scene, tmp_path / "clip.mp4")
    common = ["--config", "s2", "--init", ",".join(f"{v:g}" for v in scene.boxes[0]),
              "--no-video"]
    from_path = _run([str(clip), *common, "--out", str(tmp_path / "path")])
    assert from_path.returncode == 0, from_path.stderr
    with clip.open("rb") as redirected:
        from_redirect = _run(["-", *common, "--out", str(tmp_path / "redirect")],
                             stdin=redirected)
    assert from_redirect.returncode == 0, from_redirect.stderr
    from_pipe = _run(["-", *common, "--out", str(tmp_path / "pipe")], input=clip.read_bytes())
    assert from_pipe.returncode == 0, from_pipe.stderr
    expected = (tmp_path / "path" / "track.csv").read_bytes()
    assert expected.count(b"\n") == 31
    assert (tmp_path / "redirect" / "track.csv").read_bytes() == expected
    assert (tmp_path / "pipe" / "track.csv").read_bytes() == expected
    assert b"-: 30 frames" in from_pipe.stdout


def test_stdin_that_is_no_container_is_one_line_and_a_non_zero_exit(tmp_path: Path) -> None:
    done = _run(["-", "--init", "1,1,8,8", "--no-video", "--out", str(tmp_path / "o")],
                input=b"not a video at all\n" * 50)
    assert done.returncode != 0
    lines = done.stderr.decode().strip().splitlines()
    assert len(lines) == 1 and lines[0].startswith("vtrack: error: -:"), lines
    assert b"Traceback" not in done.stderr


def _serve(folder: Path) -> tuple[http.server.ThreadingHTTPServer, threading.Thread]:
    handler = functools.partial(http.server.SimpleHTTPRequestHandler, directory=str(folder))
    server = http.server.ThreadingHTTPServer(("127.0.0.1", 0), handler)
    thread = threading.Thread(target=server.serve_forever, daemon=True)
    thread.start()
    return server, thread


def test_http_and_a_fifo_give_the_same_csv_as_the_file(tmp_path: Path) -> None:
    """A clip served by a local HTTP server, and written into a FIFO by another process, is
    tracked as the file itself is."""
    scene = make_scene("smooth", seed=7, width=160, height=120, frames=20, fps=30)
    clip = write_video(scene, tmp_path / "clip.mp4")
    common = ["--config", "s0", "--init", ",".join(f"{v:g}" for v in scene.boxes[0]),
              "--no-video"]
    assert _run([str(clip), *common, "--out", str(tmp_path / "path")]).returncode == 0
    expected = (tmp_path / "path" / "track.csv").read_bytes()
    server, thread = _serve(tmp_path)
    try:
        url = f"http://127.0.0.1:{server.server_address[1]}/clip.mp4"
        done = _run([url, *common, "--out", str(tmp_path / "http")])
    finally:
        server.shutdown()
        thread.join()
    assert done.returncode == 0, done.stderr
    assert (tmp_path / "http" / "track.csv").read_bytes() == expected
    fifo = tmp_path / "feed"
    os.mkfifo(fifo)
    writer = subprocess.Popen([sys.executable, "-c", "import shutil, sys; shutil.copyfileobj("
                               "open(sys.argv[1], 'rb'), open(sys.argv[2], 'wb'))",
                               str(clip), str(fifo)])
    try:
        done = _run([str(fifo), *common, "--out", str(tmp_path / "fifo")])
    finally:
        writer.wait(timeout=60)
    assert done.returncode == 0, done.stderr
    assert (tmp_path / "fifo" / "track.csv").read_bytes() == expected


def test_a_url_nothing_listens_on_is_one_line_and_a_non_zero_exit(tmp_path: Path) -> None:
    with socket.socket() as probe:  # a port that was free a moment ago: nothing listens there
        probe.bind(("127.0.0.1", 0))
        port = probe.getsockname()[1]
    for url in (f"tcp://127.0.0.1:{port}", f"http://127.0.0.1:{port}/x.mp4"):
        done = _run([url, "--init", "1,1,8,8", "--out", str(tmp_path / "o")], timeout=60)
        assert done.returncode != 0
        lines = done.stderr.decode().strip().splitlines()
        assert len(lines) == 1 and lines[0].startswith(f"vtrack: error: {url}: cannot be opened")
    assert not (tmp_path / "o").exists()
    done = _run(["srt://127.0.0.1:9000", "--init", "1,1,8,8"], timeout=60)
    assert done.returncode != 0 and b"srt:// is not in the FFmpeg" in done.stderr
