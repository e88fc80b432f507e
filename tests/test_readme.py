"""Every command of the README runs as written (issue 22): each ```bash block (and the vectors
block) is run line by line in a fresh folder holding the inputs it names, generated with
``vtrack.scenes``; each line must succeed, and what a comment promises (``# -> FOLDER/``) must be
there. The Python blocks run too, the sample's summary line is the one the README quotes (its
fps aside), and every ``--set`` example is valid for the config it is given with.

Lines that need what a test machine does not have are listed in ``SKIPPED`` with the reason.
"""

from __future__ import annotations

import os
import re
import shlex
import shutil
import signal
import socket
import subprocess
import sys
import time
from pathlib import Path

import pytest
from conftest import START_BOUND_S

from vtrack.config import load_config
from vtrack.configs import DEFAULT_CONFIG
from vtrack.scenes import make_scene, write_clip

ROOT = Path(__file__).resolve().parent.parent
README = (ROOT / "README.md").read_text()

#: Lines not run, by a piece of their text, and why.
SKIPPED = {
    "pip install": "installs the package (the test runs the source tree)",
    "pytest": "the test suite itself",
    "vtrack select": "needs a person dragging a box in a browser (tests/test_select.py)",
    "ffmpeg ": "needs the ffmpeg program (the same input is tested from a file in test_io.py)",
    "mkfifo": "needs a second program writing the FIFO (tests/test_live_inputs.py)",
    "http://": "needs a web server (tests/test_live_inputs.py)",
    "udp://": "needs a live sender (tests/test_live_inputs.py)",
    "rtsp://": "needs an RTSP camera or sender (tests/test_live_inputs.py)",
    "tcp://": "needs a TCP sender (tests/test_live_inputs.py)",
    "/dev/video": "needs a camera (tests/test_live_inputs.py)",
    "--follow": "needs a program writing the file (tests/test_live_inputs.py)",
    "drone.h264": "needs a raw H.264 recording (--format is tested in tests/test_live_inputs.py)",
    "--scheduler": "needs a Dask cluster (test_readme_dask_cluster_recipe_runs)",
    "dask scheduler": "starts a Dask cluster (test_readme_dask_cluster_recipe_runs)",
    "dask worker": "starts a Dask cluster (test_readme_dask_cluster_recipe_runs)",
}


def _blocks() -> list[str]:
    """The README's shell blocks: ```bash, and bare ``` blocks of vtrack commands."""
    blocks = re.findall(r"```bash\n(.*?)```", README, re.S)
    blocks += [b for b in re.findall(r"```\n(.*?)```", README, re.S)
               if b.lstrip().startswith("vtrack ")]
    return blocks


def _commands(block: str) -> list[str]:
    """The block's command lines, comments cut off (continuation comment lines dropped)."""
    lines = []
    for line in block.splitlines():
        command = re.split(r"\s+#\s", " " + line, maxsplit=1)[0].strip()
        if command and not command.startswith("#"):
            lines.append(command)
    return lines


@pytest.fixture(scope="module")
def inputs(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """Every input the README's commands name, generated once."""
    root = tmp_path_factory.mktemp("readme-inputs")
    # seed 1: the target is where the README's --init 120,80,40,30 puts it
    scene = make_scene("smooth", seed=1, width=320, height=240, frames=150, fps=30)
    write_clip(scene, root / "clip.mp4", preset="veryfast")
    write_clip(make_scene("smooth", seed=0, frames=30), root / "Girl", fmt="images")
    for name, seed in (("a", 2), ("b", 3)):
        files = write_clip(make_scene("smooth", seed=seed, frames=30),
                           root / "footage" / f"{name}.mp4", preset="veryfast")
        # what `vtrack select` would have saved: the first box
        first = files.groundtruth.read_text().splitlines()[0]
        (root / "footage" / f"{name}.init.txt").write_text(first + "\n")
        files.groundtruth.unlink()
    (root / "data").mkdir()
    for name in ("clip.mp4", "clip.gt.txt"):
        shutil.copy(root / name, root / "data" / name)
    shutil.copytree(ROOT / "samples", root / "samples")
    return root


def _shell(tmp_path: Path) -> dict[str, str]:
    """An environment whose ``vtrack`` is this source tree's."""
    bin_dir = tmp_path / ".bin"
    bin_dir.mkdir(exist_ok=True)
    script = bin_dir / "vtrack"
    script.write_text(f'#!/bin/sh\nexec "{sys.executable}" -m vtrack "$@"\n')
    script.chmod(0o755)
    return {**os.environ, "PATH": f"{bin_dir}{os.pathsep}{os.environ['PATH']}",
            "PYTHONPATH": str(ROOT)}


@pytest.mark.parametrize("block", _blocks(), ids=lambda b: _commands(b)[0][:40])
def test_readme_block_runs(block: str, inputs: Path, tmp_path: Path) -> None:
    work = tmp_path / "work"
    shutil.copytree(inputs, work)
    env = _shell(tmp_path)
    for line in block.splitlines():
        command = _commands(line)
        if not command:
            continue
        text = command[0]
        if any(key in text for key in SKIPPED):
            continue
        if text.startswith("vtrack vectors check"):  # a bench's dump: here the vectors again
            shutil.copytree(work / "vec", work / "sim_dump")
        done = subprocess.run(["bash", "-c", text], cwd=work, env=env, capture_output=True,
                              text=True, timeout=300, check=False)
        assert done.returncode == 0, f"{text}\n{done.stderr}"
        promised = re.search(r"#\s*-> (\S+/)", line)
        if promised:
            assert (work / promised.group(1)).is_dir(), (text, promised.group(1))


def test_readme_run_lines_in_order_each_write_a_folder_of_their_own() -> None:
    """A reader who runs the README's commands in order in one folder is never refused for an
    earlier example's results: each ``vtrack run`` line writes its own folder (its ``--out``,
    else ``vtrack-out/<input>/<config>/``), unless it is the same command shown again. (Four
    lines on stdin all wrote ``vtrack-out/stdin/robust``, the ``--start 60`` one the
    ``clip.mp4`` one's, the ``--video-out`` one the UDP one's: each was refused, 'holds the
    results of an earlier run'.)"""
    from vtrack.cli.run import command, default_out_dir

    written: dict[Path, str] = {}
    for block in _blocks():
        for line in _commands(block):
            for part in re.split(r"\||&&|;", line):
                words = shlex.split(part.split("<")[0])
                if words[:2] != ["vtrack", "run"]:
                    continue
                params = command.make_context("run", words[2:], resilient_parsing=True).params
                assert not params["overwrite"], line  # -y would replace, not say so
                configs = params["config_specs"]
                name = load_config(configs[0]).name if configs else DEFAULT_CONFIG
                folder = params["out_dir"] or default_out_dir(params["input_spec"], name)
                earlier = written.setdefault(Path(folder), part.strip())
                assert earlier == part.strip(), f"{folder}: {earlier!r}, then {part.strip()!r}"
    assert len(written) >= 10


def test_readme_dask_cluster_recipe_runs(inputs: Path, tmp_path: Path) -> None:
    """README's recipe for a Dask cluster (``dask scheduler``, ``dask worker ADDRESS
    --nworkers 2 --nthreads 1`` started from another folder) runs its ``vtrack batch
    --scheduler`` line to the end; README said nothing of how to start one. On loopback: a free
    port for the scheduler's and no dashboard (its port may be taken)."""
    pytest.importorskip("distributed")
    lines = [command for block in _blocks() for command in _commands(block)]
    scheduler = next(c for c in lines if c.startswith("dask scheduler"))
    worker = next(c for c in lines if c.startswith("dask worker"))
    batch = next(c for c in lines if c.startswith("vtrack batch") and "--scheduler" in c)
    address = re.search(r"tcp://\S+", worker).group(0)
    assert f"--scheduler {address}" in batch
    with socket.socket() as probe:
        probe.bind(("127.0.0.1", 0))
        port = probe.getsockname()[1]
    env = _shell(tmp_path)
    shim = tmp_path / ".bin" / "dask"
    shim.write_text(f'#!/bin/sh\nexec "{sys.executable}" -m dask "$@"\n')
    shim.chmod(0o755)
    work, elsewhere = tmp_path / "work", tmp_path / "elsewhere"
    shutil.copytree(inputs, work)
    elsewhere.mkdir()
    local = f"tcp://127.0.0.1:{port}"
    started: list[subprocess.Popen[bytes]] = []

    def start(command: str) -> None:
        started.append(subprocess.Popen(["bash", "-c", f"exec {command}"], cwd=elsewhere,
                                        env=env, start_new_session=True,
                                        stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL))

    try:
        start(f"{scheduler} --host 127.0.0.1 --port {port} --no-dashboard")
        deadline = time.monotonic() + START_BOUND_S
        while True:  # listening before the batch asks (a refused connection is an error)
            with socket.socket() as probe:
                if probe.connect_ex(("127.0.0.1", port)) == 0:
                    break
            assert time.monotonic() < deadline and started[0].poll() is None, scheduler
            time.sleep(0.2)
        start(f"{worker.replace(address, local)} --no-dashboard")
        command = batch.replace(address, local).replace("/shared/results", "results")
        done = subprocess.run(["bash", "-c", command], cwd=work, env=env, capture_output=True,
                              text=True, timeout=300, check=False)
        assert done.returncode == 0, f"{command}\n{done.stderr}"
        assert "(1 complete)" in done.stdout, done.stdout
        assert (work / "results" / "clip" / DEFAULT_CONFIG / "run.json").is_file()
    finally:
        for process in started:
            if process.poll() is None:
                os.killpg(process.pid, signal.SIGKILL)
            process.wait()


def test_readme_sample_summary_is_what_the_command_prints(inputs: Path, tmp_path: Path) -> None:
    quoted = re.search(r"summary line such as\n`(.*?)`", README, re.S).group(1)
    command = next(c for c in _commands(_blocks()[0]) if "vtrack run" in c)
    command = command.split("&&")[-1].strip()
    shutil.copytree(inputs / "samples", tmp_path / "samples")
    done = subprocess.run(["bash", "-c", command], cwd=tmp_path, env=_shell(tmp_path),
                          capture_output=True, text=True, timeout=300, check=False)
    assert done.returncode == 0, done.stderr
    printed = done.stdout.strip().splitlines()[-1]
    fps = re.compile(r"[\d.]+ fps")
    assert fps.sub("N fps", printed) == fps.sub("N fps", " ".join(quoted.split()))


def test_readme_python_blocks_run(inputs: Path, tmp_path: Path,
                                  monkeypatch: pytest.MonkeyPatch) -> None:
    blocks = re.findall(r"```python\n(.*?)```", README, re.S)
    assert blocks
    monkeypatch.chdir(inputs)
    frames = list(make_scene("smooth", seed=4, frames=10).frames())
    # one namespace, as a reader types the blocks in order
    namespace = {"first_frame": frames[0], "frames": frames[1:], "print": lambda *a: None}
    for block in blocks:
        exec(compile(block, "README.md", "exec"), namespace)  # noqa: S102 - the README's code


def test_readme_set_examples_are_valid_for_their_config() -> None:
    """Every ``--set`` of a code span or command line loads with that span's ``-c`` (else the
    default config); quoted error messages (``vtrack: error: --set ...``) are not examples."""
    fenced = re.compile(r"```\w*\n(.*?)```", re.S)
    spans = re.findall(r"`([^`]+)`", fenced.sub("", README)) + [
        line for block in fenced.findall(README) for line in block.splitlines()]
    checked = 0
    for span in spans:
        assignments = re.findall(r"--set\s+([\w.]+=[\w.]+)", span)
        if not assignments or span.lstrip().startswith("vtrack: error"):
            continue
        config = re.search(r"(?:-c|--config)\s+(\S+)", span)
        load_config(config.group(1) if config else DEFAULT_CONFIG).with_overrides(assignments)
        checked += len(assignments)
    assert checked >= 8


def test_readme_and_help_say_the_profile_crf_0_writes(tmp_path: Path) -> None:
    """`--crf 0` writes lossless H.264 in the High 4:4:4 Predictive profile (yuv420p still),
    which many players refuse; README and --help said only 'lower is better and larger'."""
    import av

    clip = tmp_path / "c.mp4"
    done = subprocess.run([sys.executable, "-m", "vtrack", "scene", "smooth", str(clip),
                           "--frames", "12", "--crf", "0"], capture_output=True, text=True,
                          timeout=120, check=False)
    assert done.returncode == 0, done.stderr
    with av.open(str(clip)) as container:
        stream = container.streams.video[0].codec_context
        profile, pix_fmt = stream.profile, stream.pix_fmt
    assert (profile, pix_fmt) == ("High 4:4:4 Predictive", "yuv420p")
    assert f"`--crf 0` is lossless: x264 writes it in the {profile}" in " ".join(README.split())
    for command in ("run", "scene"):
        shown = subprocess.run([sys.executable, "-m", "vtrack", command, "--help"],
                               capture_output=True, text=True, timeout=60, check=True).stdout
        assert "0 is lossless, in a profile (High 4:4:4) many players refuse" in " ".join(
            shown.split()), shown


@pytest.mark.parametrize("pix_fmt", ["yuv444p", "yuv422p"])
def test_readme_and_help_say_the_profile_scene_pix_fmt_writes(tmp_path: Path,
                                                              pix_fmt: str) -> None:
    """`vtrack scene --pix-fmt yuv444p` (yuv422p) writes H.264 in the High 4:4:4 Predictive
    (High 4:2:2) profile, which many players refuse as they do `--crf 0`'s; README and
    `vtrack scene --help` said only 'encoder pixel format'."""
    import av

    clip = tmp_path / "c.mp4"
    done = subprocess.run([sys.executable, "-m", "vtrack", "scene", "smooth", str(clip),
                           "--frames", "12", "--pix-fmt", pix_fmt], capture_output=True,
                          text=True, timeout=120, check=False)
    assert done.returncode == 0, done.stderr
    with av.open(str(clip)) as container:
        profile = container.streams.video[0].codec_context.profile
    readme = " ".join(README.split())
    assert ("a `vtrack scene --pix-fmt yuv444p` or `--pix-fmt yuv422p` one: the High 4:4:4 "
            "Predictive and High 4:2:2 profiles" in readme)
    assert profile in readme
    shown = " ".join(subprocess.run([sys.executable, "-m", "vtrack", "scene", "--help"],
                                    capture_output=True, text=True, timeout=60,
                                    check=True).stdout.split())
    assert ("yuv444p and yuv422p write profiles (High 4:4:4, High 4:2:2) many players refuse"
            in shown), shown
    assert " ".join(profile.split()[:2]) in shown
