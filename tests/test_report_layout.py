"""Report details (issue 12 item 8) on real runs of generated clips: the shading legend does
not cover the data, overlap over time uses the success plot's 0..1 scale, partial runs are
marked partial, and the "All inputs" row counts only the inputs it lists."""

from __future__ import annotations

import json
import math
import subprocess
import sys
from pathlib import Path

import pytest
from matplotlib.backends.backend_agg import FigureCanvasAgg
from matplotlib.colors import to_hex

from vtrack.report import build_report, plots
from vtrack.report.runs import load_run
from vtrack.scenes import make_scene, write_groundtruth, write_video

W, H = 160, 120


def vtrack_run(clip: Path, out: Path, *args: str) -> subprocess.CompletedProcess:
    return subprocess.run([sys.executable, "-m", "vtrack", "run", str(clip), "--no-video",
                           "--quiet", "--out", str(out), *args], capture_output=True, text=True,
                          timeout=120, check=False)


def clip_with_gt(folder: Path, scenario: str, frames: int, ext: str = ".mp4"
                 ) -> tuple[Path, Path]:
    scene = make_scene(scenario, seed=0, width=W, height=H, frames=frames, fps=30)
    clip = write_video(scene, folder / f"{scenario}{ext}")
    return clip, write_groundtruth(scene, folder / f"{scenario}.gt.txt")


@pytest.fixture(scope="module")
def occluded_run(tmp_path_factory: pytest.TempPathFactory) -> Path:
    folder = tmp_path_factory.mktemp("layout")
    clip, gt = clip_with_gt(folder, "occlusion", 60)
    done = vtrack_run(clip, folder / "run", "--gt", str(gt), "-c", "s0")
    assert done.returncode == 0, done.stderr
    return folder / "run"


def test_overlap_plot_legend_is_outside_the_data_and_uses_the_success_scale(
        occluded_run: Path) -> None:
    run = load_run(occluded_run)
    assert run.frames_occluded > 0, "the occlusion scene should make S0 report occlusion"
    palette = plots.colours([run.config])
    figure = plots.overlap_figure("occlusion", [run, run], palette)
    curves = plots.curves_figure("occlusion", {run.config: run.scores.success},
                                 {run.config: run.scores.precision}, palette)
    renderer = FigureCanvasAgg(figure).get_renderer()
    figure.draw(renderer)
    (legend,) = figure.legends
    assert "occluded" in [t.get_text() for t in legend.get_texts()]
    box = legend.get_window_extent(renderer)
    for axis in figure.axes:
        assert not box.overlaps(axis.get_window_extent(renderer)), "legend covers a panel"
        assert axis.get_legend() is None
        assert axis.get_ylim() == curves.axes[0].get_ylim() == plots.SCORE_YLIM
        (line,) = axis.get_lines()
        values = [v for v in line.get_ydata() if v == v]
        assert max(values) <= 1.0 + 1e-9 and values == [o for o in run.overlaps if o is not None]


def test_overlap_panels_show_each_run_whole_at_its_own_frame_numbers(
        tmp_path: Path) -> None:
    """The panels share one frame axis, and each set its own limit: the last one's (a 20-frame
    run) cut the 60-frame run above it; a run from --start 10 was drawn from 0."""
    clip, gt = clip_with_gt(tmp_path, "occlusion", 60)
    for name, args in (("whole", []), ("short", ["--frames", "20"]), ("late", ["--start", "10"])):
        done = vtrack_run(clip, tmp_path / name, "--gt", str(gt), "-c", "s0", *args)
        assert done.returncode == 0, done.stderr
    runs = [load_run(tmp_path / name) for name in ("whole", "late", "short")]
    figure = plots.overlap_figure("occlusion", runs, plots.colours([runs[0].config]))
    for axis, run, first in zip(figure.axes, runs, (0, 10, 0), strict=True):
        assert axis.get_xlim() == (-0.5, 59.5)
        (line,) = axis.get_lines()
        assert list(line.get_xdata()) == list(range(first, first + len(run.overlaps)))


def table_rows(markdown: str, heading: str) -> list[list[str]]:
    """Body rows of the first table after ``heading`` in summary.md (bold marks removed)."""
    lines = markdown.split(heading, 1)[1].splitlines()
    start = next(i for i, x in enumerate(lines) if x.startswith("|"))
    end = next((i for i in range(start, len(lines)) if not lines[i].startswith("|")), len(lines))
    return [[c.strip().strip("*") for c in x.strip("|").split("|")] for x in lines[start + 2:end]]


def test_partial_runs_are_marked_and_averages_count_only_listed_inputs(
        tmp_path: Path, occluded_run: Path) -> None:
    # a partial run: the video is cut in half
    clip, gt = clip_with_gt(tmp_path, "smooth", 90, ".mkv")
    cut = tmp_path / "cut.mkv"
    data = clip.read_bytes()
    cut.write_bytes(data[: len(data) // 2])
    done = vtrack_run(cut, tmp_path / "runs" / "cut", "--gt", str(gt), "-c", "s1")
    assert done.returncode == 1, done.stderr
    partial = json.loads((tmp_path / "runs" / "cut" / "run.json").read_text())
    assert partial["status"] == "partial"
    # a run without ground truth that loses its target: not scored, so not an average input
    leave, leave_gt = clip_with_gt(tmp_path, "leave_return", 90)
    first = leave_gt.read_text().splitlines()[0]
    done = vtrack_run(leave, tmp_path / "runs" / "leave", "--init", first, "-c", "s1")
    assert done.returncode == 0, done.stderr
    unscored = json.loads((tmp_path / "runs" / "leave" / "run.json").read_text())
    assert unscored["summary"]["frames_lost"] > 0, "S1 should lose the target that leaves"

    report = build_report([tmp_path / "runs", occluded_run], tmp_path / "report")
    markdown = report.markdown.read_text()
    results = {row[0]: row for row in table_rows(markdown, "## Results per input")}
    total = partial["input"]["frame_count"]
    assert results["cut"][2] == f"partial: {partial['frames']} of {total} frames"
    assert results["occlusion"][2] == "complete"
    averages = {row[0]: row for row in table_rows(markdown, "## All inputs")}
    assert set(averages) == {"s0", "s1 (1 partial)"}
    s1 = averages["s1 (1 partial)"]
    assert int(s1[1]) == 1  # the one s1 input with ground truth, as the plot counts it
    assert int(s1[-1]) == partial["summary"]["frames_lost"]  # not the unscored run's
    s0 = averages["s0"]
    assert int(s0[-1]) == json.loads((occluded_run / "run.json").read_text())[
        "summary"]["frames_lost"]


def test_a_one_frame_run_is_drawn_at_a_whole_frame(tmp_path: Path) -> None:
    """The overlap plot of a one-frame run (--frames 1, or a one-frame clip) was an empty
    panel, a line of one point not being drawn, over frames -0.4 .. 0.4."""
    import numpy as np
    from matplotlib.colors import to_rgb

    clip, gt = clip_with_gt(tmp_path, "smooth", 10)
    done = vtrack_run(clip, tmp_path / "one", "--gt", str(gt), "-c", "s2", "--frames", "1")
    assert done.returncode == 0, done.stderr
    run = load_run(tmp_path / "one")
    assert len(run.overlaps) == 1 and run.overlaps[0] > 0.9
    palette = plots.colours([run.config])
    figure = plots.overlap_figure("smooth", [run], palette)
    canvas = FigureCanvasAgg(figure)
    canvas.draw()
    pixels = np.asarray(canvas.buffer_rgba())[:, :, :3].astype(int)
    colour = np.array(to_rgb(palette[run.config])) * 255
    (axis,) = figure.axes
    box = axis.get_window_extent()
    height = pixels.shape[0]
    panel = pixels[int(height - box.y1) + 1:int(height - box.y0) - 1,
                   int(box.x0) + 1:int(box.x1) - 1]
    assert (np.abs(panel - colour).max(axis=2) < 40).sum() >= 4, "the run's frame is not drawn"
    low, high = axis.get_xlim()
    assert [t for t in axis.get_xticks() if low <= t <= high] == [0]  # not -0.4, -0.2 ...


def test_curves_of_configurations_sharing_a_colour_differ_in_style() -> None:
    # 14 configurations: the colours come round again (c10 took c00's blue, c09 now does),
    # and the best 10 here hold four such pairs
    names = [f"c{n:02d}" for n in range(14)]
    best = {n: 0.9 - n / 100 if n < 6 or n >= 9 else 0.1 for n in range(14)}
    curves = {name: plots.OVERLAP_THRESHOLDS * 0 + best[n] for n, name in enumerate(names)}
    precision = {c: plots.ERROR_THRESHOLDS * 0 + v[0] for c, v in curves.items()}
    figure = plots.curves_figure("many", curves, precision, plots.colours(names))
    for axis in figure.axes:
        drawn = [(line.get_label(), line.get_color(), line.get_linestyle())
                 for line in axis.get_lines() if not line.get_label().startswith("_")]
        assert len(drawn) == plots.MAX_LEGEND and {"c00", "c09"} <= {d[0][:3] for d in drawn}
        looks = [look for _, *look in drawn]
        assert len(set(map(tuple, looks))) == len(looks), drawn  # each curve told apart


def test_no_curve_a_legend_names_is_grey_as_those_it_does_not() -> None:
    names = [f"c{n:02d}" for n in range(12)]  # the 8th by name took tab10's grey, C7
    curves = {name: plots.OVERLAP_THRESHOLDS * 0 + 0.9 - n / 100 for n, name in enumerate(names)}
    precision = {c: plots.ERROR_THRESHOLDS * 0 + v[0] for c, v in curves.items()}
    figure = plots.curves_figure("many", curves, precision, plots.colours(names))
    for axis in figure.axes:
        named = {line.get_label()[:3]: to_hex(line.get_color()) for line in axis.get_lines()
                 if not line.get_label().startswith("_")}
        assert "c07" in named and to_hex("C7") not in named.values(), named


def test_averages_over_inputs_alike_for_every_config_are_ranked_without_notes(
        tmp_path: Path) -> None:
    """An input whose ground truth never shows the target (`gone`: 90 lines 0,0,0,0) has no
    score for any config, and camshift and s0 both have no miss flagged on `smooth` (no frame
    misses): every config's averages are over the same inputs. The All inputs row said
    "0.581 (on 2 of 3 inputs)" in every score of every config and marked no best; the
    averages are now ranked as usual, no cell saying over how many, and `gone`'s heading
    says once that no frame is evaluated there."""
    (tmp_path / "in").mkdir()
    for scenario in ("jump", "smooth"):
        clip_with_gt(tmp_path / "in", scenario, 90)
    scene = make_scene("smooth", seed=0, width=W, height=H, frames=90, fps=30)
    write_video(scene, tmp_path / "in" / "gone.mp4")
    (tmp_path / "in" / "gone.gt.txt").write_text("0,0,0,0\n" * 90)
    (tmp_path / "in" / "gone.init.txt").write_text("30,80,20,16\n")
    done = subprocess.run([sys.executable, "-m", "vtrack", "batch", str(tmp_path / "in"),
                           "-c", "camshift", "-c", "s0", "--no-video", "--quiet", "--out",
                           str(tmp_path / "res")], capture_output=True, text=True,
                          timeout=300, check=False)
    assert done.returncode == 0, done.stderr
    names = ("gone", "jump", "smooth")
    runs = {(name, config): load_run(tmp_path / "res" / name / config)
            for name in names for config in ("camshift", "s0")}
    for config in ("camshift", "s0"):  # (what the test stands on)
        assert runs["gone", config].scores.frames_evaluated == 0
        assert math.isnan(runs["smooth", config].scores.miss_flagged)
        assert runs["jump", config].scores.miss_flagged >= 0
    build_report([tmp_path / "res"], tmp_path / "report")
    markdown = (tmp_path / "report" / "summary.md").read_text()
    header = markdown.split("## All inputs", 1)[1].split("| Config |", 1)[1].split("\n")[0]
    columns = ["Config", *(c.strip() for c in header.strip("|").split("|"))]
    lines = [x for x in markdown.split("## All inputs", 1)[1].split("## ", 1)[0].splitlines()
             if x.startswith("| camshift") or x.startswith("| s0")]
    cells = {row[0].strip(): dict(zip(columns, (c.strip() for c in row), strict=True))
             for row in (x.strip("|").split("|") for x in lines)}
    for config in ("camshift", "s0"):
        assert cells[config]["Inputs"] == "3"
        assert not any("inputs" in text for text in cells[config].values()), cells[config]
        flagged = runs["jump", config].scores.miss_flagged
        assert cells[config]["Miss flagged"] == f"{flagged:.3f}"
    auc = {c: (runs["jump", c].scores.auc + runs["smooth", c].scores.auc) / 2
           for c in ("camshift", "s0")}
    best = max(auc, key=auc.get)
    assert auc[best] > min(auc.values())
    assert {c for c in auc if cells[c]["AUC"].startswith("**")} == {best}, cells
    assert cells[best]["AUC"] == f"**{auc[best]:.3f}**"
    gone = markdown.split("## gone", 1)[1].split("## ", 1)[0]
    assert "No frame evaluated" in gone and "No frame evaluated" not in markdown.split(
        "## gone", 1)[0]


def test_an_input_with_no_frame_evaluated_is_not_counted_in_the_all_inputs_plot(
        tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    """`gone` (ground truth 0,0,0,0 on every frame) beside `smooth`: the All inputs plot,
    whose curves average `smooth` alone, was titled "mean over 2 inputs", and `gone`'s note
    said "the All inputs averages are over the other inputs" even in a report of `gone`
    alone. The title counts the inputs with a frame evaluated ("mean over 1 input"), and the
    note says so of other inputs only when another input has a score."""
    scene = make_scene("smooth", seed=0, width=W, height=H, frames=40, fps=30)
    gone = write_video(scene, tmp_path / "gone.mp4")
    (tmp_path / "gone.gt.txt").write_text("0,0,0,0\n" * 40)
    smooth, gt = clip_with_gt(tmp_path, "smooth", 40)
    for clip, truth, init in ((gone, tmp_path / "gone.gt.txt", ["--init", "30,80,20,16"]),
                              (smooth, gt, [])):
        done = vtrack_run(clip, tmp_path / "runs" / clip.stem, "--gt", str(truth), "-c", "s0",
                          *init)
        assert done.returncode == 0, done.stderr
    titles: list[str] = []
    drawn = plots.curves_figure

    def curves_figure(title: str, *args: object, **kwargs: object) -> object:
        titles.append(title)
        return drawn(title, *args, **kwargs)

    monkeypatch.setattr(plots, "curves_figure", curves_figure)
    build_report([tmp_path / "runs"], tmp_path / "both")
    assert titles == ["smooth", "All inputs (mean over 1 input)"], titles
    markdown = (tmp_path / "both" / "summary.md").read_text()
    assert "so no run has a score here, and the All inputs averages are over the other " \
           "inputs." in markdown.split("## gone", 1)[1], markdown
    build_report([tmp_path / "runs" / "gone"], tmp_path / "alone")
    markdown = (tmp_path / "alone" / "summary.md").read_text()
    assert "so no run has a score here." in markdown, markdown
    assert "other inputs" not in markdown, markdown
    # the other input's only run failed part way: left out of the All inputs plot, so no
    # average is over it (the note said there was one)
    record = tmp_path / "runs" / "smooth" / "run.json"
    record.write_text(record.read_text().replace('"status": "complete"', '"status": "failed"', 1))
    titles.clear()
    build_report([tmp_path / "runs"], tmp_path / "failed")
    assert "All inputs (mean over 1 input)" not in titles, titles
    markdown = (tmp_path / "failed" / "summary.md").read_text()
    assert "so no run has a score here." in markdown, markdown
    assert "other inputs" not in markdown, markdown


def test_the_all_inputs_plot_says_which_curves_are_over_fewer_inputs(
        tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    """s0 run on `smooth` and `occlusion`, s2 on `smooth` alone: the All inputs plot, titled
    "mean over 2 inputs", labelled s2's curve with its `smooth` score alone ("s2 [0.9..]"),
    ranked beside s0's mean over both, while the table's row said "(on 1 of 2 inputs)". Its
    legend now says so too, on both plots; s0's, over every input, says nothing more."""
    for scenario, configs in (("smooth", ("s0", "s2")), ("occlusion", ("s0",))):
        clip, gt = clip_with_gt(tmp_path, scenario, 60)
        for config in configs:
            done = vtrack_run(clip, tmp_path / "runs" / config / scenario, "--gt", str(gt),
                              "-c", config)
            assert done.returncode == 0, done.stderr
    legends: dict[str, list[list[str]]] = {}
    drawn = plots.curves_figure

    def curves_figure(title: str, *args: object, **kwargs: object) -> object:
        figure = drawn(title, *args, **kwargs)
        legends[title] = [[t.get_text() for t in axis.get_legend().get_texts()]
                          for axis in figure.axes]
        return figure

    monkeypatch.setattr(plots, "curves_figure", curves_figure)
    report = build_report([tmp_path / "runs"], tmp_path / "report")
    runs = {(r.input, r.config): r for r in report.runs}
    s0 = next(c for i, c in runs if c.startswith("s0"))
    s2 = next(c for i, c in runs if c.startswith("s2"))
    mean_auc = (runs["smooth", s0].scores.auc + runs["occlusion", s0].scores.auc) / 2
    success, precision = legends["All inputs (mean over 2 inputs)"]
    assert sorted(success) == sorted([
        f"{s0} [{mean_auc:.3f}]",
        f"{s2} [{runs['smooth', s2].scores.auc:.3f}, on 1 of 2 inputs]"]), success
    assert f"{s2} [{runs['smooth', s2].scores.precision20:.3f}, on 1 of 2 inputs]" in precision
    # an input's own plot has no such note: each curve there is the run's own
    assert not any("inputs" in label for label in sum(legends["smooth"], []))
