"""Trackers S1 and S2 against S0 and the OpenCV CamShift peer, with the documents' claims.

    python benchmarks/claims.py [--seeds 10] [--accuracy-seeds 3] [--quick]

Prints, as Markdown for ``benchmarks/RESULTS.md``:

1. S1's claims (patent CN105869186A): :func:`claims_s1.s1_claims` over ``--seeds`` seeds, its
   table and verdicts as ``claims_s1.py`` prints them, and one sentence per claim; then leaving
   and coming back (:mod:`claims_s1_return`) over the same seeds.
2. S2's claims (Di & Zhu 2008): :func:`claims_s2.s2_claims` (generated scenes over ``--seeds``
   seeds, real sequences, 1080p cost), its tables, and one sentence per claim. ``claims_s2.py``
   prints no verdicts; the rules used here are :func:`s2_motion_verdict` and
   :func:`s2_cost_verdict`.
3. Accuracy on every single-target sequence of ``../shared/data`` (or ``$VTRACK_DATA``): AUC
   (OTB success, 21 thresholds), precision at 20 px and mean IoU of the shipped ``s0``, ``s1``,
   ``s2`` and ``camshift`` configs, each run by the same code path as ``vtrack run``
   (:func:`common.run_sequence`). S1 is stochastic: its scores are the mean over seeds
   0 .. ``--accuracy-seeds``-1; the others are deterministic (seed 0). Then the same for the
   :data:`OPTIONS` that are not the documents' (S1 with 64 particles while lost, S2 with the
   Epanechnikov kernel) against their shipped configs. Skipped, with a message, when there is
   no data folder.
4. Per-frame cost at 1080p: the generated ``benchmark`` scene (1920x1080, 120 frames, 60 fps)
   converted to I420 frames (how decoded video reaches the pipeline) before anything is timed,
   tracked by each config; microseconds per frame of tracking work per stage as the pipeline
   measures them around each stage (decode and conversion excluded), median over rounds.

``--quick``: 3 claim seeds, 1 accuracy seed, 1 cost round.
"""

from __future__ import annotations

import argparse
import math
import statistics
import sys

import claims_s1
import claims_s1_return
import claims_s2
from claims_s1 import CLAIMED_REDUCTION, EQUAL_WITHIN, claim_1, claim_2, s1_claims, s1_cost
from claims_s2 import DOCUMENT_COST, TRACKERS, s2_claims
from common import Sequence, machine, run_sequence, single_target_sequences, to_frame

from vtrack.config import load_config
from vtrack.errors import VtrackError
from vtrack.evaluate import summarize
from vtrack.evaluate.groundtruth import read_boxes
from vtrack.pipeline import Pipeline
from vtrack.run import RunSummary
from vtrack.scenes import make_scene

#: The compared trackers (shipped configs).
CONFIGS = ("s0", "s1", "s2", "camshift")
#: Options that are not the documents' (README), each measured against its shipped config:
#: (label, config, overrides).
OPTIONS = (
    ("s1, 64 lost particles", "s1", ("particle.lost_particles=64",)),
    ("s2, Epanechnikov", "s2", ("kernel_meanshift.kernel=epanechnikov",)),
)
#: Mean IoU from which a tracker counts as following the target through a clip (OTB's usual
#: success overlap); used by the S2 motion/occlusion verdicts.
FOLLOWS_FROM = 0.5
#: The document's cost range for a 32x20 target (table 2), microseconds per frame.
DOCUMENT_US = (200.0, 1000.0)


def _print(lines: list[str] | str = "") -> None:
    print(lines if isinstance(lines, str) else "\n".join(lines))
    sys.stdout.flush()


# ------------------------------------------------------------------------------------ S1


def s1_sentences(rows: list[dict]) -> list[str]:
    """One sentence per (claim, mode) from :func:`claims_s1.s1_claims` rows and its verdicts."""
    lines = []
    for mode, _ in claims_s1.MODES:
        chosen = [r for r in rows if r["mode"] == mode]
        counted = [r for r in chosen if not r["identical"] and not math.isnan(r["reduction"][0])]
        holds = [r["sequence"] for r in counted if claim_1(r).startswith("holds")]
        median = statistics.median(r["reduction"][0] for r in counted) if counted else math.nan
        lines.append(
            f"- **Claim 1** ({mode}): centroid correction cuts the 8-particle error by "
            f"{CLAIMED_REDUCTION:.0%} — holds on {len(holds)}/{len(counted)} sequences where "
            f"correction changes anything ({', '.join(holds) or 'none'}); median reduction "
            f"{median:.0%} (claimed {CLAIMED_REDUCTION:.0%})."
        )
        ratios = [r["8c / 32p"] for r in chosen if not math.isnan(r["8c / 32p"])]
        holds_2 = [r["sequence"] for r in chosen if claim_2(r).startswith("holds")]
        median = statistics.median(ratios) if ratios else math.nan
        lines.append(
            f"- **Claim 2** ({mode}): 8 corrected particles are as accurate as 32 plain ones "
            f"(error within {EQUAL_WITHIN}x) — holds on {len(holds_2)}/{len(chosen)} sequences; "
            f"median error ratio 8c/32p {median:.2f}."
        )
    return lines


# ------------------------------------------------------------------------------------ S2


def _iou(rows: list[dict], sequence: str, tracker: str) -> float:
    return next(r["mean_iou"] for r in rows
                if r["sequence"] == sequence and r["tracker"] == tracker)


def s2_motion_verdict(rows: list[dict], sequence: str) -> str:
    """Whether S2's failure logic follows the target where plain kernel mean shift does not:
    "holds" when S2's mean IoU on ``sequence`` is at least :data:`FOLLOWS_FROM` and higher than
    without the failure logic, "partly" when higher but below :data:`FOLLOWS_FROM`, else "fails"."""
    with_logic = _iou(rows, sequence, TRACKERS[0][0])
    without = _iou(rows, sequence, TRACKERS[1][0])
    measured = f"mean IoU {with_logic:.2f} vs {without:.2f} without failure logic"
    if with_logic == without:
        measured = f"the failure logic changes nothing: mean IoU {with_logic:.2f} with and without"
    if with_logic > without and with_logic >= FOLLOWS_FROM:
        return f"holds ({measured})"
    return f"partly ({measured})" if with_logic > without else f"fails ({measured})"


def s2_cost_verdict(row: dict) -> str:
    """Whether the kernel mean shift stage (the document times mean shift alone) costs at most
    the document's upper bound per frame."""
    us = row["kernel_meanshift_us"]
    low, high = DOCUMENT_US
    where = "inside" if low <= us <= high else ("below" if us < low else "above")
    verdict = "holds" if us <= high else "fails"
    return (f"{verdict} ({us:.0f} us, {where} the document's {low:.0f}-{high:.0f} us; "
            f"+ {row['kalman_us']:.0f} us Kalman)")


def s2_sentences(success: list[dict], cost: list[dict], seeds: int) -> list[str]:
    """One sentence per S2 claim, and what the failure logic does on the real sequences."""
    doc = next(r for r in cost if r["box"] == "32x20" and r["input"] == "I420")
    real = sorted({r["sequence"] for r in success} - set(claims_s2.SCENES))
    lines = [
        f"- **Fast motion** (follows a jump larger than the target that plain mean shift loses), "
        f"{seeds} seeds: `accelerate` scene (speeds up past its width per frame, which the "
        f"predictor anticipates): {s2_motion_verdict(success, 'accelerate')}; `jump` scene "
        f"(2.5 target widths in one frame out of a slow wobble, which no predictor anticipates): "
        f"{s2_motion_verdict(success, 'jump')}.",
        f"- **Full occlusion** (rides through ~13 hidden frames), {seeds} seeds: `cover` scene "
        f"(hidden at once for 18 frames): {s2_motion_verdict(success, 'cover')}; `occlusion` "
        f"scene (behind a slab, partly hidden before and after >= 18 hidden frames): "
        f"{s2_motion_verdict(success, 'occlusion')}.",
        f"- **Cost** (200 us - 1 ms per frame, 32x20 target, DSP): 1080p I420 here "
        f"{s2_cost_verdict(doc)}.",
    ]
    if real:
        means = {label: statistics.mean(r["auc"] for r in success
                                        if r["tracker"] == label and r["sequence"] in real)
                 for label, _, _ in TRACKERS}
        lines.append("- Real sequences (mean AUC over " + str(len(real)) + "): "
                     + ", ".join(f"{label} {auc:.3f}" for label, auc in means.items()) + ".")
    return lines


# ------------------------------------------------------------------------------ accuracy


def _runs(seq: Sequence, config: str, seeds: int,
          overrides: tuple[str, ...] = ()) -> list[RunSummary] | str:
    """The runs of ``config`` (with ``overrides``) on ``seq``, one per seed, or why the tracker
    refused it."""
    try:
        runs = [run_sequence(seq, config, seed, list(overrides)) for seed in range(seeds)]
    except VtrackError as exc:  # e.g. a hue tracker on grey footage: scores 0
        return str(exc)
    failed = [r.error for r in runs if r.status != "complete"]
    return failed[0] or "incomplete run" if failed else runs


def _seeds(config: str, accuracy_seeds: int) -> int:
    """S1 is stochastic: the mean of ``accuracy_seeds`` runs; the others are deterministic."""
    return accuracy_seeds if config == "s1" else 1


def accuracy(accuracy_seeds: int) -> tuple[list[str], dict[tuple[str, str], float]]:
    """The accuracy table (and a table of lost/occluded frames) on the real sequences, and the
    AUC of each (config, sequence) (0 for a failed run)."""
    sequences = single_target_sequences()
    if not sequences:
        return ["No benchmark sequences found (../shared/data or $VTRACK_DATA): accuracy "
                "skipped."], {}
    lines = [
        "| sequence | " + " | ".join(f"{c} AUC | {c} P@20 | {c} mIoU" for c in CONFIGS) + " |",
        "|---|" + "---:|" * (3 * len(CONFIGS)),
    ]
    lost_lines = ["| sequence | frames | " + " | ".join(f"{c} lost / occluded" for c in CONFIGS)
                  + " |", "|---|---:|" + "---:|" * len(CONFIGS)]
    scores: dict[str, list[tuple[float, float, float]]] = {c: [] for c in CONFIGS}
    aucs: dict[tuple[str, str], float] = {}
    failures = []
    for seq in sequences:
        cells, lost = [], []
        for config in CONFIGS:
            runs = _runs(seq, config, _seeds(config, accuracy_seeds))
            if isinstance(runs, str):
                failures.append(f"- fail: {seq.name} [{config}]: {runs}")
                scores[config].append((0.0, 0.0, 0.0))
                aucs[(config, seq.name)] = 0.0
                cells += ["fail"] * 3
                lost.append("fail")
                continue
            auc, p20, iou = (statistics.mean(getattr(r, key) or 0.0 for r in runs)
                             for key in ("auc", "precision20", "mean_overlap"))
            scores[config].append((auc, p20, iou))
            aucs[(config, seq.name)] = auc
            cells += [f"{auc:.3f}", f"{p20:.3f}", f"{iou:.3f}"]
            lost.append(_lost_occluded(runs))
        lines.append(f"| {seq.name} | " + " | ".join(cells) + " |")
        lost_lines.append(f"| {seq.name} | {len(read_boxes(seq.groundtruth, origin=1))} | "
                          + " | ".join(lost) + " |")
    means = [f"**{statistics.mean(v[i] for v in scores[c]):.3f}**" for c in CONFIGS
             for i in range(3)]
    lines.append("| **mean** (a failed run counts 0) | " + " | ".join(means) + " |")
    return [*lines, "", *failures, "", "Frames with no box claimed (lost) / occluded (box "
            "coasting on the prediction); S1: mean over seeds:", "", *lost_lines], aucs


def _lost_occluded(runs: list[RunSummary]) -> str:
    return (f"{statistics.mean(r.frames_lost for r in runs):.0f} / "
            f"{statistics.mean(r.frames_occluded for r in runs):.0f}")


def options(accuracy_seeds: int, shipped: dict[tuple[str, str], float]) -> list[str]:
    """AUC of each of :data:`OPTIONS` against its shipped config (``shipped``: the AUCs of
    :func:`accuracy`) on every real sequence, with the option's lost / occluded frames."""
    sequences = single_target_sequences()
    if not sequences or not shipped:
        return []
    lines = ["| sequence | " + " | ".join(f"{config} AUC | {label} AUC | {label} lost / occluded"
                                          for label, config, _ in OPTIONS) + " |",
             "|---|" + "---:|" * (3 * len(OPTIONS))]
    totals: dict[str, list[float]] = {label: [] for label, _, _ in OPTIONS}
    for seq in sequences:
        cells = []
        for label, config, overrides in OPTIONS:
            runs = _runs(seq, config, _seeds(config, accuracy_seeds), overrides)
            auc = 0.0 if isinstance(runs, str) else statistics.mean(r.auc or 0.0 for r in runs)
            totals[label].append(auc)
            cells += [f"{shipped[(config, seq.name)]:.3f}", f"{auc:.3f}",
                      "fail" if isinstance(runs, str) else _lost_occluded(runs)]
        lines.append(f"| {seq.name} | " + " | ".join(cells) + " |")
    means = []
    for label, config, _ in OPTIONS:
        base = statistics.mean(shipped[(config, seq.name)] for seq in sequences)
        means += [f"**{base:.3f}**", f"**{statistics.mean(totals[label]):.3f}**", ""]
    lines.append("| **mean** | " + " | ".join(means) + " |")
    return lines


# ---------------------------------------------------------------------------------- cost


def cost(rounds: int) -> list[str]:
    """Microseconds per frame per stage at 1080p for every config (median over ``rounds``)."""
    scene = make_scene("benchmark", seed=0, width=1920, height=1080, frames=120, fps=60)
    frames = [to_frame(i, scene.fps, bgr) for i, bgr in enumerate(scene.frames())]
    assert scene.boxes[0] is not None
    samples: dict[str, list[dict[str, float]]] = {c: [] for c in CONFIGS}
    ious: dict[str, float] = {}
    for _ in range(rounds):
        for config in CONFIGS:  # alternate, so drift of a shared machine hits all alike
            pipeline = Pipeline(load_config(config).build(), seed=0)
            predicted = [r.box for r in pipeline.track(frames, scene.boxes[0])]
            samples[config].append(pipeline.stage_microseconds_per_frame())
            ious[config] = summarize(predicted, scene.boxes)["mean_overlap"] or 0.0
    lines = ["| tracker | us/frame (sum of stages) | per stage (us/frame) | mean IoU |",
             "|---|---:|---|---:|"]
    for config in CONFIGS:
        stages = {name: statistics.median(s[name] for s in samples[config])
                  for name in samples[config][0]}
        per = ", ".join(f"{name} {us:.0f}" for name, us in stages.items())
        lines.append(f"| {config} | {sum(stages.values()):.0f} | {per} | {ious[config]:.3f} |")
    return lines


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--seeds", type=int, default=10, help="seeds of the claim tables")
    parser.add_argument("--accuracy-seeds", type=int, default=3, help="S1 seeds, accuracy table")
    parser.add_argument("--rounds", type=int, default=3, help="rounds of the 1080p cost")
    parser.add_argument("--quick", action="store_true", help="3 claim seeds, 1 S1 seed, 1 round")
    args = parser.parse_args()
    if args.quick:
        args.seeds, args.accuracy_seeds, args.rounds = 3, 1, 1
    command = ("python benchmarks/claims.py --quick" if args.quick else
               f"python benchmarks/claims.py --seeds {args.seeds} "
               f"--accuracy-seeds {args.accuracy_seeds} --rounds {args.rounds}")
    _print([f"Command: `{command}`  ", machine(), ""])

    _print(f"### S1 claims (CN105869186A), {args.seeds} seeds\n")
    rows = s1_claims(args.seeds)
    _print(claims_s1.claims_table(rows) + [""] + claims_s1.claims_summary(rows) + [""])
    _print(s1_sentences(rows) + [""])
    _print(claims_s1.cost_table(s1_cost()) + [""])
    _print(f"S1 leaving and coming back (`leave_return` scene, {args.seeds} seeds; delays: "
           "median [min..max] frames):\n")
    returns = claims_s1_return.return_rows(args.seeds)
    _print(claims_s1_return.return_table(returns) + [""])
    _print(claims_s1_return.return_sentences(returns) + [""])

    _print(f"### S2 claims (Di & Zhu 2008), generated scenes over {args.seeds} seeds\n")
    measured = s2_claims(args.seeds)
    success = [r for r in measured if "input" not in r]
    s2_cost = [r for r in measured if "input" in r]
    _print(claims_s2.success_table(success) + [""] + claims_s2.cost_table(s2_cost) + [""])
    _print([DOCUMENT_COST, ""] + s2_sentences(success, s2_cost, args.seeds) + [""])

    _print(f"### Accuracy on the real sequences (S1: mean of {args.accuracy_seeds} seeds)\n")
    table, shipped = accuracy(args.accuracy_seeds)
    _print(table + [""])
    if shipped:
        _print(f"Options that are not the documents' (README; S1: mean of {args.accuracy_seeds} "
               "seeds):\n")
        _print(options(args.accuracy_seeds, shipped) + [""])

    _print(f"### Cost per frame at 1080p (I420, 120 frames, median of {args.rounds} rounds)\n")
    _print(cost(args.rounds))


if __name__ == "__main__":
    main()
