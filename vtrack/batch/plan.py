"""Planning a batch: every input x config, minus the results already complete (resume)."""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field, fields, replace
from pathlib import Path
from typing import Any

from vtrack.batch.discover import BatchInput, unscored_by_multi_target
from vtrack.batch.jobs import Job, Outcome
from vtrack.config import Config
from vtrack.errors import COMMAND_NAMES, ConfigError, InputError, OutputError, cut
from vtrack.evaluate.groundtruth import (
    MULTI_TARGET_CONFIGS,
    groundtruth_names,
)
from vtrack.geometry import Box
from vtrack.io.files import SharedFolders, folder_name
from vtrack.io.identity import outputs_intact
from vtrack.io.jsonfile import read_run_record
from vtrack.io.outdir import refuse_replacing
from vtrack.io.sidecar import read_sidecar, sidecar_path
from vtrack.pipeline import Pipeline
from vtrack.request import RunRequest
from vtrack.run import STATUS_COMPLETE, STATUS_FAILED, RunSummary


def _read(out_dir: Path) -> dict[str, Any] | None:
    """The ``run.json`` in ``out_dir``, whatever run it records; None when there is none that
    can be read."""
    try:
        return read_run_record(out_dir / "run.json")
    except (OSError, InputError):
        return None


def _of(request: RunRequest, record: dict[str, Any] | None) -> dict[str, Any] | None:
    """``record`` if it records a run of exactly ``request`` (:meth:`RunRequest.same_run`),
    else None."""
    if record is None or "request" not in record:
        return None
    return record if request.same_run(record["request"]) else None


def _summary(record: dict[str, Any], out_dir: Path) -> RunSummary | None:
    """The record's summary, its results where they are now: ``out_dir`` (a batch folder may
    have been moved since), a multi-target run's MOT scores (``mot``) from the record's
    ``metrics`` (its ``summary`` leaves them there), so its line is the one the run printed."""
    try:
        names = {f.name for f in fields(RunSummary)}
        summary = RunSummary(**{k: v for k, v in record["summary"].items() if k in names})
        summary.status = record["status"]
        summary.out_dir = str(out_dir)
        metrics = record.get("metrics")
        if summary.multi_target and isinstance(metrics, dict) and metrics:
            summary.mot = dict(metrics)
    except (KeyError, TypeError, AttributeError):
        return None
    return summary


def recorded_summary(request: RunRequest, since: float | None = None) -> RunSummary | None:
    """The summary ``run.json`` in ``request.out_dir`` records for a run of exactly
    ``request`` (every field, :meth:`RunRequest.same_run`), whatever its status; None if there
    is none, it is another request's, or it was written before the time ``since``."""
    try:
        if since is not None and (request.out_dir / "run.json").stat().st_mtime < since:
            return None
    except OSError:
        return None
    record = _of(request, _read(request.out_dir))
    return None if record is None else _summary(record, request.out_dir)


def completed_summary(request: RunRequest) -> RunSummary | None:
    """The summary of a finished run of exactly ``request`` in ``request.out_dir`` that still
    stands, else None.

    Finished means ``run.json`` (written last, atomically, after its outputs were verified)
    says ``complete``; exactly means its ``request`` is this one (:meth:`RunRequest.same_run`);
    still stands means its input and ground truth have the identity it recorded (size and
    modification time, :mod:`vtrack.io.identity`) and every output it lists is there with the
    size it recorded.
    """
    return _completed(request, _of(request, _read(request.out_dir)))


def _completed(request: RunRequest, record: dict[str, Any] | None) -> RunSummary | None:
    """:func:`completed_summary` of ``record``, the ``run.json`` of exactly ``request`` (None:
    there is none)."""
    if record is None or record.get("status") != STATUS_COMPLETE:
        return None
    csv_name = "tracks.csv" if (record.get("summary") or {}).get("multi_target") else "track.csv"
    required = [csv_name] + (["annotated.mp4"] if request.video else [])
    if (record.get("identity") != request.file_identities()
            or not outputs_intact(request.out_dir, record, required)):
        return None
    return _summary(record, request.out_dir)


@dataclass
class Plan:
    """Every input x config of a batch (``order``: input-major): ``jobs`` to run, and
    ``known`` outcomes that need no run; ``warnings``: what the batch should say before it
    runs them (one line each); ``ground_truth``: the ground-truth file of each pair that has
    one (by input and config), for the rows of pairs whose folder holds no run to read."""

    jobs: list[Job]
    known: list[Outcome]
    order: list[tuple[str, str]]
    warnings: list[str] = field(default_factory=list)
    #: The OTB sequences of several targets whose targets (``SEQ-N``) are planned: an earlier
    #: batch's row of ``SEQ`` itself that is the refusal of a vtrack before targets were
    #: inputs is no result, :class:`~vtrack.batch.summary.SummaryWriter` drops it.
    split: set[str] = field(default_factory=set)
    ground_truth: dict[tuple[str, str], Path] = field(default_factory=dict)


#: The results folders of configs taken so far, each with its label and config.
ConfigFolders = SharedFolders[tuple[str, Config]]


def folder_clash(label: str, configs: ConfigFolders) -> tuple[str, str] | None:
    """The label of the first config in ``configs`` (the folders taken so far:
    :meth:`~vtrack.io.files.SharedFolders.take` each label with ``(label, config)``) whose
    results folder would be the one of a config labelled ``label``, and why (one phrase,
    naming both and that config's source, ending in what to do); None when ``label``'s folder
    is its own. One folder: the same :func:`~vtrack.io.files.folder_name`, or names that
    differ only in case (``s0`` and ``S0`` are one folder on a case-insensitive disk: macOS's,
    Windows')."""
    clash = configs.clash(label)
    if clash is None:
        return None
    (other, config), by_case = clash
    if by_case:
        return other, (f"the results folders of '{label}' and of '{other}' "
                       f"({cut(config.source)}) differ only in case, one folder on a "
                       "case-insensitive disk (macOS, Windows): rename one")
    return other, (f"another config has the results folder of '{label}' "
                   f"({cut(config.source)}); results are kept per name, rename one")


def _refuse_shared_folders(configs: Mapping[str, Config]) -> None:
    """ConfigError (:func:`folder_clash`'s phrase) when two of ``configs`` would write into
    one results folder."""
    earlier: ConfigFolders = SharedFolders()
    for label, config in configs.items():
        clash = folder_clash(label, earlier)
        if clash is not None:
            raise ConfigError(clash[1])
        earlier.take(label, (label, config))


def plan(inputs: Sequence[BatchInput], configs: dict[str, Config], out_dir: Path,
         settings: RunRequest, threads: int = 1, force: bool = False,
         overwrite: bool = True) -> Plan:
    """What to do for every input x config, results in ``out_dir/<input>/<config>/`` (each
    name made one safe folder name, :func:`~vtrack.io.files.folder_name`: a config named
    ``../x`` or ``/tmp/x`` still writes inside ``out_dir``), but the pairs the input is not for
    (:meth:`~vtrack.batch.discover.BatchInput.taken_by`: a multi-target config runs once on
    an OTB sequence of several targets, ``SEQ``, a single-target one on each ``SEQ-N``).

    Each job's request is ``settings`` (what ``vtrack batch`` was given: video, preset, crf,
    seed, max_frames) with the input, output folder, config and ground truth of the job.

    Known outcomes: ``complete`` (``resumed``) for results complete from an earlier batch
    (unless ``force``),
    ``failed`` for a single-target config on an input with neither ground truth nor a readable
    initial box, and, unless ``overwrite``, for a folder holding the results of a run made
    with other settings (as ``vtrack run`` without ``--overwrite``; the same run unfinished is
    run again). ``threads`` is the number of OpenCV threads of each job.
    Raises ConfigError when two ``configs`` would write into one results folder
    (:func:`folder_clash`), before anything is planned.
    """
    _refuse_shared_folders(configs)
    result = Plan([], [], [])
    out_dir = out_dir.resolve()
    pipelines = {label: Pipeline(config.build()) for label, config in configs.items()}
    for item in inputs:
        for label, config in configs.items():
            if not item.taken_by(pipelines[label].multi_target):
                continue
            if pipelines[label].multi_target:
                gt_path, gt_origin = item.mot_groundtruth, 0
            else:
                gt_path, gt_origin = item.groundtruth, item.gt_origin
            result.order.append((item.name, label))
            if item.target is not None:
                result.split.add(item.path.name)
            if gt_path is not None:
                result.ground_truth[item.name, label] = gt_path
            if item.problem is not None:
                result.known.append(Outcome(item.name, label, STATUS_FAILED, error=item.problem))
                continue
            try:
                init = (_init_box(item, label, gt_path, settings)
                        if pipelines[label].needs_init_box else None)
            except InputError as exc:
                result.known.append(Outcome(item.name, label, STATUS_FAILED, error=str(exc)))
                continue
            folder = out_dir / folder_name(item.name, "input") / folder_name(label)
            request = replace(settings, input=str(item.path), out_dir=folder,
                              config=config, init_box=init, gt_path=gt_path, gt_origin=gt_origin,
                              init_from=None if init is None else str(sidecar_path(item.path)),
                              target=item.target)
            # the folder's run.json, read once: whether it stands, is this run's, or another's
            on_disk = _read(folder) if not (force and overwrite) else None
            same = _of(request, on_disk)
            done = None if force else _completed(request, same)
            if not overwrite and (same is None or _summary(same, folder) is None):
                try:
                    refuse_replacing(request.out_dir)
                except OutputError as exc:
                    result.known.append(Outcome(
                        item.name, label, STATUS_FAILED,
                        error=f"{exc} ({_other_settings(request, on_disk, folder)})",
                        kept=None if on_disk is None else _summary(on_disk, folder)))
                    continue
            if done is not None:
                result.known.append(Outcome(item.name, label, STATUS_COMPLETE, done,
                                            resumed=True))
            else:
                result.jobs.append(Job(item.name, label, request, threads=threads))
    unscored = unscored_by_multi_target(
        inputs, [label for label, pipeline in pipelines.items() if pipeline.multi_target])
    result.warnings += [unscored] if unscored else []
    return result


def _other_settings(request: RunRequest, record: dict[str, Any] | None, folder: Path) -> str:
    """``made with other settings``, naming those that differ from ``request``'s in
    ``record``, the ``run.json`` of ``folder``; None (no ``run.json`` could be read): that
    what made them is unknown, as its ``run.json`` cannot be read, or as there is none (a run
    killed before it recorded itself leaves its ``track.csv`` so)."""
    if record is None and (folder / "run.json").is_file():
        return "its run.json cannot be read: what made them is unknown"
    if record is None:
        return ("no run.json says what made them: a run stopped before it recorded itself "
                "leaves its files so")
    changed = [] if "request" not in record else request.differences(record["request"])
    return "made with other settings" + (f": {', '.join(changed)}" if changed else "")


def _init_box(item: BatchInput, config: str, gt_path: Path | None,
              settings: RunRequest) -> Box | None:
    """The first box of an input from its sidecar file (``NAME.init.txt``, ``init.txt`` in a
    sequence folder: 0-based pixels whatever ``--gt-origin`` says, as ``vtrack run`` reads it);
    None when it has none but has ground truth (the run takes its first box). The sidecar
    holds frame 0's box: a batch that starts later (``--start``) takes the ground truth's box
    of that frame instead, as ``vtrack run`` does; one target of an OTB sequence of several
    (``item.target``) starts from its own ground truth, never the sequence's sidecar. Raises
    InputError when there is neither (naming the MOTChallenge ground truth the input has,
    which only multi-target configs read), or the sidecar is malformed."""
    own_box = settings.starts_later or item.target is not None
    box = None if own_box else read_sidecar(item.path)
    if box is None and gt_path is None:
        given = COMMAND_NAMES.start_given(settings.start, settings.start_s)
        names = [p.name for p in (*groundtruth_names(item.path), sidecar_path(item.path))]
        if settings.starts_later:
            raise InputError(f"{item.path}: {given}: config '{config}' needs the target's box "
                             "in that frame, and there is no ground "
                             f"truth ({', '.join(names[:-1])}; a sidecar box is frame 0's)")
        found = ""
        if item.mot_groundtruth is not None:  # a MOTChallenge sequence: its targets are many
            mot = item.mot_groundtruth.relative_to(item.path.parent)
            found = (f"; {mot} is MOTChallenge ground truth, of many targets, which a "
                     f"multi-target config reads (--config {MULTI_TARGET_CONFIGS})")
        raise InputError(f"{item.path}: config '{config}' tracks a given target, but there is "
                         f"no ground truth or initial box ({', '.join(names)}){found}")
    return box
