"""``vtrack stages``: every stage with its parameters, from the stages' own declarations."""

from __future__ import annotations

import click

from vtrack.cli._messages import echo_result
from vtrack.cli._options import VtrackCommand
from vtrack.cli._paths import NonEmptyText


def limits_text() -> str:
    """The "Limits" section of docs/stages.md: the limits every run keeps (tests/test_fuzz.py
    checks them)."""
    from vtrack.geometry import MAX_FRAME_SIDE, MIN_BOX_SIDE
    from vtrack.stages.detect import MAX_KERNEL
    from vtrack.stages.kernel_meanshift import ITERATION_BUDGET, SAMPLED_ABOVE
    from vtrack.stages.particle import PIXEL_BUDGET
    from vtrack.stages.robust_model import WIDE_WINDOW

    return f"""\
## Limits

Every number a stage takes has a declared range, shown after its help below. A value outside it,
or one that is not finite (NaN, inf), is refused before anything runs with one line naming the
stage, the parameter and the range (exit code 2). Each stage's entry ends with the values it
needs from earlier stages of a chain and those it gives, and each rule its values or its place
in a chain must keep: a config breaking one is refused the same way. Frames are at most
{MAX_FRAME_SIDE}x{MAX_FRAME_SIDE} pixels (checked from the file's header or `--raw WxH` before a
frame is allocated). An initial box (`--init` or the first ground-truth box) must be finite,
at least {MIN_BOX_SIDE:g}x{MIN_BOX_SIDE:g} pixels, no larger than the frame and overlap it.

Per frame, with N the frame's pixels, every config stays within these bounds:

- work: at most a fixed number of passes over N pixels per stage, times its declared cap:
  `meanshift.iterations` (<= 100); `kernel_meanshift.max_iterations` (<= 100, for each of 3
  bandwidths, twice when fast motion reruns the search), but the steps of one bandwidth cover
  at most {ITERATION_BUDGET} N pixels of window in all (a box larger than a tenth of the frame
  gets fewer steps than the default 20), and a window over {SAMPLED_ABOVE:g} N is read on
  every s-th row and column, to at most {SAMPLED_ABOVE:g} N; `particle.particles` and
  `particle.lost_particles` (<= 1024 windows), whose histograms count at most
  {PIXEL_BUDGET} N pixels in all (beyond, every n-th row of each window);
  `background.open`/`close` (<= 255) apply kernels of at most {MAX_KERNEL} working pixels
  (a larger one runs on the mask shrunk to fit); search windows
  are clipped to the frame (`hue.search_scale` <= 16, widened by `occlusion.max_growth` <= 16);
- multi-target work: at most `blobs.max_blobs` (<= 1000) detections a frame (a det.txt's:
  `mot_detections.max_detections`, <= 1000); `mht` keeps at
  most `max_hypotheses` (<= 64) hypotheses and extends each branch with at most `max_branches`
  (<= 16) measurements, searching a bounded number of combinations per hypothesis, each of
  at most `max_tracks` (<= 1000) tracks whatever `miss`, `delete` and `max_coast` allow;
  `kalman_tracks` and `byte_tracks` keep at most `max_tracks` (<= 1000) tracks whatever
  `max_coast` allows;
  multi-target runs keep no track boxes of past frames (with ground truth each frame is
  scored as it goes);
- memory: a few frame-sized buffers (at most ~32 N bytes beyond the decoded frames and the
  writers' queues), plus the particle filter's histograms (at most 4 x 1024 particles x 256
  bins x 8 bytes = 8 MiB) and the `robust` tracker's search patch, resampled to about
  `robust_model.working_area`^2 (<= 250^2) working pixels at ~40 bytes each, whatever the frame
  size (while lost, 8 more such patches a frame and, with `robust_model.filter_redetect`, one
  window of at most {WIDE_WINDOW[0]}x{WIDE_WINDOW[1]} working pixels at ~100 bytes each).
  tests/test_fuzz.py checks these bounds for every stage's parameters.
"""


def contract(cls: type) -> list[str]:
    """What a stage's place in a chain takes, a line each, as ``vtrack stages`` and
    docs/stages.md list it: the values it needs from earlier stages and those it gives (the
    chain check, :func:`vtrack.config.check_chain`, refuses a stage whose needs no earlier
    stage gives), then each rule its values and place must keep (its ``rules``)."""
    from vtrack.stages.base import PIPELINE_PROVIDES

    needs = ", ".join(sorted(cls.requires - PIPELINE_PROVIDES)) or "nothing"
    lines = [f"needs: {needs}; gives: {', '.join(sorted(cls.provides))}"]
    return lines + [f"rule: {rule}" for rule in cls.rules]


def _plain(name: str, cls: type, sets: list[tuple[str, dict]] | None = None) -> list[str]:
    """One stage's plain-text entry: its summary, a line per parameter, its CSV columns; with
    configs' ``sets`` (config name, its settings of this stage), each parameter a config sets
    to other than its default says so, for every config that does."""
    lines = [f"{name}: {cls.summary}"]
    for param in cls.params:
        line = f"    {param.describe()}"
        for config, settings in sets or ():
            value = settings.get(param.name, param.default)
            if value != param.default:
                line += f"; {config} sets {param.value_text(value)}"
        lines.append(line)
    lines += [f"    {line}" for line in contract(cls)]
    if cls.columns:
        lines.append(f"    csv columns: {', '.join(cls.columns)}")
    return lines


def _selected(names: tuple[str, ...]) -> dict[str, list[tuple[str, dict]]]:
    """The stages ``names`` ask for, in the order first named (a stage by its name, a shipped
    config or a config file, as ``--config`` takes them, as its chain), each with the settings
    of every named config holding it (config name or file, settings). ConfigError for a name
    that is none of them, or a config file with a mistake (as ``vtrack run`` says it)."""
    import os
    from pathlib import Path

    from vtrack.config import load_config, shipped_configs
    from vtrack.errors import ConfigError, cut, did_you_mean
    from vtrack.stages.base import all_stages

    known, configs = all_stages(), shipped_configs()
    chosen: dict[str, list[tuple[str, dict]]] = {}
    for name in dict.fromkeys(names):  # a name given twice: listed once
        if name in known:
            chosen.setdefault(name, [])
        elif name in configs or Path(name).suffix == ".toml" or "/" in name \
                or os.path.exists(name):  # a folder too: load_config says what it is
            # (os.path.exists: False for a name too long for the file system, not OSError)
            for stage, settings in load_config(name).stages:
                chosen.setdefault(stage, []).append((name, settings))
        else:
            raise ConfigError(f"{cut(name)}: not a stage, a shipped config or a config file "
                              f"(stages: {', '.join(known)}; configs: "
                              f"{', '.join(sorted(configs))})"
                              f"{did_you_mean(name, [*known, *configs])}")
    return chosen


def stages_text(markdown: bool = False, names: tuple[str, ...] = ()) -> str:
    """The stage reference (plain text for the terminal, or Markdown for docs/stages.md);
    with ``names`` (stages, shipped configs or config files), only those stages' parameters,
    and for a config the values it sets."""
    from vtrack.config import load_config, shipped_configs
    from vtrack.stages.base import all_stages

    stages = all_stages()
    if names:
        lines = []
        for name, sets in _selected(names).items():
            lines += _plain(name, stages[name], sets)
        return "\n".join(lines)
    lines: list[str] = []
    if markdown:
        lines += ["# Stages and parameters", "",
                  "Generated by `vtrack stages --markdown` from the stages' own declarations.", "",
                  limits_text()]
    for name, cls in stages.items():
        if markdown:
            lines += [f"## `{name}`", "", cls.summary, ""]
            lines += [f"- `{p.name}`{p.describe().removeprefix(p.name)}" for p in cls.params]
            for line in contract(cls):
                lines += ["", f"{line[0].upper()}{line[1:]}"]
            if cls.columns:
                lines += ["", "CSV columns: " + ", ".join(f"`{c}`" for c in cls.columns)]
            lines.append("")
        else:
            lines += _plain(name, cls)
    if markdown:
        lines += ["## Shipped configs", ""]
    else:
        lines.append("shipped configs:")
    for name in sorted(shipped_configs()):
        config = load_config(name)
        chain = " -> ".join(stage for stage, _ in config.stages)
        classes = [stages[stage] for stage, _ in config.stages]
        unscored = not any("score" in cls.provides or cls.multi_target for cls in classes)
        description = config.description + ("; no score: no stage of its chain gives one, "
                                            "track.csv's score is empty" if unscored else "")
        lines.append(f"- `{name}`: {description} ({chain})" if markdown
                     else f"    {name}: {chain}  # {description}")
    return "\n".join(lines)


def config_toml(name: str) -> str:
    """The TOML text of config ``name`` (a shipped config's name or a config file, as
    ``--config`` takes it), checked first as ``vtrack run`` checks it: a shipped config's own
    file, with the comments that say where each value comes from, to copy and change (a value
    a config file leaves out is its stage's default, not the config it was copied from).
    ConfigError for a stage's name, or a config that does not load."""
    from vtrack.config import config_and_text
    from vtrack.errors import ConfigError
    from vtrack.stages.base import all_stages

    if name in all_stages():
        raise ConfigError(f"{name}: a stage, not a config: --toml prints a config's file "
                          "(vtrack stages lists the shipped configs)")
    return config_and_text(name)[1]  # its mistakes said as run says them


@click.command("stages", cls=VtrackCommand)
@click.argument("names", nargs=-1, metavar="[STAGE|CONFIG]...",
                type=NonEmptyText("a stage's name, a shipped config's name or a TOML file "
                                  "(vtrack stages lists them)"))
@click.option("--markdown", is_flag=True, help="Print Markdown (the source of docs/stages.md).")
@click.option("--toml", is_flag=True,
              help="Print the one CONFIG named as its TOML file, to start a config of your own "
                   "from (vtrack stages robust --toml > mine.toml): values a file leaves out "
                   "are the stages' defaults, not robust's.")
def command(names: tuple[str, ...], markdown: bool, toml: bool) -> None:
    """List the stages, their parameters (type, default, help), what each needs from earlier
    stages and gives, the rules its values and place in a chain keep, and the shipped configs;
    with STAGE or CONFIG names (vtrack stages robust_model, vtrack stages s0, vtrack stages
    mine.toml), only those stages, and for a CONFIG (a shipped name or a file, as --config
    takes) the values it sets."""
    if names and markdown:
        raise click.UsageError("--markdown prints the whole reference; give no names with it")
    if toml:
        if markdown or len(names) != 1:
            raise click.UsageError("--toml prints one config's file: give one CONFIG "
                                   "(vtrack stages robust --toml > mine.toml)")
        echo_result(config_toml(names[0]), "the config", nl=False)
        return
    echo_result(stages_text(markdown, names), "the listing")
