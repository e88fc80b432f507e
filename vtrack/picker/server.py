"""The local web page of ``vtrack select`` (stdlib ``http.server``, no extra dependency).

Routes, under a per-session secret path ``/TOKEN/`` (the URL the command prints): ``GET`` the
page (:mod:`.page`), ``GET info`` the input's name, size, frame count, start frame and any box
already saved, ``GET frame/N`` frame N as JPEG (for a number the input passes over, 404 with
the nearest frames it has, ``previous`` and ``next``), ``POST select`` ``{"box": [x, y, w,
h], "frame": N}`` which validates the box, writes the sidecar file and ends the selection. The
server listens on 127.0.0.1 only (reach it from elsewhere with an SSH port forward), on a free
port unless one is asked for.

What another web page in the user's browser could try is refused: a ``Host`` other than
127.0.0.1 / localhost (DNS rebinding) and an ``Origin`` other than the page's own are answered
403, a path without the token 404; a body over :data:`MAX_BODY` bytes, a ``Content-Length``
that is not a small number, a frame number or box value out of range or of the wrong type, JSON
nested too deep or not UTF-8 are answered 400 with a one-line JSON error. At most
:data:`MAX_CONNECTIONS` connections are served at once, each closed after
:data:`IDLE_TIMEOUT_S` idle. Nothing a request holds reaches the terminal.
"""

from __future__ import annotations

import hmac
import json
import math
import re
import secrets
import threading
from dataclasses import dataclass
from http.server import BaseHTTPRequestHandler, ThreadingHTTPServer
from pathlib import Path
from typing import Any
from urllib.parse import urlsplit

from vtrack.errors import ConfigError, InputError, VtrackError
from vtrack.geometry import Box, check_init_box
from vtrack.io.sidecar import format_box, has_sidecar, read_sidecar, write_sidecar
from vtrack.picker.frames import AbsentFrame, FrameStore
from vtrack.picker.page import PAGE

HOST = "127.0.0.1"
#: Host names a request may carry (with any port): the loopback the server listens on.
LOCAL_HOSTS = frozenset({"127.0.0.1", "localhost"})
#: Largest request body (a box is ~40 bytes).
MAX_BODY = 4096
#: Largest frame number a request may ask for (nine digits).
MAX_FRAME = 999_999_999
#: Largest box value (frames are at most 16384 pixels a side).
MAX_COORDINATE = 1e6


#: The answer to a confirm after the box was taken (from another page, or a second click).
ALREADY_CONFIRMED = "a box was already confirmed (on another page?): this one is not taken"

#: Connections served at once (a page makes a few); more are closed unanswered.
MAX_CONNECTIONS = 16
#: Seconds a connection may stay idle (mid-request or between requests) before it is closed.
IDLE_TIMEOUT_S = 10.0


class _BoundedServer(ThreadingHTTPServer):
    """A threading server with at most :data:`MAX_CONNECTIONS` connections (threads) at once,
    and no traceback on the terminal for a connection that breaks."""

    daemon_threads = True

    def __init__(self, *args: Any) -> None:
        self._slots = threading.BoundedSemaphore(MAX_CONNECTIONS)
        super().__init__(*args)

    def process_request(self, request: Any, client_address: Any) -> None:
        if not self._slots.acquire(blocking=False):
            self.shutdown_request(request)  # too many at once: closed, unanswered
            return
        try:
            super().process_request(request, client_address)
        except BaseException:
            self._slots.release()
            raise

    def process_request_thread(self, request: Any, client_address: Any) -> None:
        try:
            super().process_request_thread(request, client_address)
        finally:
            self._slots.release()

    def handle_error(self, request: Any, client_address: Any) -> None:
        pass  # a dropped or timed-out connection: nothing for the user's terminal


class _Refused(Exception):
    """A request answered with ``status`` and the one-line ``message``."""

    def __init__(self, status: int, message: str) -> None:
        super().__init__(message)
        self.status = status


def _local(authority: str) -> bool:
    """Whether ``host[:port]`` names the loopback (any port)."""
    try:
        return (urlsplit(f"//{authority}").hostname or "") in LOCAL_HOSTS
    except ValueError:
        return False


def _box_values(values: Any) -> list[float]:
    """Four finite numbers (JSON numbers, not booleans) within +-``MAX_COORDINATE``."""
    if not isinstance(values, list) or len(values) != 4:
        raise ConfigError("expected a box [x, y, w, h]")
    numbers = []
    for value in values:
        if isinstance(value, bool) or not isinstance(value, int | float):
            raise ConfigError("expected a box of four numbers [x, y, w, h]")
        try:
            number = float(value)
        except OverflowError:
            number = math.inf
        if not math.isfinite(number) or abs(number) > MAX_COORDINATE:
            raise ConfigError(f"box values must be finite and within +-{MAX_COORDINATE:g}")
        numbers.append(number)
    return numbers


@dataclass(frozen=True)
class Selection:
    """What the user confirmed: the box, the frame it was drawn on, the sidecar written (None
    for an input that has none: stdin, a URL, a device; and for a box drawn on a frame other
    than 0, since the sidecar holds frame 0's box)."""

    box: Box
    frame: int
    sidecar: Path | None


class SelectionServer:
    """Serves the page for one input until the user confirms a box (:meth:`wait`)."""

    def __init__(self, input_spec: str, store: FrameStore, frame: int, port: int = 0) -> None:
        self.input_spec = input_spec
        self.store = store
        self.frame = frame
        self.selection: Selection | None = None
        self._done = threading.Event()
        self._confirming = threading.Lock()  # one confirmed box, however many arrive at once
        #: Why an existing sidecar could not be read (it is replaced on confirm), if it could not.
        self.unreadable: str | None = None
        try:
            self._saved = read_sidecar(input_spec)
        except InputError as exc:
            self._saved, self.unreadable = None, str(exc)
        self.token = secrets.token_urlsafe(16)
        try:
            self._httpd = _BoundedServer((HOST, port), self._handler())
        except OSError as exc:
            raise ConfigError(f"--port {port}: cannot listen on {HOST}:{port} "
                              f"({exc.strerror or exc})") from None
        self.port = self._httpd.server_address[1]
        self.url = f"http://{HOST}:{self.port}/{self.token}/"
        self._thread = threading.Thread(target=self._httpd.serve_forever, name="vtrack-select",
                                        daemon=True)

    def info(self) -> dict[str, Any]:
        info = self.store.info
        return {"name": info.name, "width": info.width, "height": info.height,
                "frames": self.store.count, "frame": self.frame,
                "box": list(self._saved) if self._saved else None}

    def select(self, body: dict[str, Any]) -> Selection:
        """Validate a confirmed box (inside the frame, positive size), write the sidecar."""
        box = Box(*_box_values(body.get("box")))
        width, height = self.store.info.width, self.store.info.height
        if box.w < 1 or box.h < 1:
            raise ConfigError("the box is empty: drag a box around the target")
        if box.x < 0 or box.y < 0 or box.x + box.w > width or box.y + box.h > height:
            raise ConfigError(f"the box {format_box(box)} is not inside the {width}x{height} "
                              "frame")
        check_init_box(box, width, height, "select")  # what vtrack run refuses (under 4x4)
        frame = body.get("frame", self.frame)
        last = MAX_FRAME if self.store.count is None else self.store.count - 1
        if isinstance(frame, bool) or not isinstance(frame, int) or not 0 <= frame <= last:
            raise ConfigError(f"frame {frame!r}: the input's frames are 0..{last}")
        # the sidecar holds frame 0's box: one drawn on a later frame is printed, not saved
        sidecar = (write_sidecar(self.input_spec, box)
                   if has_sidecar(self.input_spec) and frame == 0 else None)
        return Selection(box, frame, sidecar)

    def wait(self) -> Selection:
        """Serve until a box is confirmed; return it. Ctrl-C raises KeyboardInterrupt."""
        self._thread.start()
        try:
            while not self._done.wait(0.2):  # wake up for Ctrl-C
                pass
        finally:
            self._httpd.shutdown()
            self._httpd.server_close()
        assert self.selection is not None
        return self.selection

    def _handler(self) -> type[BaseHTTPRequestHandler]:
        server = self
        frame_route = re.compile(r"frame/(\d{1,9})")

        class Handler(BaseHTTPRequestHandler):
            timeout = IDLE_TIMEOUT_S  # a connection that sends nothing is closed

            def log_message(self, format: str, *args: Any) -> None:  # noqa: A002
                pass  # the terminal shows the URL and the result, not every request

            def send_error(self, code: int, message: str | None = None,
                           explain: str | None = None) -> None:
                # http.server's own refusals (a request line too long, a bad header): the same
                # one-line JSON as ours, nothing on the terminal
                self.close_connection = True
                self._json({"error": message or "bad request"}, code)

            def _send(self, status: int, body: bytes, kind: str) -> None:
                self.send_response(status)
                self.send_header("Content-Type", kind)
                self.send_header("Content-Length", str(len(body)))
                self.send_header("Cache-Control", "no-store")
                self.send_header("X-Content-Type-Options", "nosniff")
                self.end_headers()
                self.wfile.write(body)

            def _json(self, data: Any, status: int = 200) -> None:
                self._send(status, json.dumps(data).encode(), "application/json")

            def _route(self) -> str:
                """The path below the token, after the Host/Origin checks (_Refused)."""
                if not _local(self.headers.get("Host") or ""):
                    raise _Refused(403, "this page answers only to 127.0.0.1 and localhost")
                origin = self.headers.get("Origin")
                if origin is not None and not (origin.startswith("http://")
                                               and _local(origin[7:])):
                    raise _Refused(403, "requests from other sites are refused")
                if self.headers.get("Sec-Fetch-Site") == "cross-site":
                    raise _Refused(403, "requests from other sites are refused")
                path = self.path.split("?", 1)[0]
                head, _, rest = path.lstrip("/").partition("/")
                if not hmac.compare_digest(head.encode(), server.token.encode()):
                    raise _Refused(404, "not found: open the URL vtrack select printed")
                return rest

            def _answer(self, respond: Any) -> None:
                try:
                    respond(self._route())
                except _Refused as exc:
                    self._json({"error": str(exc)}, exc.status)
                except VtrackError as exc:
                    self._json({"error": str(exc)}, 400)
                except Exception as exc:  # never a traceback on the user's terminal
                    self._json({"error": f"internal error: {type(exc).__name__}"}, 500)

            def do_GET(self) -> None:  # noqa: N802 (http.server's name)
                self._answer(self._get)

            def do_POST(self) -> None:  # noqa: N802
                self._answer(self._post)

            def _get(self, route: str) -> None:
                frame = frame_route.fullmatch(route)
                if route == "":
                    self._send(200, PAGE.encode(), "text/html; charset=utf-8")
                elif route == "info":
                    self._json(server.info())
                elif frame is not None:
                    try:
                        data = server.store.get(int(frame.group(1)))
                    except AbsentFrame as exc:  # the page steps over it to a frame it has
                        self._json({"error": str(exc), "previous": exc.previous,
                                    "next": exc.following}, 404)
                        return
                    if data is None:  # past the end: the count is then known
                        self._json({"error": server.store.no_frame_text(int(frame.group(1))),
                                    "frames": server.store.count}, 404)
                    else:
                        self._send(200, data, "image/jpeg")
                else:
                    raise _Refused(404, "not found")

            def _post(self, route: str) -> None:
                if route != "select":
                    raise _Refused(404, "not found")
                if server.selection is not None:
                    raise _Refused(409, ALREADY_CONFIRMED)
                if (self.headers.get("Content-Type") or "").split(";")[0] != "application/json":
                    raise _Refused(415, "expected Content-Type: application/json")
                body = self._body()
                with server._confirming:
                    if server.selection is not None:  # another confirm came first
                        raise _Refused(409, ALREADY_CONFIRMED)
                    selection = server.select(body if isinstance(body, dict) else {})
                    server.selection = selection
                try:
                    self._json({"init": format_box(selection.box),
                                "sidecar": None if selection.sidecar is None
                                else selection.sidecar.name})
                finally:  # answered before wait() stops the server and the process exits
                    server._done.set()

            def _body(self) -> Any:
                """The request's JSON body, read only when small (_Refused otherwise)."""
                length = (self.headers.get("Content-Length") or "0").strip()
                if not re.fullmatch(r"\d{1,9}", length):
                    raise _Refused(400, "Content-Length must be a byte count")
                if int(length) > MAX_BODY:
                    self.close_connection = True
                    raise _Refused(413, f"the request body is over {MAX_BODY} bytes")
                try:
                    return json.loads(self.rfile.read(int(length)).decode("utf-8") or "{}")
                except (ValueError, RecursionError):
                    raise _Refused(400, "the request body is not JSON") from None

        return Handler
