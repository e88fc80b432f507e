"""Issue 21 item 4: a run that fails before its first frame is out (the tracker refuses the
target, exit 2) leaves its folder as it was: the earlier run's files stay, byte for byte."""

from __future__ import annotations

from pathlib import Path

import pytest
from test_cli import assert_one_line_error, vtrack

from vtrack import Tracker
from vtrack.errors import InputError
from vtrack.scenes import make_scene, write_groundtruth, write_video


def clip(folder: Path, scenario: str) -> tuple[Path, Path]:
    scene = make_scene(scenario, seed=0, width=96, height=72, frames=60, fps=30.0)
    write_video(scene, folder / f"{scenario}.mp4")
    write_groundtruth(scene, folder / f"{scenario}.gt.txt")
    return folder / f"{scenario}.mp4", folder / f"{scenario}.gt.txt"


def snapshot(folder: Path) -> dict[str, bytes]:
    return {p.name: p.read_bytes() for p in sorted(folder.iterdir())}


@pytest.mark.parametrize("video", [True, False])
def test_a_run_refused_at_frame_0_leaves_the_folder_as_it_was(tmp_path: Path,
                                                              video: bool) -> None:
    colour, grey = clip(tmp_path, "smooth"), clip(tmp_path, "grey")
    out = tmp_path / "out"
    flags = [] if video else ["--no-video"]
    first = vtrack("run", str(colour[0]), "--gt", str(colour[1]), "-c", "s0", "-o", str(out))
    assert first.returncode == 0, first.stderr.decode()
    before = snapshot(out)
    assert {"annotated.mp4", "track.csv", "run.json"} <= set(before)
    again = vtrack("run", str(grey[0]), "--gt", str(grey[1]), "-c", "s0", *flags, "-y", "-o",
                   str(out))
    assert_one_line_error(again, "no colour")
    assert again.returncode == 2
    assert snapshot(out) == before


def test_a_refused_run_into_a_new_folder_leaves_no_folder(tmp_path: Path) -> None:
    grey = clip(tmp_path, "grey")
    result = vtrack("run", str(grey[0]), "--gt", str(grey[1]), "-c", "s0",
                    "-o", str(tmp_path / "new" / "out"))
    assert result.returncode == 2
    assert not (tmp_path / "new").exists()


@pytest.mark.parametrize(("config", "start"), [("s0", "0"), ("camshift", "5")])
def test_a_stage_refusing_the_first_frame_names_the_input_and_frame(tmp_path: Path, config: str,
                                                                    start: str) -> None:
    """A stage's refusal of the first frame said `backproject: no pixel of the initial box ...`
    without the input it was about; it now begins with the input and the refused frame, as the
    run's other input errors do. The library keeps the stage's own words."""
    grey = clip(tmp_path, "grey")
    result = vtrack("run", str(grey[0]), "--init", "30,20,24,18", "-c", config, "--start",
                    start, "-o", str(tmp_path / "out"))
    line = assert_one_line_error(result, "no colour")
    assert line.startswith(f"vtrack: error: {grey[0]}: frame {start}: backproject: no pixel "), line
    assert result.returncode == 2
    assert not (tmp_path / "out").exists()
    picture = make_scene("grey", seed=0, width=96, height=72, frames=10, fps=30.0).frame(0)
    with pytest.raises(InputError, match=r"^backproject: no pixel of the initial box"):
        Tracker(config).init(picture, (30, 20, 24, 18))


def test_the_librarys_first_frame_refusal_is_the_stages_own_exception() -> None:
    """The pipeline raised a new FirstFrameError in place of a stage's (``raise exc.at(index)
    from None``): the traceback ended in the pipeline, not at the stage's line that refused,
    and a subclass of FirstFrameError came back as the base class. The stage's own exception
    now goes on, given the refused frame's index."""
    import traceback

    from vtrack.errors import FirstFrameError

    picture = make_scene("grey", seed=0, width=96, height=72, frames=10, fps=30.0).frame(0)
    with pytest.raises(FirstFrameError) as caught:
        Tracker("s0").init(picture, (30, 20, 24, 18))
    assert caught.value.frame_index == 0
    refused_in = traceback.extract_tb(caught.value.__traceback__)[-1]
    assert Path(refused_in.filename).parts[-2:] == ("stages", "backproject.py"), refused_in
