"""Planning a batch: every input x config, minus the results already complete (resume)."""

from __future__ import annotations

import json
from collections.abc import Sequence
from dataclasses import dataclass, fields, replace
from pathlib import Path

from vtrack.batch.discover import SEQUENCE_GT, SEQUENCE_INIT, VIDEO_GT, VIDEO_INIT, BatchInput
from vtrack.batch.jobs import STATUS_SKIPPED, Job, Outcome
from vtrack.config import Config
from vtrack.errors import InputError
from vtrack.evaluate.groundtruth import read_boxes
from vtrack.geometry import Box
from vtrack.pipeline import Pipeline
from vtrack.request import RunRequest
from vtrack.run import STATUS_COMPLETE, STATUS_FAILED, RunSummary


def completed_summary(request: RunRequest) -> RunSummary | None:
    """The summary of a finished run of exactly ``request`` in ``request.out_dir``, else None.

    Finished means ``run.json`` (written last, atomically) says ``complete``; exactly means its
    ``request`` is this one, every field (:meth:`RunRequest.same_run`).
    """
    try:
        record = json.loads((request.out_dir / "run.json").read_text(encoding="utf-8"))
        if record.get("status") != STATUS_COMPLETE or not request.same_run(record["request"]):
            return None
        names = {f.name for f in fields(RunSummary)}
        return RunSummary(**{k: v for k, v in record["summary"].items() if k in names})
    except (OSError, ValueError, KeyError, TypeError, AttributeError):
        return None


@dataclass
class Plan:
    """Every input x config of a batch (``order``: input-major): ``jobs`` to run, and
    ``known`` outcomes that need no run."""

    jobs: list[Job]
    known: list[Outcome]
    order: list[tuple[str, str]]


def plan(inputs: Sequence[BatchInput], configs: dict[str, Config], out_dir: Path,
         settings: RunRequest, threads: int = 1, force: bool = False) -> Plan:
    """What to do for every input x config, results in ``out_dir/<input>/<config>/``.

    Each job's request is ``settings`` (what ``vtrack batch`` was given: video, preset, crf,
    seed, max_frames) with the input, output folder, config and ground truth of the job.

    Known outcomes: ``skipped`` for results complete from an earlier batch (unless ``force``),
    ``failed`` for a single-target config on an input with neither ground truth nor a readable
    initial box. ``threads`` is the number of OpenCV threads of each job.
    """
    result = Plan([], [], [])
    out_dir = out_dir.resolve()
    pipelines = {label: Pipeline(config.build()) for label, config in configs.items()}
    for item in inputs:
        for label, config in configs.items():
            if pipelines[label].multi_target:
                gt_path, gt_origin = item.mot_groundtruth, 0
            else:
                gt_path, gt_origin = item.groundtruth, item.gt_origin
            result.order.append((item.name, label))
            try:
                init = (_init_box(item, label) if gt_path is None
                        and pipelines[label].needs_init_box else None)
            except InputError as exc:
                result.known.append(Outcome(item.name, label, STATUS_FAILED, error=str(exc)))
                continue
            request = replace(settings, input=str(item.path), out_dir=out_dir / item.name / label,
                              config=config, init_box=init, gt_path=gt_path, gt_origin=gt_origin)
            done = None if force else completed_summary(request)
            if done is not None:
                result.known.append(Outcome(item.name, label, STATUS_SKIPPED, done))
            else:
                result.jobs.append(Job(item.name, label, request, threads=threads))
    return result


def _init_box(item: BatchInput, config: str) -> Box:
    """The first box of an input without single-target ground truth, from its init file."""
    if item.init is None:
        if item.path.is_dir():
            names = (*SEQUENCE_GT, SEQUENCE_INIT)
        else:
            names = tuple(p.format(item.path.stem) for p in (*VIDEO_GT, VIDEO_INIT))
        raise InputError(f"{item.path}: config '{config}' tracks a given target, but there is "
                         f"no ground truth or initial box ({', '.join(names)})")
    box = read_boxes(item.init, origin=item.gt_origin)[0]
    if box is None:
        raise InputError(f"{item.init}: the initial box is empty")
    return box
