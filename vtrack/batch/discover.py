"""Finding the inputs of a batch folder and their ground truth (see :mod:`vtrack.batch`)."""

from __future__ import annotations

import errno
import os
from collections import Counter
from collections.abc import Iterable
from dataclasses import dataclass
from pathlib import Path
from typing import NamedTuple

from vtrack.errors import InputError, plural, quoted
from vtrack.evaluate.groundtruth import (
    groundtruth_beside,
    gt_origin_of,
    is_sequence_folder,
    numbered_groundtruth,
    target_input,
    target_number,
)
from vtrack.io.files import SharedFolders, folder_key, folder_name
from vtrack.io.outdir import BATCH_SUMMARY, is_batch_folder
from vtrack.io.sidecar import SEQUENCE_SIDECAR as SEQUENCE_INIT
from vtrack.io.sidecar import VIDEO_SIDECAR as VIDEO_INIT
from vtrack.io.specs import BATCH_SUFFIXES

#: The batch's own file in its results folder, beside the inputs' folders: no input's folder.
SUMMARY_FILE = BATCH_SUMMARY
#: MOTChallenge ground truth inside a sequence folder, first found wins.
SEQUENCE_MOT_GT = ("groundtruth_mot.txt", "gt.txt", "gt/gt.txt")
#: MOTChallenge ground truth beside ``name.mp4``.
VIDEO_MOT_GT = ("{}.mot.txt",)


class NoInputsError(InputError):
    """A batch folder that holds no input (:func:`find_inputs`)."""


@dataclass(frozen=True)
class BatchInput:
    """One input of a batch folder: its unique name (the results folder), path and ground truth.

    ``groundtruth`` is for single-target configs, ``mot_groundtruth`` for multi-target ones;
    ``init`` holds the first box when there is no ``groundtruth`` (0-based pixels, as every
    sidecar file); ``gt_origin`` is the origin of the boxes of ``groundtruth`` (see the
    module docstring), 0 when there is none, as ``vtrack run`` records it.
    """

    name: str
    path: Path
    groundtruth: Path | None = None
    mot_groundtruth: Path | None = None
    init: Path | None = None
    gt_origin: int = 0
    #: Why this input cannot be run (a broken link, a FIFO): it is reported ``failed``.
    problem: str | None = None
    #: Which target of an OTB sequence of several it is (``groundtruth``:
    #: ``groundtruth_rect.N.txt``, N; the name ``SEQ-N``); None: the input's only one.
    target: int | None = None
    #: Whether single-target configs run on it: not on the folder of an OTB sequence of
    #: several targets that says nothing else of them (its targets are inputs ``SEQ-N``).
    single_target: bool = True

    def taken_by(self, multi_target: bool) -> bool:
        """Whether a config runs on this input: a multi-target one (``multi_target``) on every
        input but a target of an OTB sequence of several (it tracks all the sequence's targets
        in one run, of the folder ``SEQ``), a single-target one on every input but such a
        sequence's folder when its targets' files are all it says of them."""
        return self.target is None if multi_target else self.single_target

    @property
    def shown(self) -> str:
        """The input as a user finds it in the batch's folder: its file or folder name, and a
        target's ground truth (``Jogging/groundtruth_rect.1.txt``)."""
        if self.target is None or self.groundtruth is None:
            return self.path.name
        return f"{self.path.name}/{self.groundtruth.name}"


def _first(folder: Path, names: Iterable[str]) -> Path | None:
    return next((folder / n for n in names if (folder / n).is_file()), None)


def _sequence(folder: Path, gt_origin: int | None, multi_target: bool) -> list[BatchInput]:
    """The inputs of sequence folder ``folder``: the folder itself (``SEQ``), and one per
    target of an OTB sequence of several (``groundtruth_rect.N.txt``: ``SEQ-N``, tracked from
    its own boxes), which only single-target configs run on (:meth:`BatchInput.taken_by`);
    those run on the folder too only when it says more of its targets (other ground truth or
    a box). The folder is left out when no config runs on it (none is ``multi_target``, and
    single-target ones do not)."""
    groundtruth = groundtruth_beside(folder)
    mot_groundtruth = _first(folder, SEQUENCE_MOT_GT)
    init = _first(folder, [SEQUENCE_INIT])
    numbered = numbered_groundtruth(folder)
    # every target's file lies in the one folder: one origin for them all
    origin = _origin(numbered[0], gt_origin) if numbered else 0
    targets = [BatchInput(name=target_input(folder.name, number), path=folder,
                          groundtruth=path, mot_groundtruth=mot_groundtruth,
                          gt_origin=origin, target=number)
               for path in numbered for number in [target_number(path)]]
    single = not targets or any(p is not None for p in (groundtruth, mot_groundtruth, init))
    whole = BatchInput(name=folder.name, path=folder, groundtruth=groundtruth,
                       mot_groundtruth=mot_groundtruth, init=init,
                       gt_origin=_origin(groundtruth, gt_origin), single_target=single)
    return [whole, *targets] if single or multi_target else targets


def _video(path: Path, name: str, gt_origin: int | None) -> BatchInput:
    stem = path.stem
    groundtruth = groundtruth_beside(path)
    return BatchInput(
        name=name,
        path=path,
        groundtruth=groundtruth,
        mot_groundtruth=_first(path.parent, (p.format(stem) for p in VIDEO_MOT_GT)),
        init=_first(path.parent, [VIDEO_INIT.format(stem)]),
        gt_origin=_origin(groundtruth, gt_origin),
    )


def _origin(groundtruth: Path | None, gt_origin: int | None) -> int:
    """The origin of ``groundtruth``'s boxes, as ``vtrack run --gt`` reads them
    (:func:`~vtrack.evaluate.groundtruth.gt_origin_of`; ``gt_origin`` None: auto); 0 when
    there is no ground truth (a sidecar's box is 0-based whatever the origin)."""
    return 0 if groundtruth is None else gt_origin_of(groundtruth, gt_origin)


def _video_names(videos: list[Path], taken: set[str]) -> dict[Path, str]:
    """A distinct name per video: its stem, or its full file name where stems (or another
    input's name) clash, as results folders (:func:`~vtrack.io.files.folder_key`: ``a b``
    and ``a_b`` are one folder, ``a`` and ``A`` one on a case-insensitive disk). Switching a
    clashing name to the full one may make it clash with another's stem (``a.mp4`` and
    ``a.mp4.mkv``): repeated until nothing clashes or every clashing name is a full file name
    (:func:`find_inputs` then refuses the folder)."""
    names = {path: path.stem for path in videos}
    while True:
        counts = Counter(folder_key(name, "input") for name in [*taken, *names.values()])
        clashing = [p for p, name in names.items()
                    if counts[folder_key(name, "input")] > 1 and name != p.name]
        if not clashing:
            return names
        for path in clashing:
            names[path] = path.name


def _folder(name: str) -> str:
    """The results folder of an input named ``name``."""
    return folder_name(name, "input")


def _unusable(path: Path) -> BatchInput:
    """An entry with a video's suffix that is no file to read: failed, with the reason."""
    if path.is_symlink() and not path.exists():
        try:
            os.stat(path)
            reason = "a link that cannot be followed"
        except OSError as exc:
            reason = (f"a link in a loop (to {os.readlink(path)}, a link back to itself)"
                      if exc.errno == errno.ELOOP
                      else f"a broken link (to {os.readlink(path)}, which does not exist)")
    else:
        reason = "not a regular file (a FIFO, socket or device is no batch input)"
    return BatchInput(name=path.name, path=path, problem=f"{path}: {reason}")


def _results_folder(folder: Path) -> bool:
    """Whether ``folder`` holds vtrack's results: a run's (``run.json``) or a batch's
    (:func:`~vtrack.io.outdir.is_batch_folder`), whose files and folders are no inputs."""
    return (folder / "run.json").is_file() or is_batch_folder(folder)


def find_inputs(folder: Path, gt_origin: int | None = None,
                multi_target: bool = True) -> list[BatchInput]:
    """Every input directly inside ``folder`` (or ``folder`` itself if it is a sequence folder),
    sorted by name, with the ground truth found beside or inside each (module docstring).
    ``multi_target``: whether the batch has a multi-target config; without one, the folder
    ``SEQ`` of an OTB sequence of several targets that says nothing else of them is no input
    (no config runs on it, :meth:`BatchInput.taken_by`: its targets ``SEQ-N`` are), and its
    name is free for a video (``SEQ.mp4`` is ``SEQ``).

    Inputs are named after their file stem (folder name for sequences; ``SEQ-N`` for target N
    of an OTB sequence of several, :func:`_sequence`); videos whose stem is
    taken twice (``a.mp4`` and ``a.avi`` or ``A.avi``, a folder ``a/``, ``a.mp4`` and
    ``a.mp4.mkv``, or ``summary.csv.mp4`` and the batch's ``summary.csv``) keep their full file
    names, so every input has a results folder of its own.
    Raises InputError when ``folder`` is not a folder or holds no input (NoInputsError), or
    when two inputs would still share a results folder (``a.mp4`` and ``A.mp4``: one folder on
    a case-insensitive disk; a folder ``Jogging-1`` beside ``Jogging``'s target 1).
    """
    folder = Path(folder)
    if not folder.is_dir():
        missing = ("no such folder (broken link)" if folder.is_symlink() else "no such folder")
        raise InputError(f"{folder}: {missing if not folder.exists() else 'not a folder'}")
    if is_sequence_folder(folder):
        found = _sequence(folder.resolve(), gt_origin, multi_target)
        _refuse_shared_folders(folder, found)
        return sorted(found, key=lambda i: i.name)
    entries = sorted(folder.resolve().iterdir())
    named = [p for p in entries if p.suffix.lower() in BATCH_SUFFIXES]
    videos = [p for p in named if p.is_file()]
    found = [item for p in entries if p.is_dir() and not _results_folder(p)
             and is_sequence_folder(p) for item in _sequence(p, gt_origin, multi_target)]
    found += [_unusable(p) for p in named if not p.is_file() and not p.is_dir()]
    found += [_video(p, name, gt_origin) for p, name in _video_names(
        videos, {item.name for item in found} | {SUMMARY_FILE}).items()]
    if not found:
        raise NoInputsError(
            f"{folder}: no inputs (video files or sequence folders: images in img/ or img1/, "
            "or in color/ or the folder itself beside their groundtruth.txt, "
            "groundtruth_rect.txt or init.txt)"
        )
    _refuse_shared_folders(folder, found)
    return sorted(found, key=lambda i: i.name)


def _refuse_shared_folders(folder: Path, found: list[BatchInput]) -> None:
    """InputError when two of the inputs ``found`` in ``folder`` (or one and the batch's own
    summary) would share a results folder, naming both (:attr:`BatchInput.shown`)."""
    folders: SharedFolders[BatchInput | None] = SharedFolders("input")
    folders.take(SUMMARY_FILE, None)  # the batch's own file, no input's
    for item in found:
        clash = folders.clash(item.name)
        if clash is None:
            folders.take(item.name, item)
            continue
        other, by_case = clash
        if other is None:
            case = f" {SUMMARY_FILE} on a case-insensitive disk (macOS, Windows)" if by_case else ""
            raise InputError(f"{folder}: {quoted(item.shown)} would have the results folder "
                             f"{quoted(_folder(item.name))}, the batch's own summary{case}: "
                             "rename it")
        if by_case:
            raise InputError(
                f"{folder}: the results folders of {quoted(other.shown)} and of "
                f"{quoted(item.shown)} differ only in case, one folder on a case-insensitive "
                "disk (macOS, Windows): rename one")
        why = (f"both are named {quoted(item.name)}" if other.name == item.name else
               "names differ only in characters a folder name cannot hold")
        raise InputError(
            f"{folder}: {quoted(other.shown)} and {quoted(item.shown)} would share the results "
            f"folder {quoted(_folder(item.name))} ({why}): rename one")


def unscored_by_multi_target(inputs: Iterable[BatchInput], configs: list[str]) -> str | None:
    """The warning for inputs with single-target ground truth only (their own, or that of
    each target of an OTB sequence of several, ``groundtruth_rect.N.txt``), when ``configs``
    (the batch's multi-target ones) read MOTChallenge ground truth: their runs are not
    scored. One line, naming the first such file (or sequence folder, with its targets'
    files) and the MOTChallenge names looked for beside it and counting the others; None
    when there are none."""
    inputs = list(inputs)
    targets: dict[Path, list[str]] = {}  # each sequence folder's targets' files
    for item in inputs:
        if item.target is not None and item.groundtruth is not None:
            targets.setdefault(item.path, []).append(item.groundtruth.name)
    unscored = [item for item in inputs if item.problem is None
                and (item.groundtruth or item.path in targets)
                and item.mot_groundtruth is None and item.taken_by(multi_target=True)]
    if not unscored or not configs:
        return None
    first = unscored[0]
    truth = (f"{first.groundtruth}{{}}: one target's ground truth" if first.groundtruth else
             f"{first.path}{{}}: one target's ground truth per file "
             f"({', '.join(targets[first.path])})")
    if first.path.is_dir():
        wanted = f"{' or '.join(SEQUENCE_MOT_GT)} in {first.path.name}/"
    else:
        wanted = " or ".join(p.format(first.path.stem) for p in VIDEO_MOT_GT)
        wanted += f" beside {first.path.name}"
    others = len(unscored) - 1
    more = f" (and {plural(others, 'other input')}'{'s' if others == 1 else ''})" if others else ""
    one = len(configs) == 1
    named = [repr(c) for c in configs]
    named = [", ".join(named[:-1]), named[-1]] if len(named) > 1 else named
    return (f"{truth.format(more)}; "
            f"{'config' if one else 'configs'} {' and '.join(named)} "
            f"{'tracks' if one else 'track'} several targets and {'reads' if one else 'read'} "
            f"MOTChallenge ground truth ({wanted}): "
            f"{'its run is' if len(unscored) == 1 and one else 'their runs are'} not scored")


#: The folders :func:`nested_inputs` lists at most (each sub-folder once, those at the top
#: included): a batch given a big tree (``/usr``) says what it found near the top at once.
NESTED_LOOKS = 500


class NestedInputs(NamedTuple):
    """What :func:`nested_inputs` found, and whether it looked at every folder (``whole``:
    else ``found`` is some of them, those nearest ``folder`` first)."""

    found: list[Path]
    whole: bool


def nested_inputs(folder: Path, looks: int = NESTED_LOOKS) -> NestedInputs:
    """What :func:`find_inputs` does not take in sub-folders of ``folder``, nearest first (by
    depth, then name): the video files (by suffix) and sequence folders below a sub-folder
    that is not a sequence folder (``IN/group/clip.mp4``, ``IN/group/seq/img/``), listing
    ``looks`` sub-folders at most, breadth first (each counted as it is listed, those at the
    top included). Sequence folders and results folders (a run's ``run.json``, a batch's
    ``summary.csv``: their ``annotated.mp4`` are no inputs) are not looked into;
    links to folders are not followed. Nothing when ``folder`` is itself a sequence folder."""
    folder = Path(folder)
    if not folder.is_dir() or is_sequence_folder(folder):
        return NestedInputs([], True)
    found: list[Path] = []
    level = [top for top in sorted(folder.iterdir()) if top.is_dir() and not top.is_symlink()
             and not _results_folder(top) and not is_sequence_folder(top)]
    listed = 0
    while level:
        deeper: list[Path] = []
        for here in level:
            if listed == looks:
                return NestedInputs(sorted(found, key=_nearest), False)
            listed += 1
            for entry in _listed(here):
                if entry.is_dir():
                    if _results_folder(entry):
                        continue
                    if is_sequence_folder(entry):
                        found.append(entry)
                    elif not entry.is_symlink():
                        deeper.append(entry)
                elif entry.suffix.lower() in BATCH_SUFFIXES and entry.is_file():
                    found.append(entry)
        level = deeper
    return NestedInputs(sorted(found, key=_nearest), True)


def _nearest(path: Path) -> tuple[int, Path]:
    """The order of :func:`nested_inputs`' finds: by depth, then name."""
    return len(path.parts), path


def _listed(folder: Path) -> list[Path]:
    """What ``folder`` holds, sorted; nothing when it cannot be listed."""
    try:
        return sorted(folder.iterdir())
    except OSError:
        return []
