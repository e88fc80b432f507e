"""Config files as users write them, hostile ones too: each problem is one line naming the file
(and the stage and parameter when there is one), exit 2, no traceback, whichever command reads
the config (``run``, ``batch``, ``stages``)."""

from __future__ import annotations

import json
import re
from pathlib import Path
from typing import TYPE_CHECKING

import pytest
from click.testing import CliRunner, Result
from conftest import one_error_line

from vtrack.cli import main
from vtrack.errors import ConfigError
from vtrack.stages.base import all_stages
from vtrack.tracker import Tracker

if TYPE_CHECKING:
    from conftest import ClipFactory

CHAIN_TAIL = '[[stage]]\nname = "backproject"\n[[stage]]\nname = "meanshift"\n'


def vtrack(*args: str) -> Result:
    return CliRunner().invoke(main, list(args))


def refusals(config: Path, tmp_path: Path) -> list[str]:
    """The error line of each command given ``config``: run, batch and stages."""
    folder = tmp_path / "inputs"
    folder.mkdir(exist_ok=True)
    return [one_error_line(vtrack(*args)) for args in (
        ("run", "in.mp4", "-c", str(config), "--init", "1,1,9,9", "--out", str(tmp_path / "o")),
        ("batch", str(folder), "-c", str(config), "--out", str(tmp_path / "b")),
        ("stages", str(config)),
    )]


@pytest.mark.parametrize(("text", "said"), [
    ('name = "x"\nk = ' + "[" * 5000 + "]" * 5000 + "\n",
     "arrays or tables nested too deeply to read (a config's values are numbers, text and "
     "true/false)"),
    ('name = "x"\nk = ' + "{a = " * 3000 + "}" * 3000 + "\n", "nested too deeply to read"),
    ("name = " + "1" * 5000 + "\n", "an integer of more than 4300 digits, too long to read"),
], ids=["arrays", "inline-tables", "5000-digits"])
def test_a_config_toml_cannot_turn_into_values_is_one_line(text: str, said: str,
                                                          tmp_path: Path) -> None:
    """A 50 kB config of 5000 nested arrays (or 3000 nested inline tables) ended `vtrack run`,
    `batch` and `stages` with a traceback: 'RecursionError: maximum recursion depth exceeded';
    `name = 111...` (5000 digits) with 'ValueError: Exceeds the limit (4300 digits) for integer
    string conversion ... use sys.set_int_max_str_digits()'."""
    config = tmp_path / "deep.toml"
    config.write_text(text)
    for line in refusals(config, tmp_path):
        assert line.startswith(f"vtrack: error: {config}: ") and said in line, line


@pytest.mark.parametrize(("param", "value", "said"), [
    ("sat_min", "0x" + "f" * 5000, "parameter 'sat_min' must be in the range 0 to 255, got an "
                                   "integer of more than 4000 digits"),
    ("search_scale", "0x" + "f" * 5000, "parameter 'search_scale' must be in the range 1 to 16, "
                                        "got an integer of more than 4000 digits"),
    ("mask_model_only", "0x" + "f" * 5000, "parameter 'mask_model_only' must be true or false, "
                                           "got an integer of more than 4000 digits"),
    ("hue_scale", '"' + "x" * 900_000 + '"', "parameter 'hue_scale' must be one of 'full', "
                                            "'opencv', got 'xxxxxxxx"),
    ("sat_min", "[" + "1, " * 200_000 + "]", "parameter 'sat_min' must be an integer in the "
                                             "range 0 to 255, got [1, 1, 1, 1, 1, 1, ...]"),
    ("k" * 900_000, "1", "unknown parameter 'kkkkkkkk"),
], ids=["int", "float", "bool", "long-text", "long-array", "long-name"])
def test_a_huge_value_in_a_config_is_named_in_a_short_line(param: str, value: str, said: str,
                                                           tmp_path: Path) -> None:
    """`sat_min = 0xfff...` (5000 hex digits) ended vtrack with a traceback, 'ValueError:
    Exceeds the limit (4300 digits) for integer string conversion' (search_scale:
    'OverflowError: int too large to convert to float'); a 900 kB string, array or parameter
    name was echoed whole: a 900 kB error line."""
    config = tmp_path / "huge.toml"
    config.write_text(f'name = "x"\n[[stage]]\nname = "hue"\n{param} = {value}\n{CHAIN_TAIL}')
    for line in refusals(config, tmp_path):
        assert line.startswith(f"vtrack: error: {config}: stage 'hue': "), line[:300]
        assert said in line and len(line) < 400, line[:300]


@pytest.mark.parametrize(("value", "got"), [
    ("1e400", "got a number beyond a float's range"),
    ("-1_000e400", "got a number beyond a float's range"),
    ("inf", "got inf, not a finite number"),
    ("-inf", "got -inf, not a finite number"),
    ("nan", "got nan, not a number"),
], ids=["1e400", "-1e400", "inf", "-inf", "nan"])
def test_a_number_that_is_not_finite_is_named_as_the_user_wrote_it(value: str, got: str,
                                                                  tmp_path: Path) -> None:
    """`search_scale = 1e400` in a config file (tomllib reads inf) said 'must be a finite
    number in the range 1 to 16, got inf', and `--set hue.search_scale=inf` the same, in
    words the user did not write (1e400 is no inf; a finite number is what it is not)."""
    config = tmp_path / "big.toml"
    config.write_text(f'name = "x"\n[[stage]]\nname = "hue"\nsearch_scale = {value}\n'
                      f"{CHAIN_TAIL}")
    said = f"stage 'hue': parameter 'search_scale' must be in the range 1 to 16, {got}"
    for line in refusals(config, tmp_path):
        assert line == f"vtrack: error: {config}: {said}", line
    line = one_error_line(vtrack("run", "in.mp4", "-c", "s0", "--set",
                                 f"hue.search_scale={value}", "--init", "1,1,9,9"))
    assert line == f"vtrack: error: --set hue.search_scale={value}: {said}", line


def test_a_huge_value_given_to_the_tracker_is_named_in_a_short_line() -> None:
    """Tracker("s0", hue__search_scale=10**400) raised 'OverflowError: int too large to convert
    to float', hue__sat_min=16**5000 'ValueError: Exceeds the limit (4300 digits)', and a
    1,000,000-character hue_scale was echoed twice: a 2 MB message."""
    with pytest.raises(ConfigError, match=r"^hue.search_scale=an integer of 401 digits: stage "
                       r"'hue': parameter 'search_scale' must be in the range 1 to 16, got an "
                       r"integer of 401 digits$"):
        Tracker("s0", hue__search_scale=10**400)
    with pytest.raises(ConfigError, match="parameter 'sat_min' must be in the range 0 to 255, "
                       "got an integer of more than 4000 digits$"):
        Tracker("s0", hue__sat_min=16**5000)
    with pytest.raises(ConfigError, match="parameter 'hue_scale' must be one of") as caught:
        Tracker("s0", hue__hue_scale="x" * 1_000_000)
    assert len(str(caught.value)) < 400


@pytest.mark.parametrize("args", [
    ("run", "in.mp4", "-c", "LONG", "--init", "1,1,9,9"),
    ("run", "in.mp4", "-c", "d/LONG.toml", "--init", "1,1,9,9"),
    ("stages", "LONG"),
    ("run", "in.mp4", "-c", "s0", "--set", "LONG", "--init", "1,1,9,9"),
    ("run", "in.mp4", "-c", "s0", "--set", "hue.sat_min=LONG", "--init", "1,1,9,9")])
def test_an_overlong_config_name_or_set_value_is_cut_in_its_line(args: tuple[str, ...]) -> None:
    """A 100000-character config name gave a 100054-character "one line" (`vtrack stages` a
    traceback: OSError File name too long); such a value is now cut, its length said."""
    given = [arg.replace("LONG", "a" * 100_000) for arg in args]
    line = one_error_line(vtrack(*given))
    assert len(line) < 1000, line[:1000]
    long = max(given, key=len)
    assert f"{long[:100]}...{long[-30:]} ({len(long)} characters)" in line, line


@pytest.mark.parametrize(("text", "said"), [
    ('nmae = "x"\n[[stage]]\nname = "hue"\n', "unknown top-level key(s) 'nmae'"),
    ("name = \n", "not valid TOML")])
def test_a_readable_config_at_a_long_path_is_named_cut_when_refused(
        tmp_path: Path, text: str, said: str) -> None:
    """A config file at a 250-character path that could be read but not taken (a key it
    lacks, TOML it is not) was refused naming the whole path, though a file it could not read
    was named cut (and the path is kept whole only in run.json's record)."""
    folder = tmp_path / ("c" * 120) / ("d" * 120)
    folder.mkdir(parents=True)
    config = folder / "mine.toml"
    config.write_text(text)
    line = one_error_line(vtrack("run", "in.mp4", "-c", str(config), "--init", "1,1,9,9"))
    long = str(config)
    assert f"{long[:100]}...{long[-30:]} ({len(long)} characters): {said}" in line, line


def test_a_config_at_a_long_path_is_named_cut_in_later_refusals(
        tmp_path: Path, clip_factory: ClipFactory) -> None:
    """A config at a 2000-character path was named whole in the refusals built later from
    its source (no box given to a tracker that needs one; two batch --configs of one results
    folder, either way round), though the refusals of the file itself cut it. Cut there too;
    run.json's record keeps it whole."""
    folder = tmp_path.joinpath(*["d" * 200] * 10)
    folder.mkdir(parents=True)
    config = folder / "s0.toml"
    config.write_text(vtrack("stages", "s0", "--toml").stdout)
    long = str(config)
    named = f"{long[:100]}...{long[-30:]} ({len(long)} characters)"
    clip = clip_factory("smooth", width=160, height=120, frames=10)
    alone = tmp_path / "alone.mp4"  # no ground truth or initial box beside it
    alone.write_bytes(clip.path.read_bytes())
    inputs = tmp_path / "inputs"
    inputs.mkdir()
    lines = [one_error_line(vtrack(*args)) for args in (
        ("run", str(alone), "-c", long, "--no-video", "-o", str(tmp_path / "o")),
        ("batch", str(inputs), "-c", long, "-c", "s0", "-o", str(tmp_path / "b")),
        ("batch", str(inputs), "-c", "s0", "-c", long, "-o", str(tmp_path / "b")))]
    for line in lines:
        assert long not in line and named in line and len(line) < 1000, line[:1000]
    assert "this tracker needs an initial box" in lines[0]
    assert "another config has the results folder of 's0'" in lines[1]
    run = tmp_path / "run"
    assert vtrack("run", str(clip.path), "-c", long, "--init", clip.gt.read_text().split()[0],
                  "--no-video", "-o", str(run)).exit_code == 0
    assert json.loads((run / "run.json").read_text())["config"]["source"] == long


def test_a_long_config_path_is_named_cut_in_refusals_of_the_loaded_config(
        tmp_path: Path, clip_factory: ClipFactory) -> None:
    """Refusals the Config builds once loaded named a 2000-character path whole: a
    mot_detections stage with no path (vtrack run, and a Tracker), a --set whose value
    contradicts another parameter. Cut there too."""
    folder = tmp_path.joinpath(*["d" * 200] * 10)
    folder.mkdir(parents=True)
    mot = folder / "mot.toml"
    mot.write_text('[[stage]]\nname = "mot_detections"\n[[stage]]\nname = "kalman_tracks"\n')
    robust = folder / "robust.toml"
    robust.write_text(vtrack("stages", "robust", "--toml").stdout)
    clip = clip_factory("smooth", width=160, height=120, frames=10)
    box = clip.gt.read_text().split()[0]
    lines = [one_error_line(vtrack("run", str(clip.path), "--no-video", "-o",
                                   str(tmp_path / "o"), *args)) for args in (
        ("-c", str(mot)),
        ("-c", str(robust), "--init", box, "--set", "robust_search.interp_scales=5"))]
    with pytest.raises(ConfigError) as info:
        Tracker(config=str(mot))
    lines.append(str(info.value))
    for line, config in zip(lines, (mot, robust, mot), strict=True):
        named = f"{str(config)[:100]}...{str(config)[-30:]} ({len(str(config))} characters)"
        assert str(config) not in line and named in line and len(line) < 1000, line[:1000]
    assert "stage 'mot_detections': parameter 'path' must name the file it reads" in lines[0]
    assert "interp_scales (5) is smaller than scales (17)" in lines[1]


def test_an_empty_name_given_to_stages_says_what_it_takes() -> None:
    """`vtrack stages ''` said ': not a stage, a shipped config or a config file (stages: ...)',
    naming nothing, where `vtrack run -c ''` says what --config takes."""
    line = one_error_line(vtrack("stages", "s0", ""))
    assert "'[STAGE|CONFIG]...': empty; give a stage's name, a shipped config's name or a TOML " \
           "file (vtrack stages lists them)" in line, line


@pytest.mark.parametrize(("head", "said"), [
    ('nmae = "x"\n', "unknown top-level key(s) 'nmae' (expected name, description, [[stage]]); "
     "did you mean 'name'?"),
    ('nmae = "x"\ndescriptoin = "y"\nfoo = 1\n',
     "unknown top-level key(s) 'descriptoin', 'foo', 'nmae' (expected name, description, "
     "[[stage]]); did you mean 'description' for 'descriptoin', 'name' for 'nmae'?"),
    ("foo = 1\n", "unknown top-level key(s) 'foo' (expected name, description, [[stage]])"),
    ('name = "x"\nNAME = "y"\n', "unknown top-level key(s) 'NAME' (expected name, "
     "description, [[stage]])"),
    ("".join(f"k{i} = 1\nnam{i} = 2\n" for i in range(8)),
     "unknown top-level key(s) 'k0', 'k1', 'k2', 'k3', 'k4' and 11 more (expected name, "
     "description, [[stage]]); did you mean 'name' for 'nam0', 'name' for 'nam1', 'name' for "
     "'nam2', 'name' for 'nam3', 'name' for 'nam4' and 3 more?")])
def test_a_mistyped_top_level_key_is_offered_the_near_one(tmp_path: Path, head: str,
                                                          said: str) -> None:
    """`nmae = "s0"` in a config was refused with no suggestion, where a mistyped stage or
    parameter gets one ("did you mean ..."); a key near none of them still gets none. `NAME`
    beside `name` was asked "did you mean 'name'?" (a key the file has), and 16 unknown keys
    were all listed, each with its guess: the first 5 and how many more now."""
    config = tmp_path / "my4.toml"
    config.write_text(head + CHAIN_TAIL)
    for line in refusals(config, tmp_path):
        assert line == f"vtrack: error: {config}: {said}", line


def test_a_config_saved_as_utf16_says_so(tmp_path: Path) -> None:
    """A config saved by Windows Notepad as "Unicode" (UTF-16 with its byte-order mark) was
    refused 'config is not text (not UTF-8)': it is text, in another encoding."""
    config = tmp_path / "mine.toml"
    config.write_bytes(f'name = "x"\n[[stage]]\nname = "hue"\n{CHAIN_TAIL}'.encode("utf-16"))
    for line in refusals(config, tmp_path):
        assert line == f"vtrack: error: {config}: config is UTF-16 text; vtrack reads UTF-8 " \
                       "(save it as UTF-8)", line
    config.write_bytes(b'\xef\xbb\xbfname = "x"\r\n[[stage]]\r\nname = "hue"\r\n'
                       + CHAIN_TAIL.replace("\n", "\r\n").encode())  # UTF-8, BOM, CRLF: read
    assert vtrack("stages", str(config)).exit_code == 0


@pytest.mark.parametrize(("chain", "said"), [
    (("hue_bp_fixed", "kernel_meanshift_int"),
     "stages hue_bp_fixed and kernel_meanshift_int both keep the chain's fixed-point record, "
     "each of its own document's model (S0, S2): a chain computes one"),
    (("kernel_meanshift_int", "kalman_f32"),
     "stage 'kalman_f32': it reads the S0 fixed-point record of hue_bp_fixed, which must come "
     "before it (kernel_meanshift_int keeps S2's, another model)"),
], ids=["two-records", "s2-record-read-as-s0"])
def test_a_chain_mixing_the_fixed_point_models_is_refused_when_loaded(
        chain: tuple[str, ...], said: str, tmp_path: Path) -> None:
    """A config chaining hue_bp_fixed (S0's fixed-point stages) with kernel_meanshift_int
    (S2's) was taken, then its run failed at frame 1, after writing its outputs, with
    'meanshift_fixed and kalman_f32 read the S0 record of hue_bp_fixed, which must be the last
    fixed-point stage before them', naming two stages not in the chain and no file;
    kernel_meanshift_int then kalman_f32 the same at frame 0."""
    config = tmp_path / "mix.toml"
    config.write_text('name = "mix"\n' + "".join(f'[[stage]]\nname = "{n}"\n' for n in chain))
    for line in refusals(config, tmp_path):
        assert line == f"vtrack: error: {config}: {said}", line


def test_a_folder_given_to_stages_is_named_a_folder_as_run_names_it(
        tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    """`vtrack stages mine` (mine a folder) said 'mine: not a stage, a shipped config or a
    config file (stages: ...)' where `vtrack run -c mine` says 'mine: is a folder, not a config
    file'."""
    monkeypatch.chdir(tmp_path)
    (tmp_path / "mine").mkdir()
    assert one_error_line(vtrack("stages", "mine")) == \
        "vtrack: error: mine: is a folder, not a config file"
    (tmp_path / "hue").mkdir()  # a stage's name is the stage
    assert vtrack("stages", "hue").output.startswith("hue: ")


def test_a_detections_file_left_unnamed_is_refused_before_a_batch_runs(
        tmp_path: Path, clip_factory: ClipFactory) -> None:
    """A config of mot_detections -> byte_tracks without `path` was taken: `vtrack batch` ran
    every input, each failing with "stage 'mot_detections': parameter 'path' must name a
    det.txt file (...)", no config file named, then '1 run (1 failed)', exit 1; `vtrack run`
    and Tracker said the same at the first frame. It is one line naming the file now, before
    anything runs (exit 2); --set names the file as before."""
    clip = clip_factory("multi", width=160, height=120, frames=60)
    config = tmp_path / "det.toml"
    config.write_text('name = "det"\n[[stage]]\nname = "mot_detections"\n'
                      '[[stage]]\nname = "byte_tracks"\n')
    said = (f"vtrack: error: {config}: stage 'mot_detections': parameter 'path' must name the "
            'file it reads (path = "FILE" in its [[stage]] table, or --set '
            "mot_detections.path=FILE)")
    folder = tmp_path / "inputs"
    folder.mkdir()
    (folder / clip.path.name).symlink_to(clip.path)
    assert one_error_line(vtrack("batch", str(folder), "-c", str(config), "--no-video",
                                 "--out", str(tmp_path / "b"))) == said
    assert not (tmp_path / "b").exists()
    assert one_error_line(vtrack("run", str(clip.path), "-c", str(config), "--no-video",
                                 "--out", str(tmp_path / "r"))) == said
    with pytest.raises(ConfigError, match="parameter 'path' must name the file it reads"):
        Tracker(str(config))
    det = tmp_path / "det.txt"
    det.write_text("1,-1,10,10,20,20,0.9,-1,-1,-1\n")
    result = vtrack("run", str(clip.path), "-c", str(config), "--set",
                    f"mot_detections.path={det}", "--no-video", "--out", str(tmp_path / "s"))
    assert result.exit_code == 0, result.output


def test_a_detections_file_with_an_empty_box_is_refused_naming_its_line(
        tmp_path: Path, clip_factory: ClipFactory) -> None:
    """`vtrack run clip.mp4 -c det.toml` (mot_detections -> byte_tracks) on a det.txt whose
    second row has w -20 ran (exit 0, tracks.csv written), the row dropped without a word. It
    is one line naming the file and the line now, exit 2, nothing written."""
    clip = clip_factory("multi", width=160, height=120, frames=60)
    det = tmp_path / "det.txt"
    det.write_text("1,-1,10,10,20,20,0.9\n2,-1,10,10,-20,20,0.9\n")
    config = tmp_path / "det.toml"
    config.write_text(f'name = "det"\n[[stage]]\nname = "mot_detections"\npath = "{det}"\n'
                      '[[stage]]\nname = "byte_tracks"\n')
    line = one_error_line(vtrack("run", str(clip.path), "-c", str(config), "--no-video", "-q",
                                 "--out", str(tmp_path / "o")))
    assert line == (f"vtrack: error: {det} line 2: a detection's w and h must be > 0, got "
                    "w -20, h 20")
    assert not (tmp_path / "o").exists()


@pytest.mark.parametrize("text", ["", "\n \n"])
def test_an_empty_detections_file_is_no_detection_with_a_warning(
        tmp_path: Path, clip_factory: ClipFactory, text: str) -> None:
    """`vtrack run clip.mp4 -c det.toml` (mot_detections -> byte_tracks) on an empty det.txt (a
    detector that found nothing in the scene) was refused, "det.txt: MOT file is empty", while
    an empty gt.txt scores. It runs now, no detection in any frame (tracks.csv has no row), and
    warns of it on stderr and in run.json."""
    clip = clip_factory("multi", width=160, height=120, frames=60)
    det = tmp_path / "det.txt"
    det.write_text(text)
    config = tmp_path / "det.toml"
    config.write_text(f'name = "det"\n[[stage]]\nname = "mot_detections"\npath = "{det}"\n'
                      '[[stage]]\nname = "byte_tracks"\n')
    out = tmp_path / "o"
    result = vtrack("run", str(clip.path), "-c", str(config), "--no-video", "-q",
                    "--out", str(out))
    assert result.exit_code == 0, result.output
    note = (f"{det}: the file holds no detection (0 bytes or blank lines only): no frame had "
            "any to track")
    assert result.stderr == f"vtrack: warning: {note}\n"
    assert json.loads((out / "run.json").read_text())["warnings"] == [note]
    assert (out / "tracks.csv").read_text().splitlines()[1:] == []


@pytest.mark.parametrize("shipped", ["robust", "fixed_camera", "s0"])
def test_a_shipped_config_printed_as_toml_loads_back_as_the_same_chain(
        tmp_path: Path, shipped: str) -> None:
    """A config file leaves its stages' defaults where it says nothing (robust's stages'
    defaults are not robust's values): ``vtrack stages CONFIG --toml`` prints the whole shipped
    file to start one's own from, and that file is the same chain as the shipped config."""
    from vtrack.config import load_config

    printed = vtrack("stages", shipped, "--toml")
    assert printed.exit_code == 0, printed.output
    mine = tmp_path / "mine.toml"
    mine.write_text(printed.stdout)
    assert load_config(str(mine)).stages == load_config(shipped).stages
    again = vtrack("stages", str(mine), "--toml")
    assert again.exit_code == 0 and again.stdout == printed.stdout


@pytest.mark.parametrize(("args", "said"), [
    (("stages", "hue", "--toml"), "hue: a stage, not a config"),
    (("stages", "--toml"), "give one CONFIG"),
    (("stages", "s0", "s2", "--toml"), "give one CONFIG"),
    (("stages", "missing.toml", "--toml"), "missing.toml: config file not found"),
])
def test_toml_of_anything_but_one_config_is_one_line(args: tuple[str, ...], said: str) -> None:
    assert said in one_error_line(vtrack(*args))



@pytest.mark.parametrize(("config", "first", "second", "equal", "said"), [
    ("fixed_camera", "blobs.min_area=100", "blobs.max_area=10", "blobs.max_area=100",
     "stage 'blobs': min_area (100) is larger than max_area (10): no blob would be kept; "
     "lower min_area, or raise max_area (0: no limit)"),
    ("fixed_camera", "byte_tracks.low=0.9", "byte_tracks.high=0.1", "byte_tracks.high=0.9",
     "stage 'byte_tracks': low (0.9) is above high (0.1): no detection would score from low "
     "up to high (ByteTrack's second pass); give low <= high"),
    ("robust", "robust_search.scales=33", "robust_search.interp_scales=17",
     "robust_search.interp_scales=33",
     "stage 'robust_search': interp_scales (17) is smaller than scales (33): the response of "
     "33 scale samples is interpolated up to interp_scales, never down; give interp_scales >= "
     "scales (equal: no interpolation, DSST)"),
], ids=["areas", "scores", "scales"])
def test_contradictory_parameter_pairs_are_refused_naming_both(
        config: str, first: str, second: str, equal: str, said: str,
        clip_factory: ClipFactory, tmp_path: Path) -> None:
    """`vtrack run clip.mp4 -c fixed_camera --set blobs.min_area=100 --set blobs.max_area=10`
    (no blob can be kept) and `--set byte_tracks.low=0.9 --set byte_tracks.high=0.1` (no
    detection reaches the second pass) ran without a word (0 tracks, exit 0), as did
    `-c robust --set robust_search.scales=33 --set robust_search.interp_scales=17` (fDSST
    interpolates the scale response up, never down: it silently ran with 33). All are
    refused in one line naming both parameters, in a run and in the API; equal values (a
    blob of exactly that area, no second pass, DSST's uninterpolated scales) still run."""
    clip = clip_factory("multi", width=160, height=120, frames=60)
    box = ("--init", "20,20,16,16") if config == "robust" else ()
    line = one_error_line(vtrack("run", str(clip.path), "-c", config, *box, "--set", first,
                                 "--set", second, "--no-video", "-q", "--out",
                                 str(tmp_path / "o")))
    assert line == f"vtrack: error: {config}: {said}"
    assert not (tmp_path / "o").exists()
    values = {key.replace(".", "__"): json.loads(value)
              for key, value in (first.split("="), second.split("="))}
    with pytest.raises(ConfigError, match=f"^{config}: {re.escape(said)}$"):
        Tracker(config, **values)
    done = vtrack("run", str(clip.path), "-c", config, *box, "--set", first, "--set", equal,
                  "--no-video", "-q", "--out", str(tmp_path / "eq"))
    assert done.exit_code == 0, done.output


def test_scales_past_interp_scales_run_when_the_scale_filter_is_off(
        clip_factory: ClipFactory, tmp_path: Path) -> None:
    """`vtrack run clip.mp4 -c robust --init ... --set robust_search.scale=false --set
    robust_search.scales=33 --set robust_search.interp_scales=17` was refused ("interp_scales
    (17) is smaller than scales (33)"), though with the scale filter off neither is used; as
    blobs' min_area past a max_area of 0 (no limit), the pair is checked only where it counts:
    the run and the API take it, and track as with the filter off and the defaults."""
    clip = clip_factory("multi", width=160, height=120, frames=60)
    off = ("--set", "robust_search.scale=false")
    pair = ("--set", "robust_search.scales=33", "--set", "robust_search.interp_scales=17")
    for name, sets in (("pair", off + pair), ("alone", off)):
        done = vtrack("run", str(clip.path), "-c", "robust", "--init", "20,20,16,16", *sets,
                      "--no-video", "-q", "--out", str(tmp_path / name))
        assert done.exit_code == 0, done.output
    assert (tmp_path / "pair" / "track.csv").read_text() == \
        (tmp_path / "alone" / "track.csv").read_text()
    Tracker("robust", robust_search__scale=False, robust_search__scales=33,
            robust_search__interp_scales=17)


def test_a_value_of_the_wrong_type_is_refused_with_its_range_in_the_same_line(
        tmp_path: Path) -> None:
    """`search_scale = "2"` (a string for a number) said "parameter 'search_scale' must be a
    number, got '2'" and `hue_scale = 1` "must be a string, got 1": what the value may be was
    left to `vtrack stages`, unlike a number out of range ("must be in the range 1 to 16"). Now
    every parameter of every stage, given a value of another type, names its type and its
    declared range or choices in the line that refuses it (the whole line checked, true/false
    and text parameters too: bool ones and mot_detections.path)."""
    config = tmp_path / "typed.toml"
    config.write_text(f'name = "x"\n[[stage]]\nname = "hue"\nsearch_scale = "2"\n{CHAIN_TAIL}')
    for line in refusals(config, tmp_path):
        assert line == (f"vtrack: error: {config}: stage 'hue': parameter 'search_scale' must "
                        "be a number in the range 1 to 16, got '2'"), line
    kinds = {int: "an integer", float: "a number", bool: "true or false", str: "a string"}
    for name, cls in all_stages().items():
        for param in cls.params:
            wrong = 1 if param.type is str else "x"
            with pytest.raises(ConfigError) as refused:
                param.validate(wrong, f"mine.toml: stage '{name}'")
            wanted = kinds[param.type]
            if param.min is not None and param.max is not None:
                wanted += f" in the range {param.range_text()}"
            elif param.choices is not None:
                wanted += ", one of " + ", ".join(repr(c) for c in param.choices)
            assert str(refused.value) == (f"mine.toml: stage '{name}': parameter "
                                          f"'{param.name}' must be {wanted}, got {wrong!r}")


@pytest.mark.parametrize(("text", "said"), [
    ('[stage]\nname = "hue"\n', "stage is one table ([stage]), not a list of them: write each "
                                "stage as a [[stage]] table (two brackets), in the order of the "
                                "chain"),
    ('stage = "hue"\n', "stage = 'hue': write each stage as a [[stage]] table (name = \"hue\" "
                        "...), in the order of the chain"),
], ids=["one-bracket", "text"])
def test_stages_not_written_as_stage_tables_are_told_how_to_write_them(
        text: str, said: str, tmp_path: Path) -> None:
    """A config of `[stage]` (one bracket: a table, not an array of tables) or `stage = "hue"`
    was told "no [[stage]] tables: a config is a chain of stages", as if it had none."""
    config = tmp_path / "one.toml"
    config.write_text(text)
    for line in refusals(config, tmp_path):
        assert line == f"vtrack: error: {config}: {said}", line


def test_a_stage_named_twice_is_refused_before_its_values(tmp_path: Path) -> None:
    """A chain naming hue twice, the second with `sat_min = 999`, said "stage 'hue': parameter
    'sat_min' must be in the range 0 to 255, got 999" (which of the two hue tables was left
    unsaid), and only once that was fixed "stage 'hue' appears 2 times". The repeated stage is
    the mistake named first; an unknown name still before it."""
    config = tmp_path / "twice.toml"
    config.write_text(f'[[stage]]\nname = "hue"\n{CHAIN_TAIL}[[stage]]\nname = "hue"\n'
                      "sat_min = 999\n")
    for line in refusals(config, tmp_path):
        assert line == (f"vtrack: error: {config}: stage 'hue' appears 2 times; a chain runs "
                        "each stage once"), line
    config.write_text('[[stage]]\nname = "hu"\n[[stage]]\nname = "hu"\n')
    for line in refusals(config, tmp_path):
        assert line.startswith(f"vtrack: error: {config}: unknown stage 'hu' "), line


@pytest.mark.parametrize("given", ["s0.toml", "./s0", "configs/robust.toml"])
def test_a_shipped_configs_name_given_as_a_missing_file_is_told_the_shipped_name(
        given: str, tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    """`-c s0.toml` (or `./s0`, `configs/robust.toml` outside the source tree) where no such
    file is said "s0.toml: config file not found" only, though s0 is shipped: the name that
    loads it was left to guess. The line now names it; another missing file is unchanged,
    and so is one in another folder or with another extension (`exp/robust.toml`,
    `x/s0.json`: the user's own file, which the shipped one is not)."""
    monkeypatch.chdir(tmp_path)
    name = Path(given).stem
    (tmp_path / "inputs").mkdir()
    for line in [one_error_line(vtrack(*args)) for args in (
            ("run", "in.mp4", "-c", given, "--init", "1,1,9,9"),
            ("batch", "inputs", "-c", given), ("stages", given))]:
        assert line == (f"vtrack: error: {given}: config file not found; did you mean the "
                        f"shipped config '{name}' (named without a path or .toml)?"), line
    for mine in ("mine.toml", "exp/robust.toml", "x/s0.json", "my_configs/robust.toml"):
        assert refusals(Path(mine), tmp_path)[0] == (
            f"vtrack: error: {mine}: config file not found")
    (tmp_path / "loop").symlink_to("loop")  # a folder that cannot be resolved: no hint
    looped = Path("loop") / Path(given).name
    assert refusals(looped, tmp_path)[0] == f"vtrack: error: {looped}: config file not found"
    here = tmp_path / f"{name}.toml"  # the current folder written whole ($PWD/s0.toml)
    assert one_error_line(vtrack("stages", str(here))) == (
        f"vtrack: error: {here}: config file not found; did you mean the shipped config "
        f"'{name}' (named without a path or .toml)?")
