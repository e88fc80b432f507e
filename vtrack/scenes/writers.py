"""Writing scenes to files: H.264 video, OTB / MOTChallenge ground truth, image folders, raw.

Ground-truth conventions:

- OTB text (``write_groundtruth``): one ``x,y,w,h`` line per frame, 2 decimals, top-left
  corner, not clipped to the frame (a box partly outside has a negative ``x`` or runs past the
  edge). A frame where the target is entirely outside the frame is ``0,0,0,0`` (the UAV123 /
  LaSOT convention for an absent target). A fully *occluded* target keeps its true box (see
  :class:`~vtrack.scenes.scene.Scene`).
- MOTChallenge (``write_mot_groundtruth``): ``frame,id,x,y,w,h,1,1,visibility`` with 1-based
  frames, one line per object at least partly inside the frame.

Every writer creates missing parent folders, writes temporary names renamed when complete (a
failed write leaves no partial file and the earlier one as it was) and turns an OS failure into
:class:`~vtrack.errors.OutputError` naming the path.
"""

from __future__ import annotations

import sys
from collections.abc import Callable, Iterable, Iterator
from contextlib import contextmanager
from dataclasses import dataclass
from fractions import Fraction
from pathlib import Path

import av
import cv2
import numpy as np
from tqdm import tqdm

from vtrack.errors import ConfigError, OutputError, quoted_or_cut
from vtrack.io.files import (
    ffmpeg_file,
    os_reason,
    removing_new_folders,
    replacing,
    same_file,
    written_file,
)
from vtrack.io.images import SEQUENCE_INFO, encode_image
from vtrack.io.raw import PIX_FMTS as RAW_PIX_FMTS  # (write_raw's layouts: those vtrack reads)
from vtrack.params import X264_PRESETS
from vtrack.scenes.scene import Scene

#: What ``write_clip`` can write.
CLIP_FORMATS = ("mp4", "images", "raw")
#: The encoder of ``write_video`` and of ``write_clip``'s mp4 clips.
CODEC = "libx264"
#: What makes an x264 encode depend on its frames and parameters alone: mb-tree off (with it,
#: x264's AVX-512 code reads memory it has not written, and one scene encoded ten times gave
#: up to seven different files) and a fixed count of frame threads (the bytes depend on the
#: count, which x264 otherwise takes from the machine's cores).
DETERMINISTIC_X264 = {"x264-params": "mbtree=0", "threads": "4"}
#: The image format of ``write_image_sequence`` and of ``write_clip``'s image folders.
IMAGE_EXT = "jpg"


@contextmanager
def _writing(path: Path) -> Iterator[None]:
    """Create ``path``'s parent folder; report OS / FFmpeg failures as OutputError naming
    ``path``."""
    try:
        path.parent.mkdir(parents=True, exist_ok=True)
        yield
    except (OSError, av.FFmpegError) as exc:
        raise OutputError(f"{path}: cannot write ({os_reason(exc)})") from exc
    except ValueError as exc:  # PyAV: no container format for the file's name
        raise _no_container(path, exc) from exc


def _no_container(path: Path, reason: Exception) -> OutputError:
    """The error for a video name FFmpeg has no container format for."""
    return OutputError(f"{path}: no video container format for this file name ({reason}); "
                       "name it .mp4, .mkv, .avi or .mov, or use --format images / raw")


def _check_container(path: Path) -> None:
    """OutputError when FFmpeg has no container format for ``path``'s name (found without
    touching the disk: an output container creates its file only when encoding starts)."""
    try:
        av.open(ffmpeg_file(path), "w").close()
    except ValueError as exc:
        raise _no_container(path, exc) from None


def _check_folder(folder: Path) -> None:
    """OutputError when ``folder``, where an image folder goes, is an existing file."""
    if folder.exists() and not folder.is_dir():
        raise OutputError(f"{folder}: is a file; --format images writes a folder there "
                          "(img/0001.jpg ... and its ground truth): name a folder")


#: Progress of a clip's writing: True for a tqdm bar on stderr, or a function called with
#: (frames done, frames) after each frame (``vtrack scene``'s bar or lines in a log).
Progress = bool | Callable[[int, int], None]


def _progress(scene: Scene, enabled: Progress, what: str) -> Iterable[np.ndarray]:
    """The scene's frames, with a tqdm bar on stderr when ``enabled`` is True, or telling
    ``enabled`` after each frame when it is a function."""
    if callable(enabled):
        return _telling(scene, enabled)
    return tqdm(
        scene.frames(),
        total=len(scene),
        desc=what,
        unit="frame",
        file=sys.stderr,
        disable=not enabled,
        leave=False,
    )


def _telling(scene: Scene, progress: Callable[[int, int], None]) -> Iterator[np.ndarray]:
    total = len(scene)
    for done, bgr in enumerate(scene.frames(), 1):
        yield bgr
        progress(done, total)


def _need_even(scene: Scene, what: str) -> None:
    if scene.width % 2 or scene.height % 2:
        raise ConfigError(
            f"{what} needs an even width and height, the scene is {scene.width}x{scene.height}"
        )


def _need_even_for(scene: Scene, layout: av.VideoFormat, what: str) -> None:
    """ConfigError when ``layout`` (a pixel format of a 2x2 frame) halves the chroma planes'
    width or height and the scene's is odd: yuv420p and nv12 need both even, yuv422p an even
    width, yuv444p and gray neither."""
    chroma = [c for c in layout.components if c.is_chroma]
    half_width = any(c.width < 2 for c in chroma)
    half_height = any(c.height < 2 for c in chroma)
    if half_width and half_height:
        _need_even(scene, what)
    elif half_width and scene.width % 2:
        raise ConfigError(f"{what} needs an even width, the scene is "
                          f"{scene.width}x{scene.height}")
    elif half_height and scene.height % 2:
        raise ConfigError(f"{what} needs an even height, the scene is "
                          f"{scene.width}x{scene.height}")


def write_video(
    scene: Scene,
    path: str | Path,
    crf: int = 23,
    preset: str = "medium",
    codec: str = CODEC,
    pix_fmt: str = "yuv420p",
    progress: Progress = False,
    keyint: int | None = None,
) -> Path:
    """Encode every frame of ``scene`` to ``path`` (container from the suffix, e.g. ``.mp4``).

    Constant frame rate ``scene.fps``, exactly ``len(scene)`` frames, pts = frame index.
    ``crf`` / ``preset`` are passed to the encoder (x264 / x265 understand both). For yuv420p
    the BGR -> I420 conversion is done by OpenCV (width and height must be even). ``keyint``:
    a key frame at least every that many frames (a stream a receiver may join part way; None:
    the encoder's choice). With libx264 (the default; ``h264`` opens it too) the bytes are
    deterministic too: the same scene and parameters give the same file
    (:data:`DETERMINISTIC_X264`; another encoder's need not be). ``path`` appears only once
    the video is complete.
    """
    path = Path(path)
    encoder = _check_video(scene, path, preset, codec, pix_fmt)
    with replacing(path) as (temp,):
        _encode_video(scene, path, temp, crf, preset, encoder, pix_fmt, progress, keyint)
    return path


def _check_video(scene: Scene, path: Path, preset: str, codec: str, pix_fmt: str) -> str:
    """The name of the encoder ``codec`` opens (``libx264`` for ``h264``); OutputError naming
    ``path`` when FFmpeg has no container for its name; then ConfigError when the encoder,
    preset or pixel format cannot be used."""
    _check_container(path)
    try:
        encoder = av.codec.Codec(codec, "w")
    except ValueError as exc:
        raise ConfigError(f"{path}: no video encoder named {quoted_or_cut(codec)}") from exc
    if encoder.name in ("libx264", "libx265") and preset not in X264_PRESETS:
        raise ConfigError(f"{path}: preset {quoted_or_cut(preset)}: choose one of "
                          f"{', '.join(X264_PRESETS)}")
    try:
        layout = av.VideoFormat(pix_fmt, 2, 2)
    except ValueError as exc:
        raise ConfigError(f"{path}: {quoted_or_cut(pix_fmt)} is not a pixel format") from exc
    taken = [f.name for f in encoder.video_formats or ()]
    grey = ""
    if encoder.name == "libx264":  # it takes grey frames, but writes them as 4:2:0 colour
        if pix_fmt in taken and len(layout.components) == 1:  # gray10le as yuv420p10le
            grey = f" (it writes grey as {pix_fmt.replace('gray', 'yuv420p')})"
        taken = [name for name in taken if len(av.VideoFormat(name).components) > 1]
    if taken and pix_fmt not in taken:
        raise ConfigError(f"{path}: {codec} does not take pixel format {pix_fmt}{grey}; it "
                          f"takes {', '.join(taken)}")
    _need_even_for(scene, layout, f"{path}: pixel format {pix_fmt}")
    return encoder.name


def _encode_video(scene: Scene, path: Path, temp: Path, crf: int, preset: str, codec: str,
                  pix_fmt: str, progress: Progress, keyint: int | None) -> None:
    """What :func:`write_video` promises, written to ``temp`` (errors name ``path``)."""
    rate = Fraction(scene.fps).limit_denominator(1001)
    with _writing(path), av.open(ffmpeg_file(temp), "w") as container:
        options = {"crf": str(crf), "preset": preset,
                   **(DETERMINISTIC_X264 if codec == "libx264" else {})}
        if keyint is not None:
            options["g"] = str(keyint)
        stream = container.add_stream(codec, rate=rate, options=options)
        stream.width, stream.height = scene.width, scene.height
        stream.pix_fmt = pix_fmt
        stream.thread_type = "FRAME"
        for index, bgr in enumerate(_progress(scene, progress, path.name)):
            if pix_fmt == "yuv420p":
                i420 = cv2.cvtColor(bgr, cv2.COLOR_BGR2YUV_I420)
                frame = av.VideoFrame.from_ndarray(i420, format="yuv420p")
            else:
                frame = av.VideoFrame.from_ndarray(bgr, format="bgr24")
            frame.pts = index
            container.mux(stream.encode(frame))
        container.mux(stream.encode(None))


def _box_line(values: Iterable[float]) -> str:
    return ",".join(f"{v:.2f}" for v in values)


def _fraction(value: float) -> str:
    """A fraction 0..1 with 4 decimals at most: ``1``, ``0``, ``0.4375``."""
    return f"{value:.4f}".rstrip("0").rstrip(".")


def write_groundtruth(scene: Scene, path: str | Path, origin: int = 0) -> Path:
    """OTB ground truth: one ``x,y,w,h`` line per frame; ``0,0,0,0`` where the target is absent.

    ``origin=1`` writes MATLAB-style 1-based boxes, as OTB's ``groundtruth_rect.txt`` files are.
    """
    path = Path(path)
    with replacing(path) as (temp,):
        _groundtruth_to(scene, path, temp, origin)
    return path


def _groundtruth_to(scene: Scene, path: Path, temp: Path, origin: int) -> None:
    """What :func:`write_groundtruth` promises, written to ``temp`` (errors name ``path``)."""
    lines = [
        _box_line(box._replace(x=box.x + origin, y=box.y + origin)) if box is not None
        else "0,0,0,0"
        for box in scene.boxes
    ]
    with _writing(path):
        temp.write_text("\n".join(lines) + "\n")


def write_mot_groundtruth(scene: Scene, path: str | Path) -> Path:
    """MOTChallenge ground truth: ``frame,id,x,y,w,h,1,1,visibility`` per object at least
    partly inside the frame, 1-based frames; visibility is the fraction of the object that can
    be seen (inside the frame and not hidden behind another), 0 to 1."""
    path = Path(path)
    with replacing(path) as (temp,):
        _mot_groundtruth_to(scene, path, temp)
    return path


def _mot_groundtruth_to(scene: Scene, path: Path, temp: Path) -> None:
    """What :func:`write_mot_groundtruth` promises, written to ``temp`` (errors name ``path``)."""
    lines = [
        f"{index + 1},{track_id},{_box_line(box)},1,1,{_fraction(seen[track_id])}"
        for index, (tracks, seen) in enumerate(
            zip(scene.tracks, scene.track_visibility, strict=True))
        for track_id, box in tracks
    ]
    with _writing(path):
        temp.write_text("".join(line + "\n" for line in lines))


def write_image_sequence(
    scene: Scene, folder: str | Path, ext: str = IMAGE_EXT, progress: Progress = False
) -> Path:
    """OTB layout: ``folder/img/0001.<ext>`` ... (1-based, >= 4 digits) and
    ``folder/groundtruth_rect.txt`` with 1-based boxes, as OTB writes them (read it with
    ``--gt-origin 1``). JPEG quality 95; ``ext`` is ``jpg`` or ``png``. Both appear once
    every image is written: ``folder/img`` replaces the folder there as a whole."""
    folder = Path(folder)
    _check_image_ext(ext)
    _check_folder(folder)
    images, groundtruth = folder / "img", folder / "groundtruth_rect.txt"
    with replacing(images, groundtruth) as (images_temp, groundtruth_temp):
        _images_to(scene, images, images_temp, ext, progress)
        _groundtruth_to(scene, groundtruth, groundtruth_temp, origin=1)
    return folder


def _check_image_ext(ext: str) -> None:
    if ext not in ("jpg", "png"):
        raise ConfigError(f"image format {quoted_or_cut(ext)}: choose jpg or png")


def _images_to(scene: Scene, images: Path, temp: Path, ext: str, progress: Progress) -> None:
    """The numbered images of :func:`write_image_sequence`, in the new folder ``temp``
    (errors name ``images``)."""
    digits = max(4, len(str(len(scene))))
    with _writing(images):
        temp.mkdir()
        for index, bgr in enumerate(_progress(scene, progress, images.parent.name)):
            name = temp / f"{index + 1:0{digits}d}.{ext}"
            name.write_bytes(encode_image(bgr, f".{ext}", quality=95))


def _sequence_info_to(scene: Scene, path: Path, temp: Path) -> None:
    """A MOTChallenge ``seqinfo.ini`` giving the image folder's frame rate (``frameRate``, which
    ``vtrack run`` / ``frame`` read it at), written to ``temp`` (errors name ``path``)."""
    rate = repr(float(scene.fps)).removesuffix(".0")  # 25, 29.97: as given
    with _writing(path):
        temp.write_text(f"[Sequence]\nimDir=img\nframeRate={rate}\n"
                        f"seqLength={len(scene)}\nimWidth={scene.width}\n"
                        f"imHeight={scene.height}\nimExt=.{IMAGE_EXT}\n")


#: The conversion from BGR of each layout ``write_raw`` writes (None: as it is).
_RAW_CONVERSIONS = {
    "bgr24": None,
    "rgb24": cv2.COLOR_BGR2RGB,
    "yuv420p": cv2.COLOR_BGR2YUV_I420,
    "gray": cv2.COLOR_BGR2GRAY,
}


def write_raw(
    scene: Scene, path: str | Path, pix_fmt: str = "bgr24", progress: Progress = False
) -> Path:
    """Frames back to back, no header, in ``pix_fmt`` (one of :data:`RAW_PIX_FMTS`);
    ``path`` appears only once every frame is written."""
    path = Path(path)
    _check_raw(scene, path, pix_fmt)
    with replacing(path) as (temp,):
        _raw_to(scene, path, temp, pix_fmt, progress)
    return path


def _check_raw(scene: Scene, path: Path, pix_fmt: str) -> None:
    if pix_fmt not in _RAW_CONVERSIONS:
        raise ConfigError(f"raw pixel format {quoted_or_cut(pix_fmt)}: choose one of "
                          f"{', '.join(RAW_PIX_FMTS)}")
    if pix_fmt == "yuv420p":
        _need_even(scene, f"{path}: pixel format yuv420p")


def _raw_to(scene: Scene, path: Path, temp: Path, pix_fmt: str, progress: Progress) -> None:
    """What :func:`write_raw` promises, written to ``temp`` (errors name ``path``)."""
    code = _RAW_CONVERSIONS[pix_fmt]
    with _writing(path), temp.open("wb") as out:
        for bgr in _progress(scene, progress, path.name):
            out.write((bgr if code is None else cv2.cvtColor(bgr, code)).tobytes())


def sidecar(path: str | Path, kind: str) -> Path:
    """``clip.mp4`` -> ``clip.<kind>.txt`` (ground-truth files written beside a clip)."""
    return Path(path).with_suffix(f".{kind}.txt")


@dataclass(frozen=True)
class ClipFiles:
    """What ``write_clip`` wrote: the clip (file or folder), OTB and (multi) MOT ground truth."""

    clip: Path
    groundtruth: Path
    mot: Path | None


def clip_paths(out: Path, fmt: str) -> tuple[Path, Path, Path, list[Path]]:
    """The files writing a ``fmt`` clip to ``out`` puts in place: the clip (an image folder's
    ``img/``), its OTB and its MOTChallenge ground truth, and (an image folder only) the file
    of its frame rate, ``seqinfo.ini``."""
    if fmt == "images":
        return (out / "img", out / "groundtruth_rect.txt", out / "groundtruth_mot.txt",
                [out / SEQUENCE_INFO])
    return out, sidecar(out, "gt"), sidecar(out, "mot"), []


def write_clip(
    scene: Scene,
    out: str | Path,
    fmt: str = "mp4",
    pix_fmt: str | None = None,
    crf: int = 23,
    preset: str = "medium",
    progress: Progress = False,
    settled: Callable[[], object] | None = None,
) -> ClipFiles:
    """Write ``scene`` and its ground truth the way ``vtrack scene`` does (``settled()`` is
    called as the files start to be put in place: :class:`~vtrack.io.files.StagedFiles`).

    - ``mp4``: video ``out`` (``pix_fmt`` default yuv420p) and ``out`` -> ``<stem>.gt.txt``;
    - ``raw``: raw frames ``out`` (``pix_fmt`` default bgr24) and ``<stem>.gt.txt``;
    - ``images``: OTB folder ``out`` (``out/img/0001.jpg``, ``out/groundtruth_rect.txt``) and
      its frame rate in ``out/seqinfo.ini`` (MOTChallenge's ``frameRate``), as vtrack reads it.

    Scenes with more than one tracked object (``multi``) also get MOTChallenge ground truth:
    ``<stem>.mot.txt`` beside a file, ``out/groundtruth_mot.txt`` in an image folder.
    Every file (and ``out/img``) is written under a temporary name and they are renamed
    together once all are complete: when a write fails none of them appears, and an earlier
    clip there is left as it was. Written over an earlier clip, nothing of that one is left:
    ``out/img`` is replaced as a whole, and a MOTChallenge file the new scene does not have is
    removed. A file ``out`` that is a symbolic link is written through (the file it leads to
    is replaced, the link kept: :func:`~vtrack.io.files.written_file`); its ground truth is
    written beside the link, named after it. ``progress``: see :data:`Progress`.
    """
    out = Path(out)
    if fmt not in CLIP_FORMATS:
        raise ConfigError(f"clip format {quoted_or_cut(fmt)}: choose one of "
                          f"{', '.join(CLIP_FORMATS)}")
    pix = pix_fmt or ("yuv420p" if fmt == "mp4" else "bgr24")
    if fmt == "mp4":
        _check_video(scene, out, preset, CODEC, pix)
    elif fmt == "raw":
        _check_raw(scene, out, pix)
    else:
        _check_folder(out)
    multi = any(len(tracks) > 1 for tracks in scene.tracks)
    clip, gt, mot, rate = clip_paths(out, fmt)
    if fmt != "images":  # a link OUT is written through; its ground truth goes beside it
        clip = written_file(clip, str(out))
        beside = next((path for path in (gt, mot, *rate) if same_file(clip, path)), None)
        if beside is not None:
            raise OutputError(f"{out}: its link leads to {beside.name}, the scene's own "
                              "ground-truth file: name OUT another file")
    # stopped part way (an error, Ctrl-C, SIGTERM), it leaves no folder it created
    with (removing_new_folders(clip.parent),
          replacing(clip, gt, *rate, *([mot] if multi else []), settled=settled) as temps):
        if fmt == "mp4":
            _encode_video(scene, out, temps[0], crf, preset, CODEC, pix, progress, keyint=None)
        elif fmt == "raw":
            _raw_to(scene, out, temps[0], pix, progress)
        else:
            _images_to(scene, clip, temps[0], IMAGE_EXT, progress)
            _sequence_info_to(scene, rate[0], temps[2])
        _groundtruth_to(scene, gt, temps[1], origin=1 if fmt == "images" else 0)
        if multi:
            _mot_groundtruth_to(scene, mot, temps[-1])
    if not multi:
        with _writing(mot):
            mot.unlink(missing_ok=True)
    return ClipFiles(out, gt, mot if multi else None)
