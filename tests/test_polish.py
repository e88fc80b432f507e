"""What a daily user notices (issue 22): help that states the real defaults, one error style,
messages that name the real problem, options that agree between commands."""

from __future__ import annotations

import os
import shlex
import subprocess
import sys
from pathlib import Path

import pytest

from vtrack.configs import DEFAULT_CONFIG


def vtrack(*args: str, cwd: Path | None = None) -> subprocess.CompletedProcess:
    return subprocess.run([sys.executable, "-m", "vtrack", *args], capture_output=True,
                          text=True, cwd=cwd, timeout=120, check=False)


def one_error_line(result: subprocess.CompletedProcess) -> str:
    """Exit code != 0 and stderr is exactly one ``vtrack: error:`` line."""
    assert result.returncode != 0, result.stderr
    lines = result.stderr.strip().splitlines()
    assert len(lines) == 1 and lines[0].startswith("vtrack: error: "), result.stderr
    return lines[0]


@pytest.mark.parametrize("command", ["run", "batch"])
def test_help_names_the_default_config_the_code_uses(command: str) -> None:
    text = " ".join(vtrack(command, "--help").stdout.split())
    assert f"Default: {DEFAULT_CONFIG}." in text
    assert "Default: s0" not in text


def test_library_defaults_are_the_same_constant() -> None:
    import inspect

    import vtrack

    assert inspect.signature(vtrack.Tracker).parameters["config"].default == DEFAULT_CONFIG
    # track's None (so that a config named beside a RunRequest can be told apart) is the same
    assert inspect.signature(vtrack.track).parameters["config"].default is None
    assert vtrack.Tracker().config.name == vtrack.Tracker(None).config.name == DEFAULT_CONFIG


@pytest.mark.parametrize("args", [
    ("run", "clip.mp4", "--bogus"),
    ("run", "clip.mp4", "--crf", "99"),
    ("scene", "smooth", "x.mp4", "--crf", "99"),
    ("scene", "smooth", "x.mp4", "--preset", "speedy"),
    ("nocommand",),
])
def test_usage_errors_are_one_vtrack_error_line(args: tuple[str, ...], tmp_path: Path) -> None:
    line = one_error_line(vtrack(*args, cwd=tmp_path))
    assert "--help" in line
    assert not list(tmp_path.iterdir())


def test_an_overlong_unknown_command_is_shown_cut(tmp_path: Path) -> None:
    """`vtrack xxx...` (300 characters) echoed the whole word in "No such command '...'",
    where other messages cut an overlong name (errors.cut). It is cut now; a word up to the
    limit is shown whole, quoted, as before."""
    line = one_error_line(vtrack("x" * 300, cwd=tmp_path))
    assert line == (f"vtrack: error: No such command {'x' * 100}...{'x' * 30} (300 characters). "
                    "(see 'python -m vtrack --help')")
    assert one_error_line(vtrack("y" * 200, cwd=tmp_path)).startswith(
        f"vtrack: error: No such command '{'y' * 200}'. (see ")


@pytest.mark.parametrize("name", ["q" * 205 + " x.mp4", "it's " + "q" * 205 + ".mp4"],
                         ids=["space", "apostrophe"])
def test_an_overlong_file_given_as_a_command_is_told_whole_and_quoted(tmp_path: Path,
                                                                      name: str) -> None:
    """The command to paste for a file given as a command (``vtrack "qqq... x.mp4"``, 211
    characters) was cut and unquoted by the cut of click's quoted words: "to track it: vtrack
    run qqq...qqq x.mp4 (211 characters)", which runs something else (an apostrophe in the
    name broke its shell quoting). The name is cut where it is refused, and the command to
    paste is whole and shell-quoted, as no_such_command writes it."""
    line = one_error_line(vtrack(name, cwd=tmp_path))
    assert line == (f"vtrack: error: No such command {name[:100]}...{name[-30:]} "
                    f"({len(name)} characters); to track it: vtrack run {shlex.quote(name)} "
                    "(see 'python -m vtrack --help')")


@pytest.mark.parametrize(("args", "said"), [
    (("run", "--" + "x" * 300), "No such option {}...{} (302 characters). "),
    (("run", "clip.mp4", "--preset", "p" * 400),
     "Invalid value for '--preset': {}...{} (400 characters) is not one of 'ultrafast', "),
    (("scene", "occlusion", "o.mp4", "--size", "s" * 300),
     "--size {}...{} (300 characters): expected WIDTHxHEIGHT"),
])
def test_an_overlong_option_word_is_shown_cut(tmp_path: Path, args: tuple[str, ...],
                                             said: str) -> None:
    """An unknown option of 300 characters and a --preset value of 400 were echoed whole
    (click's "No such option" and "is not one of"), where an overlong command word is cut
    (errors.cut), and so was vtrack scene's --size; all are cut now, as it is."""
    word = args[-1]
    line = one_error_line(vtrack(*args, cwd=tmp_path))
    assert line.startswith("vtrack: error: " + said.format(word[:100], word[-30:])), line
    assert not list(tmp_path.iterdir())


@pytest.mark.parametrize(("byte", "escape"), [("\udcff", "\\xff"), ("\x01", "\\x01")],
                         ids=["not-utf8", "control"])
def test_a_quoted_word_is_measured_and_cut_as_typed(tmp_path: Path, byte: str,
                                                   escape: str) -> None:
    """A quoted word of click's message was measured and cut as its escaped text: a --preset
    value of 60 bytes 0xff (``\\udcff`` each, 360 characters) was cut mid-escape and shown as
    "\\udcff...\\udc... (360 characters)", an option of 60 control characters as "(242
    characters)". The word is measured as typed now: 60 characters are quoted whole, 260 are
    cut as errors.cut cuts them, each character shown as its usual escape."""
    for word, args in ((byte * 60, ("--preset", byte * 60)), ("--" + byte * 260,
                                                               ("--" + byte * 260,))):
        line = one_error_line(vtrack("run", "clip.mp4", *args, cwd=tmp_path))
        if len(word) <= 200:
            assert " characters)" not in line and "..." not in line, line
        else:
            shown = word.replace(byte, escape)
            assert (f" {shown[:2 + 4 * 98]}...{escape * 30} ({len(word)} characters)"
                    in line), line
    assert not list(tmp_path.iterdir())


@pytest.mark.parametrize(("args", "said"), [
    (("run", "clip.mp4", "--preset", "{}"), "Invalid value for '--preset': "),
    (("scene", "{}", "o.mp4"), "unknown scenario "),
    (("run", "clip.mp4", "-o", "--fps", "--{}"), "No such option --"),
], ids=["click-preset", "scene-name", "option-taken-as-value"])
def test_an_overlong_word_tells_a_typed_backslash_from_a_byte(
        tmp_path: Path, args: tuple[str, ...], said: str) -> None:
    """A word over 200 characters is shown cut and unquoted: a typed ``\\xff`` and a byte 0xff
    both read ``\\xff`` (`--preset '\\xff'aaa...`, `--preset $'\\xff'aaa...`). A typed
    backslash is written ``\\\\`` there now, as in the quoted words: in click's messages
    (errors.cut_quoted) and in vtrack's own (errors.quoted_or_cut: `vtrack scene '\\xff'aaa...
    o.mp4`, `vtrack run clip.mp4 -o --fps '--\\xff'aaa...`, which still said ``\\xff``)."""
    lines = [one_error_line(vtrack(*(arg.format(first + "a" * 300) for arg in args),
                                   cwd=tmp_path)) for first in ("\\xff", "\udcff")]
    typed = len(next(arg for arg in args if "{}" in arg).format("\\xff" + "a" * 300))
    assert lines[0].startswith("vtrack: error: " + said + "\\\\xffaaa"), lines[0]
    assert lines[1].startswith("vtrack: error: " + said + "\\xffaaa"), lines[1]
    assert f"({typed} characters)" in lines[0], lines[0]
    assert f"({typed - 3} characters)" in lines[1], lines[1]
    assert not list(tmp_path.iterdir())


@pytest.mark.parametrize(("args", "said"), [
    (("run", "clip.mp4", "--preset", "\udcff" * 10),
     "Invalid value for '--preset': '" + "\\xff" * 10 + "' is not one of "),
    (("run", "clip.mp4", "--preset", "it's\udcff"),
     "Invalid value for '--preset': \"it's\\xff\" is not one of "),
    (("run", "clip.mp4", "--x\udcfe"), "No such option '--x\\xfe'."),
    (("\udcff" * 3,), "No such command '" + "\\xff" * 3 + "'."),
    # a backslash typed is kept as repr shows it, before a byte and before "udcff"
    (("run", "clip.mp4", "--preset", "\\\udcff"),
     "Invalid value for '--preset': '\\\\\\xff' is not one of "),
    (("run", "clip.mp4", "--preset", "\\udcff"),
     "Invalid value for '--preset': '\\\\udcff' is not one of "),
    (("\\udcff",), "No such command '\\\\udcff'"),
    (("scene", "occlusion", "o.mp4", "--size", "\udcff320x240"),
     "--size '\\xff320x240': expected WIDTHxHEIGHT"),
    (("scene", "occl\udcffusion", "o.mp4"), "unknown scenario 'occl\\xffusion'; choose one of: "),
    (("scene", "\udcffbad", "occlusion"),
     "unknown scenario '\\xffbad': NAME comes before OUT"),
    (("scene", "occlusion", "o.mp4", "--pix-fmt", "a\udcff"),
     "o.mp4: 'a\\xff' is not a pixel format"),
    (("scene", "occlusion", "o.mp4", "--pix-fmt", "a\\xff"),
     "o.mp4: 'a\\\\xff' is not a pixel format"),
    (("scene", "occlusion", "o.raw", "--format", "raw", "--pix-fmt", "a\udcff"),
     "raw pixel format 'a\\xff': choose one of "),
], ids=["preset", "apostrophe", "option", "command", "backslash-byte", "backslash-text",
        "backslash-command", "scene-size", "scenario", "scenario-before-out", "scene-pix-fmt",
        "scene-pix-fmt-backslash", "scene-raw-pix-fmt"])
def test_a_quoted_word_shows_a_byte_not_utf8_as_the_other_messages_do(
        tmp_path: Path, args: tuple[str, ...], said: str) -> None:
    """A short word with bytes that are not UTF-8 was quoted as repr writes it, Python's
    surrogate escape: `vtrack run clip.mp4 --preset $'\\xff...'` said "Invalid value for
    '--preset': '\\udcff\\udcff...'", `vtrack $'\\xff'` "No such command '\\udcff'", where
    vtrack's other messages write the byte as \\xff; so did vtrack scene's own refusals of
    --size and of a scenario's name (``--size '\\udcff320x240'``, ``unknown scenario
    '\\udcffbad'``) and of a pixel format (``vtrack scene occlusion o.mp4 --pix-fmt
    $'a\\xff'``: "o.mp4: 'a\\udcff' is not a pixel format", raw frames too). They do too now;
    a backslash the user typed is still shown as repr shows it (\\\\)."""
    line = one_error_line(vtrack(*args, cwd=tmp_path))
    assert line.startswith("vtrack: error: " + said), line
    assert not list(tmp_path.iterdir())


@pytest.mark.parametrize(("args", "said"), [
    (("--follow", "w" * 300), "; if it is INPUT, put it before --follow or give the seconds "
                              "(--follow 5 {}...{} (300 characters)) (see "),
    (("w" * 300,), "vtrack: error: Got unexpected extra argument ({}...{} (300 characters)) "),
    (("x'" + "q" * 300 + "'y",),
     "vtrack: error: Got unexpected extra argument ({}...{} (304 characters)) "),
], ids=["follow-hint", "extra-argument", "apostrophes"])
def test_an_overlong_word_click_does_not_quote_is_shown_cut(tmp_path: Path,
                                                           args: tuple[str, ...],
                                                           said: str) -> None:
    """An overlong word was still echoed whole where no quotes mark it: the --follow hint
    "(--follow 5 www...)" and click's "Got unexpected extra argument (www...)", 300
    characters each; in ``x'qqq...'y`` the cut of quoted words took the stray apostrophes for
    quotes. Each is cut as errors.cut cuts it now, the word's own ends and length."""
    word = args[-1]
    line = one_error_line(vtrack("run", "a.mp4", *args, cwd=tmp_path))
    assert said.format(word[:100], word[-30:]) in line, line
    assert word not in line
    assert not list(tmp_path.iterdir())


_Q205 = "q" * 205 + " x.gt.txt"  # (an overlong ground-truth name: the hint pastes it whole)
_APOSTROPHE = "it's " + "q" * 190 + ".png"
_Q150 = "q" * 150


@pytest.mark.parametrize(("args", "said"), [
    (("run", "clip.mp4", "clip.gt.txt"),
     " (clip.gt.txt); if it is the ground truth: --gt clip.gt.txt"),
    (("run", "clip.mp4", "groundtruth_rect.txt"),
     " (groundtruth_rect.txt); if it is the ground truth: --gt groundtruth_rect.txt"),
    (("frame", "clip.mp4", "frame.png"), " (frame.png); if it is the image to write: -o frame.png"),
    (("run", "clip.mp4", "frame.png"), " (frame.png)"),  # (run's -o is a folder)
    (("run", "clip.mp4", "notes.txt"), " (notes.txt)"),
    (("run", "clip.mp4", _Q205),
     f" ({_Q205[:100]}...{_Q205[-30:]} (214 characters)); if it is the ground truth: "
     f"--gt '{_Q205}'"),
    (("frame", "clip.mp4", _APOSTROPHE),
     f" ({_APOSTROPHE}); if it is the image to write: -o {shlex.quote(_APOSTROPHE)}"),
    (("run", "clip.mp4", "it's", _Q150, _Q150, "don't"), f"s (it's {_Q150} {_Q150} don't)"),
    (("run", "clip.mp4", "--gt", "a.gt.txt", "b.gt.txt"), " (b.gt.txt)"),
    (("frame", "clip.mp4", "-o", "a.png", "b.png"), " (b.png)"),
    (("frame", "clip.mp4", "--out=a.png", "b.png"), " (b.png)"),
], ids=["gt", "otb-gt", "frame-image", "run-image", "other", "overlong-gt", "apostrophe-image",
        "apostrophes-across-words", "gt-given", "image-given", "image-given-attached"])
def test_an_extra_file_is_told_the_option_that_takes_it(tmp_path: Path, args: tuple[str, ...],
                                                       said: str) -> None:
    """``vtrack run clip.mp4 clip.gt.txt`` said only "Got unexpected extra argument
    (clip.gt.txt)"; a ground-truth file is told --gt now, an image given to vtrack frame its
    -o; a file of no kind a command's FILE option takes, nothing more. The hint is a word to
    paste, whole and shell-quoted: click's quoted words were cut over the whole line, which cut
    and unquoted an overlong name's hint ("--gt qqq...qqq x.gt.txt (214 characters)"), garbled
    a name with an apostrophe, and took stray apostrophes of several words for quotes. An
    option given already is not suggested again (``--gt a.gt.txt b.gt.txt`` was told "--gt
    b.gt.txt", which would replace a.gt.txt)."""
    line = one_error_line(vtrack(*args, cwd=tmp_path))
    assert line == (f"vtrack: error: Got unexpected extra argument{said} "
                    f"(see 'python -m vtrack {args[0]} --help')")
    assert not list(tmp_path.iterdir())


@pytest.mark.parametrize("args", [("--follow=-1",), ("--follow", "-1"), ("--follow=-0.5",),
                                  ("--follow", "-1e3")])
def test_a_negative_follow_is_refused_naming_the_option(tmp_path: Path,
                                                         args: tuple[str, ...]) -> None:
    """`vtrack run clip.mp4 --follow=-1` said "No such option '-1'" (click's parser read the
    value, which starts with -, as the next option, --follow taking its default 5), naming
    neither --follow nor its range; so did `--follow -1`. Refused now as `--follow 0` is."""
    line = one_error_line(vtrack("run", "clip.mp4", *args, "--init", "1,1,9,9", cwd=tmp_path))
    value = args[-1].removeprefix("--follow=")
    assert line == (f"vtrack: error: Invalid value for '--follow': '{value}' is not a number of "
                    "seconds above 0 and at most 86400 (see 'python -m vtrack run --help')")
    assert not list(tmp_path.iterdir())


@pytest.mark.parametrize("value", ["-x", "--bogus", "abc"])
def test_a_follow_value_that_cannot_be_input_gets_no_input_hint(tmp_path: Path,
                                                                value: str) -> None:
    """`vtrack run clip.mp4 --follow=-x` was told "if it is INPUT, put it before --follow or
    give the seconds (--follow 5 -x)", which then said "No such option '-x'"; a value attached
    with = (`--follow=abc`) is no INPUT either. Refused now naming the value and the range only
    (`vtrack run --follow rec.ts` keeps its hint: tests/test_messages.py)."""
    line = one_error_line(vtrack("run", "clip.mp4", f"--follow={value}", "--init", "1,1,9,9",
                                 cwd=tmp_path))
    assert line == (f"vtrack: error: Invalid value for '--follow': '{value}' is not a number of "
                    "seconds above 0 and at most 86400 (see 'python -m vtrack run --help')")


def test_a_negative_follow_is_still_another_options_value(clip_factory, tmp_path: Path) -> None:
    """`vtrack run clip.mp4 --gt GT --no-video -o --follow=-1` was refused naming --follow
    (its values were looked at before click parsed, whichever option they followed); the word
    is -o's value: the run writes its results there, as it did before --follow's values were
    looked at."""
    clip = clip_factory("smooth", frames=10)
    result = vtrack("run", str(clip.path), "--gt", str(clip.gt), "--no-video", "-q", "-o",
                    "--follow=-1", cwd=tmp_path)
    assert result.returncode == 0, result.stderr
    assert (tmp_path / "--follow=-1" / "run.json").is_file()


@pytest.mark.parametrize(("args", "said"), [
    (("-o", "--follow", "-1"), "No such option '-1': the '--follow' before it was read as -o's "
                               "value (is -o's value missing?)"),
    (("--out", "--fps", "-x"), "No such option '-x': the '--fps' before it was read as --out's "
                               "value (is --out's value missing?)"),
], ids=["follow", "fps"])
def test_an_options_name_taken_as_outs_value_is_named_so(tmp_path: Path, args: tuple[str, ...],
                                                        said: str) -> None:
    """`vtrack run clip.mp4 -o --follow -1` said "Invalid value for '--follow': '-1' is not a
    number of seconds ...", naming an option that was not given: -o took the word --follow as
    its folder, and -1 was then read as an unknown option. The refusal now says so, and that
    -o's value may be missing."""
    line = one_error_line(vtrack("run", "clip.mp4", *args, cwd=tmp_path))
    assert line == f"vtrack: error: {said} (see 'python -m vtrack run --help')"
    assert not list(tmp_path.iterdir())


def test_shell_completion_after_a_negative_follow_completes(tmp_path: Path) -> None:
    """Completing `vtrack run clip.mp4 --follow -1 --no` printed the --follow refusal and
    exited 2 (the values were checked before click parsed, even while completing); it offers
    the options again, as before."""
    env = {**os.environ, "_VTRACK_COMPLETE": "bash_complete", "COMP_CWORD": "5",
           "COMP_WORDS": "vtrack run clip.mp4 --follow -1 --no"}
    program = "from vtrack.cli import main; main(prog_name='vtrack')"
    result = subprocess.run([sys.executable, "-c", program], capture_output=True, text=True,
                            cwd=tmp_path, env=env, timeout=120, check=False)
    assert (result.returncode, result.stderr) == (0, "")
    assert result.stdout.split() == ["plain,--no-live", "plain,--no-video"]


def test_a_mistyped_command_is_offered_the_near_one(tmp_path: Path) -> None:
    """`vtrack rnu clip.mp4` said "No such command 'rnu'." and nothing more (click looks for
    near names only in the commands a group holds; vtrack's loads them on demand); `vtrack
    configs` did not say where the configs are listed; `vtrack vectors chek vec dump` read
    'chek' as an INPUT and said "Missing option '--init'"."""
    assert one_error_line(vtrack("rnu", "clip.mp4", cwd=tmp_path)).startswith(
        "vtrack: error: No such command 'rnu'. Did you mean 'run'? (see ")
    assert "vtrack stages lists the shipped configs" in one_error_line(
        vtrack("configs", cwd=tmp_path))
    assert one_error_line(vtrack("vectors", "chek", "vec", "dump", cwd=tmp_path)).startswith(
        "vtrack: error: No such command 'chek'. Did you mean 'check'? (see ")
    # an input of a name like it is still an input: named as the missing file it is
    assert one_error_line(vtrack("vectors", "chek.mp4", "--init", "1,2,40,30", "-o", "v",
                                 cwd=tmp_path)) == "vtrack: error: chek.mp4: no such file"
    assert not list(tmp_path.iterdir())


def test_a_file_given_as_a_command_is_told_how_to_track_it_not_a_near_command(
        tmp_path: Path) -> None:
    """`vtrack scene.mp4` (a file there) said "Did you mean 'scene'?", `vtrack runs/` "Did you
    mean 'run'?" and `vtrack scene clip.mp4 out.mp4` "did you mean 'clip_ramp'?": a file is
    no typo of a name. `vtrack RUN` got no guess (click compares case); `vtrack configs` ended
    in two parentheses in a row. A file or folder now gets the vtrack run that tracks it.
    That was said of any path: a folder of videos, a results folder, a config, a summary.csv
    got 'vtrack run' too, and `vtrack -` (standard input) no hint; each now gets the command
    that takes it. A name too long for the file system ended in a traceback (OSError from
    Path.is_dir), a `vtrack report` folder (or its summary.csv) was sent to `vtrack report`,
    which refuses it, and a URL ending .csv to `vtrack report http:/host`."""
    import cv2
    import numpy as np

    (tmp_path / "scene.mp4").write_bytes(b"")
    (tmp_path / "my footage").mkdir()
    (tmp_path / "seq" / "img").mkdir(parents=True)
    assert cv2.imwrite(str(tmp_path / "seq" / "img" / "0001.jpg"), np.zeros((8, 8, 3), np.uint8))
    (tmp_path / "results").mkdir()
    (tmp_path / "results" / "summary.csv").write_text("input\n")
    (tmp_path / "mine.toml").write_text("")
    (tmp_path / "rep").mkdir()
    for name in ("index.html", "summary.md", "summary.csv"):  # a vtrack report's files
        (tmp_path / "rep" / name).write_text("input\n")
    long = "a" * 300 + ".mp4"
    for word, said in (
            ("scene.mp4", "No such command 'scene.mp4'; to track it: vtrack run scene.mp4"),
            ("runs/", "No such command 'runs/'; to track it: vtrack run runs/"),
            ("seq", "No such command 'seq'; to track it: vtrack run seq"),
            ("my footage", "No such command 'my footage'; to track the inputs in it: vtrack "
                           "batch 'my footage'"),
            ("results", "No such command 'results'; to report its results: vtrack report "
                        "results"),
            ("results/summary.csv", "No such command 'results/summary.csv'; to report "
                                    "results: vtrack report results"),
            ("mine.toml", "No such command 'mine.toml'; a config: vtrack run INPUT -c "
                          "mine.toml"),
            ("-", "No such command '-'; to track it: vtrack run -"),
            (long, f"No such command {'a' * 100}...{'a' * 26}.mp4 (304 characters); to "
                   f"track it: vtrack run {long}"),  # (the name cut; the command to paste not)
            ("rep", "No such command 'rep'; a vtrack report's folder: open rep/index.html"),
            ("rep/summary.csv", "No such command 'rep/summary.csv'; a vtrack report's table: "
                                "open rep/index.html"),
            ("http://host/a.csv", "No such command 'http://host/a.csv'; to track it: vtrack "
                                  "run http://host/a.csv"),
            ("RUN", "No such command 'RUN'. Did you mean 'run'?"),
            ("configs", "No such command 'configs'; vtrack stages lists the shipped configs "
                        "and their stages")):
        assert one_error_line(vtrack(word, cwd=tmp_path)) == (
            f"vtrack: error: {said} (see 'python -m vtrack --help')")
    assert one_error_line(vtrack("vectors", "CHECK", "vec", "dump", cwd=tmp_path)).startswith(
        "vtrack: error: No such command 'CHECK'. Did you mean 'check'? (see ")
    line = one_error_line(vtrack("scene", "clip.mp4", "out.mp4", cwd=tmp_path))
    assert line.startswith("vtrack: error: unknown scenario 'clip.mp4'; choose one of: ")
    assert "did you mean" not in line
    assert sorted(p.name for p in tmp_path.iterdir()) == ["mine.toml", "my footage", "rep",
                                                         "results", "scene.mp4", "seq"]


def test_a_set_without_its_stage_is_offered_the_one_stage_that_declares_it(
        tmp_path: Path) -> None:
    """`vtrack run clip.mp4 --set padding=2` said only "expected stage.param=value", when one
    stage of the chain (robust_model) has a parameter padding: that stage is now offered, with
    the value given; a name two stages declare, or none, is offered nothing."""
    import vtrack as library

    line = one_error_line(vtrack("run", "clip.mp4", "--set", "padding=2", cwd=tmp_path))
    assert line == ("vtrack: error: --set padding=2: expected stage.param=value; did you mean "
                    "robust_model.padding=2?")
    with pytest.raises(library.ConfigError) as caught:
        library.load_config("robust").with_values({"padding": 2})
    assert str(caught.value).endswith("; did you mean robust_model.padding?"), caught.value
    _no_stage_offered(("nosuch=1", "initial=1"), declared_twice=True)


def _no_stage_offered(givens: tuple[str, ...], declared_twice: bool = False) -> None:
    """Each ``--set`` of ``givens`` on s3 (a name none of its stages declares, and
    ``initial``, which two of them declare) is refused with no stage offered."""
    import vtrack as library

    s3 = library.load_config("s3")
    if declared_twice:
        assert sum(any(p.name == "initial" for p in cls.params)
                   for cls in s3.stage_classes()) > 1
    for given in givens:
        with pytest.raises(library.ConfigError) as caught:
            s3.with_overrides([given])
        assert str(caught.value) == f"--set {given}: expected stage.param=value"


def test_a_set_without_its_stage_or_value_is_offered_the_one_stage_that_declares_it(
        tmp_path: Path) -> None:
    """`vtrack run clip.mp4 --set padding` (no `=`) said only "expected stage.param=value",
    while `--set padding=2` is offered robust_model.padding=2: it is offered
    robust_model.padding=VALUE now; a name two stages declare, or none, is offered nothing."""
    line = one_error_line(vtrack("run", "clip.mp4", "--set", "padding", cwd=tmp_path))
    assert line == ("vtrack: error: --set padding: expected stage.param=value; did you mean "
                    "robust_model.padding=VALUE?")
    _no_stage_offered(("nosuch", "initial"))


def test_a_set_with_its_stage_and_no_value_or_an_empty_one_is_told_to_give_a_value(
        tmp_path: Path) -> None:
    """`--set robust_model.padding` (no `=`) got no hint, and `--set padding=` was offered
    `robust_model.padding=`, which is refused in turn: told to give a value now, and offered
    robust_model.padding=VALUE; a stage.param the chain does not declare gets no hint."""
    import vtrack as library

    line = one_error_line(vtrack("run", "clip.mp4", "--set", "robust_model.padding",
                                 cwd=tmp_path))
    assert line == ("vtrack: error: --set robust_model.padding: expected stage.param=value; "
                    "give a value: robust_model.padding=VALUE")
    line = one_error_line(vtrack("run", "clip.mp4", "--set", "padding=", cwd=tmp_path))
    assert line == ("vtrack: error: --set padding=: expected stage.param=value; did you mean "
                    "robust_model.padding=VALUE?")
    robust = library.load_config("robust")
    for given in ("robust_model.nosuch", "hue.padding"):
        with pytest.raises(library.ConfigError) as caught:
            robust.with_overrides([given])
        assert str(caught.value) == f"--set {given}: expected stage.param=value"


def test_a_mistyped_config_stage_or_parameter_is_offered_the_near_name() -> None:
    """`-c robst`, `-c S0`, `--set meanshft.iterations=3`, `--set meanshift.iteration=3` and
    `vtrack stages meanshif` listed every name and left the reader to find the one meant;
    the near one is now named at the end (case aside), and a name near none gets no guess.
    `-c fixed` guessed 's2-fixed', though 's0-fixed' is as near: names tied are all named."""
    import vtrack as library

    s0 = library.load_config("s0")
    for make, said in (
            (lambda: library.load_config("robst"), "; did you mean 'robust'?"),
            (lambda: library.load_config("S0"), "; did you mean 's0'?"),
            (lambda: s0.with_overrides(["meanshft.iterations=3"]),
             "is not in the chain (hue -> backproject -> meanshift -> occlusion -> kalman); "
             "did you mean 'meanshift'?"),
            (lambda: library.Tracker("s0", meanshift__iteration=3),
             "; did you mean 'iterations'?")):
        with pytest.raises(library.ConfigError) as caught:
            make()
        assert str(caught.value).endswith(said), caught.value
    with pytest.raises(library.ConfigError) as caught:
        library.load_config("xyz")
    assert "did you mean" not in str(caught.value)
    # names as near as each other: all of them, not the one a dict's order put first
    for given, said in (("fixed", "; did you mean one of 's0-fixed', 's2-fixed'?"),
                        ("s", "; did you mean one of 's0', 's1', 's2', 's3', 's4'?")):
        with pytest.raises(library.ConfigError) as caught:
            library.load_config(given)
        assert str(caught.value).endswith(said), caught.value
    assert one_error_line(vtrack("stages", "meanshif")).endswith(
        "; did you mean 'meanshift'?")


def test_an_unknown_parameter_is_said_one_way_wherever_it_is_given(tmp_path: Path) -> None:
    """`--set meanshift.iteration=3` said "stage 'meanshift' has no parameter 'iteration'",
    a config file or a keyword "stage 'meanshift': unknown parameter 'iteration'": one
    message in two wordings. `vtrack frame --help` gave --step's limit twice ("at most 16384
    (...)" and click's [2<=x<=16384])."""
    import vtrack as library

    said = ("stage 'meanshift': unknown parameter 'iteration' (parameters: method, "
            "iterations, ")
    s0 = library.load_config("s0")
    for make, where in ((lambda: s0.with_overrides(["meanshift.iteration=3"]),
                         "--set meanshift.iteration=3"),
                        (lambda: s0.with_values({"meanshift.iteration": 3}),
                         "meanshift.iteration=3")):
        with pytest.raises(library.ConfigError) as caught:
            make()
        assert str(caught.value).startswith(f"{where}: {said}"), caught.value
    config = tmp_path / "bad.toml"
    config.write_text('name = "bad"\n[[stage]]\nname = "meanshift"\niteration = 3\n')
    with pytest.raises(library.ConfigError) as caught:
        library.load_config(str(config))
    assert str(caught.value).startswith(f"{config}: {said}"), caught.value
    step = vtrack("frame", "--help").stdout.split("--step", 1)[1].split("--no-grid", 1)[0]
    assert step.count("16384") == 1, step


@pytest.mark.parametrize(("stage", "line", "said", "near"), [
    ("backprojct", "", "unknown stage 'backprojct' (known stages: background, backproject, ",
     "backproject"),
    ("backproject", "search_scal = 2", "stage 'hue': unknown parameter 'search_scal' "
                                      "(parameters: search_scale, ", "search_scale"),
], ids=["stage", "parameter"])
def test_a_mistyped_stage_or_parameter_in_a_config_file_is_offered_the_near_name(
        stage: str, line: str, said: str, near: str, tmp_path: Path) -> None:
    """`name = "backprojct"` or `search_scal = 2` in a config file listed every name and left
    the reader to find the one meant, while `--set` and `-c` named it."""
    config = tmp_path / "bad.toml"
    config.write_text(f'name = "bad"\n[[stage]]\nname = "hue"\n{line}\n[[stage]]\n'
                      f'name = "{stage}"\n[[stage]]\nname = "meanshift"\n')
    for args in (("stages", str(config)), ("run", "clip.mp4", "-c", str(config))):
        error = one_error_line(vtrack(*args, cwd=tmp_path))
        assert error.startswith(f"vtrack: error: {config}: {said}"), error
        assert error.endswith(f"; did you mean '{near}'?"), error


def test_scene_names_a_mistyped_scenario_and_arguments_given_the_other_way_round(
        tmp_path: Path) -> None:
    """`vtrack scene occlusoin clip.mp4` listed the 23 scenarios without pointing at the one
    meant; `vtrack scene clip.mp4 occlusion` said "unknown scenario 'clip.mp4'", not that NAME
    comes first. Neither writes anything."""
    assert one_error_line(vtrack("scene", "occlusoin", "clip.mp4", cwd=tmp_path)).endswith(
        "; did you mean 'occlusion'?")
    assert one_error_line(vtrack("scene", "clip.mp4", "occlusion", cwd=tmp_path)) == (
        "vtrack: error: unknown scenario 'clip.mp4': NAME comes before OUT (vtrack scene "
        "occlusion clip.mp4)")
    assert not list(tmp_path.iterdir())


def test_stages_takes_stage_and_config_names() -> None:
    one = vtrack("stages", "robust_model")
    assert one.returncode == 0 and one.stdout.startswith("robust_model: ")
    assert "\nhue:" not in one.stdout
    chain = vtrack("stages", "s0").stdout
    assert [line.split(":")[0] for line in chain.splitlines() if not line.startswith(" ")] == [
        "hue", "backproject", "meanshift", "occlusion", "kalman"]
    assert "not a stage, a shipped config or a config file" in one_error_line(
        vtrack("stages", "nope"))


def test_stages_of_a_config_show_the_values_it_sets() -> None:
    """``vtrack stages robust`` says where the config differs from a parameter's default (what
    a run of that config uses); a stage named alone shows the defaults only."""
    from vtrack.config import load_config
    from vtrack.stages.base import all_stages

    blocks: dict[str, list[str]] = {}
    for line in vtrack("stages", "robust").stdout.splitlines():
        if not line.startswith(" "):
            current = blocks.setdefault(line.split(":")[0], [])
        else:
            current.append(line.strip())
    for stage, settings in load_config("robust").stages:
        for param in all_stages()[stage].params:
            line = next(x for x in blocks[stage] if x.startswith(f"{param.name} ("))
            value = settings.get(param.name, param.default)
            if value == param.default:
                assert "; robust sets" not in line
            else:
                shown = str(value).lower() if isinstance(value, bool) else str(value)
                assert line.endswith(f"; robust sets {shown}"), line
    assert any(x.startswith("padding (") and x.endswith("; robust sets 1.5")
               for x in blocks["robust_model"])
    assert "sets" not in vtrack("stages", "robust_model").stdout


def test_stages_of_several_configs_show_what_each_sets_in_a_stage_they_share() -> None:
    """Probe 51c: ``vtrack stages s4 fixed_camera`` (or ``background fixed_camera``) listed a
    shared stage once, with the first name's values only: fixed_camera's MOG2 background, its
    shadows and its 200-pixel blobs were nowhere, though --help promises a config's values."""
    def line(out: str, stage: str, param: str) -> str:
        block = out.split(f"\n{stage}: ", 1)[1] if not out.startswith(f"{stage}: ") else out
        return next(x for x in block.splitlines() if x.strip().startswith(f"{param} ("))

    both = vtrack("stages", "s4", "fixed_camera").stdout
    assert line(both, "background", "method").endswith("; fixed_camera sets 'mog2'")
    assert line(both, "blobs", "min_area").endswith("; fixed_camera sets 200")
    assert line(both, "kalman", "model").endswith("; s4 sets 'gravity'")
    assert [x for x in both.splitlines() if not x.startswith(" ")].count(
        "blobs: connected components of the foreground -> detections (centroid, box, area, grey)"
    ) == 1
    named = vtrack("stages", "background", "fixed_camera", "fixed_camera").stdout
    assert line(named, "background", "shadows").endswith("; fixed_camera sets true")
    assert named.count("; fixed_camera sets 'mog2'") == 1


def test_stages_of_a_config_file_show_the_values_it_sets(tmp_path: Path) -> None:
    """`vtrack stages mine.toml` (the file `vtrack run -c mine.toml` takes) said 'mine.toml:
    not a stage or a shipped config', though --help offers CONFIG names. A config file is
    now listed as a shipped config is, with the values it sets; one with a mistake is told
    as `vtrack run -c` tells it."""
    chain = "".join(f'[[stage]]\nname = "{name}"\n' for name in ("hue", "backproject"))
    (tmp_path / "mine.toml").write_text(chain + '[[stage]]\nname = "meanshift"\n'
                                        'iterations = 7\n')
    out = vtrack("stages", "mine.toml", cwd=tmp_path)
    assert out.returncode == 0, out.stderr
    assert [x.split(":")[0] for x in out.stdout.splitlines() if not x.startswith(" ")] == [
        "hue", "backproject", "meanshift"]
    assert any(x.strip().startswith("iterations (") and x.endswith("; mine.toml sets 7")
               for x in out.stdout.splitlines()), out.stdout
    (tmp_path / "bad.toml").write_text(chain + '[[stage]]\nname = "meanshift"\n'
                                       'iterations = "many"\n')
    assert one_error_line(vtrack("stages", "bad.toml", cwd=tmp_path)) == (
        "vtrack: error: bad.toml: stage 'meanshift': parameter 'iterations' must be an "
        "integer in the range 1 to 100, got 'many'")


def test_a_missing_input_is_named_before_what_else_is_missing(tmp_path: Path) -> None:
    line = one_error_line(vtrack("run", "nothere.mp4", cwd=tmp_path))
    assert line == "vtrack: error: nothere.mp4: no such file"


def test_single_target_ground_truth_for_s3_says_it_needs_mot(clip_factory, tmp_path) -> None:
    clip = clip_factory("smooth", frames=10)
    line = one_error_line(vtrack("run", str(clip.path), "-c", "s3", "--gt", str(clip.gt),
                                 cwd=tmp_path))
    assert "expected at least 6 numbers" in line and "MOTChallenge" in line
    assert not list(tmp_path.iterdir())


def test_a_tracker_that_cannot_start_leaves_no_folder(clip_factory, tmp_path: Path) -> None:
    clip = clip_factory("grey", frames=10)
    box = clip.gt.read_text().splitlines()[0]
    line = one_error_line(vtrack("run", str(clip.path), "--init", box, "-c", "camshift",
                                 cwd=tmp_path))
    assert "no colour for a hue tracker" in line
    assert not (tmp_path / "vtrack-out").exists()
    # an earlier run's results in the folder stay as they were
    out = tmp_path / "kept"
    assert vtrack("run", str(clip.path), "--init", box, "-o", str(out), "--no-video",
                  cwd=tmp_path).returncode == 0
    before = {p.name: p.read_bytes() for p in out.iterdir()}
    one_error_line(vtrack("run", str(clip.path), "--init", box, "-c", "camshift", "-o",
                          str(out), "-y", cwd=tmp_path))
    assert {p.name: p.read_bytes() for p in out.iterdir()} == before


def test_gt_origin_is_the_same_option_in_run_batch_and_report() -> None:
    import importlib

    declared = []
    for name in ("run", "batch", "report"):
        command = importlib.import_module(f"vtrack.cli.{name}").command
        param = next(p for p in command.params if p.name == "gt_origin")
        declared.append((param.opts, param.help, param.default, list(param.type.choices)))
    assert declared[0] == declared[1] == declared[2]
    assert declared[0][2:] == ("auto", ["auto", "0", "1"])
    assert "[auto|0|1]" in vtrack("report", "--help").stdout


def test_an_otb_folder_scene_writes_is_scored_with_its_own_file(clip_factory, tmp_path) -> None:
    clip = clip_factory("smooth", frames=12, fmt="images")
    assert clip.gt.name == "groundtruth_rect.txt"
    overlaps = {}
    for origin in ("auto", "1", "0"):
        out = tmp_path / origin
        result = vtrack("run", str(clip.path), "--gt", str(clip.gt), "--gt-origin", origin,
                        "--no-video", "-q", "-o", str(out))
        assert result.returncode == 0, result.stderr
        import json

        overlaps[origin] = json.loads((out / "run.json").read_text())["metrics"]["mean_overlap"]
    assert overlaps["auto"] == overlaps["1"] != overlaps["0"]


def test_a_same_named_input_does_not_replace_results_silently(clip_factory, tmp_path) -> None:
    clip = clip_factory("smooth", frames=10)
    for name in ("a", "b"):
        (tmp_path / name).mkdir()
        (tmp_path / name / "clip.mp4").write_bytes(clip.path.read_bytes())
    first = vtrack("run", "a/clip.mp4", "--gt", str(clip.gt), "--no-video", "-q", cwd=tmp_path)
    assert first.returncode == 0, first.stderr
    out = tmp_path / "vtrack-out" / "clip" / DEFAULT_CONFIG
    before = (out / "run.json").read_bytes()
    line = one_error_line(vtrack("run", "b/clip.mp4", "--gt", str(clip.gt), cwd=tmp_path))
    assert "holds the results of an earlier run" in line and "--overwrite (-y)" in line
    assert (out / "run.json").read_bytes() == before
    again = vtrack("run", "b/clip.mp4", "--gt", str(clip.gt), "--no-video", "-q", "-y",
                   cwd=tmp_path)
    assert again.returncode == 0, again.stderr
    assert (out / "run.json").read_bytes() != before


def test_start_tracks_from_a_later_frame(clip_factory, tmp_path: Path) -> None:
    import csv
    import json

    import av

    clip = clip_factory("smooth", frames=40)
    out = tmp_path / "out"
    result = vtrack("run", str(clip.path), "--gt", str(clip.gt), "--start", "25", "-q",
                    "-o", str(out))
    assert result.returncode == 0, result.stderr
    with (out / "track.csv").open(newline="") as handle:
        rows = list(csv.DictReader(handle))
    assert [int(r["frame"]) for r in rows] == list(range(25, 40))
    record = json.loads((out / "run.json").read_text())
    assert record["init"] == pytest.approx(
        [float(v) for v in clip.gt.read_text().splitlines()[25].split(",")])
    assert record["request"]["start"] == 25
    assert record["metrics"]["frames_evaluated"] == 15 and record["metrics"]["auc"] > 0.8
    with av.open(str(out / "annotated.mp4")) as container:
        frames = list(container.decode(video=0))
    assert len(frames) == 15 and frames[0].time == 0
    # past the end, and without a box for that frame: one line, nothing written
    line = one_error_line(vtrack("run", str(clip.path), "--gt", str(clip.gt), "--start", "40",
                                 "-o", str(tmp_path / "late")))
    assert line.endswith("has no frame 40 (frames 0..39)"), line  # was: "ground-truth box of
    # frame 40 is missing (... is frame 40 past the input's end?)": the input says it is
    # a file shorter than the input is named as one cause (was only: 'is frame 30 past the
    # input's end?' of a 40-frame clip); a box marked absent is said to be so (was: 'empty')
    short = tmp_path / "short.txt"
    short.write_text("".join(clip.gt.read_text().splitlines(keepends=True)[:30]))
    line = one_error_line(vtrack("run", str(clip.path), "--gt", str(short), "--start", "30",
                                 "-o", str(tmp_path / "late")))
    assert "the ground-truth box of frame 30 is missing: the file has boxes for frames 0..29 " \
        "only (a file shorter than the input" in line, line
    short.write_text("NaN,NaN,NaN,NaN\n" + clip.gt.read_text().split("\n", 1)[1])
    line = one_error_line(vtrack("run", str(clip.path), "--gt", str(short), "-o",
                                 str(tmp_path / "late")))
    assert line.endswith("the first ground-truth box is marked absent (NaN, or w or h <= 0: the "
                         "target out of view); give --init x,y,w,h"), line
    line = one_error_line(vtrack("run", str(clip.path), "--init", "10,10,20,20", "--start",
                                 "40", "-o", str(tmp_path / "late")))
    assert line.endswith("has no frame 40 (frames 0..39)")  # was: "frames are numbered from 0"
    line = one_error_line(vtrack("run", str(clip.path), "--start", "5", "-o",
                                 str(tmp_path / "late")))
    assert "needs the target's box in frame 5" in line
    assert not (tmp_path / "late").exists()


def test_progress_lines_when_stderr_is_not_a_terminal(clip_factory, tmp_path: Path) -> None:
    import re

    clip = clip_factory("smooth", frames=12)
    result = vtrack("run", str(clip.path), "--gt", str(clip.gt), "--no-video", "--frames", "10",
                    "--stats-period", "0", "-o", str(tmp_path / "out"))
    assert result.returncode == 0, result.stderr
    lines = result.stderr.splitlines()
    # the input named as the summary line names it (the progress said clip, the summary clip.mp4)
    name = re.escape(str(clip.path))
    assert re.fullmatch(rf"{name}: 10 frames, .* -> {re.escape(str(tmp_path / 'out'))}",
                        result.stdout.strip()), result.stdout
    assert [int(m.group(1)) for line in lines
            if (m := re.fullmatch(rf"{name}: (\d+)/10 frames \(\d+%\), [\d.]+ fps, [\d:?]+ left",
                                  line))] == list(range(1, 11)), lines
    assert "\r" not in result.stderr  # no bar drawn into a log
    quiet = vtrack("run", str(clip.path), "--gt", str(clip.gt), "--no-video", "-q", "-y",
                   "--stats-period", "0", "-o", str(tmp_path / "out"))
    assert quiet.returncode == 0 and quiet.stderr == ""


def test_batch_summary_keeps_earlier_configs_and_resumed_rows_say_complete(
        clip_factory, tmp_path: Path) -> None:
    import csv
    import shutil

    clip = clip_factory("smooth", frames=12)
    folder = tmp_path / "in"
    folder.mkdir()
    shutil.copy(clip.path, folder / "walk.mp4")
    shutil.copy(clip.gt, folder / "walk.gt.txt")

    def rows() -> dict[tuple[str, str], str]:
        with (tmp_path / "res" / "summary.csv").open(newline="") as handle:
            return {(r["input"], r["config"]): r["status"] for r in csv.DictReader(handle)}

    common = ("--no-video", "--jobs", "1", "-q", "--out", str(tmp_path / "res"))
    assert vtrack("batch", str(folder), "-c", "s0", *common).returncode == 0
    assert vtrack("batch", str(folder), "-c", "robust", *common).returncode == 0
    assert rows() == {("walk", "s0"): "complete", ("walk", "robust"): "complete"}
    again = vtrack("batch", str(folder), "-c", "robust", "-c", "s0", "--no-video", "--jobs",
                   "1", "--out", str(tmp_path / "res"))
    assert again.returncode == 0, again.stderr
    assert rows() == {("walk", "s0"): "complete", ("walk", "robust"): "complete"}
    assert "2 runs (2 complete; 2 of them complete before, not run again)" in again.stdout


def test_batch_start_is_recorded_per_run(clip_factory, tmp_path: Path) -> None:
    import csv
    import shutil

    clip = clip_factory("smooth", frames=20)
    folder = tmp_path / "in"
    folder.mkdir()
    shutil.copy(clip.path, folder / "walk.mp4")
    shutil.copy(clip.gt, folder / "walk.gt.txt")
    out = tmp_path / "res"
    done = vtrack("batch", str(folder), "--start", "8", "--no-video", "--jobs", "1", "-q",
                  "--out", str(out))
    assert done.returncode == 0, done.stderr
    with (out / "walk" / DEFAULT_CONFIG / "track.csv").open(newline="") as handle:
        assert [int(r["frame"]) for r in csv.DictReader(handle)] == list(range(8, 20))


def test_frames_also_takes_a_duration_like_ffmpeg_t(clip_factory, tmp_path: Path) -> None:
    """``--frames 0.5s`` tracks the first 0.5 s from ``--start`` (15 frames at 30 fps): the
    same track as ``--frames 15``; run.json keeps the duration as given; a batch takes it too;
    a duration that is not one is a one-line error and nothing is written."""
    import csv
    import json
    import shutil

    clip = clip_factory("smooth", frames=40)  # 30 fps
    by_count, by_time = tmp_path / "count", tmp_path / "time"
    for out, frames in ((by_count, "15"), (by_time, "0.5s")):
        done = vtrack("run", str(clip.path), "--gt", str(clip.gt), "--start", "10",
                      "--frames", frames, "-q", "--no-video", "-o", str(out))
        assert done.returncode == 0, done.stderr
    assert (by_time / "track.csv").read_bytes() == (by_count / "track.csv").read_bytes()
    with (by_time / "track.csv").open(newline="") as handle:
        assert [int(r["frame"]) for r in csv.DictReader(handle)] == list(range(10, 25))
    record = json.loads((by_time / "run.json").read_text())
    assert (record["request"]["max_frames"], record["request"]["max_s"]) == (None, 0.5)
    for bad in ("0", "0s", "-2", "2x", "nans", "1e99s"):
        line = one_error_line(vtrack("run", str(clip.path), "--gt", str(clip.gt), "--frames",
                                     bad, "-o", str(tmp_path / "bad")))
        assert "--frames" in line and "10s" in line, line
    assert not (tmp_path / "bad").exists()
    folder = tmp_path / "in"
    folder.mkdir()
    shutil.copy(clip.path, folder / "walk.mp4")
    shutil.copy(clip.gt, folder / "walk.gt.txt")
    done = vtrack("batch", str(folder), "--frames", "1s", "--no-video", "--jobs", "1", "-q",
                  "--out", str(tmp_path / "res"))
    assert done.returncode == 0, done.stderr
    with (tmp_path / "res" / "walk" / DEFAULT_CONFIG / "track.csv").open(newline="") as handle:
        assert [int(r["frame"]) for r in csv.DictReader(handle)] == list(range(30))


def test_start_also_takes_a_time_like_ffmpeg_ss(clip_factory, tmp_path: Path) -> None:
    """``--start 0.5s`` starts at the first frame at or after 0.5 s (frame 15 at 30 fps): the
    same track as ``--start 15``; run.json keeps the time as given and the frame it found;
    a batch resumed with the same time reuses its runs; the report scores them from there."""
    import json
    import shutil

    clip = clip_factory("smooth", frames=40)  # 30 fps
    by_frame, by_time = tmp_path / "frame", tmp_path / "time"
    for out, start in ((by_frame, "15"), (by_time, "0.5s")):
        done = vtrack("run", str(clip.path), "--gt", str(clip.gt), "--start", start, "-q",
                      "--no-video", "-o", str(out))
        assert done.returncode == 0, done.stderr
    assert (by_time / "track.csv").read_bytes() == (by_frame / "track.csv").read_bytes()
    record = json.loads((by_time / "run.json").read_text())
    assert record["start_frame"] == 15
    assert (record["request"]["start"], record["request"]["start_s"]) == (0, 0.5)
    for bad in ("2.5x", "-1s", "nans", "1e99s"):
        line = one_error_line(vtrack("run", str(clip.path), "--start", bad, "-o",
                                     str(tmp_path / "bad")))
        assert "--start" in line and "2.5s" in line, line
        assert ("is negative" in line) == (bad == "-1s"), line  # said, not only implied
    line = one_error_line(vtrack("run", str(clip.path), "--init", "10,10,20,20", "--start",
                                 "2s", "-o", str(tmp_path / "bad")))
    assert line.endswith("--start 2s: " + f"{clip.path}: has no frame at or after 2 s (its last "
                         "frame is frame 39, at 1.3 s)")  # where the clip ends
    assert not (tmp_path / "bad").exists()

    folder = tmp_path / "in"
    folder.mkdir()
    shutil.copy(clip.path, folder / "walk.mp4")
    shutil.copy(clip.gt, folder / "walk.gt.txt")
    batch = ("batch", str(folder), "--start", "0.5s", "--no-video", "--jobs", "1",
             "--out", str(tmp_path / "res"))
    assert vtrack(*batch, "-q").returncode == 0
    again = vtrack(*batch)
    assert again.returncode == 0, again.stderr
    assert "1 of them complete before, not run again" in again.stdout, again.stdout
    report = vtrack("report", str(tmp_path / "res"), "-q", "--out", str(tmp_path / "report"))
    assert report.returncode == 0, report.stderr
    summary = (tmp_path / "report" / "summary.csv").read_text().splitlines()
    assert summary[1].split(",")[4] == "25"  # frames_evaluated: frames 15..39


def _variable_rate_clip(tmp_path: Path) -> tuple[Path, Path]:
    """A 40-frame H.264 clip at a variable rate, and its ground truth: 20 frames 10 ms apart
    (0 .. 0.19 s), a pause, then 20 frames 100 ms apart (0.3 .. 2.2 s); the stream's nominal
    rate comes out as 100 fps."""
    from fractions import Fraction

    import av

    from vtrack.scenes import make_scene, write_groundtruth

    scene = make_scene("smooth", seed=3, width=160, height=120, frames=40, fps=30)
    times_ms = [10 * i for i in range(20)] + [300 + 100 * i for i in range(20)]
    clip = tmp_path / "vfr.mp4"
    with av.open(str(clip), "w") as out:
        stream = out.add_stream("libx264", rate=30, options={"preset": "ultrafast"})
        stream.width, stream.height, stream.pix_fmt = 160, 120, "yuv420p"
        stream.codec_context.time_base = stream.time_base = Fraction(1, 1000)
        for ms, picture in zip(times_ms, scene.frames(), strict=True):
            frame = av.VideoFrame.from_ndarray(picture, format="bgr24")
            frame.pts = ms
            out.mux(stream.encode(frame))
        out.mux(stream.encode())
    gt = tmp_path / "vfr.gt.txt"
    write_groundtruth(scene, gt)
    return clip, gt


def test_a_start_time_in_a_variable_rate_video_is_found_by_the_timestamps(
        tmp_path: Path) -> None:
    """``--start Ts`` on a variable-frame-rate video counted frames at the stream's nominal
    rate (100 fps here: frame 100 of 40, refused); it starts at the first frame whose
    timestamp is at or after T, with that frame's ground-truth box."""
    import csv
    import json

    clip, gt = _variable_rate_clip(tmp_path)
    for start, frame, time_s in (("1s", 27, 1.0), ("0.25s", 20, 0.3), ("0.05s", 5, 0.05)):
        done = vtrack("run", str(clip), "--gt", str(gt), "-c", "s2", "--start", start, "-q",
                      "--no-video", "-o", str(tmp_path / start))
        assert done.returncode == 0, done.stderr
        with (tmp_path / start / "track.csv").open(newline="") as handle:
            rows = list(csv.DictReader(handle))
        assert [int(r["frame"]) for r in rows] == list(range(frame, 40))
        assert float(rows[0]["time_s"]) == pytest.approx(time_s, abs=1e-6)
        assert json.loads((tmp_path / start / "run.json").read_text())["start_frame"] == frame
    line = one_error_line(vtrack("run", str(clip), "--gt", str(gt), "--start", "2.25s",
                                 "-o", str(tmp_path / "past")))
    assert line.endswith(f"--start 2.25s: {clip}: has no frame at or after 2.25 s (its last "
                         "frame is frame 39, at 2.2 s)"), line
    assert not (tmp_path / "past").exists()


def test_a_duration_in_a_variable_rate_video_ends_by_the_timestamps(tmp_path: Path) -> None:
    """``--frames Ts`` on a variable-frame-rate video took ceil(T x nominal fps) frames (50 of
    a 100 fps guess: 0.5 s ran to the end of a 2.2 s clip); it tracks the frames whose
    timestamp is less than T past the first tracked one's, at least that one, and the ground
    truth beyond is not warned of."""
    import csv
    import json

    clip, gt = _variable_rate_clip(tmp_path)
    cases = ((None, "0.5s", range(0, 22)),  # 0 .. 0.19 s, 0.3 and 0.4 s
             ("1s", "0.5s", range(27, 32)),  # 1.0 .. 1.4 s
             ("5", "0.25s", range(5, 20)),  # 0.05 .. 0.19 s: 0.3 s is the end, not in
             ("0.2s", "0.05s", range(20, 21)),  # 0.3 s, none other within 0.05 s
             (None, "3s", range(0, 40)))
    for start, span, frames in cases:
        out = tmp_path / f"{start}-{span}"
        done = vtrack("run", str(clip), "--gt", str(gt), "-c", "s2", "--frames", span, "-q",
                      "--no-video", "-o", str(out), *(("--start", start) if start else ()))
        assert done.returncode == 0, done.stderr
        with (out / "track.csv").open(newline="") as handle:
            assert [int(r["frame"]) for r in csv.DictReader(handle)] == list(frames), out
        record = json.loads((out / "run.json").read_text())
        assert (record["status"], record["warnings"]) == ("complete", []), out


@pytest.fixture(scope="module")
def report_runs(clip_factory, tmp_path_factory) -> tuple[Path, object]:
    """A batch of s0, s1 and robust on two generated clips (no ground truth recorded in one)."""
    import shutil

    root = tmp_path_factory.mktemp("report")
    folder = root / "in"
    folder.mkdir()
    for scenario in ("occlusion", "leave_return"):
        clip = clip_factory(scenario, frames=90)
        shutil.copy(clip.path, folder / f"{scenario}.mp4")
        shutil.copy(clip.gt, folder / f"{scenario}.gt.txt")
    done = vtrack("batch", str(folder), "-c", "s0", "-c", "s1", "-c", "robust", "--jobs", "1",
                  "-q", "--out", str(root / "results"))
    assert done.returncode == 0, done.stderr
    return root, clip_factory("occlusion", frames=90)


def test_report_explains_its_columns_and_ranks_only_what_ranks(report_runs) -> None:
    import html
    import re

    root, _ = report_runs
    done = vtrack("report", str(root / "results"), "-q", "--out", str(root / "report"))
    assert done.returncode == 0, done.stderr
    page = (root / "report" / "index.html").read_text()
    assert page.count('<table class="sortable">') >= 2 and "<script>" in page
    for title in ("Tracking miss", "Miss flagged", "Lost frames"):
        assert re.search(rf'<th title="[^"]+">{title}</th>', page), title
    assert "honest" in html.unescape(page.split("<footer>")[1])
    # the columns that describe a run mark no best cell
    table = page.split('id="results"')[1].split("</table>")[0]
    header = re.findall(r"<th[^>]*>([^<]+)</th>", table)
    for row in re.findall(r"<tr[^>]*>(.*?)</tr>", table)[1:]:
        cells = re.findall(r'<td class="([^"]*)"', row)
        for column in ("Miss flagged", "Lost frames", "Frames"):
            assert "best" not in cells[header.index(column)], (column, row)


def test_report_gt_scores_a_run_made_with_frames(clip_factory, tmp_path: Path) -> None:
    clip = clip_factory("smooth", frames=30)
    box = clip.gt.read_text().splitlines()[0]
    for start, name in ((0, "head"), (10, "middle")):
        args = ["--start", str(start)] if start else []
        line = clip.gt.read_text().splitlines()[start]
        done = vtrack("run", str(clip.path), "--init", line if start else box, "--frames", "12",
                      *args, "--no-video", "-q", "-o", str(tmp_path / name))
        assert done.returncode == 0, done.stderr
    done = vtrack("report", str(tmp_path / "head"), str(tmp_path / "middle"), "--gt",
                  str(clip.gt), "-o", str(tmp_path / "report"))
    assert done.returncode == 0 and "not scored" not in done.stderr, done.stderr
    import csv

    with (tmp_path / "report" / "summary.csv").open(newline="") as handle:
        rows = list(csv.DictReader(handle))
    assert [int(r["frames_evaluated"]) for r in rows] == [12, 12]
    assert all(float(r["auc"]) > 0.8 for r in rows), rows


def test_report_without_ground_truth_shows_state_and_score_over_time(clip_factory,
                                                                     tmp_path: Path) -> None:
    import cv2

    clip = clip_factory("occlusion", frames=90)
    box = clip.gt.read_text().splitlines()[0]
    for config in ("robust", "s0"):
        done = vtrack("run", str(clip.path), "--init", box, "-c", config, "--no-video", "-q",
                      "-o", str(tmp_path / config))
        assert done.returncode == 0, done.stderr
    done = vtrack("report", str(tmp_path / "robust"), str(tmp_path / "s0"), "-q", "-o",
                  str(tmp_path / "report"))
    assert done.returncode == 0, done.stderr
    page = (tmp_path / "report" / "index.html").read_text()
    plots = list((tmp_path / "report" / "plots").glob("state_*.png"))
    assert len(plots) == 1 and f'src="plots/{plots[0].name}"' in page
    assert "nothing to plot" not in page
    image = cv2.imread(str(plots[0]))
    assert image.shape[0] > 250  # two panels


def test_report_shows_failure_frames_of_every_config_side_by_side(report_runs) -> None:
    import cv2

    root, _ = report_runs
    done = vtrack("report", str(root / "results"), "-q", "--out", str(root / "failures"))
    assert done.returncode == 0, done.stderr
    page = (root / "failures" / "index.html").read_text()
    thumbnails = sorted((root / "failures" / "plots").glob("failures_*.png"))
    assert thumbnails, list((root / "failures" / "plots").iterdir())
    for path in thumbnails:
        assert f'src="plots/{path.name}"' in page
        image = cv2.imread(str(path))
        assert image.shape[1] >= 3 * 300  # a column per config (s0, s1, robust)


def test_batch_replaces_results_of_other_settings_only_with_overwrite(clip_factory,
                                                                      tmp_path: Path) -> None:
    import csv
    import shutil

    clip = clip_factory("smooth", frames=12)
    folder = tmp_path / "in"
    folder.mkdir()
    shutil.copy(clip.path, folder / "walk.mp4")
    shutil.copy(clip.gt, folder / "walk.gt.txt")
    common = ("batch", str(folder), "-c", "s0", "--no-video", "--jobs", "1", "-q", "--out",
              str(tmp_path / "res"))
    assert vtrack(*common).returncode == 0
    record = tmp_path / "res" / "walk" / "s0" / "run.json"
    before = record.read_bytes()
    summary = (tmp_path / "res" / "summary.csv").read_text()
    refused = vtrack(*[a for a in common if a != "-q"], "--set", "meanshift.iterations=5")
    assert refused.returncode == 1 and "made with other settings" in refused.stderr
    assert record.read_bytes() == before
    # the refused pair's row went on describing its folder's run (it said `failed`, while
    # `vtrack report` found that run complete); the tally counts it as its row does (it
    # said `1 failed` beside a row that said complete)
    assert (tmp_path / "res" / "summary.csv").read_text() == summary
    # ... and its line says it was not run (it said `failed` above a tally of `1 complete`)
    assert refused.stdout.startswith("walk [s0]: not run: ")
    assert "vtrack: error: walk [s0]: not run: " in refused.stderr
    assert refused.stdout.splitlines()[-1].startswith(
        "1 run (1 complete; 1 of them made with other settings, not run again "
        "(--overwrite replaces them)) -> ")
    replaced = vtrack(*common, "--set", "meanshift.iterations=5", "-y")
    assert replaced.returncode == 0, replaced.stderr
    with (tmp_path / "res" / "summary.csv").open(newline="") as handle:
        assert [r["status"] for r in csv.DictReader(handle)] == ["complete"]
    assert record.read_bytes() != before


def test_batch_progress_counts_frames_in_a_log(clip_factory, tmp_path: Path) -> None:
    import re
    import shutil

    folder = tmp_path / "in"
    folder.mkdir()
    for scenario in ("smooth", "jump"):
        clip = clip_factory(scenario, frames=60)
        shutil.copy(clip.path, folder / f"{scenario}.mp4")
        shutil.copy(clip.gt, folder / f"{scenario}.gt.txt")
    done = vtrack("batch", str(folder), "-c", "s0", "--jobs", "1", "--no-video",
                  "--stats-period", "0", "--out", str(tmp_path / "res"))
    assert done.returncode == 0, done.stderr
    lines = [re.fullmatch(r"batch: (\d+)/(\d+) frames \(\d+%\), [\d.]+ fps, [\d:?]+ left, "
                          r"(\d)/2 runs", line) for line in done.stderr.splitlines()]
    assert lines and all(lines), done.stderr
    frames = [int(m.group(1)) for m in lines]
    assert frames == sorted(frames) and frames[-1] == 120
    assert int(lines[-1].group(2)) == 120 and lines[-1].group(3) == "2"
    # as soon as the first run opened its input: the frames of every run to do, estimated
    assert (frames[0], int(lines[0].group(2)), lines[0].group(3)) == (0, 120, "0")


def test_frame_step_help_says_where_its_range_is_shown() -> None:
    """`vtrack frame --help` said --step goes "up to the largest frame side vtrack reads, the
    range below", where click prints that range at the end of the same text ([2<=x<=16384]);
    the particle stage's near_share help cited "6 of [0042]'s 8", a count [0042] does not
    give."""
    step = " ".join(vtrack("frame", "--help").stdout.split())
    assert "the range shown at the end). Default: a round step giving ~16 lines. " \
           "[2<=x<=16384]" in step, step
    stages = " ".join(vtrack("stages", "particle").stdout.split())
    assert "no count given; 0.75: 6 of S1's 8 particles" in stages, stages
