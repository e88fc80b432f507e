"""The local web page of ``vtrack select`` (stdlib ``http.server``, no extra dependency).

Routes: ``GET /`` the page (:mod:`.page`), ``GET /info`` the input's name, size, frame count,
start frame and any box already saved, ``GET /frame/N`` frame N as JPEG, ``POST /select``
``{"box": [x, y, w, h], "frame": N}`` which validates the box, writes the sidecar file and ends
the selection. The server listens on 127.0.0.1 only (reach it from elsewhere with an SSH port
forward), on a free port unless one is asked for.
"""

from __future__ import annotations

import json
import math
import threading
from dataclasses import dataclass
from http.server import BaseHTTPRequestHandler, ThreadingHTTPServer
from pathlib import Path
from typing import Any

from vtrack.errors import ConfigError, VtrackError
from vtrack.geometry import Box
from vtrack.io.sidecar import format_box, read_sidecar, write_sidecar
from vtrack.picker.frames import FrameStore
from vtrack.picker.page import PAGE

HOST = "127.0.0.1"


@dataclass(frozen=True)
class Selection:
    """What the user confirmed: the box, the frame it was drawn on, the sidecar written."""

    box: Box
    frame: int
    sidecar: Path


class SelectionServer:
    """Serves the page for one input until the user confirms a box (:meth:`wait`)."""

    def __init__(self, input_spec: str, store: FrameStore, frame: int, port: int = 0) -> None:
        self.input_spec = input_spec
        self.store = store
        self.frame = frame
        self.selection: Selection | None = None
        self._done = threading.Event()
        self._saved = read_sidecar(input_spec)
        try:
            self._httpd = ThreadingHTTPServer((HOST, port), self._handler())
        except OSError as exc:
            raise ConfigError(f"--port {port}: cannot listen on {HOST}:{port} "
                              f"({exc.strerror or exc})") from None
        self._httpd.daemon_threads = True
        self.port = self._httpd.server_address[1]
        self.url = f"http://{HOST}:{self.port}/"
        self._thread = threading.Thread(target=self._httpd.serve_forever, name="vtrack-select",
                                        daemon=True)

    def info(self) -> dict[str, Any]:
        info = self.store.info
        return {"name": info.name, "width": info.width, "height": info.height,
                "frames": self.store.count, "frame": self.frame,
                "box": list(self._saved) if self._saved else None}

    def select(self, body: dict[str, Any]) -> Selection:
        """Validate a confirmed box (inside the frame, positive size), write the sidecar."""
        values = body.get("box")
        if (not isinstance(values, list) or len(values) != 4
                or not all(isinstance(v, int | float) and math.isfinite(v) for v in values)):
            raise ConfigError(f"expected a box [x, y, w, h], got {values!r}")
        box = Box(*(float(v) for v in values))
        width, height = self.store.info.width, self.store.info.height
        if box.w < 1 or box.h < 1:
            raise ConfigError("the box is empty: drag a box around the target")
        if box.x < 0 or box.y < 0 or box.x + box.w > width or box.y + box.h > height:
            raise ConfigError(f"the box {format_box(box)} is not inside the {width}x{height} "
                              "frame")
        frame = body.get("frame")
        return Selection(box, frame if isinstance(frame, int) else self.frame,
                         write_sidecar(self.input_spec, box))

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

        class Handler(BaseHTTPRequestHandler):
            def log_message(self, format: str, *args: Any) -> None:  # noqa: A002
                pass  # the terminal shows the URL and the result, not every request

            def _send(self, status: int, body: bytes, kind: str) -> None:
                self.send_response(status)
                self.send_header("Content-Type", kind)
                self.send_header("Content-Length", str(len(body)))
                self.send_header("Cache-Control", "no-store")
                self.end_headers()
                self.wfile.write(body)

            def _json(self, data: Any, status: int = 200) -> None:
                self._send(status, json.dumps(data).encode(), "application/json")

            def do_GET(self) -> None:  # noqa: N802 (http.server's name)
                path = self.path.split("?", 1)[0]
                if path == "/":
                    self._send(200, PAGE.encode(), "text/html; charset=utf-8")
                elif path == "/info":
                    self._json(server.info())
                elif path.startswith("/frame/") and path[7:].isdigit():
                    try:
                        data = server.store.get(int(path[7:]))
                    except VtrackError as exc:
                        self._json({"error": str(exc)}, 500)
                        return
                    if data is None:
                        self._json({"error": f"no frame {path[7:]}"}, 404)
                    else:
                        self._send(200, data, "image/jpeg")
                else:
                    self._json({"error": "not found"}, 404)

            def do_POST(self) -> None:  # noqa: N802
                if self.path != "/select" or server._done.is_set():
                    self._json({"error": "not found"}, 404)
                    return
                try:
                    length = int(self.headers.get("Content-Length") or 0)
                    body = json.loads(self.rfile.read(length) or b"{}")
                    selection = server.select(body if isinstance(body, dict) else {})
                except (ValueError, VtrackError) as exc:
                    self._json({"error": str(exc)}, 400)
                    return
                server.selection = selection
                self._json({"init": format_box(selection.box),
                            "sidecar": selection.sidecar.name})
                server._done.set()

        return Handler
