"""Send a video file to a URL at its own pace, as ``ffmpeg -re -i FILE -c copy -f FMT URL`` does.

A live source for tests, benchmarks and demonstrations on a machine without the ``ffmpeg``
program: the packets are copied (no re-encoding) and each is sent when its timestamp comes due
on the wall clock, so the receiver sees a stream arriving in real time.

``python -m vtrack.scenes.send FILE URL [FORMAT]`` (FORMAT default ``mpegts``).
"""

from __future__ import annotations

import argparse
import sys
import time
from urllib.parse import urlsplit

import av

from vtrack.io.files import ffmpeg_file, os_reason
from vtrack.io.video import text_file_problem


def send(path: str, url: str, fmt: str = "mpegts", *, realtime: bool = True) -> int:
    """Copy the video stream of ``path`` into ``url`` as ``fmt``, each packet sent when its
    timestamp is due (``realtime``), and return the number of packets sent."""
    try:
        source = av.open(ffmpeg_file(path))
    except (av.FFmpegError, OSError) as exc:
        raise SendError(f"{path}: {os_reason(exc)}") from None
    with source:
        if not source.streams.video:
            raise SendError(f"{path}: has no video stream")
        text = text_file_problem(path, source)
        if text:
            raise SendError(text)
        video = source.streams.video[0]
        _check_port(url)
        try:
            sink = av.open(url, "w", format=fmt)
        except (av.FFmpegError, OSError, ValueError) as exc:
            raise SendError(f"{url}: {os_reason(exc)}") from None
        with sink:
            return _copy(source, video, sink, realtime)


def _check_port(url: str) -> None:
    """SendError naming ``url`` when it gives a port outside 1..65535 (FFmpeg takes
    ``udp://127.0.0.1:99999`` and sends to port 99999 mod 65536, where no one listens)."""
    try:
        port = urlsplit(url).port
    except ValueError:
        port = -1
    if port is not None and not 1 <= port <= 65535:
        raise SendError(f"{url}: the port must be a number from 1 to 65535")


class SendError(Exception):
    """The file or the URL of :func:`send` failed: the message names which."""


def _copy(source: av.container.InputContainer, video: av.VideoStream,
          sink: av.container.OutputContainer, realtime: bool) -> int:
    """The packets of ``video`` muxed into ``sink``, each when due (``realtime``); how many."""
    out = sink.add_stream_from_template(video)
    started = time.perf_counter()
    first: float | None = None
    sent = 0
    for packet in source.demux(video):
        if packet.dts is None:
            continue  # the demuxer's flush packet
        if realtime and packet.pts is not None and packet.time_base is not None:
            due = float(packet.pts * packet.time_base)
            first = due if first is None else first
            wait = started + (due - first) - time.perf_counter()
            if wait > 0:
                time.sleep(wait)
        packet.stream = out
        sink.mux(packet)
        sent += 1
    return sent


def main(argv: list[str] | None = None) -> int:
    """``python -m vtrack.scenes.send FILE URL [FORMAT]``: a usage line and exit code 2 for
    missing or extra arguments, one line and exit code 1 when the file or the URL fails."""
    parser = argparse.ArgumentParser(
        prog="python -m vtrack.scenes.send",
        description="Send the video stream of FILE to URL in real time (as ffmpeg -re -i FILE "
                    "-c copy -f FORMAT URL).")
    parser.add_argument("file", metavar="FILE", help="a video file")
    parser.add_argument("url", metavar="URL", help="where to send it, e.g. udp://127.0.0.1:5000")
    parser.add_argument("format", metavar="FORMAT", nargs="?", default="mpegts",
                        help="the container sent (default: mpegts)")
    args = parser.parse_args(argv)
    try:
        send(args.file, args.url, args.format)
    except SendError as exc:
        print(f"{parser.prog}: error: {exc}", file=sys.stderr)
        return 1
    except (av.FFmpegError, OSError, ValueError) as exc:  # while sending (the receiver left)
        print(f"{parser.prog}: error: {args.file} -> {args.url}: {os_reason(exc)}",
              file=sys.stderr)
        return 1
    except KeyboardInterrupt:
        return 130
    return 0


if __name__ == "__main__":
    sys.exit(main())
