"""Folders of inputs: every input x configuration, in parallel, resumable, failure-isolated.

``vtrack batch`` is :func:`find_inputs` (``discover``) -> :func:`plan` (``plan``: what to run,
what is already done) -> :func:`run_batch` (``summary``) through a :class:`LocalExecutor` or
:class:`DaskExecutor` (``executors``), whose workers call :func:`execute` (``worker``); jobs and
outcomes are in ``jobs``. Each job is one :func:`vtrack.run.run` writing the files of
``vtrack run`` into ``OUT/<input>/<config>/``; ``OUT/summary.csv`` has one row per input x
config and is rewritten (atomically) as each job finishes.

Inputs (:func:`find_inputs`), looked for directly inside the folder (video files in its other
sub-folders, and sequence folders there, are not inputs: :func:`nested_inputs` finds them, for
the batch to say so):

- video files (by suffix, :data:`VIDEO_SUFFIXES`) and animations (GIF, APNG:
  :data:`ANIMATION_SUFFIXES`; one in a sequence folder is no input: a thumbnail), with
  ground truth beside them:
  ``name.gt.txt`` or ``name.txt`` (single target, ``x,y,w,h`` lines) and ``name.mot.txt``
  (MOTChallenge, for multi-target configs);
- sequence folders (:func:`is_sequence_folder`: images in OTB's ``img/`` or MOTChallenge's
  ``img1/``; in VOT2017+'s ``color/`` beside ``groundtruth.txt`` (``groundtruth_rect.txt``,
  ``init.txt``); or VOT's older layout, at least two images directly beside it and no video),
  with ground truth inside them (results folders, a run's or a batch's, are none):
  ``groundtruth_rect.txt`` or ``groundtruth.txt`` (single target) and ``groundtruth_mot.txt``,
  ``gt.txt`` or ``gt/gt.txt`` (MOTChallenge). For single-target configs, each target of an
  OTB sequence of several (``Jogging``: ``groundtruth_rect.1.txt``, ``groundtruth_rect.2.txt``)
  is an input of its own, named as OTB names it (``Jogging-1``, ``Jogging-2``) and tracked from
  its own boxes; multi-target configs run once on the sequence (``Jogging``).

An input without single-target ground truth still runs: detecting (multi-target) configs need
nothing, single-target ones take their first box from ``name.init.txt`` beside the video or
``init.txt`` in the sequence folder (one ``x,y,w,h`` line); its ``track.csv`` then has no overlap.

Ground-truth origin (``gt_origin=None``, the CLI's ``--gt-origin auto``): a sequence folder's
``groundtruth_rect.txt``, and a ``groundtruth.txt`` beside ``img/`` (UAV123, LaSOT), are read
as the MATLAB toolkits' 1-based boxes, a ``groundtruth.txt`` in VOT's layouts (images beside it,
or ``color/``) as VOT's 0-based ones (the VOT toolkit's pixel 0 is the image's first), a file
beside a video as 0-based (what ``vtrack scene`` writes)
(:func:`~vtrack.evaluate.groundtruth.gt_origin_of`). ``0`` or ``1`` forces one origin on all.

Resume: a job whose ``run.json`` says ``complete`` and records the same configuration, input,
ground truth, seed and output settings is not run again (its row says ``complete``, as its
``run.json`` does) while it still stands: every output it lists has its recorded size and the
input and ground truth the identity it recorded (size and modification time,
:mod:`vtrack.io.identity`). Anything else is run again, replacing the earlier run's files (only
those: :data:`vtrack.io.outdir.RUN_OUTPUTS`); results of a run with other settings only with
``--overwrite``.
The results folder is locked for the whole batch (a second batch or run on it is refused) and
each job's folder for its run. Failure isolation: a job's user error (unreadable input, bad
ground truth) or crash is recorded in its row (status ``failed``); an input that breaks part way
is ``partial``. A worker process that dies is retried once, then reported ``failed``.
"""

from __future__ import annotations

from vtrack.batch.discover import (
    SEQUENCE_INIT,
    SEQUENCE_MOT_GT,
    VIDEO_INIT,
    VIDEO_MOT_GT,
    BatchInput,
    find_inputs,
    is_sequence_folder,
    nested_inputs,
)
from vtrack.batch.executors import RETRIES, DaskExecutor, Executor, LocalExecutor
from vtrack.batch.jobs import SUMMARY_COLUMNS, Job, Outcome
from vtrack.batch.plan import Plan, completed_summary, plan
from vtrack.batch.summary import SummaryWriter, run_batch
from vtrack.batch.worker import execute
from vtrack.evaluate.groundtruth import SEQUENCE_GT, VIDEO_GT
from vtrack.io.specs import ANIMATION_SUFFIXES, BATCH_SUFFIXES, VIDEO_SUFFIXES
from vtrack.machine import cpu_count
from vtrack.run import STATUS_FAILED

__all__ = [
    "ANIMATION_SUFFIXES", "BATCH_SUFFIXES", "RETRIES", "SEQUENCE_GT", "SEQUENCE_INIT",
    "SEQUENCE_MOT_GT", "STATUS_FAILED",
    "SUMMARY_COLUMNS", "VIDEO_GT", "VIDEO_INIT", "VIDEO_MOT_GT", "VIDEO_SUFFIXES", "BatchInput",
    "DaskExecutor", "Executor", "Job", "LocalExecutor", "Outcome", "Plan", "SummaryWriter",
    "completed_summary", "cpu_count", "execute", "find_inputs", "is_sequence_folder",
    "nested_inputs", "plan", "run_batch",
]
