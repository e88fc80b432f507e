"""vtrack's configs against peer trackers, same frames, same scorer (issues 14 and 20).

    python benchmarks/robust_bench.py [--configs robust,s0,...] [--peers CSRT,ECO-HC,Nano,...]
        [--contrib-python PATH] [--eco-python PATH --eco-dir DIR] [--nano-models DIR]
        [--only SEQ ...] [--details] [--seeds 3] [--hd-frames 60] [--no-sequences] [--no-scenes]

The peers are optional and never dependencies of vtrack; a peer that is not set up is printed as
n/a with the reason:

- OpenCV's meanShift tutorial and MIL run in this Python. KCF and CSRT live in
  ``opencv-contrib-python-headless``: create a separate venv for it and give its python
  (``--contrib-python`` or ``VTRACK_CONTRIB_PYTHON``)::

      python -m venv ~/venv-contrib
      ~/venv-contrib/bin/pip install opencv-contrib-python-headless numpy

- NanoTrack v2 (``Nano``) runs through ``cv2.TrackerNano`` (OpenCV >= 4.7, in the contrib venv
  when given, else here) on the two ONNX files of HonglinChu/SiamTrackers'
  ``NanoTrack/models/nanotrackv2/`` in ``--nano-models DIR`` (or ``VTRACK_NANO_MODELS``).
- ECO-HC runs in the Python port StrangerZhang/pyECO in its own venv (Python 3.11, numpy<2,
  scipy<1.13): ``bash benchmarks/peers/setup_eco.sh PYECO_DIR VENV`` prepares both, then give
  ``--eco-python VENV/bin/python --eco-dir PYECO_DIR`` (or ``VTRACK_ECO_PYTHON``,
  ``VTRACK_ECO_DIR``); ``peers/eco_runner.py`` runs it.

Prints Markdown:

1. On the single-target sequences of ``../shared/data`` (or ``$VTRACK_DATA``; skipped when
   absent): AUC per sequence and tracker (OTB success, 21 thresholds, first ground-truth box
   given; check sequences marked), the mean AUC over the tune sequences, the check sequences
   (``common.CHECK_SEQUENCES``, the data's split) and all; then per tracker the means of AUC,
   precision at 20 px, mean IoU, the share of frames called ``tracking`` whose box misses the
   target (IoU 0), the share of missed frames (IoU 0 or no box) called ``occluded``/``lost``
   (:mod:`vtrack.evaluate.metrics`), the median tracking fps over the sequences, and the median
   over sequences of the tracker's fps divided by CSRT's and by ECO-HC's on the same frames.
   ``--details`` adds every column per sequence.
2. Scenes: mean IoU per randomised scene of :mod:`vtrack.scenes.hard` over ``--seeds`` seeds
   (320x240, 150 frames) for every tracker.
3. Tracking cost at 1080p: the ``benchmark`` scene (1920x1080, ``--hd-frames`` frames) per
   tracker.

Every tracker gets the same pixels (each image read with ``cv2.imread``, as ``robust_tune.py``
reads them; ``vtrack run`` decodes JPEG with PyAV, whose pixels differ by a few levels) and the
first ground-truth box, on one thread (``--threads``: OpenCV's thread pool here, and the thread
variables of the peers' processes). vtrack's configs run in-process on the frames held in
memory, timed around the pipeline only (decoding excluded); the peers run in subprocesses
(``opencv_trackers.py``, ``peers/eco_runner.py``) timed around init + update only. The peers have
no ``occluded``: an OpenCV tracker's frame whose update fails is ``lost`` (no box), every other
frame ``tracking``; ECO-HC always claims a box. ``s3`` is not in the table: it is a multi-target
tracker whose output is a set of tracks, not one box. ``s4`` needs no ``--init`` and ignores it:
it follows the largest moving blob it detects (background subtraction), target or not.
"""

from __future__ import annotations

import argparse
import json
import math
import os
import statistics
import subprocess
import sys
import tempfile
import time
from dataclasses import dataclass
from pathlib import Path

import cv2
from common import CHECK_SEQUENCES, Sequence, load_clip, machine, single_target_sequences

from vtrack.config import load_config
from vtrack.errors import VtrackError
from vtrack.evaluate import metrics
from vtrack.frame import BgrFrame, Frame
from vtrack.geometry import Box
from vtrack.pipeline import Pipeline
from vtrack.scenes import make_scene
from vtrack.scenes.hard import HARD_SCENARIOS

HERE = Path(__file__).resolve().parent
#: vtrack configs compared by default.
CONFIGS = ("robust", "s0", "s1", "s2", "s4", "camshift")
#: OpenCV trackers run by ``opencv_trackers.py``; KCF and CSRT need contrib, Nano its models.
OPENCV = ("meanshift", "MIL", "KCF", "CSRT", "Nano")
NEEDS_CONTRIB = ("KCF", "CSRT")
ECO = "ECO-HC"
PEERS = (*OPENCV, ECO)
#: Peers whose fps the others' are divided by (median over sequences of the ratio).
SPEED_REFERENCES = ("CSRT", ECO)
COLUMNS = ("AUC", "P@20", "mIoU", "tracking miss", "miss flagged", "fps")


@dataclass
class Outcome:
    """One tracker on one clip: per-frame boxes and states, tracking seconds (None: n/a)."""

    boxes: list[Box | None] | None
    states: list[str] | None
    seconds: float | None
    note: str = ""
    failed: bool = False  # the tracker refused or broke (counts 0), rather than n/a

    def scores(self, gt: list[Box | None]) -> tuple[float, ...]:
        """(AUC, P@20, mean IoU, tracking miss, miss flagged, fps); NaN where not computable."""
        if self.boxes is None or self.states is None or self.seconds is None:
            return (math.nan,) * len(COLUMNS)
        overlaps, errors = metrics.frame_scores(self.boxes, gt)
        return (metrics.auc(overlaps), metrics.precision_at(errors),
                metrics.mean_overlap(overlaps),
                metrics.tracking_miss_rate(self.states, overlaps),
                metrics.flagged_miss_rate(self.states, overlaps),
                len(self.boxes) / self.seconds if self.seconds > 0 else math.nan)


@dataclass(frozen=True)
class Peers:
    """Which peers run and where: the Pythons and files each needs (None: not set up)."""

    names: tuple[str, ...]
    contrib_python: str | None
    eco_python: str | None
    eco_dir: str | None
    nano_models: str | None
    threads: int

    def env(self) -> dict[str, str]:
        """The peers' process environment: ``threads`` threads for OpenCV and BLAS/OpenMP."""
        count = str(self.threads)
        return dict(os.environ, OPENCV_FOR_THREADS_NUM=count, OMP_NUM_THREADS=count,
                    OPENBLAS_NUM_THREADS=count, MKL_NUM_THREADS=count)

    def missing(self, name: str) -> str | None:
        """Why peer ``name`` cannot run here (None: it can)."""
        if name in NEEDS_CONTRIB and self.contrib_python is None:
            return "n/a: needs opencv-contrib-python-headless (--contrib-python)"
        if name == "Nano" and self.nano_models is None:
            return "n/a: needs NanoTrack v2's ONNX files (--nano-models)"
        if name == ECO and (self.eco_python is None or self.eco_dir is None):
            return "n/a: needs pyECO and its venv (--eco-python, --eco-dir)"
        return None


def run_vtrack(config: str, frames: list[Frame], init: Box) -> Outcome:
    """``config`` over in-memory ``frames`` as ``vtrack run`` tracks them (seed 0)."""
    pipeline = Pipeline(load_config(config).build(), seed=0)
    boxes: list[Box | None] = []
    states: list[str] = []
    started = time.perf_counter()
    try:
        for result in pipeline.track(iter(frames), init):
            boxes.append(result.box)
            states.append(result.state)
    except VtrackError as exc:  # e.g. a refusal: scores as lost from there on
        return Outcome(None, None, None, f"{config}: {exc}", failed=True)
    return Outcome(boxes, states, time.perf_counter() - started)


def _records(command: list[str], peers: Peers, n: int) -> dict[str, Outcome]:
    """Run a peer ``command`` that prints one JSON line per tracker; its outcomes by name."""
    done = subprocess.run(command, capture_output=True, text=True, env=peers.env())
    outcomes: dict[str, Outcome] = {}
    for line in done.stdout.splitlines():
        record = json.loads(line)
        if "error" in record:
            outcomes[record["tracker"]] = Outcome(None, None, None, record["error"])
            continue
        boxes = [Box(*b) if b is not None else None for b in record["boxes"]][:n]
        states = ["tracking" if ok else "lost" for ok in record["ok"]][:n]
        outcomes[record["tracker"]] = Outcome(boxes, states, record["seconds"])
    if done.returncode != 0:
        last = (done.stderr.strip().splitlines() or ["no message"])[-1]
        outcomes["error"] = Outcome(None, None, None, f"exit {done.returncode}: {last}",
                                    failed=True)
    return outcomes


def run_peers(peers: Peers, folder: Path, init: Box, n: int) -> dict[str, Outcome]:
    """The peers on the image ``folder`` in subprocesses; n/a (with the reason) where not set
    up, failed (counts 0) where the peer broke."""
    outcomes = {name: Outcome(None, None, None, reason) for name in peers.names
                if (reason := peers.missing(name)) is not None}
    box = ",".join(f"{v:.2f}" for v in init)
    opencv = [name for name in peers.names if name in OPENCV and name not in outcomes]
    commands: list[tuple[list[str], list[str]]] = []
    if opencv:
        command = [peers.contrib_python or sys.executable, str(HERE / "opencv_trackers.py"),
                   str(folder), box, *opencv]
        if peers.nano_models:
            command += ["--nano-models", peers.nano_models]
        commands.append((command, opencv))
    if ECO in peers.names and ECO not in outcomes:
        assert peers.eco_python is not None and peers.eco_dir is not None
        commands.append(([peers.eco_python, str(HERE / "peers" / "eco_runner.py"),
                          peers.eco_dir, str(folder), box], [ECO]))
    for command, names in commands:
        found = _records(command, peers, n)
        broken = found.pop("error", None)
        for name in names:
            outcomes[name] = found.get(name) or broken or Outcome(
                None, None, None, "printed no result", failed=True)
    return outcomes


def track_all(frames: list[Frame], folder: Path, init: Box, peers: Peers,
              configs: list[str]) -> dict[str, Outcome]:
    """Every tracker on one clip (``frames`` in memory, the same frames as files in ``folder``)."""
    results = {c: run_vtrack(c, frames, init) for c in configs}
    results.update(run_peers(peers, folder, init, len(frames)))
    return results


def _cell(value: float, digits: int = 3) -> str:
    return "n/a" if math.isnan(value) else f"{value:.{digits}f}"


def _row(label: str, values: tuple[float, ...]) -> str:
    cells = [_cell(v) for v in values[:-1]] + [_cell(values[-1], 0)]
    return f"| {label} | " + " | ".join(cells) + " |"


def _header(first: str) -> list[str]:
    return [f"| {first} | " + " | ".join(COLUMNS) + " |", "|---|" + "---:|" * len(COLUMNS)]


def _nanmean(values: list[float]) -> float:
    kept = [v for v in values if not math.isnan(v)]
    return statistics.mean(kept) if kept else math.nan


def _auc_mean(table: dict[str, tuple[float, ...]], names: list[str]) -> float:
    """Mean AUC over ``names`` (a failed run counts 0; NaN when the tracker never ran)."""
    values = [table[name][0] for name in names]
    if all(math.isnan(v) for v in values) or not values:
        return math.nan
    return statistics.mean(0.0 if math.isnan(v) else v for v in values)


def _speed_ratio(table: dict[str, dict[str, tuple[float, ...]]], tracker: str,
                 reference: str) -> float:
    """Median over sequences of ``tracker``'s fps / ``reference``'s fps on the same frames."""
    if reference not in table:
        return math.nan
    ratios = [table[tracker][s][-1] / table[reference][s][-1] for s in table[reference]
              if not math.isnan(table[reference][s][-1]) and not math.isnan(table[tracker][s][-1])]
    return statistics.median(ratios) if ratios else math.nan


def auc_table(table: dict[str, dict[str, tuple[float, ...]]], names: list[str]) -> None:
    """AUC per sequence (rows) and tracker (columns), then the tune, check and all means."""
    trackers = list(table)
    print("### AUC per sequence (check sequences marked *)\n")
    print("| sequence | " + " | ".join(trackers) + " |")
    print("|---|" + "---:|" * len(trackers))
    for name in names:
        mark = " *" if name in CHECK_SEQUENCES else ""
        print(f"| {name}{mark} | " + " | ".join(_cell(table[t][name][0]) for t in trackers)
              + " |")
    tune = [n for n in names if n not in CHECK_SEQUENCES]
    check = [n for n in names if n in CHECK_SEQUENCES]
    for label, part in ((f"tune {len(tune)}", tune), (f"check {len(check)}", check),
                        (f"all {len(names)}", names)):
        if part:
            print(f"| **mean, {label}** | " + " | ".join(
                f"**{_cell(_auc_mean(table[t], part))}**" for t in trackers) + " |")
    print()


def sequences_section(peers: Peers, configs: list[str], only: list[str], details: bool) -> None:
    sequences = [s for s in single_target_sequences() if not only or s.name in only]
    if not sequences:
        print("no benchmark sequences found (../shared/data or $VTRACK_DATA): skipped\n")
        return
    trackers = [*configs, *peers.names]
    table: dict[str, dict[str, tuple[float, ...]]] = {t: {} for t in trackers}
    notes: list[str] = []
    for seq in sequences:
        scores = sequence_scores(seq, peers, configs, notes)
        for tracker in trackers:
            table[tracker][seq.name] = scores[tracker]
        if details:
            print(f"### {seq.name}\n")
            print("\n".join(_header("tracker")))
            for tracker in trackers:
                print(_row(tracker, scores[tracker]))
            print()
        else:
            print(f"<!-- {seq.name}: " + ", ".join(f"{t} {_cell(scores[t][0])}"
                                                   for t in trackers) + " -->")
        sys.stdout.flush()
    print()
    auc_table(table, [seq.name for seq in sequences])
    references = [r for r in SPEED_REFERENCES if r in table]
    print(f"### Means over the {len(sequences)} sequences\n")
    print("(AUC, P@20, mIoU: a run that failed counts 0; tracking miss / miss flagged: mean over "
          "the sequences where they are defined; fps: median over the sequences; x CSRT, "
          "x ECO-HC: median over sequences of the tracker's fps / the peer's fps on the same "
          "frames)\n")
    print("| tracker | " + " | ".join(COLUMNS) + " |" + "".join(f" x {r} fps |"
                                                              for r in references))
    print("|---|" + "---:|" * (len(COLUMNS) + len(references)))
    for tracker in trackers:
        rows = list(table[tracker].values())
        means = [_auc_mean(table[tracker], list(table[tracker]))] + [
            statistics.mean(0.0 if math.isnan(r[i]) else r[i] for r in rows) for i in (1, 2)]
        means += [_nanmean([r[i] for r in rows]) for i in (3, 4)]
        fps = [r[-1] for r in rows if not math.isnan(r[-1])]
        means.append(statistics.median(fps) if fps else math.nan)
        ratios = "".join(f" {_cell(_speed_ratio(table, tracker, r), 1)} |" for r in references)
        print(_row(f"**{tracker}**", tuple(means)) + ratios)
    print()
    for note in dict.fromkeys(notes):
        print(f"- {note}")
    print()


def sequence_scores(seq: Sequence, peers: Peers, configs: list[str],
                    notes: list[str]) -> dict[str, tuple[float, ...]]:
    clip = load_clip(seq)
    frames: list[Frame] = [BgrFrame(i, i / 30.0, bgr) for i, bgr in enumerate(clip.frames)]
    gt = clip.boxes
    assert gt[0] is not None
    outcomes = track_all(frames, seq.folder, gt[0], peers, configs)
    for name, outcome in outcomes.items():
        if outcome.note:
            notes.append(f"{seq.name} [{name}]: {outcome.note}")
    return {name: outcome.scores(gt) for name, outcome in outcomes.items()}


def _scene_clip(name: str, seed: int, folder: Path, width: int = 320, height: int = 240,
                frames: int | None = None) -> tuple[list[Frame], list[Box | None]]:
    """Scene ``name``/``seed`` rendered once: in-memory frames and PNG files in ``folder``."""
    scene = make_scene(name, seed=seed, width=width, height=height, frames=frames)
    folder.mkdir(parents=True, exist_ok=True)
    images = []
    for i, bgr in enumerate(scene.frames()):
        cv2.imwrite(str(folder / f"{i + 1:04d}.png"), bgr)
        images.append(BgrFrame(i, i / scene.fps, bgr))
    return images, scene.boxes


def scenes_section(peers: Peers, configs: list[str], seeds: int) -> None:
    trackers = [*configs, *peers.names]
    names = [s.name for s in HARD_SCENARIOS]
    print(f"### Scenes: mean IoU over seeds 0..{seeds - 1} (320x240, 150 frames, parameters "
          "randomised per seed; a refused run counts 0)\n")
    print("| scene | " + " | ".join(trackers) + " |")
    print("|---|" + "---:|" * len(trackers))
    all_means: dict[str, list[float]] = {t: [] for t in trackers}
    for name in names:
        per: dict[str, list[float]] = {t: [] for t in trackers}
        for seed in range(seeds):
            with tempfile.TemporaryDirectory() as tmp:
                frames, gt = _scene_clip(name, seed, Path(tmp))
                assert gt[0] is not None
                outcomes = track_all(frames, Path(tmp), gt[0], peers, configs)
            for t in trackers:
                per[t].append(0.0 if outcomes[t].failed else outcomes[t].scores(gt)[2])
        cells = []
        for t in trackers:
            value = _nanmean(per[t])
            all_means[t].append(value)
            cells.append(_cell(value))
        print(f"| {name} | " + " | ".join(cells) + " |")
        sys.stdout.flush()
    print("| **mean** | " + " | ".join(f"**{_cell(_nanmean(all_means[t]))}**"
                                        for t in trackers) + " |")
    print()


def hd_section(peers: Peers, configs: list[str], frames: int) -> None:
    print(f"### Tracking cost at 1080p (`benchmark` scene, 1920x1080, {frames} frames, "
          "decoded frames in memory, tracking work only)\n")
    print("| tracker | ms per frame | fps | mean IoU |")
    print("|---|---:|---:|---:|")
    with tempfile.TemporaryDirectory() as tmp:
        clip, gt = _scene_clip("benchmark", 0, Path(tmp), 1920, 1080, frames)
        assert gt[0] is not None
        outcomes = track_all(clip, Path(tmp), gt[0], peers, configs)
    for name, outcome in outcomes.items():
        scores = outcome.scores(gt)
        ms = 1000.0 / scores[-1] if scores[-1] > 0 else math.nan
        print(f"| {name} | {_cell(ms, 2)} | {_cell(scores[-1], 0)} | {_cell(scores[2])} |")
    print()


def _names(value: str, known: tuple[str, ...], what: str) -> list[str]:
    """A comma-separated list of ``known`` names; exits with one line naming an unknown one."""
    names = [n.strip() for n in value.split(",") if n.strip()]
    for name in names:
        if name not in known:
            sys.exit(f"{what}: unknown name {name!r} (one of {', '.join(known)})")
    return names


def _peer_versions(peers: Peers) -> None:
    """One line per peer environment that is set up: what runs the peers."""
    if peers.contrib_python is not None:
        version = subprocess.run([peers.contrib_python, "-c",
                                  "import cv2; print(cv2.__version__)"],
                                 capture_output=True, text=True, check=True).stdout.strip()
        print(f"OpenCV peers: opencv-contrib-python-headless {version} (separate venv)\n")
    if peers.eco_python is not None and peers.eco_dir is not None:
        version = subprocess.run([peers.eco_python, "-c",
                                  "import sys, numpy, scipy, cv2; print(sys.version.split()[0], "
                                  "numpy.__version__, scipy.__version__, cv2.__version__)"],
                                 capture_output=True, text=True, check=True).stdout.split()
        commit = subprocess.run(["git", "-C", peers.eco_dir, "rev-parse", "--short", "HEAD"],
                                capture_output=True, text=True).stdout.strip() or "unknown"
        print(f"ECO-HC: pyECO {commit} (OTBHCConfig), Python {version[0]}, NumPy {version[1]}, "
              f"SciPy {version[2]}, OpenCV {version[3]} (separate venv)\n")
    for name in peers.names:
        reason = peers.missing(name)
        if reason is not None:
            print(f"{name}: {reason}\n")


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--configs", default=",".join(CONFIGS),
                        help="vtrack configs, comma-separated (default: %(default)s)")
    parser.add_argument("--peers", default=",".join(PEERS),
                        help="peer trackers, comma-separated (default: %(default)s)")
    parser.add_argument("--contrib-python", default=os.environ.get("VTRACK_CONTRIB_PYTHON"),
                        help="python of a venv with opencv-contrib-python-headless (KCF, CSRT)")
    parser.add_argument("--eco-python", default=os.environ.get("VTRACK_ECO_PYTHON"),
                        help="python of pyECO's venv (peers/setup_eco.sh)")
    parser.add_argument("--eco-dir", default=os.environ.get("VTRACK_ECO_DIR"),
                        help="pyECO checkout, prepared by peers/setup_eco.sh")
    parser.add_argument("--nano-models", default=os.environ.get("VTRACK_NANO_MODELS"),
                        help="folder of NanoTrack v2's two ONNX files")
    parser.add_argument("--threads", type=int, default=1,
                        help="threads every tracker may use (default 1)")
    parser.add_argument("--only", action="append", default=[], help="sequence names")
    parser.add_argument("--details", action="store_true", help="every column per sequence")
    parser.add_argument("--seeds", type=int, default=3, help="seeds per scene")
    parser.add_argument("--hd-frames", type=int, default=60, help="frames of the 1080p clip")
    parser.add_argument("--no-sequences", action="store_true")
    parser.add_argument("--no-scenes", action="store_true")
    args = parser.parse_args()
    configs = _names(args.configs, tuple(CONFIGS), "--configs")
    peers = Peers(tuple(_names(args.peers, PEERS, "--peers")), args.contrib_python,
                  args.eco_python, args.eco_dir, args.nano_models, args.threads)
    cv2.setNumThreads(args.threads)
    print("Command: `python benchmarks/robust_bench.py " + " ".join(
        a if not a.startswith("/") else "PATH" for a in sys.argv[1:]) + "`\n")
    print(machine() + f"; {args.threads} thread(s) per tracker\n")
    _peer_versions(peers)
    if not args.no_sequences:
        sequences_section(peers, configs, args.only, args.details)
    if not args.no_scenes:
        scenes_section(peers, configs, args.seeds)
        if args.hd_frames > 0:
            hd_section(peers, configs, args.hd_frames)


if __name__ == "__main__":
    main()
