"""``vtrack vectors``: the files an HDL bench reads, consistent with the golden model, and
``vtrack vectors check`` on the vectors themselves and on a copy with one byte changed."""

from __future__ import annotations

import csv
import json
import shutil
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest
from conftest import sigterm_as_called

from vtrack.golden.s0 import hue8
from vtrack.scenes import write_image_sequence

FRAMES = 4


def vtrack(*args: str) -> subprocess.CompletedProcess:
    return subprocess.run([sys.executable, "-m", "vtrack", *args], capture_output=True,
                          timeout=120, check=False, text=True)


def readmemh(path: Path) -> np.ndarray:
    """What $readmemh loads: one hex word per line."""
    return np.array([int(line, 16) for line in path.read_text().split()], np.int64)


@pytest.fixture(scope="module")
def vectors(clip_factory, tmp_path_factory) -> tuple[Path, object]:
    clip = clip_factory("smooth", frames=30)
    box = clip.scene.boxes[0]
    out = tmp_path_factory.mktemp("vectors") / "s0"
    result = vtrack("vectors", str(clip.path), "--config", "s0-fixed", "--init",
                    f"{box.x},{box.y},{box.w},{box.h}", "--frames", str(FRAMES), "--out", str(out))
    assert result.returncode == 0, result.stderr
    return out, clip


def test_files_are_readmemh_text_consistent_with_the_model(vectors) -> None:
    out, clip = vectors
    manifest = json.loads((out / "manifest.json").read_text())
    width, height = manifest["files"]["rgb.hex"]["width"], manifest["files"]["rgb.hex"]["height"]
    assert (width, height) == (320, 240)
    hist = np.array(manifest["s0"]["histogram_counts"])
    with (out / "trace.csv").open() as handle:
        rows = list(csv.DictReader(handle))
    assert [int(r["frame"]) for r in rows] == list(range(FRAMES))
    for k in range(FRAMES):
        folder = out / f"frame_{k:04d}"
        rgb = readmemh(folder / "rgb.hex")
        assert rgb.size == width * height and all(
            len(line) == 6 for line in (folder / "rgb.hex").read_text().split()[:100])
        r, g, b = rgb >> 16, (rgb >> 8) & 255, rgb & 255
        hue = readmemh(folder / "hue.hex")
        np.testing.assert_array_equal(hue, hue8(r, g, b))
        assert (folder / "bp.hex").is_file() == (k >= 1)
        if k == 0:
            # the manifest's histogram is the count of the first frame's window's hues
            x, y, w, h = (int(rows[0][c]) for c in ("win_x", "win_y", "win_w", "win_h"))
            box = hue.reshape(height, width)[y : y + h, x : x + w]
            np.testing.assert_array_equal(np.bincount(box.ravel(), minlength=256), hist)
            continue
        bp = readmemh(folder / "bp.hex")
        np.testing.assert_array_equal(bp, hist[hue] * 255 // hist.max())  # eq. 4
        # the trace's sums are the full-frame BP summed over the trace's window
        row = rows[k]
        x, y, w, h = (int(row[c]) for c in ("win_x", "win_y", "win_w", "win_h"))
        part = bp.reshape(height, width)[y : y + h, x : x + w]
        xs, ys = np.arange(x, x + w) - (x + w // 2), np.arange(y, y + h) - (y + h // 2)
        assert int(part.sum()) == int(row["sum_bp"])
        assert int((part * xs[None, :]).sum()) == int(row["sum_bp_dx"])
        assert int((part * ys[:, None]).sum()) == int(row["sum_bp_dy"])
        assert np.float32(row["kx_x"]).view(np.uint32) == int(row["kx_x_hex"], 16)


def test_check_passes_on_the_vectors_and_names_one_changed_byte(vectors, tmp_path) -> None:
    out, _ = vectors
    same = vtrack("vectors", "check", str(out), str(out))
    assert same.returncode == 0, same.stdout + same.stderr
    # a dump with two files; one hex digit of one pixel of frame 2's BP changed
    dump = tmp_path / "dump"
    (dump / "frame_0002").mkdir(parents=True)
    shutil.copy(out / "frame_0002" / "bp.hex", dump / "frame_0002" / "bp.hex")
    shutil.copy(out / "trace.csv", dump / "trace.csv")
    assert vtrack("vectors", "check", str(out), str(dump)).returncode == 0
    path = dump / "frame_0002" / "bp.hex"
    data = bytearray(path.read_bytes())
    x, y = 37, 11
    at = 3 * (y * 320 + x)
    old = data[at : at + 2].decode()
    data[at] = ord("a") if data[at] != ord("a") else ord("b")
    path.write_bytes(bytes(data))
    differ = vtrack("vectors", "check", str(out), str(dump))
    assert differ.returncode == 1
    lines = differ.stdout.splitlines()
    assert len(lines) == 1, differ.stdout
    new = data[at : at + 2].decode()
    assert "frame_0002/bp.hex" in lines[0] and f"line {y * 320 + x + 1} (x={x}, y={y})" in lines[0]
    assert f"expected {old}, got {new}" in lines[0]
    # a trace column changed is named with its frame and column
    with (dump / "trace.csv").open() as handle:
        rows = list(csv.reader(handle))
    column = rows[0].index("sum_bp")
    rows[3][column] = str(int(rows[3][column]) + 1)  # row 0 is the header: frame 2
    with (dump / "trace.csv").open("w", newline="") as handle:
        csv.writer(handle).writerows(rows)
    differ = vtrack("vectors", "check", str(out), str(dump))
    assert differ.returncode == 1
    assert any("trace.csv" in line and "frame 2 column sum_bp" in line
               for line in differ.stdout.splitlines()), differ.stdout


def test_vectors_bad_input_is_one_line(vectors, tmp_path) -> None:
    out, clip = vectors
    too_many = vtrack("vectors", str(clip.path), "--init", "1,1,5,5", "--frames", "100000",
                      "--out", str(tmp_path / "x"))
    assert too_many.returncode == 2 and "--frames" in too_many.stderr
    assert "Traceback" not in too_many.stderr
    float_config = vtrack("vectors", str(clip.path), "--config", "s0", "--init", "1,1,5,5",
                          "--out", str(tmp_path / "y"))
    assert float_config.returncode == 2 and "fixed-point" in float_config.stderr
    empty = tmp_path / "empty"
    empty.mkdir()
    nothing = vtrack("vectors", "check", str(out), str(empty))
    assert nothing.returncode == 2 and "none of the vector files" in nothing.stderr


def _dump_trace(out: Path, dump: Path, header: list[str], value: str | None = None,
                bom: bool = False) -> None:
    """``dump/trace.csv``: the vectors' rows under ``header`` (every cell ``value`` if given)."""
    with (out / "trace.csv").open(newline="") as handle:
        rows = list(csv.reader(handle))[1:]
    dump.mkdir()
    with (dump / "trace.csv").open("w", newline="", encoding="utf-8-sig" if bom else "utf-8"
                                   ) as handle:
        writer = csv.writer(handle)
        writer.writerow(header)
        writer.writerows([[value] * len(r) for r in rows] if value is not None else rows)


def test_a_dump_trace_missing_columns_of_the_vectors_differs(vectors, tmp_path) -> None:
    """A dump whose trace.csv header was the real one in upper case, every value 999, was
    `1 file(s) equal`, exit 0: its columns matched none of the vectors', so none was compared."""
    out, _ = vectors
    with (out / "trace.csv").open(newline="") as handle:
        header = next(csv.reader(handle))
    _dump_trace(out, tmp_path / "upper", [c.upper() for c in header], "999")
    upper = vtrack("vectors", "check", str(out), str(tmp_path / "upper"))
    assert upper.returncode == 1, upper.stdout + upper.stderr
    assert upper.stdout.startswith(f"trace.csv: missing {len(header)} column(s) of the vectors: "
                                   "frame, win_x"), upper.stdout
    assert "case-sensitive" in upper.stdout and "equal" not in upper.stdout
    # the columns an RTL produces (one left out): compared on those, as docs/hardware.md says
    _dump_trace(out, tmp_path / "less", [*header[:-1], "extra"])
    less = vtrack("vectors", "check", str(out), str(tmp_path / "less"))
    assert less.returncode == 0 and less.stdout == "1 file(s) equal\n", less.stdout
    # without `frame`, the rows cannot be told apart: a difference naming it
    _dump_trace(out, tmp_path / "noframe", ["Frame", *header[1:]])
    noframe = vtrack("vectors", "check", str(out), str(tmp_path / "noframe"))
    assert noframe.returncode == 1
    assert noframe.stdout.startswith("trace.csv: missing 1 column(s) of the vectors: frame "
                                     "(column names are case-sensitive)"), noframe.stdout


def test_a_dump_trace_with_a_byte_order_mark_is_compared_whole(vectors, tmp_path) -> None:
    """A header saved with a UTF-8 BOM (Excel) named its first column '\\ufeffframe', skipped."""
    out, _ = vectors
    with (out / "trace.csv").open(newline="") as handle:
        header = next(csv.reader(handle))
    _dump_trace(out, tmp_path / "same", header, bom=True)
    same = vtrack("vectors", "check", str(out), str(tmp_path / "same"))
    assert same.returncode == 0 and same.stdout == "1 file(s) equal\n", same.stdout + same.stderr
    (tmp_path / "frame").mkdir()
    (tmp_path / "frame" / "trace.csv").write_bytes(
        b"\xef\xbb\xbf" + "\n".join(["frame", *(str(10 + k) for k in range(FRAMES))]).encode())
    frame = vtrack("vectors", "check", str(out), str(tmp_path / "frame"))
    assert frame.returncode == 1
    assert "frame 0 column frame: expected 0, got 10" in frame.stdout, frame.stdout


@pytest.mark.parametrize(("name", "content", "problem"), [
    ("manifest.json", b'{"model": "s0"}\n', "manifest.json: not a vectors manifest"),
    ("manifest.json", b"[1, 2]\n", "manifest.json: not a vectors manifest"),
    ("manifest.json", b'{"files": {"rgb.hex": {"width": "abc"}}}\n',
     "manifest.json: not a vectors manifest"),
    ("manifest.json", b'{"files": {"rgb.hex": {"width": 0}}}\n',
     "manifest.json: not a vectors manifest"),
    ("manifest.json", b"\xff\xfe{}", "not a vectors folder (manifest.json: "),
    ("trace.csv", None, "trace.csv: not a vectors CSV file ("),
])
def test_a_foreign_vectors_folder_is_one_error_line(vectors, tmp_path, name: str,
                                                    content: bytes | None, problem: str) -> None:
    """A tampered or foreign manifest.json raised KeyError/TypeError/ValueError and a non-UTF-8
    trace.csv UnicodeDecodeError, all exit 1: the code of a dump that differs."""
    out, _ = vectors
    tampered = tmp_path / "vec"
    shutil.copytree(out, tampered)
    path = tampered / name
    path.write_bytes(content if content is not None else path.read_bytes() + b"\xff\xfe\n")
    dump = tmp_path / "dump"
    dump.mkdir()
    shutil.copy(out / "trace.csv", dump / "trace.csv")
    done = vtrack("vectors", "check", str(tampered), str(dump))
    assert done.returncode == 2, done.stdout + done.stderr
    assert done.stdout == "" and len(done.stderr.splitlines()) == 1, done.stderr
    assert done.stderr.startswith(f"vtrack: error: {tampered}") and problem in done.stderr


def test_a_dump_and_vectors_given_swapped_are_told_the_order(vectors, tmp_path) -> None:
    """`vtrack vectors check DUMP VECTORS` said 'DUMP: not a vectors folder (manifest.json: No
    such file or directory)', nothing about the order; two dumps still say only that, as does a
    first argument that is no folder (missing, or a file): the order it gave was refused too."""
    out, _ = vectors
    dump = tmp_path / "dump"
    dump.mkdir()
    shutil.copy(out / "trace.csv", dump / "trace.csv")
    not_vectors = (f"vtrack: error: {dump}: not a vectors folder (manifest.json: No such file "
                   "or directory)")
    done = vtrack("vectors", "check", str(dump), str(out))
    assert (done.returncode, done.stdout) == (2, ""), done.stdout + done.stderr
    assert done.stderr == (f"{not_vectors}; {out} is one: the vectors come first, then the "
                           f"dump (vtrack vectors check {out} {dump})\n")
    done = vtrack("vectors", "check", str(dump), str(dump))
    assert (done.returncode, done.stderr) == (2, f"{not_vectors}\n")
    for first in (tmp_path / "nosuch", dump / "trace.csv"):
        done = vtrack("vectors", "check", str(first), str(out))
        assert done.returncode == 2, done.stdout + done.stderr
        assert done.stderr.startswith(f"vtrack: error: {first}: ") and "come first" not in \
            done.stderr, done.stderr
    assert vtrack("vectors", "check", str(out), str(dump)).returncode == 0


@pytest.mark.parametrize(("box", "problem"), [
    ("500,500,40,30", "lies outside the"), ("0,0,2,2", "smaller than 4x4"),
    ("0,0,5000,5000", "larger than the"),
])
def test_vectors_refuse_the_initial_boxes_run_refuses(vectors, tmp_path, box: str,
                                                      problem: str) -> None:
    """A box with no pixel in the frame gave vectors of nothing (exit 0)."""
    _, clip = vectors
    result = vtrack("vectors", str(clip.path), "--init", box, "--frames", "2", "--out",
                    str(tmp_path / "v"))
    assert result.returncode == 2 and "Traceback" not in result.stderr, result.stderr
    assert result.stderr.strip().startswith(f"vtrack: error: --init: the box {box}")
    assert problem in result.stderr and not (tmp_path / "v").exists()


def test_an_undecodable_frame_is_named_and_the_folders_keep_frame_numbers(
        vectors, tmp_path) -> None:
    """A frame skipped as undecodable went unmentioned, and the folders were renumbered past it
    (frame_0006 held frame 7's picture while trace.csv said 7)."""
    _, clip = vectors
    folder = write_image_sequence(clip.scene, tmp_path / "seq")
    (folder / "img" / "0007.jpg").write_bytes(b"junk")  # frame 6 (0-based)
    box = clip.scene.boxes[0]
    out = tmp_path / "v"
    result = vtrack("vectors", str(folder), "--config", "s0-fixed", "--init",
                    f"{box.x},{box.y},{box.w},{box.h}", "--frames", "8", "--out", str(out))
    assert result.returncode == 0, result.stderr
    assert "0007.jpg" in result.stderr and "frame 6 skipped" in result.stderr
    with (out / "trace.csv").open(newline="") as handle:
        frames = [int(row["frame"]) for row in csv.DictReader(handle)]
    assert frames == [0, 1, 2, 3, 4, 5, 7, 8]
    assert sorted(p.name for p in out.glob("frame_*")) == [f"frame_{i:04d}" for i in frames]



def test_vectors_written_again_leave_nothing_of_the_earlier_ones(vectors, tmp_path) -> None:
    """Six frames of s0-fixed, then two of s2-fixed into the same folder: frame_0002..0005
    and s0's hue/bp files stayed, and `vectors check` compared a dump with those stale frames."""
    _, clip = vectors
    box = clip.scene.boxes[0]
    out = tmp_path / "vec"
    (out / "frame_0000").mkdir(parents=True)
    (out / "notes.txt").write_text("mine")  # not vtrack's: kept
    for config, frames in (("s0-fixed", "6"), ("s2-fixed", "2")):
        result = vtrack("vectors", str(clip.path), "--config", config, "--init",
                        f"{box.x},{box.y},{box.w},{box.h}", "--frames", frames, "--out",
                        str(out))
        assert result.returncode == 0, result.stderr
    assert sorted(p.name for p in out.iterdir()) == [
        "frame_0000", "frame_0001", "iterations.csv", "manifest.json", "notes.txt", "trace.csv"]
    assert sorted(p.name for p in (out / "frame_0000").iterdir()) == ["gray.hex", "rgb.hex"]



def _tree(folder: Path) -> dict[str, bytes]:
    return {str(p.relative_to(folder)): p.read_bytes() for p in sorted(folder.rglob("*"))
            if p.is_file()}


def test_a_file_at_a_frame_folders_path_is_refused_and_the_earlier_vectors_stay(
        vectors, tmp_path) -> None:
    """`vtrack vectors c.mp4 ... --frames 10 -o v`, then `rm -r v/frame_0005; echo x >
    v/frame_0005` and the same command again: 'v/frame_0005: cannot write (Not a
    directory)', exit 2, with the earlier vectors removed first, the new ones put in place
    part way (frame_0000..0004) and no manifest.json. The file is now refused before
    anything is put in place or removed: one line, and the folder as it was."""
    _, clip = vectors
    box = clip.scene.boxes[0]
    out = tmp_path / "v"
    args = ("vectors", str(clip.path), "--init", f"{box.x},{box.y},{box.w},{box.h}",
            "--frames", "10", "--out", str(out))
    assert vtrack(*args).returncode == 0
    shutil.rmtree(out / "frame_0005")
    (out / "frame_0005").write_text("x\n")
    before = _tree(out)
    result = vtrack(*args)
    assert result.returncode == 2, result.stderr
    assert result.stderr.strip().splitlines() == [
        f"vtrack: error: {out / 'frame_0005'}: cannot write output here (a file, not a "
        "folder)"]  # (a third wording: "cannot write (a file, not a folder, is in the way)")
    assert _tree(out) == before
    assert not [p for p in out.rglob(".*")]  # no temporary name left


def test_a_folder_named_trace_csv_in_the_output_is_one_error_line(vectors, tmp_path) -> None:
    """`mkdir -p v2/trace.csv; vtrack vectors ... -o v2` ended in a traceback
    (IsADirectoryError from unlink). Now one line naming it, exit 2, nothing written."""
    _, clip = vectors
    box = clip.scene.boxes[0]
    out = tmp_path / "v2"
    (out / "trace.csv").mkdir(parents=True)
    result = vtrack("vectors", str(clip.path), "--init", f"{box.x},{box.y},{box.w},{box.h}",
                    "--frames", "3", "--out", str(out))
    assert result.returncode == 2, result.stderr
    assert result.stderr.strip().splitlines() == [
        f"vtrack: error: {out / 'trace.csv'}: cannot write (a folder of that name is in the "
        "way)"]
    assert [p.name for p in out.iterdir()] == ["trace.csv"]


def test_a_signal_once_the_vectors_are_in_place_changes_nothing(vectors, tmp_path) -> None:
    """SIGTERM as soon as v/manifest.json appeared on `vtrack vectors big.mp4 --init ...
    --frames 20 -o v` (1280x720) ended 'vtrack: interrupted' (143) in 6 runs of 8, the
    vectors whole and final: the signal still interrupted while the staged files' names were
    cleared, the input's warnings told and the input closed. Now exit 0. The signal is sent
    to the main thread as the staged files' leftovers are discarded, after their commit (a
    trace function)."""
    from click.testing import CliRunner

    from vtrack.cli import main
    from vtrack.io.files import StagedFiles

    _, clip = vectors
    box = clip.scene.boxes[0]
    with sigterm_as_called(StagedFiles.discard.__code__):
        result = CliRunner().invoke(main, [
            "vectors", str(clip.path), "--init", f"{box.x},{box.y},{box.w},{box.h}",
            "--frames", "3", "--out", str(tmp_path / "v")])
    assert result.exit_code == 0, result.output
    assert len(list((tmp_path / "v").glob("frame_*"))) == 3

def test_a_clip_shorter_than_the_frames_asked_for_is_said(vectors, tmp_path) -> None:
    _, clip = vectors
    box = clip.scene.boxes[0]
    result = vtrack("vectors", str(clip.path), "--config", "s0-fixed", "--init",
                    f"{box.x},{box.y},{box.w},{box.h}", "--frames", "40", "--out",
                    str(tmp_path / "v"))
    assert result.returncode == 0, result.stderr
    assert (f"vtrack: warning: {clip.path}: 30 frames to write of the 40 asked for (--frames)"
            in result.stderr)


def test_vectors_help_lists_the_options_of_vtrack_vectors_input() -> None:
    result = vtrack("vectors", "--help")
    assert result.returncode == 0, result.stderr
    text = result.stdout
    options = text.split("Options of vtrack vectors INPUT:")[1]
    for option in ("--config", "--init", "--frames", "--out", "--set"):
        assert option in options, text
    assert "[default: 10]" in options and "Commands:" in text and "check" in text
    # every row is an option (click 8.5.1 gave the argument INPUT a bare row of its own)
    rows = [line.split()[0] for line in options.splitlines() if line[2:3].strip()]
    assert rows and all(row.startswith("-") for row in rows), options


def _s2_vectors(clip, out: Path, frames: int) -> Path:
    """``vtrack vectors`` of ``frames`` frames of ``clip`` with s2-fixed into ``out``."""
    box = clip.scene.boxes[0]
    made = vtrack("vectors", str(clip.path), "--config", "s2-fixed", "--init",
                  f"{box.x},{box.y},{box.w},{box.h}", "--frames", str(frames), "--out", str(out))
    assert made.returncode == 0, made.stderr
    return out


def test_s2_vectors_manifest_says_what_every_trace_and_iteration_column_is(vectors,
                                                                           tmp_path) -> None:
    """S0's manifest.json described its trace.csv (the s0 section) but S2's said nothing of
    trace.csv nor iterations.csv (r, r_prime, s, rho, c, s_t, c_prime ...: units, blanks) and
    left out the model histogram q_u a bench starts from."""
    _, clip = vectors
    out = _s2_vectors(clip, tmp_path / "s2", frames=3)
    section = json.loads((out / "manifest.json").read_text())["s2"]
    described = " ".join(section[key] for key in ("trace", "iterations"))
    words = {w.strip(",=:;()") for w in described.split()}
    for name in ("trace.csv", "iterations.csv"):
        with (out / name).open() as f:
            header = next(csv.reader(f))
        assert [c for c in header if c not in words and c != "frame"] == [], name
    with (out / "trace.csv").open() as f:
        first = next(csv.DictReader(f))
    assert sum(section["histogram_counts"]) == int(first["c"])  # C = sum q_u
    assert max(section["histogram_counts"]) == section["histogram_max"] > 0


def test_check_reads_a_dump_as_readmemh_does(vectors, tmp_path) -> None:
    """A dump written by a simulator's $writememh (a '//' header, '@addr' words, no leading
    zeros) loads into the same memory as the vectors but was '12256 differing value(s); line 1
    (x=0, y=0): expected .., got //'; a real difference in it is still named."""
    out, _ = vectors
    words = (out / "frame_0001" / "hue.hex").read_text().split()
    dump = tmp_path / "dump" / "frame_0001"
    dump.mkdir(parents=True)
    body = "".join(f"@{i:x} {int(w, 16):x}\n" for i, w in enumerate(words))
    (dump / "hue.hex").write_text("// memory data file\n/* format=hex */\n" + body)
    same = vtrack("vectors", "check", str(out), str(dump.parent))
    assert (same.returncode, same.stdout) == (0, "1 file(s) equal\n"), same.stdout
    changed = (int(words[5], 16) + 1) % 256
    (dump / "hue.hex").write_text(body + f"@5 {changed:x}\n")  # a later word at address 5
    differ = vtrack("vectors", "check", str(out), str(dump.parent))
    assert differ.returncode == 1
    assert differ.stdout == (f"frame_0001/hue.hex: 1 differing value(s); line 6 (x=5, y=0): "
                             f"expected {words[5]}, got {changed:02x}\n")


def test_check_says_what_kind_of_difference_a_dump_has(vectors, tmp_path) -> None:
    """A vector set of another config was compared file by file ('missing 17 column(s)...');
    an empty value read 'got ' and a truncated dump '0 differing value(s); 100 lines,
    expected 76800'."""
    out, clip = vectors
    s2 = _s2_vectors(clip, tmp_path / "s2", frames=2)
    other = vtrack("vectors", "check", str(out), str(s2))
    assert (other.returncode, other.stdout) == (2, ""), other.stdout
    assert other.stderr == (f"vtrack: error: {s2}: vectors of s2-fixed, {out} holds vectors of "
                            "s0-fixed (their manifest.json): compare vectors of one config\n")
    # one value left empty, one file cut short
    with (out / "trace.csv").open(newline="") as handle:
        rows = list(csv.reader(handle))
    column = rows[0].index("sum_bp")
    expected, rows[2][column] = rows[2][column], ""  # frame 1
    dump = tmp_path / "dump"
    (dump / "frame_0001").mkdir(parents=True)
    with (dump / "trace.csv").open("w", newline="") as handle:
        csv.writer(handle).writerows(rows)
    words = (out / "frame_0001" / "hue.hex").read_text().splitlines()
    (dump / "frame_0001" / "hue.hex").write_text("".join(w + "\n" for w in words[:100]))
    differ = vtrack("vectors", "check", str(out), str(dump))
    assert differ.returncode == 1, differ.stderr
    assert differ.stdout.splitlines() == [
        f"frame_0001/hue.hex: truncated (100 of {len(words)} lines)",
        f"trace.csv: 1 differing value(s); frame 1 column sum_bp: expected {expected}, "
        "got nothing"]


def test_a_vector_word_that_is_no_number_is_compared_not_a_traceback() -> None:
    """A vectors file holding a word ``$readmemh`` loads as no number (``xx``) was read with
    ``int(w, 16)``: a ValueError traceback instead of a difference line."""
    from vtrack.golden.vectors import _hex_differences

    assert _hex_differences("rgb.hex", b"xx\n01\n", b"xx\n01\n", 2) is None
    found = _hex_differences("rgb.hex", b"xx\n01\n", b"00\n01\n", 2)
    assert found is not None and "expected xx, got 00" in found, found


def test_an_error_of_vtrack_vectors_input_names_the_command_typed() -> None:
    """`vtrack vectors clip.mp4 -o out` (no --init) said "(see 'vtrack vectors generate
    --help')", a command no help lists; the usage of `vtrack vectors clip.mp4 --help` said
    'vtrack vectors generate [OPTIONS] INPUT'. Both now name what was typed, vtrack vectors."""
    result = vtrack("vectors", "clip.mp4", "-o", "out")
    assert result.returncode == 2
    line = result.stderr.strip()  # (run as python -m vtrack)
    assert line.startswith("vtrack: error: Missing option '--init'.") and "\n" not in line, line
    assert line.endswith(" vtrack vectors --help')"), line
    usage = vtrack("vectors", "clip.mp4", "--help").stdout
    assert "vtrack vectors [OPTIONS] INPUT" in usage and "generate" not in usage, usage


def test_a_dumps_names_and_values_stay_one_line_each(vectors, tmp_path) -> None:
    """A dump's trace.csv value holding a newline (a quoted CSV cell) and a dumped file named
    with a newline or a terminal escape were printed as they are: 'trace.csv: ... got 12' then
    a line 'fake line: ok' of its own, and ESC [2J cleared the user's terminal."""
    out, _ = vectors
    with (out / "trace.csv").open(newline="") as handle:
        rows = list(csv.reader(handle))
    column = rows[0].index("sum_bp")
    expected, rows[2][column] = rows[2][column], "12\nfake line: ok"  # frame 1
    dump = tmp_path / "dump"
    dump.mkdir()
    with (dump / "trace.csv").open("w", newline="") as handle:
        csv.writer(handle).writerows(rows)
    (dump / "evil\nname.hex").write_text("00\n")
    (dump / "\x1b[2Jclear.hex").write_text("00\n")
    differ = vtrack("vectors", "check", str(out), str(dump))
    assert differ.returncode == 1, differ.stderr
    assert differ.stdout.splitlines() == [
        "\\x1b[2Jclear.hex: not in the vectors",
        "evil\\nname.hex: not in the vectors",
        f"trace.csv: 1 differing value(s); frame 1 column sum_bp: expected {expected}, "
        "got 12\\nfake line: ok"]


@pytest.mark.parametrize(("name", "damage", "problem"), [
    ("frame_0001/rgb.hex", lambda data: data[: len(data) // 2],
     "(38400 lines where its manifest.json gives 76800)"),
    ("frame_0001/rgb.hex", lambda data: data[:1000], "(its last line, 143, is cut short)"),
    ("frame_0001/bp.hex", lambda data: data.replace(data[:3], b"zz\n", 1),
     "(line 1 is zz, not 2 hex digits)"),
    ("trace.csv", lambda data: data[: data.rindex(b"\n", 0, -1) + 1],
     f"({FRAMES - 1} rows where its manifest.json gives {FRAMES} frames)"),
    ("trace.csv", lambda data: data[:-40] + b"\n", f"(line {FRAMES + 1} has "),
    ("trace.csv", lambda data: data[:-3], f"(its last line, {FRAMES + 1}, is cut short)"),
    ("trace.csv", lambda data: data.replace(b"\n", b"\n\n", 1)[:-40] + b"\n",  # a blank line
     f"(line {FRAMES + 2} has "),
])
def test_damaged_vectors_are_an_error_not_a_difference_of_the_dump(
        vectors, tmp_path, name: str, damage, problem: str) -> None:
    """A vectors folder with a file cut short or changed was compared as if it were whole, and
    the dump got the blame (exit 1): 'frame_0001/rgb.hex: 76800 lines, expected 38400',
    'trace.csv: 4 rows, expected 3', 'line 1 (x=0, y=0): expected zz, got ..'."""
    out, _ = vectors
    damaged = tmp_path / "vec"
    shutil.copytree(out, damaged)
    (damaged / name).write_bytes(damage((out / name).read_bytes()))
    done = vtrack("vectors", "check", str(damaged), str(out))
    assert (done.returncode, done.stdout) == (2, ""), done.stdout + done.stderr
    assert done.stderr.startswith(f"vtrack: error: {damaged / name}: not the file vtrack "
                                  f"vectors wrote {problem}"), done.stderr
    assert done.stderr.endswith("; write the vectors again\n") and done.stderr.count("\n") == 1
    whole = vtrack("vectors", "check", str(out), str(out))
    assert (whole.returncode, whole.stderr) == (0, ""), whole.stderr


@pytest.mark.parametrize(("name", "change"), [
    ("frame_0001/bp.hex", lambda data: data.replace(b"\n", b"\r\n")),  # a Windows checkout
    ("frame_0001/rgb.hex", bytes.upper),  # re-saved by an HDL tool
    ("notes.csv", lambda _: b"note,value\nlast,1"),  # the user's own, with no last newline
    ("notes.csv", lambda _: b"a,b\n1\n"),  # the user's own, a row short of a value
    ("notes.csv", lambda _: b"a,b\n1\n1,2,3\n"),  # ... and a row with a value past the header
    ("mytest/rgb.hex", lambda _: b"ff0000\n00ff"),  # the user's own, named like a vector
])
def test_vectors_changed_but_not_damaged_are_compared_as_before(
        vectors, tmp_path, name: str, change) -> None:
    """Vectors a checkout or a tool changed without changing a value (and the user's own files
    in the folder) were refused as damaged: 'frame_0001/bp.hex: not the file vtrack vectors
    wrote (line 1 is 13\\r, not 2 hex digits)'. They compare with the dump as before."""
    out, _ = vectors
    changed, dump = tmp_path / "vec", tmp_path / "dump"
    shutil.copytree(out, changed)
    shutil.copytree(out, dump)
    ours = (out / name).is_file()
    data = change((out / name).read_bytes() if ours else b"")
    # a vector changed is checked against the whole dump; a file of the user's own is in both
    for folder in (changed,) if ours else (changed, dump):
        (folder / name).parent.mkdir(exist_ok=True)
        (folder / name).write_bytes(data)
    done = vtrack("vectors", "check", str(changed), str(dump))
    assert (done.returncode, done.stderr) == (0, ""), done.stdout + done.stderr
    assert done.stdout.endswith(" file(s) equal\n"), done.stdout


@pytest.mark.parametrize(("mine", "dumped", "difference"), [
    (b"a,b\n1\n", b"a,b\n1,2\n", "frame 0 column b: expected nothing, got 2"),
    (b"a,b\n1,2,3\n", b"a,b\n1,2,4\n", "frame 0 values past the header: expected 3, got 4"),
    (b"a,b\n1,2\n", b"a,b\n1,2,3,4\n",
     "frame 0 values past the header: expected nothing, got 3,4"),
    # a row short of its frame value is named by its place (it said "frame  column a")
    (b"a,frame\n1\n", b"a,frame\n2\n", "frame 0 column a: expected 1, got 2"),
])
def test_ragged_rows_of_the_users_own_csv_are_a_difference(
        vectors, tmp_path, mine: bytes, dumped: bytes, difference: str) -> None:
    """A CSV of the user's own with a row short of a value or with values past the header
    crashed vtrack vectors check with a TypeError traceback (float(None), float(['3'])), or
    said equal when only the dump had the values past the header. A missing value is nothing,
    the values past the header are compared as one text."""
    out, _ = vectors
    changed, dump = tmp_path / "vec", tmp_path / "dump"
    shutil.copytree(out, changed)
    shutil.copytree(out, dump)
    (changed / "notes.csv").write_bytes(mine)
    (dump / "notes.csv").write_bytes(dumped)
    done = vtrack("vectors", "check", str(changed), str(dump))
    assert (done.returncode, done.stderr) == (1, ""), done.stdout + done.stderr
    assert f"notes.csv: 1 differing value(s); {difference}\n" in done.stdout, done.stdout


def test_check_says_when_the_vectors_are_of_another_vtrack_version(vectors, tmp_path) -> None:
    """``vtrack vectors check`` ignored the manifest's ``vtrack`` version: vectors written by
    another version are still compared (the format is stable), with one warning line naming
    both versions; vectors of this version, none."""
    from vtrack import __version__

    out, _ = vectors
    same = vtrack("vectors", "check", str(out), str(out))
    assert (same.returncode, same.stderr) == (0, ""), same.stderr
    older = tmp_path / "older"
    shutil.copytree(out, older)
    manifest = json.loads((older / "manifest.json").read_text())
    assert manifest["vtrack"] == __version__
    manifest["vtrack"] = "0.0.1"
    (older / "manifest.json").write_text(json.dumps(manifest))
    done = vtrack("vectors", "check", str(older), str(out))
    assert done.returncode == 0, done.stderr
    assert done.stderr == (f"vtrack: warning: {older}: vectors written by vtrack 0.0.1, checked "
                           f"by vtrack {__version__} (manifest.json): a difference may be the "
                           "versions'\n")
    assert done.stdout.endswith("file(s) equal\n")
