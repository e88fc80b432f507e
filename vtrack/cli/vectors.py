"""``vtrack vectors INPUT ...`` (write test vectors) and ``vtrack vectors check DIR DUMP``.

One group with a default action: when the first argument is not a subcommand name (``check``),
the arguments are handed to the hidden ``generate`` command. So both forms of the issue work as
written, ``vtrack vectors --help`` documents both, and an input literally named ``check`` is
given as ``./check``.
"""

from __future__ import annotations

import sys
from pathlib import Path

import click

from vtrack.cli._messages import echo_result, echo_summary, no_such_command, warn
from vtrack.cli._options import HelpPrinted, NumberWord, VtrackCommand
from vtrack.cli._paths import CONFIG, INPUT, PATH
from vtrack.cli._signals import stopping_as_interrupted
from vtrack.errors import close_names, names_a_path


class _DefaultGroup(HelpPrinted, click.Group):
    """A group whose arguments go to ``generate`` unless they start with a subcommand name."""

    def parse_args(self, ctx: click.Context, args: list[str]) -> list[str]:
        if args and args[0] not in self.commands and args[0] not in ("-h", "--help"):
            _refuse_a_mistyped_command(ctx, args[0], [name for name, command in
                                                      self.commands.items()
                                                      if not command.hidden])
            args = ["generate", *args]
        return super().parse_args(ctx, args)

    def format_options(self, ctx: click.Context, formatter: click.HelpFormatter) -> None:
        """The group's options and commands, then those of ``vtrack vectors INPUT`` (the hidden
        ``generate``), so ``vtrack vectors --help`` shows what the first form takes."""
        super().format_options(ctx, formatter)
        # its options only: INPUT is in the usage line above (click 8.5.1 gives an argument a
        # help row too, which showed as a bare 'INPUT' among the options)
        rows = [record for param in self.commands["generate"].params
                if isinstance(param, click.Option)
                and (record := param.get_help_record(ctx)) is not None]
        with formatter.section("Options of vtrack vectors INPUT"):
            formatter.write_dl(rows)


def _refuse_a_mistyped_command(ctx: click.Context, word: str, commands: list[str]) -> None:
    """Refuse ``word``, given where ``vtrack vectors`` takes INPUT or a command, when it is a
    near miss of a command (``chek``, ``CHECK``) and names no file, folder or URL: read as
    INPUT it was refused for a missing ``--init``, which said nothing of the typo."""
    if not names_a_path(word) and close_names(word, commands):
        raise no_such_command(ctx, word, commands)


class _NamedAsTheGroup(click.Context):
    """The hidden ``generate``'s context, named as the group: a user types ``vtrack vectors
    INPUT``, so its usage line and an error's ``(see '... --help')`` say ``vtrack vectors``
    (they said ``vtrack vectors generate``, a command no help lists)."""

    @property
    def command_path(self) -> str:
        return self.parent.command_path if self.parent is not None else super().command_path


class _Generate(VtrackCommand):
    context_class = _NamedAsTheGroup


@click.group("vectors", cls=_DefaultGroup, context_settings={"help_option_names": ["-h", "--help"]})
def command() -> None:
    """Test vectors of the fixed-point golden models for an HDL simulation bench.

    \b
    vtrack vectors INPUT --config s0-fixed --init x,y,w,h --frames N --out DIR
    vtrack vectors check DIR DUMP

    The first writes DIR/frame_NNNN/{rgb,hue,bp}.hex ($readmemh text, one value per pixel),
    DIR/trace.csv and DIR/manifest.json; the second compares a simulator's dump laid out the
    same way (any subset of the files) with them: exit 0 when equal, 1 when not.
    """


@command.command("generate", cls=_Generate, hidden=True)
@click.argument("input_spec", metavar="INPUT", type=INPUT)
@click.option("--config", "-c", "config_spec", default="s0-fixed", show_default=True, type=CONFIG,
              metavar="NAME|FILE", help="A fixed-point config: s0-fixed or s2-fixed.")
@click.option("--init", "init_text", required=True, metavar="x,y,w,h",
              help="Initial box (top-left x, y, width, height): x,y,w,h or x y w h.")
@click.option("--frames", "count", type=NumberWord(int, "a whole number of frames, 1 to 300"),
              default=10, show_default=True,
              help="Frames to write, from 1 to 300 (a 1080p frame is ~25 MB of hex).")
@click.option("--out", "-o", "out_dir", type=PATH, required=True,
              metavar="DIR", help="Output folder (created; existing vector files are replaced).")
@click.option("--set", "-s", "overrides", multiple=True, metavar="STAGE.PARAM=VALUE",
              help="Override a stage parameter (repeatable).")
def generate(input_spec: str, config_spec: str, init_text: str, count: int, out_dir: Path,
             overrides: tuple[str, ...]) -> None:
    """Write the vectors of INPUT's first N frames."""
    import itertools

    from vtrack import __version__
    from vtrack.config import load_config
    from vtrack.errors import ConfigError, plural
    from vtrack.evaluate.groundtruth import parse_box
    from vtrack.geometry import check_init_box
    from vtrack.golden.vectors import MAX_FRAMES, fixed_stage
    from vtrack.golden.vectors import generate as write_vectors
    from vtrack.io import open_source
    from vtrack.pipeline import Pipeline

    if not 1 <= count <= MAX_FRAMES:
        raise ConfigError(f"--frames {count}: must be 1..{MAX_FRAMES}")
    config = load_config(config_spec).with_overrides(list(overrides))
    stages = config.build()
    fixed_stage(stages, config_spec)
    init_box = parse_box(init_text)
    extra = {"input": Path(input_spec).name, "config": config.name, "init": list(init_box),
             "vtrack": __version__}
    # SIGTERM as Ctrl-C: the staged vector files are removed, earlier vectors stay whole;
    # once they go in place, a signal changes nothing (the input's closing included)
    with stopping_as_interrupted() as settled, open_source(input_spec) as source:
        check_init_box(init_box, source.info.width, source.info.height, "--init",
                       source.info.turned_note())
        frames = itertools.islice(iter(source), count)
        written = write_vectors(frames, stages, Pipeline(stages), init_box, out_dir, extra,
                                settled)
        for warning in source.warnings:  # frames skipped as undecodable, as vtrack run says
            warn(warning)
    if written < count:
        warn(f"{input_spec}: {plural(written, 'frame')} to write of the {count} asked for "
             "(--frames)")
    echo_summary(f"wrote {plural(written, 'frame')} of {config.name} vectors to {out_dir}")


@command.command("check", cls=VtrackCommand)
@click.argument("vectors_dir", metavar="DIR", type=PATH)
@click.argument("dump_dir", metavar="DUMP", type=PATH)
def check(vectors_dir: Path, dump_dir: Path) -> None:
    """Compare a simulator's DUMP (same layout, any subset of the files) with the vectors DIR."""
    from vtrack import __version__
    from vtrack.errors import InputError
    from vtrack.golden.vectors import check as compare
    from vtrack.golden.vectors import other_version

    lines, compared = compare(vectors_dir, dump_dir)
    written = other_version(vectors_dir, __version__)
    if written is not None:  # the format is the same: said, not refused
        warn(f"{vectors_dir}: vectors written by vtrack {written}, checked by vtrack "
             f"{__version__} (manifest.json): a difference may be the versions'")
    if compared == 0 and not lines:
        raise InputError(f"{dump_dir}: holds none of the vector files (frame_NNNN/*.hex, "
                         "trace.csv, iterations.csv)")
    if lines:
        echo_result("\n".join(lines), "the list of differences")
        sys.exit(1)
    echo_result(f"{compared} file(s) equal", "the comparison")
