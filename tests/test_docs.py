"""The docs that are generated from the stages' declarations are up to date, and the README's
commands name things that exist."""

from __future__ import annotations

import re
from pathlib import Path

from vtrack.cli.stages import stages_text
from vtrack.config import shipped_configs

ROOT = Path(__file__).resolve().parent.parent


def test_stage_reference_matches_the_declarations() -> None:
    current = (ROOT / "docs" / "stages.md").read_text()
    assert current.strip() == stages_text(markdown=True).strip(), (
        "docs/stages.md is stale: regenerate it with `vtrack stages --markdown > docs/stages.md`"
    )


#: Each document config's paper, as its TOML comments (``vtrack stages CONFIG --toml``) name it.
PAPERS = {
    "s0": "Improved Mean Shift target tracking algorithm",
    "s0-fixed": "Improved Mean Shift target tracking algorithm",
    "s1": "patent CN105869186A",
    "s2": "An algorithm for real-time tracking target in complex",
    "s2-fixed": "An algorithm for real-time tracking target in complex",
    "s3": "A progressed MHT algorithm for infrared target tracking",
    "s4": "Modeling and simulation of moving target tracking system",
    "s4_multi": "Modeling and simulation of moving target tracking system",
}


def test_what_a_user_reads_cites_the_papers_not_files_a_clone_lacks() -> None:
    """`vtrack stages CONFIG --toml` wrote 'seeds/000_ed28ecd3d98e2ba5.txt; restated in
    ALGORITHMS.md S0' and "the design card's chain"; `vtrack stages` and docs/stages.md said
    'ALGORITHMS.md default': files no user has; they and README cited its item numbers ('S1
    item 6', '(S0 2-3)'). They cite the papers themselves: steps, sections, equations."""
    from vtrack.cli.stages import config_toml

    texts = {name: " ".join(config_toml(name).split()) for name in shipped_configs()}
    texts |= {"vtrack stages": stages_text(), "--markdown": stages_text(markdown=True)}
    for name, text in texts.items():
        for unavailable in ("ALGORITHMS.md", "DESIGN.md", "seeds/", "design card"):
            assert unavailable not in text, (name, unavailable)
        assert not re.search(r"\b\d{3}_[0-9a-f]{16}\.txt", text), name
    # ALGORITHMS.md's item numbers ('S1 item 6', 'S0 2-3'): the papers' steps, sections, eq.
    texts["README.md"] = (ROOT / "README.md").read_text()
    for name, text in texts.items():
        assert not re.search(r"\bS[0-4] (items? )?[0-9]", text), (name, re.findall(
            r".{30}\bS[0-4] (?:items? )?[0-9].{10}", text))
    for name, paper in PAPERS.items():
        assert paper in texts[name], name


def test_readme_configs_exist_and_set_up_commands_come_first() -> None:
    readme = (ROOT / "README.md").read_text()
    section = readme.split("### Trackers", 1)[1]
    table = re.search(r"(?:^\|.*\|\n)+", section, re.M).group(0)  # its first table
    listed = re.findall(r"^\| `([\w-]+)`", table, re.M)
    assert sorted(listed) == sorted(shipped_configs())
    # the table speaks of S0..S4 and "the documents": what they are is said before it, in
    # this section
    assert "S0 to S4 are the five published designs" in section[:section.index(table)]
    blocks = re.findall(r"```bash\n(.*?)```", readme, re.S)
    assert "pip install ." in blocks[0] and "vtrack run samples/" in blocks[0]
    assert "pytest" in blocks[1]
    ci = (ROOT / ".ci" / "run").read_text()
    assert blocks[1].strip() in ci
    sample = re.search(r"vtrack run (samples/\S+)", blocks[0])
    assert sample and (ROOT / sample.group(1)).is_file()


RESULTS = ROOT / "benchmarks" / "RESULTS.md"


def _results_section(number: int) -> str:
    """The text of RESULTS.md's section ``## number.`` (up to the next ``## ``)."""
    text = RESULTS.read_text()
    start = re.search(rf"^## {number}\. .*$", text, re.M)
    assert start, f"RESULTS.md has no section {number}"
    rest = text[start.end():]
    end = re.search(r"^## \d+\. ", rest, re.M)
    return rest[: end.start()] if end else rest


def _last_table(section: str) -> list[list[str]]:
    """The rows (cells stripped, header and rule dropped) of the section's last Markdown table."""
    tables = re.findall(r"((?:^\|.*\|\n)+)", section, re.M)
    assert tables
    rows = [[c.strip() for c in line.strip("|").split("|")] for line in tables[-1].splitlines()]
    return rows[2:]


def _readme_text() -> str:
    """The README with its line breaks as spaces (a quoted number may wrap)."""
    return " ".join((ROOT / "README.md").read_text().split())


def test_readme_results_sections_exist() -> None:
    readme = _readme_text()
    named = {int(n) for n in re.findall(r"RESULTS\.md\]?[^.;]{0,40}?,? section (\d+)", readme)}
    assert {1, 5, 6, 8, 12} <= named
    for number in named:
        _results_section(number)


def test_readme_scene_list_is_the_generators() -> None:
    from vtrack.scenes.scenarios import SCENARIOS

    row = next(line for line in (ROOT / "README.md").read_text().splitlines()
               if line.startswith("| `vtrack scene NAME"))
    listed = re.findall(r"`(\w+)`", row.split("exact ground truth", 1)[1])
    assert sorted(listed) == sorted(SCENARIOS)


def test_readme_start_up_bound_is_the_latest_measured() -> None:
    """The README's start-up figure is the largest ratio of section 6's latest table."""
    rows = _last_table(_results_section(6))
    ratios = [float(row[2].rstrip("x")) for row in rows]
    readme = _readme_text()
    latest = re.search(r"the latest run: ([\d.]+)x for", readme)
    assert latest and float(latest.group(1)) == round(max(ratios), 2)
    bound = re.search(r"Start-up of every command is at most ([\d.]+)x", readme)
    assert bound and float(bound.group(1)) >= max(ratios)


def test_readme_live_figures_are_the_latest_measured() -> None:
    """The frames `robust` and `s0` tracked live, as the latest table of section 12 has them."""
    rows = {row[0]: row for row in _last_table(_results_section(12))}
    readme = _readme_text()
    robust, video, s0 = (rows["robust, --no-video"][1], rows["robust, annotated.mp4"][1],
                         rows["s0, annotated.mp4"][1])
    assert f"`s0` tracked {s0} of 600" in readme
    assert f"`robust` {robust} without it" in readme and f"{video} with it" in readme


def test_readme_speed_ratios_are_the_latest_measured() -> None:
    """Section 1 puts its newest run first: `robust`'s ratios there are the README's."""
    section = _results_section(1)
    table = re.search(r"((?:^\|.*\|\n)+)", section, re.M).group(1)
    ratio = {row.split("|")[1].strip(): row.split("|")[4].strip() for row in table.splitlines()}
    no_video = float(ratio["`vtrack run CLIP --no-video --config robust`"].split()[0])
    video = float(ratio["`vtrack run CLIP --config robust --preset ultrafast` (annotated video)"]
                  .split()[0])
    readme = _readme_text()
    assert f"{no_video:.2f}x a decode-only PyAV process" in readme.replace("**", "")
    assert f"{video:.2f}x (robust)" in readme


def test_readme_architecture_names_each_package_where_it_is() -> None:
    """README's architecture block listed report/ under vtrack/batch/ (it is vtrack/report/),
    and left out vtrack/features/. Every path opening one of its lines exists, and every
    package of vtrack/ opens one."""
    block = (ROOT / "README.md").read_text().split("## Architecture", 1)[1].split("```")[1]
    named = [line.split()[0] for line in block.splitlines() if line.startswith("vtrack/")]
    assert [path for path in named if not (ROOT / path).exists()] == []
    packages = sorted(f"vtrack/{p.parent.name}/" for p in (ROOT / "vtrack").glob("*/*.py"))
    assert sorted(set(packages) - set(named)) == []


def test_readme_names_the_files_a_batch_takes_as_a_videos_ground_truth() -> None:
    """README's batch section never said where `vtrack batch` finds a video's ground truth
    (`clip.gt.txt` beside `clip.mp4`: its own example's data/ holds one); `vtrack batch
    --help` did."""
    from vtrack.batch import VIDEO_GT, VIDEO_INIT, VIDEO_MOT_GT

    readme = " ".join((ROOT / "README.md").read_text().split())
    section = readme.split("A batch's inputs are", 1)[1].split("### As a library", 1)[0]
    for pattern in (*VIDEO_GT, *VIDEO_MOT_GT, VIDEO_INIT):
        assert f"`{pattern.format('NAME')}`" in section, pattern


def test_readme_robust_pairs_are_in_results_section_8() -> None:
    """Every tune / check (/ all) figure of the README's account of `robust` is one RESULTS.md
    section 8 records, as `A / B` or as neighbouring table cells. The README gave the mirrored
    variant 0.625 / 0.592, a split section 8 does not hold (probe RD)."""
    readme = _readme_text()
    account = readme[readme.index("`robust` is the default of `vtrack run`"):
                     readme.index("Every part can be switched off")]
    section = " ".join(_results_section(8).split())
    pairs = re.findall(r"\d\.\d{3}(?: / \d\.\d{3})+", account)
    assert len(pairs) >= 8
    missing = [pair for pair in pairs
               if pair not in section and f"| {pair.replace(' / ', ' | ')} |" not in section]
    assert missing == []


def test_readme_names_the_packages_ci_installs() -> None:
    """Every package `.ci/run` installs for a test is one the README's Development section
    names: it installed `ffmpeg` for an RTSP test the README did not mention (probe RD)."""
    script = (ROOT / ".ci" / "run").read_text()
    packages = {word for line in re.findall(r"apt-get install ([^>|&;]+)", script)
                for word in line.split() if not word.startswith("-")}
    assert {"chromium", "chromium-driver", "ffmpeg"} <= packages
    development = (ROOT / "README.md").read_text().split("## Development", 1)[1]
    assert [name for name in sorted(packages) if f"`{name}`" not in development] == []
