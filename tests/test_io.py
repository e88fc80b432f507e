"""Readers and writers: real files written with PyAV/NumPy, read back and compared pixel-wise."""

from __future__ import annotations

import csv
import fcntl
import itertools
import json
import os
import signal
import sys
import threading
import time
from collections.abc import Callable
from fractions import Fraction
from pathlib import Path

import av
import cv2
import numpy as np
import pytest
from conftest import sigterm_as_called

from vtrack.annotate import Annotator
from vtrack.errors import (
    ConfigError,
    InputError,
    Interrupted,
    OutputError,
    PartialInputError,
    handling_stop_signals,
    interrupt,
)
from vtrack.frame import BgrFrame, GrayFrame, I420Frame
from vtrack.geometry import Box, Window
from vtrack.io import (
    CsvWriter,
    RawFormat,
    VideoWriter,
    open_source,
    prepare_output_dir,
    write_json,
)
from vtrack.io.files import temp_path
from vtrack.io.threads import Prefetcher, _Producer, aside_running, run_aside
from vtrack.io.video import (
    DECODER_PICTURE_BUDGET,
    MIN_DECODER_THREADS,
    FFmpegInput,
    decoder_threads,
)
from vtrack.machine import cpu_count
from vtrack.pipeline import FrameResult
from vtrack.stages.base import TrackState

W, H = 160, 120


def pictures(n: int, width: int = W, height: int = H, seed: int = 0) -> list[np.ndarray]:
    """``n`` distinct BGR pictures: smooth texture plus a bright square moving right."""
    rng = np.random.default_rng(seed)
    base = cv2.GaussianBlur(rng.integers(0, 256, (height, width, 3), np.uint8), (0, 0), 2)
    out = []
    for i in range(n):
        img = base.copy()
        x = (4 * i) % (width - 20)
        img[height // 3 : height // 3 + 20, x : x + 20] = (40, 200, 240)
        out.append(img)
    return out


def write_video(
    path: Path,
    frames: list[np.ndarray],
    times: list[float] | None = None,
    fmt: str | None = None,
    options: dict[str, str] | None = None,
    rotation: int = 0,
    x264_params: str | None = None,
) -> Path:
    """Encode BGR pictures with PyAV (x264, ms time base when ``times`` are given)."""
    with av.open(str(path), "w", format=fmt, options=options or {}) as out:
        stream = out.add_stream("libx264", rate=30)
        stream.width, stream.height, stream.pix_fmt = frames[0].shape[1], frames[0].shape[0], \
            "yuv420p"
        stream.options = {"preset": "ultrafast", "crf": "18",
                          **({"x264-params": x264_params} if x264_params else {})}
        if times is not None:
            stream.codec_context.time_base = stream.time_base = Fraction(1, 1000)
        if rotation:
            stream.set_display_rotation(rotation)
        encode(out, stream, frames,
               None if times is None else [round(t * 1000) for t in times])
    return path


def encode(out: av.container.OutputContainer, stream: av.VideoStream,
           pictures: list[np.ndarray], pts: list[int] | None = None) -> None:
    """Encode BGR ``pictures`` into ``stream`` of ``out`` (timestamps 0, 1, ... or ``pts``)
    and flush the encoder."""
    for i, img in enumerate(pictures):
        frame = av.VideoFrame.from_ndarray(img, format="bgr24")
        frame.pts = i if pts is None else pts[i]
        for packet in stream.encode(frame):
            out.mux(packet)
    for packet in stream.encode():
        out.mux(packet)


def decode_all(path: Path) -> list[np.ndarray]:
    with av.open(str(path)) as container:
        return [f.to_ndarray(format="yuv420p") for f in container.decode(video=0)]


def read_all(spec: str, **kwargs) -> list:
    with open_source(spec, **kwargs) as source:
        return list(source)


def i420(bgr: np.ndarray) -> np.ndarray:
    return cv2.cvtColor(bgr, cv2.COLOR_BGR2YUV_I420)


# --- video files ------------------------------------------------------------------------------


def test_video_writer_output_decodes_to_same_count_and_size(tmp_path):
    out = tmp_path / "annotated.mp4"
    with VideoWriter(out, W, H, 30.0) as writer:
        for img in pictures(12):
            writer.write(i420(img))
    assert out.exists() and not temp_path(out).exists()
    decoded = decode_all(out)
    assert len(decoded) == 12
    assert decoded[0].shape == (H * 3 // 2, W)
    with open_source(str(out)) as source:
        info = source.info
        frames = list(source)
    assert (info.kind, info.name, info.width, info.height) == ("video", "annotated", W, H)
    assert info.fps == pytest.approx(30.0) and info.frame_count == 12
    assert info.codec == "h264" and info.pix_fmt == "yuv420p" and info.rotation == 0
    assert json.dumps(info.to_dict())
    assert [f.index for f in frames] == list(range(12))
    assert all(isinstance(f, I420Frame) for f in frames)
    assert [f.time_s for f in frames] == pytest.approx([i / 30 for i in range(12)])
    # The encoded pictures are close to the originals (lossy, crf 23).
    assert np.abs(frames[5].bgr().astype(int) - pictures(12)[5]).mean() < 6


def test_decoder_threads_raise_ffmpegs_choice_within_the_picture_budget():
    assert decoder_threads(1920, 1080, 2) == MIN_DECODER_THREADS  # FFmpeg alone: 3
    assert decoder_threads(1920, 1080, 1) == 1  # one core: nothing to fill, FFmpeg's choice
    assert decoder_threads(1920, 1080, 12) == 13  # FFmpeg's own choice is more already
    assert decoder_threads(1920, 1080, 64) == 16
    eight_k = decoder_threads(7680, 4320, 2)
    assert 3 <= eight_k < MIN_DECODER_THREADS
    assert eight_k * 7680 * 4320 * 3 // 2 <= DECODER_PICTURE_BUDGET
    assert decoder_threads(16384, 16384, 2) == 3  # one picture is over the budget: FFmpeg's
    assert decoder_threads(0, 0, 2) == MIN_DECODER_THREADS  # size not in the stream header


def test_video_decoded_with_more_threads_gives_the_same_pictures(tmp_path):
    clip = write_video(tmp_path / "clip.mp4", pictures(30))
    with open_source(str(clip)) as source:
        threads = source._stream.codec_context.thread_count
        frames = [f.i420() for f in source]
    assert threads == decoder_threads(W, H, cpu_count())
    with av.open(str(clip)) as container:  # one thread
        expected = [f.to_ndarray(format="yuv420p") for f in container.decode(video=0)]
    assert len(frames) == len(expected) == 30
    for got, want in zip(frames, expected, strict=True):
        np.testing.assert_array_equal(got, want)


def test_i420_windows_of_decoded_frame_match_full_conversion(tmp_path):
    clip = write_video(tmp_path / "clip.mp4", pictures(3))
    frame = read_all(str(clip))[1]
    assert isinstance(frame, I420Frame)
    full_bgr, full_gray = frame.bgr(), frame.gray()
    np.testing.assert_array_equal(full_bgr, cv2.cvtColor(frame.i420(), cv2.COLOR_YUV2BGR_I420))
    for window in (Window(0, 0, W, H), Window(3, 5, 41, 38), Window(10, 11, 12, 14),
                   Window(W - 7, H - 9, W, H)):
        np.testing.assert_array_equal(frame.bgr(window), full_bgr[window.slices])
        np.testing.assert_array_equal(frame.gray(window), full_gray[window.slices])



def test_sampled_windows_equal_converted_then_resized(tmp_path):
    """frame.bgr_sampled (robust_model's odd-factor path) gives exactly the pixels of a full
    conversion followed by the bilinear resize it replaces, on decoded frames and on random
    Y, U, V values (every chroma combination the window's sampled pixels can meet)."""
    clip = write_video(tmp_path / "clip.mp4", pictures(2))
    rng = np.random.default_rng(0)
    noise = I420Frame(0, 0.0, rng.integers(0, 256, (96 * 3 // 2, 128), dtype=np.uint8))
    for frame in (read_all(str(clip))[1], noise):
        for k in (3, 5):
            for x0, y0, cols, rows in ((0, 0, 9, 7), (3, 5, 4, 3), (1, 2, 1, 1), (8, 0, 12, 9)):
                window = Window(x0, y0, x0 + cols * k, y0 + rows * k)
                full = frame.bgr(window)
                sampled = frame.bgr_sampled(window, k)
                np.testing.assert_array_equal(sampled, full[k // 2 :: k, k // 2 :: k])
                np.testing.assert_array_equal(
                    sampled, cv2.resize(full, (cols, rows), interpolation=cv2.INTER_LINEAR))


def test_variable_frame_rate_timestamps(tmp_path):
    times = [0.0, 0.040, 0.050, 0.200, 0.210, 0.500, 0.533, 1.000]
    clip = write_video(tmp_path / "vfr.mp4", pictures(len(times)), times=times)
    frames = read_all(str(clip))
    assert [f.time_s for f in frames] == pytest.approx(times, abs=1e-6)
    # The writer keeps the input's timing when given the frames' times.
    out = tmp_path / "copy.mp4"
    with VideoWriter(out, W, H, 30.0) as writer:
        for frame in frames:
            writer.write(frame)
    assert [f.time_s for f in read_all(str(out))] == pytest.approx(times, abs=1e-4)


def test_an_avi_with_b_frames_gives_every_picture_in_order(tmp_path):
    """AVI keeps no presentation times: with B-frames the decoder's pictures came labelled with
    their packets' times, out of order, and were taken for damage (half of them skipped)."""
    images = pictures(24)
    clip = tmp_path / "b.avi"
    with av.open(str(clip), "w") as out:
        stream = out.add_stream("libx264", rate=30, options={"preset": "veryfast", "crf": "18"})
        stream.width, stream.height, stream.pix_fmt = W, H, "yuv420p"
        for i, img in enumerate(images):
            frame = av.VideoFrame.from_ndarray(img, format="bgr24")
            frame.pts = i
            out.mux(stream.encode(frame))
        out.mux(stream.encode(None))
    with av.open(str(clip)) as container:
        labels = [frame.pts for frame in container.decode(video=0)]
    assert labels != sorted(labels)  # the file is the case: times out of order
    with open_source(str(clip)) as source:
        frames = list(source)
        assert source.frames_skipped == 0 and not source.warnings
    assert [f.index for f in frames] == list(range(len(images)))
    assert [f.time_s for f in frames] == pytest.approx([i / 30 for i in range(len(images))])
    for frame, image in zip(frames, images, strict=True):  # each picture in its place
        assert np.abs(frame.bgr().astype(int) - image).mean() < 4


def test_display_rotation_is_applied(tmp_path):
    img = np.full((H, W, 3), 60, np.uint8)
    img[:16, :16] = 250  # bright marker top-left
    clip = write_video(tmp_path / "phone.mp4", [img] * 3, rotation=90)
    with open_source(str(clip)) as source:
        assert (source.info.rotation, source.info.width, source.info.height) == (90, H, W)
        frame = next(iter(source))
    assert (frame.width, frame.height) == (H, W)
    luma = frame.gray()
    # Turned 90 degrees counter-clockwise: the top-left marker is now bottom-left.
    assert luma[-12:, :12].mean() > 200 and luma[:12, :12].mean() < 100
    assert frame.bgr().shape == (W, H, 3)


def test_full_range_video_keeps_its_colours_in_and_out(tmp_path):
    """MJPEG (yuvj420p: full-range levels, as many cameras and phones record): the pixels the
    trackers see, and the annotated video written from the frames, keep the picture's levels
    instead of stretching them as video range would (16..235 taken for 0..255)."""
    picture = pictures(1, 160, 120)[0]
    picture[:, :40] = (10, 10, 10)  # dark and bright areas, where a stretch clips
    picture[:, -40:] = (245, 245, 245)
    clip = tmp_path / "clip.avi"
    with av.open(str(clip), "w") as out:
        stream = out.add_stream("mjpeg", rate=25)
        stream.width, stream.height, stream.pix_fmt = 160, 120, "yuvj420p"
        for _ in range(3):
            out.mux(stream.encode(av.VideoFrame.from_ndarray(picture, format="bgr24")))
        out.mux(stream.encode())
    with open_source(str(clip)) as source:
        frames = list(source)
    frame = frames[0]
    assert isinstance(frame, I420Frame) and frame.full_range
    seen = frame.bgr().astype(int)
    assert np.abs(seen - picture).mean() < 4
    assert abs(seen.std() / picture.std() - 1) < 0.03
    assert abs(seen[:, :40].mean() - 10) < 4 and abs(seen[:, -40:].mean() - 245) < 4
    window = Window(7, 9, 101, 83)
    assert np.array_equal(frame.bgr(window), frame.bgr()[window.slices])
    assert np.array_equal(frame.bgr_sampled(window, 3), frame.bgr()[10:83:3, 8:101:3])
    written = tmp_path / "out.mp4"
    with VideoWriter(written, 160, 120, 25.0) as writer:
        for f in frames:
            writer.write(f)
    with av.open(str(written)) as container:
        back = next(container.decode(video=0)).to_ndarray(format="bgr24").astype(int)
    assert np.abs(back - picture).mean() < 6
    assert abs(back[:, :40].mean() - 10) < 5 and abs(back[:, -40:].mean() - 245) < 5


def test_bt709_video_keeps_its_colours(tmp_path):
    """HD video is usually BT.709 (and says so); OpenCV's conversions are BT.601's. The pixels
    the trackers see match FFmpeg's own conversion of the tagged picture, saturated colours
    too, in every way a frame converts its pixels."""
    chart = np.zeros((128, 224, 3), np.uint8)
    for i, colour in enumerate([(0, 0, 255), (0, 255, 0), (255, 0, 0), (0, 200, 255),
                                (200, 50, 150), (128, 128, 128), (30, 90, 200)]):
        chart[:, i * 32:(i + 1) * 32] = colour
    clip = tmp_path / "hd.mp4"
    with av.open(str(clip), "w") as out:
        stream = out.add_stream("libx264", rate=30)
        stream.width, stream.height, stream.pix_fmt = 224, 128, "yuv420p"
        stream.codec_context.colorspace = 1  # tagged BT.709, as cameras tag HD
        picture = av.VideoFrame.from_ndarray(chart, format="bgr24").reformat(
            format="yuv420p", dst_colorspace="ITU709")
        out.mux(stream.encode(picture))
        out.mux(stream.encode())
    with av.open(str(clip)) as container:
        ffmpeg_bgr = next(container.decode(video=0)).to_ndarray(format="bgr24").astype(int)
    assert np.abs(ffmpeg_bgr - chart).max() > 0  # (x264 is lossy: compare with FFmpeg's own)
    with open_source(str(clip)) as source:
        frame = next(iter(source))
        assert isinstance(frame, I420Frame) and frame.bt709
        seen = frame.bgr()
        assert np.abs(seen.astype(int) - ffmpeg_bgr).max() <= 4
        window = Window(5, 7, 201, 121)
        assert np.array_equal(frame.bgr(window), seen[window.slices])
        assert np.array_equal(frame.bgr_sampled(window, 3), seen[8:121:3, 6:201:3])
        shrunk = frame.bgr_shrunk(2).astype(int)
        half = cv2.resize(seen, (112, 64), interpolation=cv2.INTER_AREA).astype(int)
        assert np.abs(shrunk - half)[2:-2, 2:-2].mean() < 3


def test_truncated_video_yields_good_frames_then_partial_error(tmp_path):
    frames = pictures(40)
    for name, kwargs in (("fast.mp4", {"options": {"movflags": "faststart"}}),
                         ("clip.mkv", {}), ("clip.ts", {"fmt": "mpegts"}),
                         ("clip.h264", {"fmt": "h264"})):
        whole = write_video(tmp_path / name, frames, **kwargs)
        cut = tmp_path / f"cut_{name}"
        data = whole.read_bytes()
        cut.write_bytes(data[: len(data) // 2])
        got = []
        with open_source(str(cut)) as source, pytest.raises(PartialInputError) as err:
            for frame in source:
                got.append(frame.index)
        assert 0 < err.value.frames_done < 40
        assert got == list(range(err.value.frames_done))
        message = str(err.value)
        assert str(cut) in message and f"stopped at frame {err.value.frames_done}" in message
        assert "\n" not in message


def test_a_later_matroska_segment_is_whole_and_its_cut_half_is_not(tmp_path):
    """``ffmpeg -c copy -f segment`` to .mkv: a part after the first starts at t > 0, and
    FFmpeg's Matroska muxer writes its last timestamp as the duration; the whole part was
    reported as truncated, promised to run to start + duration."""
    whole = tmp_path / "clip.mp4"
    with av.open(str(whole), "w") as out:  # a key frame every 15 frames, where parts may start
        stream = out.add_stream("libx264", rate=30, options={"preset": "ultrafast", "g": "15"})
        stream.width, stream.height, stream.pix_fmt = W, H, "yuv420p"
        for img in pictures(60):
            out.mux(stream.encode(av.VideoFrame.from_ndarray(img, format="bgr24")))
        out.mux(stream.encode(None))
    with av.open(str(whole)) as source, av.open(
            str(tmp_path / "part%d.mkv"), "w", format="segment",
            options={"segment_time": "1", "segment_format": "matroska"}) as parts:
        stream = parts.add_stream_from_template(source.streams.video[0])
        for packet in source.demux(video=0):
            if packet.dts is not None:
                packet.stream = stream
                parts.mux(packet)
    part = tmp_path / "part1.mkv"
    with av.open(str(part)) as container:
        assert container.start_time > 0  # the case: a part that does not start at 0
    with open_source(str(part)) as source:
        frames = list(source)
        assert source.frames_skipped == 0 and not source.warnings
    assert [f.time_s for f in frames] == pytest.approx([i / 30 for i in range(30)], abs=1e-3)  # ms
    cut = tmp_path / "cut.mkv"
    data = part.read_bytes()
    cut.write_bytes(data[: len(data) // 2])
    with open_source(str(cut)) as source, pytest.raises(PartialInputError):
        list(source)


@pytest.mark.parametrize("fmt", ["image2", "image2pipe"])
def test_a_video_read_as_an_image_format_is_one_input_error(tmp_path, fmt):
    """``-f image2`` on an MP4: FFmpeg finds a stream it has no decoder for (AttributeError)."""
    clip = write_video(tmp_path / "clip.mp4", pictures(4))
    with pytest.raises(InputError, match=f"clip.mp4: no decoder .*format {fmt}; a wrong --format"):
        read_all(str(clip), ffmpeg=FFmpegInput(format=fmt))


def test_corrupt_packets_mid_stream_are_skipped(tmp_path):
    """Issue 11 item 7: damage in the middle is skipped as ffmpeg skips it; the frames after it
    keep their places and the source counts what was lost."""
    whole = write_video(tmp_path / "clip.mp4", pictures(40), options={"movflags": "faststart"})
    data = bytearray(whole.read_bytes())
    mid = len(data) // 2
    data[mid : mid + 3000] = np.random.default_rng(1).integers(0, 256, 3000, np.uint8).tobytes()
    broken = tmp_path / "broken.mp4"
    broken.write_bytes(bytes(data))
    with open_source(str(broken)) as source:
        got = [frame.index for frame in source]
        skipped = source.frames_skipped
    assert skipped > 0 and len(got) + skipped == 40 and got[-1] == 39
    assert got == sorted(set(got))
    # the skipped frames' line, and one for pictures decoded with errors if the decoder's frame
    # threads flagged any
    assert 1 <= len(source.warnings) <= 2 and all(str(broken) in w for w in source.warnings)
    assert "skipped" in source.warnings[0]


def test_scattered_damage_is_counted_and_frames_keep_their_places(tmp_path):
    """Bytes flipped all over a file: the decoder hands over pictures decoded with errors, out
    of order, or lets some vanish without an error. Every frame handed over keeps the index its
    timestamp gives (30 fps), in order; what was lost or damaged is counted and named."""
    data = write_video(tmp_path / "clip.mp4", pictures(90),
                       options={"movflags": "faststart"}).read_bytes()
    complete = 0
    for seed in range(6):
        damaged = bytearray(data)
        rng = np.random.default_rng(seed)
        for position in rng.integers(len(data) // 4, len(data), 40):
            damaged[position] = int(rng.integers(256))
        broken = tmp_path / f"broken{seed}.mp4"
        broken.write_bytes(bytes(damaged))
        frames = []
        try:
            with open_source(str(broken)) as source:
                frames = [(frame.index, frame.time_s) for frame in source]
        except PartialInputError as err:  # damage at the very end looks like a cut-off file
            assert str(broken) in str(err)
            continue
        complete += 1
        indices = [index for index, _ in frames]
        assert indices == sorted(set(indices))
        assert all(abs(time_s * 30 - index) < 1e-6 for index, time_s in frames)
        assert indices[-1] + 1 == len(frames) + source.frames_skipped
        assert source.frames_skipped + source.frames_corrupt > 0
        assert all(w.startswith(f"{broken}: ") for w in source.warnings)
        for phrase, count in (("could not be decoded", source.frames_skipped),
                              ("decoded with errors", source.frames_corrupt)):
            assert any(phrase in w for w in source.warnings) == (count > 0)
    assert complete >= 3


def _remuxed(clip: Path, out: Path, damage: Callable[[int, av.Packet], av.Packet | None],
             fmt: str | None = None) -> Path:
    """``clip``'s packets copied into ``out``, each through ``damage(index, packet)`` (None:
    the packet is left out)."""
    with av.open(str(clip)) as source, av.open(str(out), "w", format=fmt) as target:
        given = source.streams.video[0]
        stream = target.add_stream_from_template(given)
        for i, packet in enumerate(source.demux(given)):
            if packet.size == 0:
                continue
            changed = damage(i, packet)
            if changed is not None:
                changed.stream = stream
                target.mux(changed)
    return out


def test_pictures_cut_out_of_a_transport_stream_leave_their_places_empty(tmp_path):
    """A transport stream (no listed frame count) that lost five whole pictures, each its own
    key frame, without a decoding error: the later frames were renumbered 20, 21, ... and
    scored against the wrong ground truth, with no warning."""
    clip = write_video(tmp_path / "intra.ts", pictures(40), fmt="mpegts", x264_params="keyint=1")
    cut = _remuxed(clip, tmp_path / "cut.ts", lambda i, p: None if 20 <= i < 25 else p,
                   fmt="mpegts")
    with open_source(str(cut)) as source:
        frames = [(frame.index, frame.time_s) for frame in source]
    assert [index for index, _ in frames] == list(range(20)) + list(range(25, 40))
    assert all(abs(time_s * 30 - index) < 1e-6 for index, time_s in frames)
    assert source.frames_skipped == 5
    assert source.warnings == [f"{cut}: 5 damaged frames could not be decoded and were skipped"]


def test_a_refused_packet_of_a_variable_rate_video_leaves_one_place_empty(tmp_path):
    """A variable-rate Matroska file whose 31st packet is garbage: the frame index was rebuilt
    from the timestamps at the guessed rate, so one lost frame made over 10,000 "skipped"."""
    rng = np.random.default_rng(3)
    times = np.cumsum(np.r_[0, rng.uniform(0.005, 0.4, 59)])
    clip = write_video(tmp_path / "vfr.mkv", pictures(60), times=list(times))

    def garbled(i: int, packet: av.Packet) -> av.Packet:
        if i != 30:
            return packet
        bad = av.Packet(bytes(b ^ 0x5A for b in bytes(packet)))
        bad.pts, bad.dts, bad.time_base = packet.pts, packet.dts, packet.time_base
        return bad

    broken = _remuxed(clip, tmp_path / "broken.mkv", garbled)
    with open_source(str(broken)) as source:
        frames = [(frame.index, frame.time_s) for frame in source]
    assert source.frames_skipped == 1
    assert [index for index, _ in frames] == [i for i in range(60) if i != 30]
    assert [round(t, 3) for _, t in frames] == [round(t, 3) for i, t in enumerate(times)
                                                if i != 30]
    # a reader that stops early (--frames) still hears of the damage it went past
    with open_source(str(broken)) as source:
        assert len(list(itertools.islice(source, 45))) == 45
    assert source.warnings == [f"{broken}: 1 damaged frame could not be decoded and was "
                               "skipped"]


def test_the_video_stream_is_the_one_ffmpeg_takes(tmp_path):
    """A file whose first video stream is a 64x64 picture and whose second, marked default,
    is the video: the picture's one frame was tracked. A warning names the one tracked."""
    clip = tmp_path / "two.mkv"
    with av.open(str(clip), "w") as out:
        cover = out.add_stream("mpeg4", rate=1)
        cover.width = cover.height = 64
        cover.pix_fmt, cover.disposition = "yuv420p", 0
        video = out.add_stream("libx264", rate=30)
        video.width, video.height, video.pix_fmt = W, H, "yuv420p"
        video.disposition = av.stream.Disposition.default
        encode(out, cover, [np.zeros((64, 64, 3), np.uint8)])
        encode(out, video, pictures(20))
    with open_source(str(clip)) as source:
        assert (source.info.width, source.info.height) == (W, H)
        assert len(list(source)) == 20
    assert source.warnings == [f"{clip}: 2 video streams; tracking the one ffmpeg takes (#1)"]


def test_a_text_file_is_not_tracked_as_a_video(tmp_path):
    """FFmpeg's tty reader draws a .txt file's characters as 640x400 pictures: a ground truth
    given as the input was tracked over 7 frames of text."""
    notes = tmp_path / "clip.gt.txt"
    notes.write_text("10,10,40,30\n" * 200)
    with pytest.raises(InputError, match=r"clip\.gt\.txt: a text file, not a video"):
        open_source(str(notes))


def test_bad_inputs_raise_input_error_naming_them(tmp_path):
    missing = tmp_path / "clip.mp4"
    with pytest.raises(InputError, match=r"clip\.mp4: no such file"):
        open_source(str(missing))
    text = tmp_path / "notes.mp4"
    text.write_text("this is not a video\n" * 50)
    with pytest.raises(InputError) as err:
        open_source(str(text))
    assert str(err.value).startswith(f"{text}: not a video FFmpeg can decode (")
    audio = tmp_path / "sound.m4a"
    with av.open(str(audio), "w") as out:
        stream = out.add_stream("aac", rate=8000)
        samples = av.AudioFrame.from_ndarray(np.zeros((1, 1024), np.float32), format="fltp",
                                             layout="mono")
        samples.sample_rate, samples.pts = 8000, 0
        for packet in [*stream.encode(samples), *stream.encode()]:
            out.mux(packet)
    with pytest.raises(InputError, match=r"sound\.m4a: no video stream \(streams: audio\)"):
        open_source(str(audio))
    empty = tmp_path / "empty"
    empty.mkdir()
    with pytest.raises(InputError, match=r"empty: no images"):
        open_source(str(empty))
    with pytest.raises(ConfigError, match="--fps: a container on stdin"):
        open_source("-", fps=25)  # "-" without --raw is a container (tests/test_live_inputs.py)


@pytest.mark.skipif(os.geteuid() == 0, reason="root reads files regardless of permissions")
def test_unreadable_file_raises_input_error(tmp_path):
    clip = write_video(tmp_path / "clip.mp4", pictures(2))
    clip.chmod(0)
    with pytest.raises(InputError, match="permission denied"):
        open_source(str(clip))


def test_closing_mid_stream_stops_the_reader_thread(tmp_path):
    clip = write_video(tmp_path / "clip.mp4", pictures(60))
    source = open_source(str(clip))
    it = iter(source)
    assert [next(it).index for _ in range(3)] == [0, 1, 2]
    source.close()
    source.close()
    assert not [t for t in threading.enumerate() if t.name.startswith("vtrack-read")]
    with pytest.raises(RuntimeError):
        iter(source)


def test_prefetcher_hands_over_items_then_the_producer_error():
    def produce():
        yield from range(5)
        raise ValueError("broken at 5")

    got = []
    with pytest.raises(ValueError, match="broken at 5"):
        for item in Prefetcher(produce(), depth=2, name="test"):
            got.append(item)
    assert got == [0, 1, 2, 3, 4]

    def endless():
        n = 0
        while True:
            yield n
            n += 1

    prefetch = Prefetcher(endless(), depth=2, name="test-endless")
    assert next(iter(prefetch)) == 0
    assert prefetch.close() is True


def test_a_prefetcher_closed_from_another_thread_never_ends_as_complete_with_an_item_left():
    """close() from another thread as the producer was queueing the last item (past its stop
    check, not yet put) emptied a queue still empty; the item was put after, the consumer
    left on the stop without it, and reached_end said True ([1, 2] handed over, 3 still
    queued): a source closed so ended as if read to its end. An end the producer reaches
    once close() has begun is not counted now. Nor does reached_end turn True after close()
    has returned False (a producer slow to find its end, finding it later): it was final
    only in name. The interleaving is held by events, not timing."""
    prefetch = Prefetcher(iter([1, 2, 3]), depth=8, name="test-close-race")
    queue_item = prefetch._queue.put

    def put(item: object, *args: object, **kwargs: object) -> None:
        if item == 3:  # past the stop check: wait until close() has emptied the queue
            assert prefetch._stop.wait(60)
            with prefetch._closing:
                pass
        queue_item(item, *args, **kwargs)

    prefetch._queue.put = put  # type: ignore[method-assign]
    items = iter(prefetch)
    got = [next(items), next(items)]
    closer = threading.Thread(target=prefetch.close, kwargs={"timeout": 60})
    closer.start()
    got += list(items)
    closer.join(60)
    assert got == [1, 2] and not prefetch._thread.is_alive()
    assert list(prefetch._queue.queue) == [3]  # never handed over
    assert prefetch.reached_end is False

    release = threading.Event()

    def slow_end():
        yield 1
        release.wait(60)  # the end, found late

    slow = Prefetcher(slow_end(), depth=2, name="test-slow-end")
    assert next(iter(slow)) == 1
    assert slow.close(timeout=0.1) is False and slow.reached_end is False
    release.set()
    slow._thread.join(60)
    assert not slow._thread.is_alive() and slow.reached_end is False


def test_a_prefetcher_whose_start_a_signal_interrupted_closes_without_an_error():
    """SIGTERM to `vtrack vectors` as its reader's thread was being started raised in
    Thread.start's wait for the new thread (launched, not yet running); closing the source
    then said 'RuntimeError: cannot join thread before it is started', a traceback and exit
    1. close() now waits for that thread to run, then for it to end. (The main thread holds
    the signals off in start() now; a signal another thread took can still raise there.)"""
    prefetch = Prefetcher(iter(range(5)), depth=2, name="test-interrupted")
    thread = prefetch._thread

    def interrupted_start() -> None:  # as Thread.start when a signal arrives in its wait:
        # the thread is launched and runs a moment later (here: once close() has begun)
        thread._launching = True
        threading.Thread(target=lambda: (prefetch._stop.wait(), threading.Thread.start(thread)),
                         daemon=True).start()
        raise Interrupted(signal.SIGTERM)

    thread._launch = interrupted_start  # type: ignore[method-assign]
    with pytest.raises(Interrupted):
        next(iter(prefetch))
    assert prefetch.close(timeout=60) is True
    assert not thread.is_alive()



def test_a_signal_as_a_prefetchers_thread_is_started_waits_for_the_start() -> None:
    """SIGTERM landing inside Thread.start before the reader's thread was launched raised
    there; close() then waited its whole timeout for a thread that would never run and said
    the reader was stuck (False; the source warned so). The main thread now holds SIGINT and
    SIGTERM off while it starts the thread: the signal is handled once start() is over, and
    close() finds the thread started and ends it. The signal is sent to the main thread as
    Thread.start begins (a trace function)."""
    prefetch = Prefetcher(iter(range(5)), depth=2, name="test-signal-in-start")
    with (sigterm_as_called(threading.Thread.start.__code__),
          handling_stop_signals(interrupt), pytest.raises(Interrupted)):
        next(iter(prefetch))
    assert prefetch.close(timeout=10) is True
    assert not prefetch._thread.is_alive()


def _run_aside_left(started_as: object) -> tuple[list[str], threading.Event]:
    """run_aside with work that waits to be released, then gives "container": SIGTERM
    (Interrupted) in the caller's thread as ``started_as`` (a function's code) is first called
    there. The list ``discard`` fills, and the event that releases the work."""
    release, discarded = threading.Event(), []

    def work() -> str:
        release.wait(60)
        return "container"

    with (sigterm_as_called(started_as), handling_stop_signals(interrupt),
          pytest.raises(Interrupted)):
        run_aside(work, discarded.append)
    return discarded, release


def _wait_for_no_work_aside() -> None:
    deadline = time.monotonic() + 60  # a bound, not a measure
    while aside_running() and time.monotonic() < deadline:
        time.sleep(0.01)
    assert not aside_running(), "the work aside did not end"


def test_run_aside_raises_the_works_exception_and_discards_nothing() -> None:
    """What the work raised in its thread is raised in the caller's; nothing is discarded."""
    discarded: list[object] = []

    def work() -> object:
        raise av.error.ExitError(-1414092869, "Immediate exit requested")

    with pytest.raises(av.error.ExitError):
        run_aside(work, discarded.append)
    assert discarded == [] and not aside_running()


def test_run_aside_left_by_a_signal_discards_what_its_work_gives_later() -> None:
    """A signal while the caller waits raises there at once; the work goes on aside
    (aside_running) and what it gives once done is handed to discard (e.g. closed)."""
    discarded, release = _run_aside_left(threading.Thread.join.__code__)
    assert aside_running() and discarded == []
    release.set()
    _wait_for_no_work_aside()
    assert discarded == ["container"]


def test_a_signal_as_run_asides_thread_is_started_still_discards_its_result() -> None:
    """SIGTERM landing in Thread.start once the thread was launched (its wait for the thread
    to run) raised before run_aside's try: the caller was gone, yet the work's result (an
    opened container) was never handed to discard, so never closed. The signal is now handled
    once start() is over, inside the try."""
    discarded, release = _run_aside_left(threading.Event.wait.__code__)
    release.set()
    _wait_for_no_work_aside()
    assert discarded == ["container"]

def test_a_signal_before_run_asides_thread_is_launched_leaves_nothing_running() -> None:
    """SIGTERM handled as run_aside's thread was about to be started (before any thread ran)
    left run_aside's marker set for good: aside_running() stayed True with no thread behind
    it (the CLI then ended with os._exit for nothing; a library caller told to wait for it
    waited for ever)."""
    discarded, release = _run_aside_left(_Producer.start.__code__)
    release.set()
    assert discarded == [] and not aside_running()

# --- image folders ----------------------------------------------------------------------------


def test_image_folder_natural_order_and_gray_images(tmp_path):
    folder = tmp_path / "seq"
    folder.mkdir()
    for n in (10, 2, 1):
        cv2.imwrite(str(folder / f"{n}.png"), np.full((H, W), n * 20, np.uint8))
    with open_source(str(folder)) as source:
        info = source.info
        frames = list(source)
    assert (info.kind, info.name, info.frame_count, info.fps) == ("images", "seq", 3, 30.0)
    assert all(isinstance(f, GrayFrame) for f in frames)
    assert [int(f.gray()[0, 0]) for f in frames] == [20, 40, 200]
    assert [f.time_s for f in frames] == pytest.approx([0, 1 / 30, 2 / 30])


def test_an_image_missing_from_a_numbered_sequence_leaves_its_frame_empty(tmp_path):
    """OTB's seq/img/0001.jpg... with 0005 deleted: the later images were renumbered (0006.jpg
    became frame 4) and scored against the wrong ground truth, without a word."""
    img_dir = tmp_path / "seq" / "img"
    img_dir.mkdir(parents=True)
    for i, img in enumerate(pictures(8)):
        if i != 4:
            cv2.imwrite(str(img_dir / f"{i + 1:04d}.png"), img)
    with open_source(str(tmp_path / "seq")) as source:
        indices = [frame.index for frame in source]
    assert indices == [0, 1, 2, 3, 5, 6, 7]
    assert source.info.frame_count == 8 and source.frames_skipped == 1
    assert source.warnings == [f"{tmp_path / 'seq'}: 1 image missing from the numbering (the "
                               "first: frame 4, after 0004.png); their frames are skipped"]


def test_otb_layout_colour_images(tmp_path):
    img_dir = tmp_path / "Car9" / "img"
    img_dir.mkdir(parents=True)
    imgs = pictures(3)
    for i, img in enumerate(imgs):
        cv2.imwrite(str(img_dir / f"{i + 1:04d}.png"), img)
    frames = read_all(str(tmp_path / "Car9"), fps=10)
    assert all(isinstance(f, BgrFrame) for f in frames)
    for frame, img in zip(frames, imgs, strict=True):
        np.testing.assert_array_equal(frame.bgr(), img)
    assert frames[2].time_s == pytest.approx(0.2)
    with open_source(str(img_dir)) as source:
        assert source.info.name == "Car9"


def test_image_of_another_size_stops_the_sequence(tmp_path):
    for i in range(3):
        cv2.imwrite(str(tmp_path / f"{i}.jpg"), pictures(1)[0])
    cv2.imwrite(str(tmp_path / "3.jpg"), pictures(1, width=W + 2)[0])
    got = []
    with open_source(str(tmp_path)) as source, pytest.raises(PartialInputError) as err:
        for frame in source:
            got.append(frame.index)
    assert got == [0, 1, 2] and err.value.frames_done == 3
    assert str(tmp_path / "3.jpg") in str(err.value) and "162x120" in str(err.value)


# --- raw frames -------------------------------------------------------------------------------


def raw_frames(pix_fmt: str, n: int, width: int = 32, height: int = 24) -> list[np.ndarray]:
    fmt = RawFormat(width, height, pix_fmt, 30.0)
    rng = np.random.default_rng(7)
    return [rng.integers(0, 256, fmt.shape, np.uint8) for _ in range(n)]


@pytest.mark.parametrize("pix_fmt", ["bgr24", "rgb24", "yuv420p", "gray"])
def test_raw_file_reads_back_exactly(tmp_path, pix_fmt):
    stored = raw_frames(pix_fmt, 12)  # more frames than the reader's buffer ring
    path = tmp_path / "frames.raw"
    path.write_bytes(b"".join(f.tobytes() for f in stored))
    expected_type = {"bgr24": BgrFrame, "rgb24": BgrFrame, "yuv420p": I420Frame,
                     "gray": GrayFrame}[pix_fmt]
    pixels = {BgrFrame: BgrFrame.bgr, I420Frame: I420Frame.i420, GrayFrame: GrayFrame.gray}
    with open_source(str(path), RawFormat.parse("32x24", pix_fmt, 25)) as source:
        info = source.info
        # Compare each frame while it is current: the reader's buffers are reused.
        for frame, want in zip(source, stored, strict=True):
            assert isinstance(frame, expected_type)
            assert frame.time_s == pytest.approx(frame.index / 25)
            if pix_fmt == "rgb24":
                want = want[:, :, ::-1]
            np.testing.assert_array_equal(pixels[expected_type](frame), want)
    assert (info.kind, info.name, info.frame_count, info.fps) == ("raw", "frames", 12, 25.0)


def _feed(fd_or_path, data: bytes) -> threading.Thread:
    def run():
        with open(fd_or_path, "wb") as pipe:
            pipe.write(data)

    thread = threading.Thread(target=run, daemon=True)
    thread.start()
    return thread


def test_raw_stdin_pipe_reads_back_exactly_and_is_enlarged(monkeypatch):
    stored = raw_frames("bgr24", 8, 64, 48)
    read_fd, write_fd = os.pipe()
    with open(read_fd, "rb", closefd=True) as fake_stdin:
        monkeypatch.setattr(sys, "stdin", fake_stdin)
        feeder = _feed(write_fd, b"".join(f.tobytes() for f in stored))
        with open_source("-", RawFormat.parse("64x48", "bgr24", 60)) as source:
            assert source.info.name == "stdin" and source.info.frame_count is None
            assert fcntl.fcntl(read_fd, 1032) >= 1 << 20  # F_GETPIPE_SZ: enlarged to 1 MiB
            for frame, want in zip(source, stored, strict=True):
                np.testing.assert_array_equal(frame.bgr(), want)
        feeder.join()


def test_raw_fifo_with_stray_bytes_is_partial(tmp_path):
    stored = raw_frames("gray", 5)
    fifo = tmp_path / "camera.fifo"
    os.mkfifo(fifo)
    feeder = _feed(fifo, b"".join(f.tobytes() for f in stored) + b"\x00" * 100)
    got = []
    with open_source(str(fifo), RawFormat(32, 24, "gray", 30.0)) as source, \
            pytest.raises(PartialInputError) as err:
        for frame in source:
            np.testing.assert_array_equal(frame.gray(), stored[frame.index])
            got.append(frame.index)
    feeder.join()
    assert got == [0, 1, 2, 3, 4] and err.value.frames_done == 5
    assert str(err.value) == (f"{fifo}: raw stream ended with 100 stray bytes after 5 whole "
                              "frames (frame size 768 bytes for 32x24 gray)")


def test_raw_file_shorter_than_one_frame_is_an_input_error(tmp_path):
    path = tmp_path / "tiny.raw"
    path.write_bytes(b"\x01" * 10)
    with pytest.raises(InputError, match=r"tiny\.raw: raw stream ended with 10 stray bytes"):
        open_source(str(path), RawFormat(32, 24, "gray", 30.0))
    path.write_bytes(b"")
    with pytest.raises(InputError, match=r"tiny\.raw: no raw frames"):
        open_source(str(path), RawFormat(32, 24, "gray", 30.0))


@pytest.mark.parametrize(
    ("size", "pix_fmt", "fps", "match"),
    [
        ("19x", "bgr24", 30, "expected WIDTHxHEIGHT"),
        ("0x10", "bgr24", 30, "positive"),
        ("321x240", "yuv420p", 30, "even"),
        ("320x240", "nv12", 30, "--pix-fmt"),
        ("320x240", "gray", 0, "--fps"),
    ],
)
def test_raw_format_rejects_bad_values(size, pix_fmt, fps, match):
    with pytest.raises(ConfigError, match=match):
        RawFormat.parse(size, pix_fmt, fps)


def test_raw_format_parse_and_sizes():
    fmt = RawFormat.parse("1920x1080", "bgr24", 60)
    assert (fmt.width, fmt.height, fmt.frame_bytes) == (1920, 1080, 6220800)
    assert RawFormat.parse("320X240", "yuv420p", 30).frame_bytes == 320 * 240 * 3 // 2


# --- writers ----------------------------------------------------------------------------------


def test_csv_rows_are_on_disk_as_written_and_renamed_on_close(tmp_path):
    path = tmp_path / "track.csv"
    writer = CsvWriter(path, ["frame", "x", "state", "overlap", "score"])
    writer.write([0, 12.345678, "tracking", 0.12345678, float("nan")])
    writer.write([1, 3.0, "lost", None, np.float32(0.5)])
    (partial,) = tmp_path.glob(".track.tmp-*.csv")  # unique to this process and writer
    assert f"-{os.getpid()}-" in partial.name and temp_path(path) != temp_path(path)
    assert not path.exists()
    rows = list(csv.reader(partial.open()))
    assert rows == [["frame", "x", "state", "overlap", "score"],
                    ["0", "12.346", "tracking", "0.123457", ""],  # overlap: 6 decimals
                    ["1", "3", "lost", "", "0.5"]]
    writer.close()
    writer.close()
    assert not partial.exists()
    assert list(csv.reader(path.open())) == rows
    with pytest.raises(ValueError):
        CsvWriter(tmp_path / "t.csv", ["a"]).write([1, 2])


def test_a_csv_whose_close_failed_is_not_renamed_after(tmp_path):
    """When the file's close failed in finish() (the temporary removed, an error raised), a
    later close() still renamed the missing temporary: a second, wrong error ("No such file or
    directory") replaced the first. Now close() after it does nothing more."""
    path = tmp_path / "track.csv"
    with pytest.raises(OutputError) as raised, CsvWriter(path, ["frame"]) as writer:
        writer.write([0])
        os.close(writer._fd)  # the descriptor already gone: closing it fails (EBADF)
        writer.finish()
    assert str(raised.value) == f"{path}: cannot write (Bad file descriptor)"
    writer.close()  # and again: nothing is raised
    assert list(tmp_path.iterdir()) == []


def test_write_json_is_atomic_and_maps_nan_to_null(tmp_path):
    path = tmp_path / "run.json"
    write_json(path, {"fps": float("nan"), "n": np.int64(3), "box": (1.5, 2), "ok": np.bool_(1),
                      "where": tmp_path, "arr": np.array([1.0, np.inf])})
    assert json.loads(path.read_text()) == {"fps": None, "n": 3, "box": [1.5, 2], "ok": True,
                                            "where": str(tmp_path), "arr": [1.0, None]}
    assert path.read_text().startswith("{\n  ")
    assert sorted(p.name for p in tmp_path.iterdir()) == ["run.json"]


def test_unwritable_output_folder_raises_output_error(tmp_path):
    blocker = tmp_path / "file.txt"
    blocker.write_text("not a folder")
    out = blocker / "out"
    with pytest.raises(OutputError, match=r"file\.txt/out: cannot write output here"):
        prepare_output_dir(out)
    with pytest.raises(OutputError, match=r"track\.csv: cannot write"):
        CsvWriter(out / "track.csv", ["frame"])
    with pytest.raises(OutputError, match=r"annotated\.mp4: cannot write"):
        VideoWriter(out / "annotated.mp4", W, H, 30.0)
    with pytest.raises(OutputError, match=r"run\.json: cannot write"):
        write_json(out / "run.json", {})
    assert prepare_output_dir(tmp_path / "a" / "b").is_dir()


def test_video_writer_bad_preset_is_a_config_error(tmp_path):
    with pytest.raises(ConfigError, match="preset 'warp'"):
        VideoWriter(tmp_path / "v.mp4", W, H, 30.0, preset="warp")
    assert list(tmp_path.iterdir()) == []


def test_video_writer_abort_leaves_nothing_and_odd_sizes_are_cropped(tmp_path):
    writer = VideoWriter(tmp_path / "v.mp4", W, H, 30.0)
    writer.write(i420(pictures(1)[0]))
    writer.abort()
    assert list(tmp_path.iterdir()) == []
    odd = pictures(3, width=W + 1, height=H + 1)
    out = tmp_path / "odd.mp4"
    with VideoWriter(out, W + 1, H + 1, 25.0) as writer:
        for i, img in enumerate(odd):
            writer.write(BgrFrame(i, i / 25, img))
    assert (writer.width, writer.height) == (W, H)
    decoded = decode_all(out)
    assert [f.shape for f in decoded] == [(H * 3 // 2, W)] * 3
    want = i420(np.ascontiguousarray(odd[1][:H, :W]))
    assert np.abs(decoded[1].astype(int) - want).mean() < 3


def test_video_closed_after_an_interrupt_is_playable(tmp_path):
    out = tmp_path / "annotated.mp4"
    writer = VideoWriter(out, W, H, 30.0, preset="medium")  # lookahead: frames still queued
    with pytest.raises(KeyboardInterrupt):
        try:
            for i, img in enumerate(pictures(20)):
                if i == 9:
                    raise KeyboardInterrupt
                writer.write(i420(img))
        finally:
            writer.close()
    assert len(decode_all(out)) == 9 and writer.frames_written == 9


def test_annotated_video_shows_box_and_lost_caption_without_touching_the_input(tmp_path):
    grey = np.full((H, W, 3), 100, np.uint8)
    source = i420(grey)
    original = source.copy()
    box = Box(40, 30, 50, 40)
    annotator = Annotator(W, H)
    out = tmp_path / "annotated.mp4"
    with VideoWriter(out, W, H, 30.0) as writer:
        for i in range(6):
            state = TrackState.LOST if i == 5 else TrackState.TRACKING
            lost = state == TrackState.LOST
            result = FrameResult(i, i / 30, None if lost else box, state, 1.0, None)
            writer.write(source, lambda buf, r=result: annotator.draw(buf, r))
    np.testing.assert_array_equal(source, original)
    frames = decode_all(out)
    assert len(frames) == 6
    luma = frames[2][:H]
    background = int(luma[100, 140])
    assert abs(background - int(original[100, 140])) < 4
    assert abs(int(luma[30:70, 40].mean()) - background) > 40  # left edge of the box
    assert abs(int(luma[60, 120]) - background) < 4  # away from the drawing
    lost = frames[5][:H]
    top_right, top_left = lost[:12, W - 30 :], lost[:12, :30]
    assert np.abs(top_right.astype(int) - background).max() > 40
    assert np.abs(top_left.astype(int) - background).max() < 8
    assert np.abs(lost[30:70, 40].astype(int) - background).max() < 8  # no box while lost


def test_frames_lost_before_a_late_start_are_not_counted(tmp_path):
    """`vtrack run gap.mp4 --start 101` read from key frame 90 and said "skipped 1 undecodable"
    for frame 100, before the start (as does any input read from before its start). Frames
    lost before the run's first frame (start_near's index, skip_to's first frame at or after
    its time) are not counted or warned of; those from it on still are: frames 22..24 of a
    start at frame 22 (it said nothing of them)."""
    clip = write_video(tmp_path / "intra.ts", pictures(40), fmt="mpegts", x264_params="keyint=1")
    cut = _remuxed(clip, tmp_path / "cut.ts", lambda i, p: None if 20 <= i < 25 else p,
                   fmt="mpegts")
    for begin, skipped in ((lambda s: s.start_near(30), 0), (lambda s: s.start_near(22), 3),
                           (lambda s: s.skip_to(30 / 30), 0), (lambda s: s.skip_to(21.5 / 30), 0)):
        with open_source(str(cut)) as source:
            begin(source)
            frames = [frame.index for frame in source]
        assert 20 not in frames and frames[-1] == 39  # (a transport stream reads from 0)
        assert (source.frames_skipped, len(source.warnings)) == (skipped, min(skipped, 1))
    with open_source(str(cut)) as source:  # a start before the loss counts it
        source.start_near(10)
        assert [frame.index for frame in source][:1] == [0]
    assert source.frames_skipped == 5
