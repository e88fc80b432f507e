"""``vtrack batch FOLDER``: every input of a folder with every configuration, in parallel."""

from __future__ import annotations

import sys
from collections.abc import Callable
from contextlib import closing
from dataclasses import replace
from pathlib import Path
from typing import TYPE_CHECKING

import click
from click.core import ParameterSource

from vtrack.cli._messages import error_line, say, stdout_problem, warn, warning_line
from vtrack.cli._options import (
    Seconds,
    VtrackCommand,
    WholeNumber,
    gt_origin_option,
    refuse_encoding_without_video,
)
from vtrack.cli._paths import CONFIG, PATH
from vtrack.cli._signals import owns_process
from vtrack.cli.run import command as run_command
from vtrack.cli.run import default_out_dir
from vtrack.configs import DEFAULT_CONFIG
from vtrack.errors import (
    ConfigError,
    Interrupted,
    cut,
    handling_stop_signals,
    passing_stop_to,
    plural,
    shell_word,
)
from vtrack.machine import WORKER_MEMORY, available_memory, workers_memory_holds
from vtrack.params import MAX_WAIT_S

if TYPE_CHECKING:
    from vtrack.batch import LocalExecutor, Outcome, Plan
    from vtrack.batch.discover import NestedInputs
    from vtrack.batch.jobs import Progress
    from vtrack.config import Config

#: The most local worker processes ``--jobs`` starts (each a Python process with its own
#: decoder and chain of stages: far more than any machine has cores for).
MAX_JOBS = 512


def _fewer_workers(jobs: int | None, wanted: int, runs: int, workers: int,
                   available: int) -> str:
    """The warning of a batch of ``runs`` to do that starts ``workers`` local workers, not the
    ``wanted`` ones (``--jobs``, else the cores) nor one per run when fewer, as the
    ``available`` bytes of memory hold no more (less than one worker's: it starts one)."""
    asked = f"--jobs {jobs}" if jobs else f"{wanted} cores"
    needed = f"{wanted}" if wanted <= runs else f"{runs} (one per run to do)"
    each = f"{WORKER_MEMORY // 2**20} MiB"
    if available < WORKER_MEMORY:
        return (f"{asked}: too little memory for one worker of {each} (the memory available: "
                f"{available // 2**20} MiB): starting 1, not {needed}")
    return (f"{asked}: starting {plural(workers, 'worker')}, not {needed}: the memory available "
            f"({available / 2**30:.1f} GiB) holds about {workers} of {each} each")


def _local_executor(jobs: int | None, batch: Plan,
                    on_progress: Callable[[Progress], None]) -> LocalExecutor:
    """The local pool of workers for ``batch``: as many as ``--jobs`` (``jobs``, else the
    cores) and the runs to do, as this machine's memory holds (a warning when that starts
    fewer: :func:`_fewer_workers`). Sets each of ``batch``'s jobs' OpenCV threads to the
    cores shared among the workers that start (one per run to do, at most)."""
    from vtrack.batch import LocalExecutor, cpu_count

    cores = cpu_count()  # (it walks the cgroup tree: once)
    wanted = jobs or cores
    available = available_memory()
    held = workers_memory_holds(available)
    workers = wanted if held is None else min(wanted, held)
    runs = len(batch.jobs)
    if min(wanted, runs) > workers:
        warn(_fewer_workers(jobs, wanted, runs, workers, available or 0))
    threads = max(1, cores // max(1, min(workers, runs)))
    batch.jobs[:] = [replace(job, threads=threads) for job in batch.jobs]
    return LocalExecutor(workers, on_progress=on_progress)


def _run_options(*names: str) -> Callable[[click.Command], click.Command]:
    """Add ``vtrack run``'s own options of these parameter names (same flags, help, defaults)."""
    declared = {param.name: param for param in run_command.params}

    def add(command: click.Command) -> click.Command:
        command.params.extend(declared[name] for name in names)
        return command

    return add


class _StopOnce:
    """SIGINT/SIGTERM handler of the batch process: the first signal stops the batch
    (:class:`~vtrack.errors.Interrupted`); later ones are ignored, so the stop (a bounded grace
    period for running jobs, then ``summary.csv``) is not cut short by a second Ctrl-C or a
    scheduler that repeats its SIGTERM."""

    def __init__(self) -> None:
        self.stopping = False

    def __call__(self, signum: int, frame: object) -> None:
        if not self.stopping:
            self.stopping = True
            raise Interrupted(signum)


def _configs(specs: tuple[str, ...], overrides: tuple[str, ...]) -> dict[str, Config]:
    """Load every ``--config`` (with the ``--set`` overrides), keyed by config name. Configs
    whose results folders would be one are refused (:func:`~vtrack.batch.plan.folder_clash`:
    names the same, or the same but for characters a folder name cannot hold or for case),
    naming the ``--config`` that clashes; one given twice is said so."""
    from vtrack.batch.plan import ConfigFolders, folder_clash
    from vtrack.config import config_file, load_config
    from vtrack.io.files import SharedFolders

    configs: dict[str, Config] = {}
    folders: ConfigFolders = SharedFolders()
    files: dict[str, Path] = {}  # by config name: the file each config was read from
    for spec in specs or (DEFAULT_CONFIG,):
        config = load_config(spec)
        try:
            config = config.with_overrides(list(overrides))
        except ConfigError as exc:  # name the config: the chain alone did not say which
            raise ConfigError(f"--config {cut(spec)}: {exc}; each --set applies to every "
                              "--config") from None
        file = config_file(spec).resolve()  # ./mine.toml is mine.toml; s0 its shipped file
        clash = folder_clash(config.name, folders)
        if clash is not None and files[clash[0]] == file:
            raise ConfigError(f"--config {cut(spec)}: given twice; each config runs once on every "
                              "input")
        if clash is not None:
            raise ConfigError(f"--config {cut(spec)}: {clash[1]}")
        configs[config.name] = config
        folders.take(config.name, (config.name, config))
        files[config.name] = file
    return configs


def _refuse_one_video(folder: Path) -> None:
    """InputError when FOLDER is a video file (by its suffix, as a batch knows its videos): one
    line saying it is not a folder and that ``vtrack run`` tracks it."""
    from vtrack.errors import InputError
    from vtrack.io.specs import BATCH_SUFFIXES

    if folder.suffix.lower() in BATCH_SUFFIXES and folder.is_file():
        raise InputError(f"{folder}: not a folder: a batch tracks the inputs in a folder; "
                         f"vtrack run {shell_word(folder)} tracks one input")


def _check_scheduler_options(scheduler: str | None, jobs: int | None) -> None:
    """Refuse a --scheduler address that is wrong before anything connects (an empty one ran
    the batch locally), and the options of a Dask batch given without --scheduler (they were
    ignored), as ``vtrack run`` refuses options its input would ignore."""
    from vtrack.batch.executors import scheduler_address_problem

    if scheduler is None:
        source = click.get_current_context().get_parameter_source
        for name, flag in (("scheduler_timeout", "--scheduler-timeout"),
                           ("worker_timeout", "--worker-timeout")):
            if source(name) is not ParameterSource.DEFAULT:
                raise click.UsageError(f"{flag} is for a batch on a Dask scheduler: give "
                                       "--scheduler ADDRESS with it, or leave it out")
        return
    if jobs is not None:
        raise click.UsageError("--jobs and --scheduler exclude each other")
    problem = scheduler_address_problem(scheduler)
    if problem:
        raise click.UsageError(f"--scheduler {scheduler or repr(scheduler)}: {problem}")


@_run_options("overrides", "no_video", "preset", "crf", "seed", "start", "max_frames",
              "stats_period", "quiet")
@click.command("batch", cls=VtrackCommand)
@click.argument("folder", type=PATH)
@click.option("--config", "-c", "config_specs", multiple=True, metavar="FILE|NAME", type=CONFIG,
              help="Tracker config, a TOML file or a shipped name; repeat to run every input "
                   f"with each. Default: {DEFAULT_CONFIG}.")
@click.option("--out", "-o", "out_dir", type=PATH, metavar="DIR",
              help="Results: DIR/<input>/<config>/ and DIR/summary.csv. "
                   "Default: ./vtrack-out/<folder name>/")
@click.option("--jobs", "-j", type=WholeNumber(1, MAX_JOBS), default=None,
              help="Local worker processes (never more than the runs to do, nor than the "
                   f"memory available holds at about {WORKER_MEMORY // 2**20} MiB each: a "
                   "warning says so). "
                   "Default: the cores this process may use (a container's CPU quota counts).")
@click.option("--scheduler", metavar="ADDRESS",
              help="Run on this Dask distributed scheduler (tcp://host:8786) instead; workers "
                   "must see the input and output paths. Needs: pip install 'vtrack[dask]'.")
@click.option("--scheduler-timeout", type=Seconds(min=0.1, max=MAX_WAIT_S), default=10.0,
              show_default=True, metavar="SECONDS", help="Give up connecting to --scheduler "
                                                         "after this long.")
@click.option("--worker-timeout", type=Seconds(min=0, max=MAX_WAIT_S, min_open=True), default=60.0,
              show_default=True, metavar="SECONDS",
              help="With --scheduler and no worker connected: say so, wait this long for one, "
                   "then give up (exit 2).")
@gt_origin_option()
@click.option("--force", is_flag=True,
              help="Run again input x config pairs whose results are already complete; "
                   "replaces the results of runs with other settings too (as --overwrite).")
@click.option("--overwrite", "-y", is_flag=True,
              help="Replace results that runs with other settings (another --set, --start, "
                   "ground truth ...) left in DIR/<input>/<config>/; without it (or --force) "
                   "those pairs fail, naming the folder.")
def command(folder: Path, config_specs: tuple[str, ...], out_dir: Path | None,
            jobs: int | None, scheduler: str | None, scheduler_timeout: float,
            worker_timeout: float, gt_origin: int | None,
            force: bool, overwrite: bool, overrides: tuple[str, ...], no_video: bool,
            preset: str, crf: int,
            seed: int, start: tuple[int, float | None],
            max_frames: tuple[int | None, float | None] | None,
            stats_period: float,
            quiet: bool) -> None:
    """Track every input in FOLDER with every --config; write DIR/<input>/<config>/ (the files
    of `vtrack run`) and DIR/summary.csv.

    Inputs are the video files directly in FOLDER, known by their names (.mp4, .mov, .mkv,
    .mxf, .ts, .avi ...: the README lists them; ground truth beside them: name.gt.txt or
    name.txt, MOTChallenge name.mot.txt) and its sequence folders: images in img/ or
    MOTChallenge's img1/, or in VOT's color/ or the folder itself (two or more, no video
    beside them) beside their ground truth or init.txt (ground truth inside:
    groundtruth_rect.txt or groundtruth.txt, MOTChallenge
    groundtruth_mot.txt as vtrack scene writes it, gt.txt or gt/gt.txt; each target of an
    OTB sequence of several, groundtruth_rect.N.txt, is an input SEQ-N); videos and sequence
    folders in other sub-folders are not inputs (a warning counts them, the nearest first,
    looking at a few hundred folders at most: give such a folder as FOLDER). Without
    ground truth, single-target configs start from the box in name.init.txt (init.txt in a
    sequence folder). Results already complete are not run again (resume) unless --force;
    results of runs with other settings are replaced only with --overwrite (or --force). A
    failing input does not stop the others; the exit code is 1 if any failed.
    """
    # imported here, not at the top: other commands start without them (Dask loads only
    # inside DaskExecutor, with --scheduler)
    from vtrack.batch import (
        DaskExecutor,
        Executor,
        find_inputs,
        nested_inputs,
        plan,
        run_batch,
    )
    from vtrack.batch.discover import NESTED_LOOKS, SUMMARY_FILE, NoInputsError
    from vtrack.cli._progress import BatchProgress
    from vtrack.io.outdir import OutputFolder
    from vtrack.request import RunRequest

    _check_scheduler_options(scheduler, jobs)
    refuse_encoding_without_video(no_video)
    configs = _configs(config_specs, overrides)
    _refuse_one_video(folder)
    nested = nested_inputs(folder)
    left_out = _left_out(nested)
    try:
        inputs = find_inputs(folder, gt_origin,
                             multi_target=any(c.multi_target for c in configs.values()))
    except NoInputsError as exc:  # none directly in it: say where the nested ones are
        if left_out:
            raise NoInputsError(f"{exc}; {left_out}") from None
        if not nested.whole:
            raise NoInputsError(f"{exc}; none in sub-folders either, in the first "
                                f"{NESTED_LOOKS} folders looked at") from None
        raise
    if left_out:
        warn(f"{folder}: {left_out}")
    out_dir = out_dir or default_out_dir(str(folder))
    summary_path = out_dir / SUMMARY_FILE
    outcomes: list[Outcome] = []
    progress = BatchProgress(quiet, stats_period)
    # SIGTERM (kill, timeout, docker stop) stops the batch as Ctrl-C does; the results folder
    # is taken (created, checked, locked) before any job is planned. Once the batch is done,
    # the vtrack command ignores both until it exits; a host process (click's test runner, a
    # library) gets its own handlers back
    stop_once = _StopOnce()
    with handling_stop_signals(stop_once, ignored_after=owns_process()), \
            OutputFolder(out_dir, "batch"):
        dask: DaskExecutor | None = None
        if scheduler is not None:
            dask = DaskExecutor(scheduler, scheduler_timeout)
            dask.wait_for_workers(worker_timeout, say)
        settings = RunRequest(input=str(folder), out_dir=out_dir,
                              config=next(iter(configs.values())), video=not no_video,
                              preset=preset, crf=crf, seed=seed, start=start[0],
                              start_s=start[1],
                              max_frames=None if max_frames is None else max_frames[0],
                              max_s=None if max_frames is None else max_frames[1])
        batch = plan(inputs, configs, out_dir, settings, force=force,
                     overwrite=overwrite or force)
        for warning in batch.warnings:
            warn(warning)
        # a Dask cluster's workers are its own, and a job's threads are chosen on the worker
        # that runs it, from its machine's (dask_threads); the local pool's are chosen here
        executor: Executor = dask if dask is not None else _local_executor(
            jobs, batch, progress.on_progress)
        # frames tracked over the runs to do (those complete before are not counted)
        progress.runs = len(batch.jobs)
        to_run = {(job.input, job.config) for job in batch.jobs}
        late: list[Outcome] = []  # jobs that ended in a stop's grace period
        stopped: Interrupted | None = None
        running = run_batch(batch, executor, summary_path, late)
        try:
            with closing(running), passing_stop_to(running):
                for outcome in running:
                    outcomes.append(outcome)
                    if not quiet:
                        progress.write(outcome.line(out_dir))
                    for warning in outcome.warnings():
                        progress.write(warning_line(warning), err=True)
                    if (outcome.input, outcome.config) in to_run:
                        progress.finished(outcome.input, outcome.config,
                                          outcome.summary.frames if outcome.summary else 0)
        except Interrupted as exc:  # report what was done, then end as interrupted
            stopped = exc
        finally:  # summary.csv is final: a signal from here on changes nothing (the exit code
            stop_once.stopping = True  # is the one its rows call for)
            progress.close()
        if stopped is not None:
            reported = {(outcome.input, outcome.config) for outcome in outcomes}
            for outcome in late:
                if (outcome.input, outcome.config) in reported:
                    continue
                outcomes.append(outcome)
                if not quiet:
                    progress.write(outcome.line(out_dir))
                for warning in outcome.warnings():
                    progress.write(warning_line(warning), err=True)
        _report(outcomes, len(batch.order), summary_path, quiet, stopped is not None,
                progress.write)
        lost = _lost_stdout(progress.stdout_failure, summary_path)
        if lost:
            progress.write(error_line(lost), err=True)
    if stopped is not None:
        raise stopped
    if lost or any(not o.ok for o in outcomes):
        sys.exit(1)


def _lost_stdout(failure: OSError | ValueError | None, summary_path: Path) -> str | None:
    """What a batch says of the lines it could not write on standard output (``failure``,
    :attr:`~vtrack.cli._progress.BatchProgress.stdout_failure`): ``> /dev/full``, an I/O
    error, no standard output (``>&-``); None when they were all written, or when their
    reader went away (``| head``: quiet, as a pipe's writer; the batch ran on, its exit
    status says how its runs ended)."""
    return stdout_problem(failure, f"the batch's lines were not all printed there "
                                   f"({summary_path} lists every run)")


def _left_out(nested: NestedInputs) -> str | None:
    """What a batch says of the inputs in sub-folders it does not take
    (:func:`~vtrack.batch.nested_inputs`): their count ("at least" when it did not look at
    every folder), the first (the nearest), and the ``vtrack batch`` that tracks it (its
    folder, quoted for a shell); None when there are none."""
    from vtrack.batch.discover import NESTED_LOOKS

    found = nested.found
    if not found:
        return None
    folders = sum(path.is_dir() for path in found)
    kinds = [plural(len(found) - folders, "video file"), plural(folders, "sequence folder")]
    what = " and ".join(kind for kind in kinds if not kind.startswith("0 "))
    what = what if nested.whole else f"at least {what}"
    more = f" and {len(found) - 1} more" if len(found) > 1 else ""
    looked = "" if nested.whole else f", in the first {NESTED_LOOKS} folders looked at"
    verb = "is not an input" if len(found) == 1 else "are not inputs"
    where = {path.parent for path in found}
    example = "" if len(where) == 1 and nested.whole else "e.g. "
    them = "it" if len(found) == 1 and nested.whole else "them"
    return (f"{what} in sub-folders {verb} ({found[0]}{more}{looked}): a batch takes the "
            "videos directly in the folder and its sequence folders (img/, img1/, color/); to "
            f"track {them}, {example}vtrack batch {shell_word(found[0].parent)}")


def _report(outcomes: list[Outcome], pairs: int, summary_path: Path, quiet: bool,
            stopped: bool, write: Callable[..., None]) -> None:
    """The end of a batch: the tally of its ``pairs`` (input x config) by status, as the rows
    of ``summary.csv`` give it (a run refused for other settings counts as the run its folder
    keeps), and where that file is (unless ``quiet``), then one ``vtrack: error:`` line per run
    that did not complete. A ``stopped`` batch counts the pairs it never started, and names no
    error for the runs its stop interrupted (its own ``vtrack: interrupted`` line follows).
    Each line goes through ``write(line, err=False)``."""
    from vtrack.run import STATUS_INTERRUPTED

    counts: dict[str, int] = {}
    for outcome in outcomes:  # by what each pair's folder holds, as summary.csv's rows
        counts[outcome.held] = counts.get(outcome.held, 0) + 1
    if not quiet:
        tally = ", ".join(f"{n} {status}" for status, n in sorted(counts.items()))
        unstarted = pairs - len(outcomes) if stopped else 0
        if unstarted:
            tally += (", " if tally else "") + (f"{unstarted} not started: the batch was "
                                               "stopped, the same command runs them")
        resumed = sum(outcome.resumed for outcome in outcomes)
        if resumed:
            tally += f"; {resumed} of them complete before, not run again"
        refused = sum(outcome.kept is not None for outcome in outcomes)
        if refused:
            tally += (f"; {refused} of them made with other settings, not run again "
                      "(--overwrite replaces them)")
        total = len(outcomes) + unstarted
        write(f"{plural(total, 'run')} ({tally}) -> {summary_path}")
    for outcome in outcomes:
        if not outcome.ok and not (stopped and outcome.status == STATUS_INTERRUPTED):
            write(error_line(f"{outcome.input} [{outcome.config}]: {outcome.verdict}: "
                             f"{outcome.error}"), err=True)
