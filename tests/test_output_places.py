"""Issue 21 items 5, 6 and 7: files are written only where they belong. A batch config's
`name` cannot lead outside `--out`; inputs whose stems clash keep results folders of their own;
`--out ""` is refused; `vtrack report` never replaces a batch's `summary.csv`."""

from __future__ import annotations

import csv
import shutil
from pathlib import Path

import pytest
from test_cli import assert_one_line_error, vtrack

from vtrack.batch import find_inputs
from vtrack.scenes import make_scene, write_groundtruth, write_video

W, H, FRAMES = 64, 48, 20


@pytest.fixture(scope="module")
def clip(tmp_path_factory: pytest.TempPathFactory) -> tuple[Path, Path]:
    folder = tmp_path_factory.mktemp("places")
    scene = make_scene("smooth", seed=1, width=W, height=H, frames=FRAMES, fps=30.0)
    write_video(scene, folder / "occ.mp4")
    write_groundtruth(scene, folder / "occ.gt.txt")
    return folder / "occ.mp4", folder / "occ.gt.txt"


def one_input(folder: Path, clip: tuple[Path, Path], name: str = "occ.mp4") -> Path:
    folder.mkdir(parents=True, exist_ok=True)
    shutil.copy(clip[0], folder / name)
    shutil.copy(clip[1], folder / f"{Path(name).stem}.gt.txt")
    return folder


@pytest.mark.parametrize("name", ["/tmp/victim", "../../../x", ".", "..", "a/b",
                                  "x" * 300, "\u00e9" * 150])  # longer than a folder name may be
def test_a_config_name_stays_one_folder_inside_out(clip, tmp_path: Path, name: str) -> None:
    folder = one_input(tmp_path / "in", clip)
    config = tmp_path / "mine.toml"
    shipped = (Path(__file__).parents[1] / "vtrack" / "configs" / "s0.toml").read_text()
    body = shipped.replace('name = "s0"', f"name = {name!r}".replace("'", '"'), 1)
    config.write_text(body)
    out = tmp_path / "deep" / "er" / "out"
    victim = Path("/tmp/victim")
    existed = victim.exists()

    def outside() -> list[Path]:
        return sorted(p for p in tmp_path.rglob("*") if out not in (p, *p.parents)
                      and p not in out.parents)

    before = outside()
    result = vtrack("batch", str(folder), "-c", str(config), "--no-video", "-o", str(out))
    assert result.returncode == 0, result.stderr.decode()
    written = [p for p in out.rglob("track.csv")]
    assert len(written) == 1, written
    run_dir = written[0].parent
    assert run_dir.parent == out / "occ" and run_dir.name not in ("", ".", "..")
    assert len(run_dir.name.encode()) <= 200
    assert outside() == before
    assert victim.exists() == existed


def test_clashing_stems_get_folders_of_their_own(clip, tmp_path: Path) -> None:
    folder = tmp_path / "in"
    for name in ("a.mp4", "a.avi", "a.mp4.mkv"):
        one_input(folder, clip, name)
    (folder / "a.gt.txt").write_text(clip[1].read_text())
    (folder / "a.mp4.gt.txt").write_text(clip[1].read_text())
    names = [item.name for item in find_inputs(folder)]
    assert sorted(names) == ["a.avi", "a.mp4", "a.mp4.mkv"]
    out = tmp_path / "out"
    for _ in range(2):  # and a resume keeps all three
        result = vtrack("batch", str(folder), "-c", "s0", "--no-video", "-o", str(out))
        assert result.returncode == 0, result.stderr.decode()
        with (out / "summary.csv").open() as handle:
            rows = list(csv.DictReader(handle))
        assert sorted(r["input"] for r in rows) == sorted(names)
        assert all((out / n / "s0" / "track.csv").is_file() for n in names)


@pytest.mark.parametrize("command", ["run", "batch", "report", "frame"])
def test_an_empty_out_is_refused(clip, tmp_path: Path, command: str) -> None:
    work = tmp_path / "cwd"
    work.mkdir()
    (work / "track.csv").write_text("mine\n")
    target = {"run": str(clip[0]), "batch": str(clip[0].parent), "frame": str(clip[0]),
              "report": str(tmp_path)}[command]
    extra = ["--gt", str(clip[1])] if command == "run" else []
    result = vtrack(command, target, *extra, "--out", "", cwd=work)
    assert_one_line_error(result, "--out", "empty")
    assert result.returncode == 2
    assert sorted(p.name for p in work.iterdir()) == ["track.csv"]
    assert (work / "track.csv").read_text() == "mine\n"


def test_report_does_not_replace_a_batch_summary(clip, tmp_path: Path) -> None:
    folder = one_input(tmp_path / "in", clip)
    out = tmp_path / "results"
    assert vtrack("batch", str(folder), "-c", "s0", "--no-video", "-o", str(out)).returncode == 0
    kept = (out / "summary.csv").read_bytes()
    result = vtrack("report", str(out), "--out", str(out))
    assert_one_line_error(result, "summary.csv", "another folder")
    assert (out / "summary.csv").read_bytes() == kept
    result = vtrack("report", str(out), "--out", str(out / "occ" / "s0"))
    assert_one_line_error(result, "run's results folder")
    assert vtrack("report", str(out), "--out", str(tmp_path / "rep")).returncode == 0


def test_a_run_and_a_batch_do_not_write_into_each_others_results(clip, tmp_path: Path
                                                                  ) -> None:
    """`vtrack run ... -o BATCH` wrote its run.json and track.csv beside the batch's
    summary.csv, and `vtrack batch ... -o RUN` its summary.csv and input folders into a run's
    folder (exit 0 both): a report of either then mixed the two. Each is now one line, exit 2,
    nothing written; a folder holding some other summary.csv is still a run's to take."""
    folder = one_input(tmp_path / "in", clip)
    batch = tmp_path / "batch"
    assert vtrack("batch", str(folder), "-c", "s0", "--no-video", "-o", str(batch)
                  ).returncode == 0
    before = sorted(p.relative_to(batch) for p in batch.rglob("*"))
    result = vtrack("run", str(clip[0]), "--gt", str(clip[1]), "-c", "s0", "--no-video",
                    "-y", "-o", str(batch))
    assert_one_line_error(result, str(batch), "batch's results folder", "another --out")
    assert result.returncode == 2
    run = batch / "occ" / "s0"
    result = vtrack("batch", str(folder), "-c", "s0", "--no-video", "-o", str(run))
    assert_one_line_error(result, str(run), "run's results folder", "another --out")
    assert result.returncode == 2
    assert sorted(p.relative_to(batch) for p in batch.rglob("*")) == before
    other = tmp_path / "mine"
    other.mkdir()
    (other / "summary.csv").write_text("name,value\na,1\n")
    assert vtrack("run", str(clip[0]), "--gt", str(clip[1]), "-c", "s0", "--no-video",
                  "-o", str(other)).returncode == 0
    assert (other / "run.json").is_file()


def test_a_batch_folder_holding_another_index_html_is_still_a_batch(clip, tmp_path: Path
                                                                     ) -> None:
    """A batch folder holding an index.html that is not a vtrack report's (the user's own page)
    was no batch: a report of it left out its failed runs and `vtrack report X --out` it
    replaced its summary.csv. Only a page vtrack wrote makes a report's folder; a batch is
    refused an --out holding one, as a report is refused a batch's folder."""
    folder = one_input(tmp_path / "in", clip)
    (folder / "bad.mp4").write_bytes(b"not a video at all")
    batch = tmp_path / "mixd"
    batch.mkdir()
    (batch / "index.html").write_text("<html>notes</html>\n")
    assert vtrack("batch", str(folder), "-c", "s0", "--no-video", "-o", str(batch)
                  ).returncode == 1
    kept = (batch / "summary.csv").read_bytes()
    report = tmp_path / "rep"
    assert vtrack("report", str(batch), "--out", str(report)).returncode == 0
    assert "bad" in (report / "index.html").read_text()
    result = vtrack("report", str(report), "--out", str(batch))
    assert_one_line_error(result, "summary.csv", "another folder")
    assert (batch / "summary.csv").read_bytes() == kept
    before = sorted(p.relative_to(report) for p in report.rglob("*"))
    result = vtrack("batch", str(folder), "-c", "s0", "--no-video", "-o", str(report))
    assert_one_line_error(result, str(report), "vtrack report's folder", "another --out")
    assert result.returncode == 2
    assert sorted(p.relative_to(report) for p in report.rglob("*")) == before


def test_a_run_does_not_write_into_a_reports_folder(clip, tmp_path: Path) -> None:
    """`vtrack run ... -o REPORT` (a folder `vtrack report` wrote) was taken, exit 0: its
    run.json and track.csv went beside the report's index.html and summary.csv. It is one line
    naming the folder, exit 2, nothing written; a folder that already holds an earlier run's
    results (run.json) keeps the overwrite rules, whatever else it holds."""
    folder = one_input(tmp_path / "in", clip)
    batch = tmp_path / "batch"
    assert vtrack("batch", str(folder), "-c", "s0", "--no-video", "-o", str(batch)
                  ).returncode == 0
    report = tmp_path / "rep"
    assert vtrack("report", str(batch), "--out", str(report)).returncode == 0
    before = sorted(p.relative_to(report) for p in report.rglob("*"))
    result = vtrack("run", str(clip[0]), "--gt", str(clip[1]), "-c", "s0", "--no-video",
                    "-y", "-o", str(report))
    assert_one_line_error(result, f"{report}: is a vtrack report's folder", "another --out")
    assert result.returncode == 2
    assert sorted(p.relative_to(report) for p in report.rglob("*")) == before
    ran = batch / "occ" / "s0"  # an earlier run's folder that also holds a report's page
    for name in ("index.html", "summary.md"):
        shutil.copy(report / name, ran / name)
    result = vtrack("run", str(clip[0]), "--gt", str(clip[1]), "-c", "s0", "--no-video",
                    "-o", str(ran))
    assert_one_line_error(result, "earlier run", "--overwrite")
    assert vtrack("run", str(clip[0]), "--gt", str(clip[1]), "-c", "s0", "--no-video", "-y",
                  "-o", str(ran)).returncode == 0


def test_a_sequences_images_given_as_input_name_the_results_after_the_sequence(
        clip_factory, tmp_path: Path) -> None:
    """Probe O: `vtrack run PETS/img1 -c fixed_camera` wrote vtrack-out/img1/fixed_camera (its
    run.json naming the input PETS), so `vtrack run TUD/img1 -c fixed_camera` of a second camera
    was refused: 'vtrack-out/img1/fixed_camera: holds the results of an earlier run'. A
    sequence's img/ or img1/ now names its results after the sequence, as the run records it
    and a batch names its folder."""
    images = clip_factory("multi", width=W, height=H, frames=60, fmt="images").path
    for camera, folder in (("camA", "img1"), ("camB", "img1"), ("camC", "img")):
        shutil.copytree(images / "img", tmp_path / camera / folder)
    for camera, folder in (("camA", "img1"), ("camB", "img1/"), ("camC", "img")):
        result = vtrack("run", f"{camera}/{folder}", "-c", "fixed_camera", "--no-video",
                        cwd=tmp_path)
        assert result.returncode == 0, result.stderr.decode()
        assert (tmp_path / "vtrack-out" / camera / "fixed_camera" / "run.json").is_file()
    inside = tmp_path / "camC" / "img"
    assert vtrack("run", ".", "-c", "fixed_camera", "--no-video", "-o", "x", cwd=inside
                  ).returncode == 0
    assert (inside / "x" / "run.json").is_file()
    result = vtrack("frame", "img", "--at", "0", cwd=inside.parent)
    assert result.returncode == 0, result.stderr.decode()
    assert (inside.parent / "camC-frame0.png").is_file()  # not img-frame0.png
