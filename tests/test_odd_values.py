"""Values a user can type that the file system or NumPy take badly (found by a hostile probe):
names too long for a file system, a NUL in a path, a negative zero; and matplotlib's own notes
kept off the report's terminal."""

from __future__ import annotations

import json
import subprocess
import sys
from pathlib import Path

import pytest

from vtrack.config import load_config
from vtrack.errors import ConfigError
from vtrack.scenes import make_scene, write_groundtruth, write_video

LONG = "a" * 300


def _vtrack(*args: str, cwd: Path) -> subprocess.CompletedProcess[str]:
    return subprocess.run([sys.executable, "-m", "vtrack", *args], capture_output=True,
                          text=True, timeout=300, check=False, cwd=cwd)


@pytest.fixture(scope="module")
def clip(tmp_path_factory: pytest.TempPathFactory) -> Path:
    folder = tmp_path_factory.mktemp("odd")
    scene = make_scene("smooth", seed=2, width=160, height=120, frames=12, fps=30)
    write_groundtruth(scene, folder / "clip.gt.txt")
    return write_video(scene, folder / "clip.mp4")


@pytest.mark.parametrize("where", ["config", "out"])
def test_a_name_too_long_for_the_file_system_is_one_line(clip: Path, tmp_path: Path,
                                                         where: str) -> None:
    """A 300-character config file name or --out folder was an OSError traceback (ENAMETOOLONG,
    exit 1)."""
    args = ["run", str(clip), "--gt", str(clip.with_suffix(".gt.txt")), "--no-video"]
    args += ["-c", f"{LONG}.toml", "-o", "out"] if where == "config" else ["-o", LONG]
    done = _vtrack(*args, cwd=tmp_path)
    assert done.returncode == 2, done.stderr
    lines = done.stderr.strip().splitlines()
    assert len(lines) == 1 and lines[0].startswith("vtrack: error: "), lines
    assert ("File name too long" in lines[0] if where == "config"
            else "longer than 255 bytes" in lines[0])
    assert list(tmp_path.iterdir()) == []


@pytest.mark.parametrize("option", ["--out", "--stream"])
def test_a_path_too_long_for_the_system_is_one_line(clip: Path, tmp_path: Path,
                                                    option: str) -> None:
    """A path of names each short enough but longer than the system takes (4096 bytes) was an
    OSError traceback (ENAMETOOLONG, exit 1); a 300-byte --stream name too."""
    deep = "/".join(["d" * 250] * 17)
    for path in (deep, LONG) if option == "--stream" else (deep,):
        done = _vtrack("run", str(clip), "--gt", str(clip.with_suffix(".gt.txt")), "--no-video",
                       *(["-o", path] if option == "--out" else ["-o", "out", option, path]),
                       cwd=tmp_path)
        assert done.returncode == 2, done.stderr
        lines = done.stderr.strip().splitlines()
        assert len(lines) == 1 and lines[0].startswith(
            f"vtrack: error: Invalid value for '{option}"), lines
        assert "longer than" in lines[0]
    assert list(tmp_path.iterdir()) == []


def test_a_nul_in_a_path_parameter_is_refused_when_the_config_loads(tmp_path: Path) -> None:
    """`path = "det\\u0000.txt"` ran, failed at the first frame with a ValueError traceback and
    left a failed run.json and a tracks.csv."""
    config = tmp_path / "nul.toml"
    config.write_text('[[stage]]\nname = "mot_detections"\npath = "det\\u0000.txt"\n'
                      '[[stage]]\nname = "byte_tracks"\n')
    with pytest.raises(ConfigError, match=r"nul.toml: stage 'mot_detections': parameter 'path' "
                       "must not contain a NUL character"):
        load_config(config)


def test_a_negative_zero_is_zero(clip: Path, tmp_path: Path) -> None:
    """`--set particle.spread=-0` passed the range check (-0.0 >= 0), then NumPy's uniform
    refused it at frame 1 with a traceback."""
    assert load_config("s1").with_overrides(["particle.spread=-0"]).stages[0][1]["spread"] == 0
    done = _vtrack("run", str(clip), "--gt", str(clip.with_suffix(".gt.txt")), "-c", "s1",
                   "--set", "particle.spread=-0", "--no-video", "-o", "out", cwd=tmp_path)
    assert done.returncode == 0, done.stderr
    assert json.loads((tmp_path / "out" / "run.json").read_text())["frames"] == 12


def test_a_box_that_rounds_to_zero_shows_0_not_minus_0(tmp_path: Path) -> None:
    """`vtrack run --init -1e-9,0,10,10 -c s0 grey.mp4` said "no pixel of the initial box
    -0,0,10,10 passes the hue stage's saturation/value mask": a message's box (Box.text) showed
    a value that rounds to zero as -0. It shows 0 now."""
    from vtrack.geometry import Box

    assert Box(-1e-9, -0.004, 10, 10).text() == "0,0,10,10"
    scene = make_scene("grey", seed=0, width=96, height=72, frames=10, fps=30)
    grey = write_video(scene, tmp_path / "grey.mp4")
    done = _vtrack("run", "--init", "-1e-9,0,10,10", "-c", "s0", str(grey), "--no-video",
                   "-o", "out", cwd=tmp_path)
    assert done.returncode == 2, done.stderr
    assert "no pixel of the initial box 0,0,10,10 passes" in done.stderr, done.stderr


def test_a_negative_zero_outside_a_box_text_shows_0(clip: Path, tmp_path: Path) -> None:
    """Box.text showed -0 as 0, number_text did not: `vtrack.track(clip, init_box=(-0.0, 0, 2,
    2), config='s0')` said "the box -0,0,2,2 is smaller...", `--fps=-0.0` "--fps -0: ...".
    Both say 0 now."""
    import vtrack as library

    with pytest.raises(library.ConfigError) as caught:
        list(library.track(str(clip), init_box=(-0.0, 0, 2, 2), config="s0"))
    assert str(caught.value).startswith("init_box: the box 0,0,2,2 is smaller"), caught.value
    done = _vtrack("run", str(clip), "--init", "10,10,20,20", "--fps=-0.0", "--no-video", "-o",
                   "out", cwd=tmp_path)
    assert done.returncode == 2, done.stderr
    assert done.stderr.startswith("vtrack: error: --fps 0: must be a frame rate"), done.stderr


def test_the_report_keeps_matplotlibs_notes_off_the_terminal(clip: Path, tmp_path: Path) -> None:
    """A config named with an emoji and a long name: matplotlib printed UserWarnings (a missing
    glyph, a layout it could not apply) among vtrack's own lines."""
    config = tmp_path / "odd.toml"
    config.write_text('name = "' + "\U0001F3AF" + "long" * 30 + '"\n'
                      + "".join(f'[[stage]]\nname = "{s}"\n'
                                for s in ("hue", "backproject", "meanshift", "kalman")))
    run = _vtrack("run", str(clip), "--gt", str(clip.with_suffix(".gt.txt")), "-c",
                  str(config), "--no-video", "-o", "res", cwd=tmp_path)
    assert run.returncode == 0, run.stderr
    report = _vtrack("report", "res", "-o", "rep", cwd=tmp_path)
    assert report.returncode == 0, report.stderr
    assert "Warning" not in report.stderr and "warn(" not in report.stderr, report.stderr
    assert (tmp_path / "rep" / "index.html").is_file()


def test_a_long_value_is_cut_between_its_characters_not_inside_an_escape() -> None:
    """A value shown cut (params.shown) was cut on its quoted text, which could split a typed
    backslash from the ``udcff`` after it: the message then showed a byte the user never gave
    (``--start`` of 100 a's, the six characters \\udcff, 32 b's named ``\\xff``). Now the
    characters are cut, then quoted: the shown text holds no character the value did not."""
    import ast

    from vtrack.params import shown

    typed = "a" * 100 + "\\udcff" + "b" * 32
    text = shown(typed)
    assert len(text) <= 90 and "..." in text
    assert set(ast.literal_eval(text)) <= set(typed) | {"."}
    bytes_not_utf8 = "\udcff" * 60
    assert len(shown(bytes_not_utf8)) <= 90



def test_a_long_plain_value_is_shown_to_about_80_characters() -> None:
    """9fd9031 left no room for the quote marks: every plain string over 80 characters was
    halved and shown in 43 (``shown('a' * 100)``); reprlib showed 80. Now ~80, escapes and a
    typed backslash still whole."""
    import ast

    from vtrack.params import shown

    for value in ("a" * 100, "abcdefghij" * 10, "é" * 200):
        text = shown(value)
        assert 75 <= len(text) <= 80 and "..." in text, text
    typed = "\\" * 100
    text = shown(typed)
    assert 70 <= len(text) <= 80 and set(ast.literal_eval(text)) <= {"\\", "."}, text


@pytest.mark.parametrize(("args", "said"), [
    (("--set", "\udcff.a=1"), "stage '\\xff' is not in the chain"),
    (("--set", "robust_model.\udcff=1"), "unknown parameter '\\xff'"),
    (("--set", "robust_model.padding=\udcff"),
     "must be a number in the range 0.2 to 4, got '\\xff'"),
    (("--init", "\udcff"), "got '\\xff'"),
])
def test_a_byte_not_utf8_in_vtracks_own_errors_is_written_as_usage_messages_write_it(
        clip: Path, tmp_path: Path, args: tuple[str, ...], said: str) -> None:
    """Usage messages said a byte that is not UTF-8 as ``\\xff``, vtrack's own errors as
    Python's ``\\udcff`` (`--set $'\\xff'.a=1`: "stage '\\udcff' is not in the chain",
    `--init $'\\xff'`: "got '\\udcff'"). Now both as ``\\xff``."""
    init = () if args[0] == "--init" else ("--init", "10,10,20,20")
    done = _vtrack("run", str(clip), *init, *args, "--no-video", "-o", "o", cwd=tmp_path)
    lines = done.stderr.splitlines()
    assert done.returncode == 2 and len(lines) == 1, done.stderr
    assert said in lines[0] and "udc" not in lines[0], lines[0]
    assert not (tmp_path / "o").exists()
