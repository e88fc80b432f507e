"""Building a report (:func:`build_report`), as :mod:`vtrack.report` describes."""

from __future__ import annotations

import hashlib
import json
import math
import os
import re
from collections import Counter
from collections.abc import Callable, Sequence
from dataclasses import dataclass, replace
from datetime import datetime
from pathlib import Path
from warnings import catch_warnings, simplefilter

import numpy as np
from matplotlib.figure import Figure

from vtrack import __version__
from vtrack.errors import InputError, OutputError, first_few, plural
from vtrack.io.files import (
    StagedFiles,
    prepare_output_dir,
    remove_quietly,
    removing_new_folders,
    text_bytes,
)
from vtrack.io.outdir import is_batch_folder
from vtrack.report import failures, pages, plots, tables
from vtrack.report.runs import (
    FailedRun,
    GroundTruth,
    RunResult,
    failed_runs,
    load_run,
    names_a_run,
    run_folders,
    source_name,
    still_written,
)
from vtrack.report.walk import walk_results
from vtrack.run import STATUS_COMPLETE, STATUS_FAILED

DEFAULT_TITLE = "vtrack report"
#: When no run can be reported, the error line names the reasons of at most this many.
NAMED_REASONS = 4
#: A section's note of the runs its plots do not draw names at most this many.
NAMED_LEFT_OUT = 5


@dataclass
class Report:
    """What :func:`build_report` wrote and read."""

    out_dir: Path
    index: Path
    markdown: Path
    csv: Path
    plots: list[Path]
    runs: list[RunResult]
    warnings: list[str]


#: The slug of the plots over all inputs (``curves_all.png``): no input's plots take it.
ALL_INPUTS = "all"


def _slugs(names: Sequence[str]) -> dict[str, str]:
    """A distinct file-name-safe slug per name, never :data:`ALL_INPUTS` (an input named
    ``all`` gets ``all-2``: its plots are not replaced by those over all inputs)."""
    slugs: dict[str, str] = {}
    for name in names:
        base = re.sub(r"[^A-Za-z0-9_.-]+", "_", name).strip("._") or "input"
        slug, n = base, 1
        while slug in slugs.values() or slug.lower() == ALL_INPUTS:  # (case-blind file systems)
            n += 1
            slug = f"{base}-{n}"
        slugs[name] = slug
    return slugs


def _same_inputs(runs: list[RunResult]) -> dict[str, list[RunResult]]:
    """``runs`` by the input each read: its ``input_key``, an image sequence's also the
    fingerprint of its images (two datasets' ``Car/img`` of one frame count and size are two
    inputs). Runs whose records have no fingerprint (an older vtrack's) are told apart by the
    images' total size only from others that recorded one
    (:attr:`~vtrack.report.runs.RunResult.image_bytes`): runs of one total join the one input
    of their key that has a fingerprint when they are its only such total, and runs with
    neither join the one other input of their key, when there is one."""
    groups = _group(runs, lambda r: f"{r.input_key} "
                                    f"{r.image_identity or f'(bytes {r.image_bytes})'}")
    for bare in (False, True):  # (totals first: a run with neither may then have one input)
        for key, same in list(groups.items()):
            first = same[0]
            if first.image_identity is not None or (first.image_bytes is None) != bare:
                continue
            others = [k for k, g in groups.items() if k != key
                      and g[0].input_key == first.input_key]
            if not bare:  # (the key's runs with neither cannot tell two totals apart)
                totals = [k for k in others if groups[k][0].image_identity is None
                          and groups[k][0].image_bytes is not None]
                others = [] if totals else [k for k in others
                                            if groups[k][0].image_identity is not None]
            if len(others) == 1:
                groups[others[0]] += groups.pop(key)
    return groups


def _distinct_inputs(runs: list[RunResult]) -> None:
    """Name runs of one input name but different input files apart: by their file names where
    those differ (``a.mp4`` and ``a.mkv``, which a batch keeps apart), else by where their
    results are (two ``clip.mp4`` of two folders: ``clip (batch-x)``). They are different
    inputs, not different configurations."""
    for name, group in _group(runs, lambda r: r.input).items():
        files = _same_inputs(group)
        if len(files) < 2:
            continue
        names = {key: shown for key, g in files.items() if (shown := source_name(g[0]))}
        if len(names) == len(files) and len(set(names.values())) == len(names):
            labels = names
        else:
            places = _places([g[0].folder for g in files.values()])
            labels = {key: f"{name} ({place})" for key, place in zip(files, places, strict=True)}
        for key, same in files.items():
            for run in same:
                run.input = labels[key]


def _origins(runs: Sequence[RunResult], results: Sequence[Path]) -> tuple[dict[int, str],
                                                                          set[str]]:
    """The results each run belongs to (by ``id``), and the batch folders among them: a batch's
    run, its batch's folder; a ``vtrack run``'s, the folder common to the ``vtrack run``
    folders found under the same one of ``results`` (``runs`` for ``runs/Bird2``,
    ``runs/Couple``: one user's runs of one config, one label over every input), else (that
    folder is a batch's) its own."""
    batches = {str(b) for b in {_batch_of(r) for r in runs} if is_batch_folder(b)}
    places = [path.resolve() if path.is_dir() else path.resolve().parent for path in results]
    origins = {id(r): str(_batch_of(r)) for r in runs if str(_batch_of(r)) in batches}
    alone = [r for r in runs if id(r) not in origins]
    under = _group(alone, lambda r: str(next((n for n, place in enumerate(places)
                                              if r.folder.resolve().is_relative_to(place)), -1)))
    for group in under.values():
        common = os.path.commonpath([r.folder.resolve() for r in group])
        origins.update({id(r): common if common not in batches else str(r.folder.resolve())
                        for r in group})
    return origins, batches


def _distinct_labels(runs: list[RunResult], failed: list[FailedRun],
                     results: Sequence[Path] = ()) -> list[FailedRun]:
    """Give runs of one config name distinct config labels: configs of that name whose chains
    differ (two TOML files) by the values that differ (``robust (robust_search.merge=0.6)``,
    :func:`_value_labels`), else (other stages) by where they are (``s0 (batch-a)``), each one
    label over every input; then, where one input has several runs of a config label (two
    batch folders, a batch and a ``vtrack run``), every run of that label by the results it
    belongs to (:func:`_origins`: its batch folder, else the ``vtrack run`` folders found
    under one of ``results``, the arguments the runs were found under), so one batch's runs,
    and one argument's ``vtrack run`` folders, keep one label over every input and are
    averaged together (and a batch row of that label without results takes its batch's
    label: the ``failed`` returned)."""
    for name, group in _group(runs, lambda r: r.config).items():
        chains = _group(group, lambda r: r.config_key)
        if len(chains) > 1:
            places = (_value_labels(list(chains))
                      or _places([g[0].folder for g in chains.values()]))
            for same, place in zip(chains.values(), places, strict=True):
                for run in same:
                    run.config = f"{name} ({place})"
    belongs, batches = _origins(runs, results or [r.folder for r in runs])
    for label, group in _group(runs, lambda r: r.config).items():
        if all(len(same) == 1 for same in _group(group, lambda r: r.input).values()):
            continue
        origins = _joined(_group(group, lambda r: belongs[id(r)]), batches)
        if len(origins) < 2 or (not origins.keys() & batches
                                and all(len(same) == 1 for same in origins.values())):
            continue  # (each a vtrack run of its own: told apart per input, below)
        places = dict(zip(origins, _places([Path(origin) for origin in origins]), strict=True))
        for origin, same in origins.items():
            for run in same:
                run.config = f"{label} ({places[origin]})"
        failed = [replace(row, config=f"{label} ({places[str(row.batch)]})")
                  if row.config == label and str(row.batch) in places else row
                  for row in failed]
    for group in _group(runs, lambda r: f"{r.input}\0{r.config}").values():
        if len(group) > 1:  # (several runs of one input still from one results folder)
            for run, place in zip(group, _places([r.folder for r in group]), strict=True):
                run.config = f"{run.config} ({place})"
    return failed


def _joined(origins: dict[str, list[RunResult]], batches: set[str]
            ) -> dict[str, list[RunResult]]:
    """``origins`` (results folder: its runs of one config label) with the ``vtrack run``
    results (those not in ``batches``) of different inputs put together, whichever RESULTS
    argument each came from (`vtrack report res runs/A runs/B`, a shell's glob: one results,
    their common folder ``runs``); results that share an input stay apart, as do batches."""
    kept = {origin: same for origin, same in origins.items() if origin in batches}
    joined: list[tuple[list[str], list[RunResult]]] = []
    for origin, same in origins.items():
        if origin in batches:
            continue
        inputs = {r.input for r in same}
        into = next((j for j in joined if not inputs & {r.input for r in j[1]}), None)
        if into is None:
            joined.append(([origin], list(same)))
        else:
            into[0].append(origin)
            into[1].extend(same)
    for places, same in joined:
        common = os.path.commonpath(places) if len(places) > 1 else places[0]
        if common in kept or common in origins and common not in places:
            kept.update({place: origins[place] for place in places})  # (its name is taken)
        else:
            kept[common] = same
    return kept


#: A label of configs told apart by their values names at most this many.
NAMED_VALUES = 2


def _value_labels(chains: Sequence[str]) -> list[str] | None:
    """What tells configs of one name apart by their values: for each chain (a run's
    :attr:`~.runs.RunResult.config_key`), the parameters whose values differ among them
    (``robust_search.merge=0.6``; the first :data:`NAMED_VALUES`, then how many more); None
    when that cannot tell them apart (other stages, or the same values)."""
    flat: list[dict[str, str]] = []
    for chain in chains:
        stages = json.loads(chain)
        if not isinstance(stages, list) or not all(isinstance(s, dict) for s in stages):
            return None
        flat.append({f"{s.get('name')}.{key}": json.dumps(value) for s in stages
                     for key, value in s.items() if key != "name"})
        flat[-1][""] = json.dumps([s.get("name") for s in stages])  # (the stages, in order)
    if len({values[""] for values in flat}) > 1:
        return None
    differ = [key for key in flat[0] if len({values.get(key) for values in flat}) > 1]
    more = len(differ) - NAMED_VALUES
    labels = [", ".join(f"{key}={values.get(key, '-')}" for key in differ[:NAMED_VALUES])
              + (f" and {more} more" if more > 0 else "") for values in flat]
    return labels if len(set(labels)) == len(labels) else None


def _batch_of(run: RunResult) -> Path:
    """The folder of the batch ``run`` would belong to (``<batch>/<input>/<config>/``)."""
    return run.folder.resolve().parent.parent


def _counts(runs: Sequence[RunResult], failed: Sequence[FailedRun]) -> str:
    """What a report shows: ``3 runs of 2 inputs with 2 configurations``, its runs and its batch
    rows without results (``2 runs and 1 without results of ...``; ``3 runs without results of
    ...`` when it has only those), the inputs and configurations of both."""
    inputs = {r.input for r in runs} | {f.input for f in failed}
    configs = {r.config for r in runs} | {f.config for f in failed}
    if not failed:
        shown = plural(len(runs), "run")
    elif not runs:
        shown = f"{plural(len(failed), 'run')} without results"
    else:
        shown = f"{plural(len(runs), 'run')} and {len(failed)} without results"
    return (f"{shown} of {plural(len(inputs), 'input')} with "
            f"{plural(len(configs), 'configuration')}")


def _distinct_failed(failed: list[FailedRun], runs: Sequence[RunResult]) -> list[FailedRun]:
    """``failed`` with the input of a row named after the batch folder it comes from
    (``v3 (batch-b)``) where that input's name is also that of a run or failed row of another
    folder: two batches' ``v3`` need not be one input, and ``v3 [robust] never ran`` beside a
    complete ``v3 [robust]`` of another batch read as that run's."""
    elsewhere: dict[str, set[Path]] = {}
    for row in failed:
        elsewhere.setdefault(row.input, set()).add(row.batch or Path())
    for run in runs:
        if run.input in elsewhere:
            elsewhere[run.input].add(_batch_of(run))
    named = {name: dict(zip(sorted(folders), _places(sorted(folders)), strict=True))
             for name, folders in elsewhere.items() if len(folders) > 1}
    return [replace(row, input=f"{row.input} ({named[row.input][row.batch or Path()]})")
            if row.input in named else row for row in failed]


def _places(folders: Sequence[Path]) -> list[str]:
    """Where each of ``folders`` differs from the others: its first folder below their common
    one, or its whole path from there when those are not distinct."""
    common = os.path.commonpath(folders)
    if any(os.path.relpath(folder, common) == os.curdir for folder in folders):
        common = os.path.dirname(common)  # (a batch holding a vtrack run's folder: by names)
    paths = [os.path.relpath(folder, common) for folder in folders]
    heads = [path.split(os.sep)[0] for path in paths]
    return heads if len(set(heads)) == len(heads) else paths


def _group(runs: Sequence[RunResult], key: Callable[[RunResult], str]
           ) -> dict[str, list[RunResult]]:
    groups: dict[str, list[RunResult]] = {}
    for run in runs:
        groups.setdefault(key(run), []).append(run)
    return groups


def _evaluated(run: RunResult) -> bool:
    """Whether ``run`` has scores over at least one frame (its ground truth shows the target
    somewhere): the runs the curves and the All inputs plot average."""
    return run.scores is not None and run.scores.frames_evaluated > 0


def _mean_curves(runs: Sequence[RunResult]) -> tuple[dict[str, np.ndarray], dict[str, np.ndarray]]:
    """Per config, the mean success and precision curves over its scored runs (for the runs of
    one input: each run's own curves)."""
    success: dict[str, list[np.ndarray]] = {}
    precision: dict[str, list[np.ndarray]] = {}
    for run in runs:
        if _evaluated(run):
            success.setdefault(run.config, []).append(run.scores.success)
            precision.setdefault(run.config, []).append(run.scores.precision)
    return ({c: np.mean(v, axis=0) for c, v in success.items()},
            {c: np.mean(v, axis=0) for c, v in precision.items()})


def _mixed_truth_warning(name: str, runs: Sequence[RunResult]) -> str | None:
    """A warning when the scored runs of input ``name`` (its single-target runs, or its
    multi-target runs: one table's) were scored against different ground truth (files whose
    bytes differ, or that cannot be read and have different paths): the table ranks them side
    by side as if against one truth."""
    def content(path: str) -> str:
        try:
            return hashlib.sha256(Path(path).read_bytes()).hexdigest()
        except OSError:
            return path

    # (a multi-target run's metrics are its run.json's, against the file it records)
    scored = [r for r in runs if r.ground_truth and (r.scores is not None or r.multi_target)]
    digests = {path: content(path) for path in {str(r.ground_truth) for r in scored}}
    truths = _group(scored, lambda r: digests[str(r.ground_truth)])
    if len(truths) < 2:
        return None
    named = "; ".join(sorted(
        f"{' = '.join(sorted({str(r.ground_truth) for r in group}))} for "
        f"{', '.join(sorted({r.config for r in group}))}" for group in truths.values()))
    return (f"{name}: its runs were scored against different ground truth ({named}): their "
            "scores are not directly comparable")


def _mixed_span_warning(name: str, runs: Sequence[RunResult]) -> str | None:
    """A warning when the complete, scored runs of input ``name`` cover different frames
    (``--start`` / ``--frames``): the table ranks them side by side as if over one clip."""
    scored = [r for r in runs if r.scores is not None and r.overlaps
              and r.status == STATUS_COMPLETE]
    def span(run: RunResult) -> str:
        return f"{run.first_frame}..{run.first_frame + len(run.overlaps or ()) - 1}"

    spans = _group(scored, span)
    if len(spans) < 2:
        return None
    named = "; ".join(
        f"frames {span} for {', '.join(sorted({r.config for r in group}))}"
        for span, group in sorted(spans.items(), key=lambda item: item[1][0].first_frame))
    return (f"{name}: its runs cover different frames ({named}): their scores are not "
            "directly comparable")


def _refuse_batch_folder(out_dir: Path) -> None:
    """Raise OutputError when ``out_dir`` holds a batch's ``summary.csv`` (the report's own
    ``summary.csv`` would replace it) or a run's ``run.json``."""
    if is_batch_folder(out_dir):
        raise OutputError(f"--out {out_dir}: holds a batch's summary.csv, which the report "
                          "would replace; choose another folder for the report")
    if (out_dir / "run.json").exists():
        raise OutputError(f"--out {out_dir}: is a run's results folder; choose another folder "
                          "for the report")


def _refuse_two_files_for_one_input(truths: Sequence[GroundTruth]) -> None:
    """InputError for two ``--gt`` files meant for the same runs: two plain ``--gt FILE`` (every
    run would take the first: the second is never read) or two ``--gt INPUT=FILE`` naming one
    INPUT alike (the second would be said to have been replaced by the first)."""
    seen: dict[str | None, GroundTruth] = {}
    for truth in truths:
        earlier = seen.setdefault(truth.input, truth)
        if earlier is not truth:
            raise InputError(truth.second_to(earlier))


def _unused_gt_warning(truth: GroundTruth, runs: Sequence[RunResult]) -> str:
    """The warning for ``--gt INPUT=FILE``, or a plain ``--gt FILE``, that scored no run:
    saying, when it is so, that runs of that input (of any input, for a plain one) were
    scored with another ``--gt INPUT=FILE`` (for a plain one: their input's own, which it
    does not replace) or already with the ground truth they recorded (which ``--gt`` does not
    replace), and how many are multi-target runs (which it never scores)."""
    if truth.input is None:
        warning, of = f"--gt {truth.path}: no run was scored with it", ""
    else:
        warning = (f"--gt {truth.input}={truth.path}: no run of input {truth.input} was scored "
                   "with it")
        of = " of it"
    mine = [r for r in runs if truth.input is None or r.gt_given is truth]
    own = [r for r in mine if r.ground_truth and not r.multi_target and not r.gt_scored]
    # (a plain one's runs that took their input's --gt INPUT=FILE: a reason of its own)
    taken = [r.gt_given for r in mine if r.gt_scored and r.gt_given and r.gt_given is not truth]
    counts = Counter(map(id, taken))
    why = [f"{plural(n, 'run')} {'was' if n == 1 else 'were'} scored with --gt "
           f"{other.input}={other.path} instead"
           for other in {id(t): t for t in taken}.values() for n in [counts[id(other)]]]
    if own:
        files = first_few(sorted({str(r.ground_truth) for r in own}), NAMED_REASONS)
        why.append(f"{plural(len(own), 'run')}{of} {'was' if len(own) == 1 else 'were'} "
                   f"already scored with {'its' if len(own) == 1 else 'their'} own ground "
                   f"truth ({files}), which --gt does not replace")
    if multi := sum(r.multi_target for r in mine):
        why.append(f"{plural(multi, 'multi-target run')}{of} "
                   f"{'is' if multi == 1 else 'are'} scored only with the ground truth given "
                   "to vtrack run --gt")
    return "; ".join([f"{warning}: {why[0]}", *why[1:]]) if why else warning


def _same_file(one: str, other: str) -> bool:
    """Whether the paths ``one`` and ``other`` name one file (as text, or found from here: a
    run records the ground truth it read by the path found from where it started)."""
    try:
        return one == other or os.path.samefile(one, other)
    except (OSError, ValueError):  # (not a file here)
        return False


def _scored_with(truth: GroundTruth, runs: Sequence[RunResult]) -> bool:
    """Whether a run ``truth`` is for (its :attr:`~.runs.RunResult.gt_given`) was scored with
    its file: by this report, or as the run's own ground truth, that very file (``vtrack report
    RUN --gt FILE`` of ``vtrack run --gt FILE``: nothing went unused)."""
    return any(r.gt_given is truth and r.ground_truth and _same_file(r.ground_truth, truth.path)
               for r in runs)


def _gt_warnings(truths: Sequence[GroundTruth], runs: Sequence[RunResult]) -> list[str]:
    """The warnings of the report's ``--gt`` files that scored no run (and why), and of a
    plain one that scored several inputs (one file is one input's ground truth)."""
    warnings = []
    for truth in truths:
        unused = not _scored_with(truth, runs)
        if unused and (truth.input is not None or not any(map(_takes_plain_gt, runs))):
            warnings.append(_unused_gt_warning(truth, runs))
        scored = sorted({r.input for r in runs if r.gt_scored and r.gt_given is truth})
        if truth.input is None and len(scored) > 1:
            warnings.append(f"--gt {truth.path} scored {len(scored)} inputs "
                            f"({', '.join(scored)}), each of its length: give --gt INPUT=FILE "
                            "for each input")
    return warnings


def _takes_plain_gt(run: RunResult) -> bool:
    """Whether a plain ``--gt FILE`` is for ``run``: a single-target run that recorded no
    ground truth (one whose frames the file does not fit has a warning of its own)."""
    return not run.multi_target and not run.ground_truth


def build_report(results: Sequence[Path], out_dir: Path,
                 gt: Path | str | Sequence[Path | str] | None = None,
                 gt_origin: int | None = 0, title: str = DEFAULT_TITLE,
                 on_input: Callable[[int, int], None] | None = None,
                 settled: Callable[[], object] | None = None, gt_first: int = 0) -> Report:
    """Read every run below ``results`` and write the report into ``out_dir``.

    ``gt`` scores the single-target runs that recorded no ground truth (boxes from their
    ``track.csv``; ``gt_origin=1`` for 1-based OTB boxes, None to tell from each file's
    place; ``gt_first`` the frame their first box belongs to, ``--gt-first``): ``FILE`` or
    ``INPUT=FILE`` specs, one or several; a run is scored only against a
    file of its own length (else a warning names the run and the file). A run folder that
    cannot be read is left out with a warning. Raises InputError when nothing below
    ``results`` is a run (or a failed batch row) and OutputError when ``out_dir`` cannot be
    written, holds a batch's ``summary.csv`` or is a run's folder. ``on_input(done, inputs)``
    is called as each input's plots are drawn (the long part: progress); ``settled()`` as
    the written files start to be put in place (:class:`~vtrack.io.files.StagedFiles`).
    """
    _refuse_batch_folder(out_dir)
    specs = [] if gt is None else [gt] if isinstance(gt, (str, Path)) else list(gt)
    walked = walk_results(results)
    warnings = still_written(walked)
    folders = run_folders(results, walked, warnings)
    # (a --gt INPUT=FILE that reads two ways: the readings naming a run found count)
    named = names_a_run(folders)
    truths = [GroundTruth.parse(str(spec), gt_origin, gt_first, named) for spec in specs]
    _refuse_two_files_for_one_input(truths)
    runs: list[RunResult] = []
    for folder in folders:
        try:
            runs.append(load_run(folder, truths))
        except InputError as exc:
            warnings.append(f"left out: {exc}")
        else:
            if runs[-1].note:
                warnings.append(runs[-1].note)
    failed = failed_runs(results, walked, runs, warnings)
    if not runs and not failed:
        named = ", ".join(str(r) for r in results)
        if len(warnings) == 1:
            raise InputError(f"{named}: no run to report; {warnings[0]}")
        if warnings:  # every reason, up to a few (one line)
            more = len(warnings) - NAMED_REASONS
            raise InputError(f"{named}: no run to report, {len(warnings)} left out: "
                             + "; ".join(w.removeprefix("left out: ")
                                         for w in warnings[:NAMED_REASONS])
                             + (f"; and {more} more" if more > 0 else ""))
        raise InputError(f"{named}: no run.json found (give vtrack run or vtrack batch output "
                         "folders)")
    # (of the --gt files, not of runs left out: not a reason for a report without runs)
    warnings[:0] = [t.note for t in truths if t.note]
    warnings += _gt_warnings(truths, runs)
    failed = _distinct_failed(failed, runs)  # (by the runs' input names, not yet told apart)
    _distinct_inputs(runs)
    failed = _distinct_labels(runs, failed, results)
    runs.sort(key=lambda r: (r.input, r.config))
    single = [r for r in runs if not r.multi_target]
    multi = [r for r in runs if r.multi_target]
    # (not: failed before frame 1; nor a run --gt's file did not fit: its own warning says so)
    unscored = [r for r in single if r.overlaps is None and r.note is None]
    if unscored:
        warnings.append(f"{plural(len(unscored), 'single-target run')} "
                        f"{'has' if len(unscored) == 1 else 'have'} no ground truth; give "
                        "--gt FILE (or --gt INPUT=FILE per input) to score them")

    # a report stopped part way (an error, Ctrl-C, SIGTERM) leaves no folder it created
    with removing_new_folders(out_dir / "plots"):
        plot_dir = prepare_output_dir(prepare_output_dir(out_dir) / "plots")
        by_input = _group(single, lambda r: r.input)
        warnings += [line for name, group in by_input.items()
                     for warn in (_mixed_truth_warning, _mixed_span_warning)
                     if (line := warn(name, group))]
        multi_by_input = _group(multi, lambda r: r.input)
        warnings += [line for name, group in multi_by_input.items()
                     if (line := _mixed_truth_warning(name, group))]
        # a run that failed part way is listed with its frames' scores but averaged with no other
        counted = [r for r in single if r.status != STATUS_FAILED]
        if len(counted) < len(single):
            warnings.append(f"{plural(len(single) - len(counted), 'single-target run')} failed "
                            "part way: "
                            "listed per input, left out of the averages and the All inputs plot")
        by_config = _group(counted, lambda r: r.config)
        averaged = {r.input for r in counted if _evaluated(r)}  # (the All inputs plot's inputs)
        palette = plots.colours(sorted({r.config for r in runs}))
        with StagedFiles(settled) as staged, catch_warnings():  # in place together once all written
            # matplotlib's notes (a glyph the font lacks, a layout it could not fit) are about the
            # drawing, not the runs: the terminal shows vtrack's warnings only
            simplefilter("ignore", UserWarning)
            written, sections = _write_plots(staged, plot_dir, by_input, averaged, palette,
                                             warnings, on_input)
            overall = _overall_plot(staged, plot_dir, by_config, averaged, palette, warnings)
            page = pages.Page(
                title=title,
                meta=(f"{_counts(runs, failed)}; generated "
                      f"{datetime.now():%Y-%m-%d %H:%M} by vtrack {__version__}"),
                warnings=warnings,
                overall_plot=overall and overall.relative_to(out_dir).as_posix(),
                averages=tables.average_table(by_config) if by_config else None,
                results=tables.results_table(list(by_input.values())) if single else None,
                mot=tables.mot_table(list(multi_by_input.values())) if multi else None,
                failed=failed,
                sections=sections,
            )
            # the pages last: a report whose plots could not all be written has no index.html
            csv = _stage_text(staged, out_dir / "summary.csv", pages.render_csv(runs, failed))
            markdown = _stage_text(staged, out_dir / "summary.md", pages.render_markdown(page))
            index = _stage_text(staged, out_dir / "index.html", pages.render_html(page))
        written += [overall] if overall else []
        _remove_stale_plots(plot_dir, written)
    return Report(out_dir=out_dir, index=index, markdown=markdown, csv=csv, plots=written,
                  runs=runs, warnings=warnings)


#: The kinds of plot a report writes, as ``plots/<kind>_<input>.png`` (``curves_all.png``).
PLOT_KINDS = ("state", "overlap", "curves", "failures")


def _remove_stale_plots(plot_dir: Path, written: Sequence[Path]) -> None:
    """Delete the plots an earlier report left in ``plot_dir`` (files named as this report
    names its plots, :data:`PLOT_KINDS`, that it did not write now); other files are the
    user's and stay."""
    for kind in PLOT_KINDS:
        for path in plot_dir.glob(f"{kind}_*.png"):
            if path not in written and not path.is_dir():
                remove_quietly(path)


def _stage_text(staged: StagedFiles, path: Path, text: str) -> Path:
    return staged.write(path, lambda temp: temp.write_bytes(text_bytes(text)))


def _save(staged: StagedFiles, figure: Figure, path: Path) -> Path:
    return staged.write(path, lambda temp: plots.save(figure, temp))


def _write_plots(staged: StagedFiles, plot_dir: Path, by_input: dict[str, list[RunResult]],
                 averaged: set[str], palette: dict[str, str], warnings: list[str],
                 on_input: Callable[[int, int], None] | None = None
                 ) -> tuple[list[Path], list[pages.Section]]:
    """Stage the plots of each input in ``plot_dir`` (a thumbnail problem is appended to
    ``warnings``; ``on_input(done, inputs)`` after each input's): the plots written and a
    section per input (its plots relative to the report folder; an input with no frame
    evaluated says whether ``averaged``, the All inputs plot's inputs, holds others). OutputError
    naming the plot that cannot be written."""
    written: list[Path] = []
    sections = []
    once: list[str] = []  # inputs whose failure frames are not drawn: read once, live
    for done, (name, slug) in enumerate(_slugs(list(by_input)).items(), 1):
        scored = [r for r in by_input[name] if r.scores is not None]
        unscored_here = [r for r in by_input[name] if r.scores is None and r.states]
        # a panel (or thumbnail column) per run costs time and height: at most a few drawn
        scored_drawn = _drawn_by_auc(scored)
        unscored_drawn = unscored_here[:plots.MAX_RUNS_DRAWN]
        notes = [note for note in (_drawn_note(scored, scored_drawn, True),
                                   _drawn_note(unscored_here, unscored_drawn, False),
                                   _unevaluated_note(scored, bool(averaged - {name})))
                 if note]
        figures = []
        if unscored_drawn:
            figures.append(_save(staged, plots.state_figure(name, unscored_drawn, palette),
                                 plot_dir / f"state_{slug}.png"))
            warnings += [f"{name} [{r.config}]: {plots.NO_SCORE}" for r in unscored_drawn
                         if all(c is None for c in r.confidence)]
        if scored:
            figures.append(_save(staged, plots.overlap_figure(name, scored_drawn, palette),
                                 plot_dir / f"overlap_{slug}.png"))
            success, precision = _mean_curves(scored)
            if success:
                figures.append(_save(staged, plots.curves_figure(name, success, precision,
                                                                 palette),
                                     plot_dir / f"curves_{slug}.png"))
            thumbnails, problem = failures.try_failure_figure(name, scored_drawn, palette)
            if thumbnails is not None:
                figures.append(_save(staged, thumbnails, plot_dir / f"failures_{slug}.png"))
            warnings += [problem] if problem else []
            once += [name] if failures.read_once_misses(scored_drawn) else []
        written += figures
        sections.append(pages.Section(name, f"input-{slug}", [
            p.relative_to(plot_dir.parent).as_posix() for p in figures], notes))
        if on_input is not None:
            on_input(done, len(by_input))
    if once:  # one note for them all: nothing was waited for
        warnings.append(f"failure frames of {plural(len(once), 'input')} left out: "
                        f"{', '.join(once[:NAMED_LEFT_OUT])}"
                        + (f" and {len(once) - NAMED_LEFT_OUT} more" if len(once) >
                           NAMED_LEFT_OUT else "")
                        + ": a stream, URL, stdin or device, read by the runs as it came and "
                        "not read again (it would show what it sends now, not the frames "
                        "tracked)")
    return written, sections


def _auc(run: RunResult) -> float:
    """``run``'s AUC; below every AUC when it has none (no frame evaluated)."""
    auc = run.scores.auc if run.scores is not None else math.nan
    return auc if math.isfinite(auc) else -math.inf


def _by_auc(runs: Sequence[RunResult]) -> list[RunResult]:
    """``runs`` from the highest AUC, ties by configuration name."""
    return sorted(runs, key=lambda r: (-_auc(r), r.config))


def _drawn_by_auc(scored: Sequence[RunResult]) -> list[RunResult]:
    """The scored runs of one input its plots over time and failure frames draw: all of them
    up to :data:`~.plots.MAX_RUNS_DRAWN`, else the best half and the worst half of that many by
    AUC (ties by configuration name): the range of what was tracked, in ``scored``'s order
    (by configuration)."""
    if len(scored) <= plots.MAX_RUNS_DRAWN:
        return list(scored)
    ranked = _by_auc(scored)
    worst = plots.MAX_RUNS_DRAWN // 2
    chosen = {id(r) for r in ranked[:plots.MAX_RUNS_DRAWN - worst]
              + ranked[len(ranked) - worst:]}
    return [r for r in scored if id(r) in chosen]


def _named(runs: Sequence[RunResult], auc: bool = False) -> str:
    """The configurations of ``runs`` (with their AUC), the first :data:`NAMED_LEFT_OUT`."""
    names = [f"{r.config} {_auc(r):.3f}" if auc and math.isfinite(_auc(r)) else r.config
             for r in runs]
    return first_few(names, NAMED_LEFT_OUT)


def _unevaluated_note(scored: Sequence[RunResult], others: bool) -> str | None:
    """The note under an input's heading when none of its ``scored`` runs has a frame to
    evaluate (its ground truth never shows the target): the dashes in its rows, said once
    rather than beside every average it leaves alike, and, when ``others`` (another input has
    a run with a frame evaluated), that the All inputs averages are over those; None
    otherwise."""
    if not scored or any(map(_evaluated, scored)):
        return None
    return ("No frame evaluated: the ground truth never has the target in view, so no run "
            "has a score here" + (", and the All inputs averages are over the other inputs"
                                  if others else "") + ".")


def _drawn_note(runs: Sequence[RunResult], drawn: Sequence[RunResult], scored: bool
                ) -> str | None:
    """The note under an input's heading when its plots over time (and failure frames) do not
    draw all its ``scored`` runs (or, not ``scored``, its runs without ground truth): which
    they draw, why those, and which they do not; None when they draw every run."""
    if len(drawn) == len(runs):
        return None
    drawn_ids = {id(r) for r in drawn}
    left_out = [r for r in (_by_auc(runs) if scored else runs) if id(r) not in drawn_ids]
    if scored:
        ranked = _by_auc(drawn)
        best = len(drawn) - plots.MAX_RUNS_DRAWN // 2
        why = (f"the {best} best and the {len(drawn) - best} worst by AUC, the range of what "
               f"was tracked: {_named(ranked[:best], True)}; and "
               f"{_named(ranked[best:], True)}")
        where = "over time and in the failure frames"
    else:
        why = (f"the first {len(drawn)} by configuration name (no ground truth: no score to "
               f"choose by): {_named(drawn)}")
        where = "in the state plot"
    return (f"Of the {len(runs)} {'scored ' if scored else 'unscored '}runs of this input, "
            f"{len(drawn)} are drawn {where} (each plot draws at most {plots.MAX_RUNS_DRAWN}): "
            f"{why}. Not drawn: {_named(left_out, scored)}. The success and precision plots "
            "draw every scored run; the tables list them all.")


def _overall_plot(staged: StagedFiles, plot_dir: Path, by_config: dict[str, list[RunResult]],
                  averaged: set[str], palette: dict[str, str],
                  warnings: list[str]) -> Path | None:
    """Stage the success and precision plots averaged over inputs (None: no config is scored);
    warn when the configs were scored on different inputs, and say beside the score of a
    config scored on fewer inputs than the plot's on how many (``[0.948, on 1 of 2
    inputs]``)."""
    counted = [r for runs in by_config.values() for r in runs]
    success, precision = _mean_curves(counted)
    if not success:
        return None
    covered = {c: {r.input for r in v if _evaluated(r)} for c, v in by_config.items()}
    # a config's curves over fewer inputs say so beside their score, as its table row does
    # (a config scored nowhere is in no average: the no-ground-truth warning names it)
    notes = {c: tables.on_inputs(len(inputs), len(averaged)) for c, inputs in covered.items()
             if inputs and inputs != averaged}
    if notes:
        warnings.append("configurations were scored on different inputs: their averages "
                        "are not directly comparable")
    title = f"All inputs (mean over {plural(len(averaged), 'input')})"
    return _save(staged, plots.curves_figure(title, success, precision, palette, notes),
                 plot_dir / f"curves_{ALL_INPUTS}.png")
