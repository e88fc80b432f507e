"""Send a video file to a URL at its own pace, as ``ffmpeg -re -i FILE -c copy -f FMT URL`` does.

A live source for tests, benchmarks and demonstrations on a machine without the ``ffmpeg``
program: the packets are copied (no re-encoding) and each is sent when its timestamp comes due
on the wall clock, so the receiver sees a stream arriving in real time.

``python -m vtrack.scenes.send FILE URL [FORMAT]`` (FORMAT default ``mpegts``).
"""

from __future__ import annotations

import sys
import time

import av


def send(path: str, url: str, fmt: str = "mpegts", *, realtime: bool = True) -> int:
    """Copy the video stream of ``path`` into ``url`` as ``fmt``, each packet sent when its
    timestamp is due (``realtime``), and return the number of packets sent."""
    with av.open(path) as source, av.open(url, "w", format=fmt) as sink:
        video = source.streams.video[0]
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


if __name__ == "__main__":
    send(sys.argv[1], sys.argv[2], *sys.argv[3:4])
