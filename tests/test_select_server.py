"""Issue 21 items 8-10: `vtrack select`'s page server against hostile requests, the real
server in a real `vtrack select` process spoken to over real sockets. Foreign hosts and origins
are refused, so are paths without the session's token; malformed or oversized requests get one
JSON error line and nothing reaches the terminal; the frame cache stays within its budget."""

from __future__ import annotations

import contextlib
import json
import socket
import subprocess
import sys
import time
from pathlib import Path
from urllib.parse import urlsplit

import pytest
from conftest import START_BOUND_S
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st
from test_select import Select, post

from vtrack.io.sidecar import read_sidecar, sidecar_path
from vtrack.picker.frames import FrameStore
from vtrack.scenes import make_scene, write_video

W, H = 160, 120


@pytest.fixture(scope="module")
def clip(tmp_path_factory: pytest.TempPathFactory) -> Path:
    scene = make_scene("smooth", seed=3, width=W, height=H, frames=40, fps=30)
    return write_video(scene, tmp_path_factory.mktemp("server") / "clip.mp4")


@pytest.fixture(scope="module")
def server(clip: Path):
    sidecar_path(clip).unlink(missing_ok=True)
    select = Select(str(clip))
    yield select
    select.stop()


def raw(url: str, head: bytes, body: bytes = b"") -> tuple[int, bytes]:
    """Send ``head`` (request line and headers, without the blank line) and ``body``; the
    status and body of the answer."""
    parts = urlsplit(url)
    with socket.create_connection((parts.hostname, parts.port), timeout=10) as sock:
        # the server may answer and close before reading a body it refuses
        with contextlib.suppress(OSError):
            sock.sendall(head + b"\r\n\r\n" + body)
        data = b""
        while chunk := sock.recv(65536):
            data += chunk
    status = int(data.split(b" ", 2)[1])
    return status, data.split(b"\r\n\r\n", 1)[1]


def get(url: str, path: str, host: str | None = None, extra: str = "") -> tuple[int, bytes]:
    host = host or urlsplit(url).netloc
    head = f"GET {path} HTTP/1.1\r\nHost: {host}\r\nConnection: close{extra}".encode()
    return raw(url, head)


def token(url: str) -> str:
    return urlsplit(url).path


def error_line(body: bytes) -> str:
    message = json.loads(body)["error"]
    assert "\n" not in message and "Traceback" not in message
    return message


def test_foreign_hosts_origins_and_tokenless_paths_are_refused(server: Select) -> None:
    url, path = server.url, token(server.url)
    assert get(url, path + "info")[0] == 200
    assert get(url, path + "info", host=f"localhost:{urlsplit(url).port}")[0] == 200
    for host in ("evil.example", f"evil.example:{urlsplit(url).port}", "127.0.0.1.evil.example"):
        status, body = get(url, path + "info", host=host)
        assert status == 403 and "127.0.0.1" in error_line(body)
        assert get(url, path + "frame/0", host=host)[0] == 403
    for bare in ("/info", "/frame/0", "/", "/x" + path):
        assert get(url, bare)[0] == 404
    # a cross-site form post (text/plain needs no preflight), with and without its Origin
    box = b'{"box": [10, 10, 20, 20]}'
    port = urlsplit(url).port
    for extra, expected in ((b"\r\nOrigin: http://evil.example", 403),
                            (b"\r\nSec-Fetch-Site: cross-site", 403), (b"", 415)):
        head = (f"POST {path}select HTTP/1.1\r\nHost: 127.0.0.1:{port}\r\nConnection: close\r\n"
                f"Content-Type: text/plain\r\nContent-Length: {len(box)}").encode() + extra
        assert raw(url, head, box)[0] == expected
    assert not sidecar_path(Path(server.process.args[-1])).exists()


def hostile(url: str) -> list[tuple[bytes, bytes]]:
    path = token(url).encode()
    port = urlsplit(url).port
    host = f"Host: 127.0.0.1:{port}\r\nConnection: close".encode()

    def post_head(length: bytes) -> bytes:
        return (b"POST " + path + b"select HTTP/1.1\r\n" + host +
                b"\r\nContent-Type: application/json\r\nContent-Length: " + length)

    def body(text: str) -> tuple[bytes, bytes]:
        data = text.encode()
        return post_head(str(len(data)).encode()), data

    return [
        (b"GET " + path + b"frame/" + b"9" * 5000 + b" HTTP/1.1\r\n" + host, b""),
        (b"GET " + path + b"frame/\xff\xfe HTTP/1.1\r\n" + host, b""),
        (b"GET " + path + b"\xff HTTP/1.1\r\n" + host, b""),
        body('{"box": [1' + "0" * 400 + ', 1, 2, 2]}'),
        body('{"box": [true, true, 2, 2]}'),
        body('{"box": [1, 1, 2, 2], "frame": 1' + "0" * 5000 + "}"),
        body("[" * 4000),
        body('{"box": "\xff"}'),
        (post_head(b"1e11"), b"{}"),
        (post_head(b"100000000000"), b"{}"),
        (post_head(b"-5"), b""),
        (post_head(str(400 << 20).encode()), b"[" * 65536),
        (post_head(b"4"), b"\xff\xfe\xfd\xfc"),
        (b"GET /" + b"a" * 70000 + b" HTTP/1.1\r\n" + host, b""),
    ]


def test_malformed_requests_get_one_json_line(server: Select, clip: Path) -> None:
    for head, data in hostile(server.url):
        status, body = raw(server.url, head, data)
        assert 400 <= status < 500, (head[:80], status, body[:200])
        error_line(body)
    assert server.process.poll() is None
    assert not sidecar_path(clip).exists()


@settings(max_examples=60, derandomize=True, deadline=None,
          suppress_health_check=[HealthCheck.function_scoped_fixture])
@given(path=st.binary(max_size=64), payload=st.binary(max_size=256),
       length=st.one_of(st.integers(-10, 10**12).map(str), st.text(max_size=12)))
def test_fuzzed_requests_never_crash_the_handler(server: Select, path: bytes, payload: bytes,
                                                 length: str) -> None:
    clean = path.replace(b" ", b"").replace(b"\r", b"").replace(b"\n", b"")
    port = urlsplit(server.url).port
    head = (b"POST " + token(server.url).encode() + clean + b" HTTP/1.1\r\nHost: 127.0.0.1:" +
            str(port).encode() + b"\r\nConnection: close\r\nContent-Type: application/json\r\n"
            b"Content-Length: " + length.encode("utf-8", "replace").replace(b"\r", b"")
            .replace(b"\n", b""))
    status, body = raw(server.url, head, payload)
    assert status < 500, body
    if status != 200:
        error_line(body)


def threads(pid: int) -> int:
    for line in Path(f"/proc/{pid}/status").read_text().splitlines():
        if line.startswith("Threads:"):
            return int(line.split()[1])
    raise AssertionError("no thread count")


@pytest.mark.skipif(not Path("/proc/self/status").exists(), reason="reads /proc")
def test_idle_connections_are_bounded(server: Select) -> None:
    from vtrack.picker.server import MAX_CONNECTIONS

    parts = urlsplit(server.url)
    before = threads(server.process.pid)
    idle = [socket.create_connection((parts.hostname, parts.port), timeout=10)
            for _ in range(3 * MAX_CONNECTIONS)]
    try:
        time.sleep(0.5)  # let the server accept them all
        assert threads(server.process.pid) <= before + MAX_CONNECTIONS
    finally:
        for sock in idle:
            sock.close()
    status, deadline = 0, time.monotonic() + 20
    while status != 200 and time.monotonic() < deadline:
        try:
            status = get(server.url, token(server.url) + "info")[0]
        except (OSError, IndexError, ValueError):  # closed unanswered while slots were full
            time.sleep(0.1)
    assert status == 200  # the slots came back


def test_after_all_that_a_box_is_still_taken_and_nothing_reached_the_terminal(
        server: Select, clip: Path) -> None:
    status, answer = post(server.url + "select", {"box": [10, 20, 30, 40], "frame": 0})
    assert status == 200 and answer["init"] == "10,20,30,40"
    code, out, err = server.finish()
    assert code == 0 and out.strip() == "--init 10,20,30,40"
    assert "Traceback" not in err and "Error" not in err, err
    assert read_sidecar(clip) is not None


def test_the_frame_cache_stays_within_its_budget(clip: Path) -> None:
    with FrameStore(str(clip)) as whole:
        first = [whole.get(i) for i in range(40)]
    one = max(len(f) for f in first if f)
    with FrameStore(str(clip), cache_bytes=3 * one) as store:
        for i in (39, 0, 20, 21, 19, 39, 5):
            assert store.get(i) == first[i]
            assert store.cached_bytes <= 3 * one
        assert store.get(40) is None and store.count == 40


def test_a_stream_whose_early_frames_left_the_cache_says_it_cannot_be_read_again(
        clip: Path) -> None:
    """``select -``: once frame 0 left the cache, asking for it read stdin again from where it
    was and answered "not a video FFmpeg can decode"."""
    script = """if True:
        from vtrack.errors import InputError
        from vtrack.picker.frames import FrameStore
        with FrameStore("-", cache_bytes=1) as store:
            assert store.get(30) is not None
            try:
                store.get(0)
            except InputError as exc:
                print(exc)
    """
    with clip.open("rb") as stdin:
        done = subprocess.run([sys.executable, "-c", script], stdin=stdin, capture_output=True,
                              text=True, timeout=START_BOUND_S, check=False)
    assert done.returncode == 0, done.stderr
    assert done.stdout.strip() == ("-: its earlier frames are no longer held and it cannot be "
                                   "read again (a stream); pick a later frame, or give the "
                                   "input as a file")
