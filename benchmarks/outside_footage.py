"""Lay out real footage from outside ``../shared/data`` for the accuracy benchmarks.

    python benchmarks/outside_footage.py OUT --clone OWNER/NAME=PATH [--clone ...]

Reads public GitHub repositories that ship tracking sequences (each cloned beforehand, bare or
not: ``git clone https://github.com/OWNER/NAME PATH``) and writes, under ``OUT``:

- ``OUT/single/NAME/img/00001.jpg ...`` + ``groundtruth.txt`` (one 1-based ``x,y,w,h`` line a
  frame, ``nan,nan,nan,nan`` where the target is absent): the data folder's layout, for
  ``VTRACK_DATA=OUT/single python benchmarks/robust_tune.py`` and ``robust_bench.py``;
- ``OUT/mot/NAME/`` with ``gt/gt.txt`` and ``img1/`` (or the sequence's video) and
  ``seqinfo.ini``: MOTChallenge's layout, for ``VTRACK_MOT=OUT/mot/A:OUT/mot/B python
  benchmarks/multi_bench.py 1 outside``.

Sequences whose repository is not given are skipped with a line naming the clone they need;
those with a file the clone lists but does not hold (a copy made without its large files, or one
holding only the Git LFS pointer of a file whose content was never fetched) with a line naming
the file, and nothing of them is written.
None of ``robust``'s or ``fixed_camera``'s values were chosen on these (benchmarks/RESULTS.md,
sections 5 and 8, say where they were used to check a change).
"""

from __future__ import annotations

import argparse
import subprocess
import sys
from pathlib import Path

CPCF, OMFL = "vision4robotics/CPCF-Tracker", "vision4robotics/OMFL-Tracker"
MEANSHIFT, KALMAN = "lanshiyinging/MeanShift-for-Tracking", "mishless/kalman-filter-project"
MASA, RPI = "gonzalocarreteroh/MASA-OA", "nathanrooy/rpi-urban-mobility-tracker"

#: Single-target sequences: (name, repository, frames folder, ground-truth file, first frame
#: index into the folder's sorted images, ground-truth format: "xywh" or "tlp").
SINGLE = (
    ("UAV123_boat1", CPCF, "CPCF-tracker1/seq/boat1", "CPCF-tracker1/seq/boat1.txt", 0, "xywh"),
    ("UAV123_building4", CPCF, "CPCF-tracker1/seq/building4", "CPCF-tracker1/seq/building4.txt",
     0, "xywh"),
    ("UAV123_person12_1", CPCF, "CPCF-tracker1/seq/person12", "CPCF-tracker1/seq/person12_1.txt",
     0, "xywh"),
    ("UAV123_truck4_1", CPCF, "CPCF-tracker1/seq/truck4", "CPCF-tracker1/seq/truck4_1.txt", 0,
     "xywh"),
    ("UAV123_truck4_2", CPCF, "CPCF-tracker1/seq/truck4", "CPCF-tracker1/seq/truck4_2.txt", 193,
     "xywh"),
    ("UAV123_car10", OMFL, "UAV123_10fps/data_seq/car10", "UAV123_10fps/anno/car10.txt", 0,
     "xywh"),
    ("OTB_Bolt", MEANSHIFT, "MeanShift/Bolt/img", "MeanShift/Bolt/groundtruth_rect.txt", 0,
     "xywh"),
    ("OTB_Basketball", KALMAN, "data/basketball/img", "data/basketball/groundtruth_rect.txt", 0,
     "xywh"),
    ("OTB_Car1", KALMAN, "data/car/img", "data/car/groundtruth_rect.txt", 0, "xywh"),
    *((f"TLP_{name}", KALMAN, f"data/TinyTLP/{name}/img",
       f"data/TinyTLP/{name}/groundtruth_rect.txt", 0, "tlp")
      for name in ("Bike", "CarChase2", "Drone1", "Mohiniyattam", "MotorcycleChase")),
)

#: MOTChallenge sequences: (name, repository of the frames, frames folder or video file,
#: repository of the ground truth, its folder (gt/gt.txt, seqinfo.ini), frames kept or 0: all).
#: All are MOT15 training sequences filmed by a fixed camera (MOTChallenge's table of the
#: sequences); the moving-camera ones (ETH-*, KITTI-13, ADL-Rundle-8) are left out.
MOT = (
    ("TUD-Stadtmitte", MASA, "benchmarks/MOT15/TUD-Stadtmitte/TUD-Stadtmitte.mp4", MASA,
     "benchmarks/MOT15/TUD-Stadtmitte", 0),
    ("PETS09-S2L1-300", RPI, "data/images/PETS09-S2L1", MASA, "benchmarks/MOT15/PETS09-S2L1",
     300),
    *((name, MASA, f"benchmarks/MOT15/{name}/{name}.mp4", MASA, f"benchmarks/MOT15/{name}", 0)
      for name in ("PETS09-S2L1", "Venice-2", "KITTI-17", "ADL-Rundle-6")),
)


def git(clone: Path, *args: str, given: bytes | None = None) -> bytes:
    """Output of ``git -C clone ARGS`` (bare clones too), ``given`` on its standard input."""
    return subprocess.run(["git", "-C", str(clone), *args], input=given, capture_output=True,
                          check=True).stdout


def show(clone: Path, path: str) -> bytes:
    return git(clone, "show", f"HEAD:{path}")


#: How a Git LFS pointer file begins: a clone that holds one in place of a file never fetched
#: the file's content (``git lfs pull`` does).
LFS_POINTER = b"version https://git-lfs.github.com/spec/v1"
#: Git LFS pointer files are smaller than this (the specification's bound): only blobs this
#: small are read to tell a pointer.
LFS_POINTER_MAX = 1024


def absent(clone: Path, paths: list[str]) -> str | None:
    """The first of ``paths`` that the clone's HEAD lists but cannot give (a copy made without
    its large files, or a Git LFS pointer whose content was never fetched: its ~130 bytes would
    be written as the file), or None when it holds them all."""
    asked = "".join(f"HEAD:{path}\n" for path in paths)
    answer = git(clone, "cat-file", "--batch-check", given=asked.encode())
    # path: object name of the blobs small enough to be an LFS pointer, up to the first missing
    # (None), in the order of paths
    objects: dict[str, str | None] = {}
    for path, line in zip(paths, answer.decode().splitlines(), strict=True):
        if line.endswith(" missing"):
            objects[path] = None
            break
        name, kind, size = line.rsplit(" ", 2)
        if kind == "blob" and int(size) < LFS_POINTER_MAX:
            objects[path] = name
    pointers = lfs_pointers(clone, {name for name in objects.values() if name})
    return next((path for path, name in objects.items() if name is None or name in pointers),
                None)


def lfs_pointers(clone: Path, names: set[str]) -> set[str]:
    """Those of the blobs ``names`` (object names the clone holds) that are Git LFS pointers."""
    if not names:
        return set()
    answer = git(clone, "cat-file", "--batch",
                 given="".join(f"{name}\n" for name in names).encode())
    pointers, at = set(), 0
    while at < len(answer):  # each: "NAME TYPE SIZE\n", SIZE bytes, "\n"
        header_end = answer.index(b"\n", at)
        name, _, size = answer[at:header_end].decode().split(" ")
        content = answer[header_end + 1:header_end + 1 + int(size)]
        if content.startswith(LFS_POINTER):
            pointers.add(name)
        at = header_end + 1 + int(size) + 1
    return pointers


def skipped(name: str, repo: str, path: str) -> None:
    print(f"{name}: skipped ({path} is not in the clone of {repo}: clone it whole)")


def images(clone: Path, folder: str) -> list[str]:
    names = git(clone, "ls-tree", "--name-only", "HEAD", folder + "/").decode().split()
    return sorted(name for name in names if name.endswith((".jpg", ".png")))


def ground_truth(text: str, layout: str) -> list[str]:
    """One ``x,y,w,h`` line a frame; TLP's ``frame,x,y,w,h,occluded`` lines become absent
    targets where TLP flags full occlusion."""
    lines = [line.strip() for line in text.splitlines() if line.strip()]
    if layout == "xywh":
        return lines
    rows = [line.split(",") for line in lines]
    return ["nan,nan,nan,nan" if row[5] == "1" else ",".join(row[1:5]) for row in rows]


def single(out: Path, clones: dict[str, Path]) -> None:
    for name, repo, folder, truth, first, layout in SINGLE:
        if repo not in clones:
            print(f"{name}: skipped (needs --clone {repo}=PATH)")
            continue
        missing = absent(clones[repo], [truth])
        if missing:
            skipped(name, repo, missing)
            continue
        boxes = ground_truth(show(clones[repo], truth).decode(), layout)
        frames = images(clones[repo], folder)[first:first + len(boxes)]
        missing = absent(clones[repo], frames)
        if missing:
            skipped(name, repo, missing)
            continue
        target = out / "single" / name
        (target / "img").mkdir(parents=True, exist_ok=True)
        for k, path in enumerate(frames, 1):
            (target / "img" / f"{k:05d}{Path(path).suffix}").write_bytes(
                show(clones[repo], path))
        (target / "groundtruth.txt").write_text("\n".join(boxes[:len(frames)]) + "\n")
        print(f"{name}: {len(frames)} frames")


def mot(out: Path, clones: dict[str, Path]) -> None:
    for name, frames_repo, frames_path, truth_repo, truth_folder, keep in MOT:
        missing = [repo for repo in (frames_repo, truth_repo) if repo not in clones]
        if missing:
            print(f"{name}: skipped (needs " + ", ".join(f"--clone {r}=PATH" for r in missing)
                  + ")")
            continue
        video = frames_path.endswith(".mp4")
        frames = [frames_path] if video else images(clones[frames_repo], frames_path)[:keep or None]
        needed = {truth_repo: [f"{truth_folder}/gt/gt.txt", f"{truth_folder}/seqinfo.ini"]}
        needed.setdefault(frames_repo, []).extend(frames)
        gone = [(repo, path) for repo, paths in needed.items()
                if (path := absent(clones[repo], paths))]
        if gone:
            skipped(name, *gone[0])
            continue
        target = out / "mot" / name
        (target / "gt").mkdir(parents=True, exist_ok=True)
        rows = show(clones[truth_repo], f"{truth_folder}/gt/gt.txt").decode().splitlines()
        if keep:
            rows = [row for row in rows if row.strip() and int(row.split(",")[0]) <= keep]
        (target / "gt" / "gt.txt").write_text("\n".join(rows) + "\n")
        (target / "seqinfo.ini").write_bytes(show(clones[truth_repo],
                                                   f"{truth_folder}/seqinfo.ini"))
        if video:
            (target / Path(frames_path).name).write_bytes(show(clones[frames_repo], frames_path))
            print(f"{name}: video")
            continue
        (target / "img1").mkdir(exist_ok=True)
        for path in frames:
            (target / "img1" / Path(path).name).write_bytes(show(clones[frames_repo], path))
        print(f"{name}: {len(frames)} frames")


def main(argv: list[str]) -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("out", type=Path, help="folder to write the sequences into")
    parser.add_argument("--clone", action="append", default=[], metavar="OWNER/NAME=PATH",
                        help="a local clone of a repository the sequences come from")
    args = parser.parse_args(argv)
    clones = {}
    for item in args.clone:
        repo, _, path = item.partition("=")
        if not path or not Path(path).is_dir():
            parser.error(f"--clone {item}: give OWNER/NAME=PATH of an existing clone")
        clones[repo] = Path(path)
    single(args.out, clones)
    mot(args.out, clones)


if __name__ == "__main__":
    main(sys.argv[1:])
