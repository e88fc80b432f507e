"""Tracker configurations: an ordered chain of stages with parameters, from a TOML file.

File format (``configs/s0.toml``)::

    name = "s0"
    description = "Mean shift + Kalman, one iteration per frame (S0)"

    [[stage]]
    name = "hue"
    search_scale = 2.0

    [[stage]]
    name = "backproject"

A config given by name (``s0``, ``camshift`` ...) is one of the files shipped in ``configs/``.
Everything is checked at load time; errors name the file, the stage and the parameter.
"""

from __future__ import annotations

import os
import sys
import tomllib
from collections import Counter
from collections.abc import Iterable, Iterator, Mapping, Sequence
from dataclasses import dataclass
from importlib import resources
from pathlib import Path
from typing import Any

from vtrack.configs import CONFIG_HINT, DEFAULT_CONFIG
from vtrack.errors import (
    ConfigError,
    InputError,
    close_names,
    cut,
    did_you_mean,
    first_few,
    guess_text,
)
from vtrack.io.files import os_reason, real_path
from vtrack.io.limits import CONFIG_BYTES, not_a_file, read_text_bounded, special_kind
from vtrack.params import float_from_text, shown
from vtrack.stages.base import (
    DERIVED,
    PIPELINE_PROVIDES,
    Stage,
    all_stages,
    build_stage,
    checked_values,
    declared_param,
    stage_class,
)


class StageValues(dict[str, Any]):
    """A stage's explicitly set parameters in a :class:`Config`: a ``dict`` that refuses
    changes (TypeError), since the config checked them as they were; ``dict(values)`` is a
    copy to change, and a Config with other values is made with :meth:`Config.with_values`."""

    def _refuse(self, *args: Any, **kwargs: Any) -> None:
        raise TypeError("a Config's stage values are read-only (checked as it was made): make "
                        "another Config, e.g. config.with_values({'stage.param': value})")

    __setitem__ = __delitem__ = __ior__ = clear = pop = popitem = setdefault = update = _refuse

    def __hash__(self) -> int:  # type: ignore[override]
        """Hashed as its (parameter, value) pairs, in any order (values are checked scalars and
        text): a Config is hashable, as a frozen dataclass of such values is."""
        return hash(frozenset(self.items()))

    def __reduce__(self) -> tuple[type[StageValues], tuple[dict[str, Any]]]:
        """Pickled as its values (a Dask worker receives a run's Config)."""
        return StageValues, (dict(self),)


@dataclass(frozen=True)
class Config:
    """A validated chain: ``stages`` is a sequence of (stage name, explicitly set parameters),
    checked when the Config is made (:meth:`__post_init__`). Read-only once made: its fields
    cannot be set, ``stages`` is kept as a tuple and each stage's parameters as a
    :class:`StageValues` (a ``dict`` that refuses changes, hashable: so is a Config, equal
    Configs alike); :meth:`with_values` and :meth:`with_overrides` make a changed copy, checked
    again."""

    name: str
    source: str
    description: str = ""
    stages: Sequence[tuple[str, dict[str, Any]]] = ()

    def __post_init__(self) -> None:
        """Check the chain as a config file's is checked, however the Config was made (by
        :func:`load_config` or in Python): ConfigError naming ``source`` for no stage, an
        unknown stage, a parameter value its declaration refuses, a name or description that
        is not text, and a chain :func:`check_chain` refuses; TypeError for ``stages`` that
        are not a list (or tuple) of (stage name, parameters) pairs."""
        if not isinstance(self.source, str):
            raise TypeError(f"Config source: expected text (where the config came from), got "
                            f"{type(self.source).__name__}")
        if not isinstance(self.stages, list | tuple) or not all(
                isinstance(stage, tuple) and len(stage) == 2 and isinstance(stage[0], str)
                and isinstance(stage[1], dict) for stage in self.stages):
            raise TypeError("Config stages: expected a list of (stage name, {parameter: "
                            f"value}}) pairs, got {shown(self.stages)}")
        if not self.stages:
            raise ConfigError(f"{self._named}: no stages: a config is a chain of stages")
        # stages known and each once before the values: a refusal of a value of a stage named
        # twice could not say which of them
        refuse_repeats(self._named, [stage_class(name, self._named).name
                                     for name, _ in self.stages])
        # names, parameters and types checked; each value kept as its parameter's Python type
        object.__setattr__(self, "stages", tuple(
            (name, StageValues(checked_values(name, values, self._named)))
            for name, values in self.stages))
        for key in ("name", "description"):
            if not isinstance(getattr(self, key), str):
                raise ConfigError(f"{self._named}: {key} must be text, got "
                                  f"{shown(getattr(self, key))}")
        if not self.name.strip():
            raise ConfigError(f"{self._named}: name is empty: a config's name names its "
                              "results folder")
        check_chain(self)

    @property
    def _named(self) -> str:
        """``source`` as a one-line refusal names it (:func:`~vtrack.errors.cut`: a path of
        thousands of characters shortened); ``source`` and run.json keep it whole."""
        return cut(self.source)

    def build(self) -> list[Stage]:
        """Construct the stages (values were validated when the Config was made)."""
        return [build_stage(name, values, self._named) for name, values in self.stages]

    def check_files_named(self) -> None:
        """ConfigError naming ``source``, the stage and the parameter for a parameter naming a
        file its stage reads (its ``file_params``: mot_detections.path) left empty. Not asked
        of a config file as it loads (``--set`` may name the file), but of a run's request and
        a Tracker, before any frame is read."""
        for _, stage, name, value in self.file_values():
            if not value:
                raise ConfigError(f"{self._named}: stage '{stage}': parameter '{name}' must "
                                  f"name the file it reads ({name} = \"FILE\" in its "
                                  f"[[stage]] table, or --set {stage}.{name}=FILE)")

    def file_values(self) -> Iterator[tuple[int, str, str, Any]]:
        """(stage index, stage, parameter, value: None when not set) of each parameter naming a
        file its stage reads (the stage's ``file_params``: mot_detections.path), in chain
        order."""
        for index, (stage, values) in enumerate(self.stages):
            for name in stage_class(stage, self._named).file_params:
                yield index, stage, name, values.get(name)

    def stage_classes(self) -> list[type[Stage]]:
        """The stages' classes (their declarations: parameters, requires/provides, kind), no
        stage built."""
        return [stage_class(name, self._named) for name, _ in self.stages]

    @property
    def multi_target(self) -> bool:
        """True for a chain that detects several targets and numbers their tracks (s3,
        s4_multi, fixed_camera, ...: a stage of it is ``multi_target``), no stage built."""
        return any(cls.multi_target for cls in self.stage_classes())

    def resolved(self) -> dict[str, Any]:
        """Every stage with every parameter value, defaults included (for ``run.json``)."""
        return {
            "name": self.name,
            "source": self.source,
            "description": self.description,
            "stages": [{"name": s.name, **s.settings()} for s in self.build()],
        }

    def with_overrides(self, assignments: list[str]) -> Config:
        """Apply ``stage.param=value`` strings (``--set``); the stage must be in the chain. A
        text without ``=`` is refused, naming the stage's parameter when it is one of the
        chain's without its stage (``--set padding``: ``robust_model.padding=VALUE``)."""
        changes = []
        for text in assignments:
            key, sep, raw = text.partition("=")
            if not sep:
                raise ConfigError(f"--set {cut(text)}: expected stage.param=value"
                                  f"{self._stage_of(key.strip(), 'VALUE', True)}")
            changes.append((key, raw.strip(), f"--set {cut(text)}", True))
        return self._changed(changes)

    def with_values(self, values: Mapping[str, Any]) -> Config:
        """Apply ``{"stage.param": value}`` Python values (the API's keyword overrides), each
        checked as a config file's value is (a NumPy scalar counts as its Python number); a
        key that is not text is a TypeError naming it, and so is ``values`` when it is no
        mapping (None, a list of pairs)."""
        if not isinstance(values, Mapping):
            raise TypeError(f"with_values: expected a dict {{'stage.param': value}}, got "
                            f"{shown(values)}")
        for key in values:
            if not isinstance(key, str):
                raise TypeError(f"key {shown(key)}: expected text, 'stage.param', got "
                                f"{type(key).__name__}")
        return self._changed([(key, value, f"{cut(key)}={shown(value)}", False)
                              for key, value in values.items()])

    def _stage_of(self, param: str, given: Any, is_text: bool) -> str:
        """How a refusal of ``param`` given without its stage ends: ``"; did you mean
        robust_model.padding=2?"`` when one stage of the chain (by name) declares a parameter
        of that name (``=2``: the text given, only for text; ``=VALUE`` for empty text), else
        ``""``; for a ``stage.param`` of the chain (given without ``=``): ``"; give a value:
        robust_model.padding=VALUE"``."""
        if "." in param:
            return f"; give a value: {param}=VALUE" if self._declares(param) else ""
        stages = {name for name in dict(self.stages) if self._declares(f"{name}.{param}")}
        if len(stages) != 1:
            return ""
        value = f"={cut(given) or 'VALUE'}" if is_text else ""
        return f"; did you mean {stages.pop()}.{param}{value}?"

    def _declares(self, key: str) -> bool:
        """Whether ``key``, ``stage.param``, names a parameter of a stage of the chain."""
        stage, _, param = key.partition(".")
        return stage in dict(self.stages) and any(
            p.name == param for p in stage_class(stage, self._named).params)

    def _changed(self, changes: list[tuple[str, Any, str, bool]]) -> Config:
        """This chain with each ``(stage.param, value, where, is_text)`` applied: text is
        parsed as ``--set`` parses it, other values are validated as they are."""
        stages = [(name, dict(values)) for name, values in self.stages]
        for key, given, where, is_text in changes:
            stage_name, dot, param_name = key.strip().partition(".")
            if not dot or not stage_name or not param_name:
                raise ConfigError(f"{where}: expected stage.param=value"
                                  f"{self._stage_of(key.strip(), given, is_text)}")
            matches = [values for name, values in stages if name == stage_name]
            if not matches:
                chain = " -> ".join(name for name, _ in stages)
                near = did_you_mean(stage_name, (name for name, _ in stages))
                raise ConfigError(f"{where}: stage {shown(stage_name)} is not in the chain "
                                  f"({chain}){near}")
            declared = {p.name: p for p in stage_class(stage_name, where).params}
            param = declared_param(where, stage_name, param_name, declared)
            place = f"{where}: stage '{stage_name}'"
            value = param.parse(given, place) if is_text else param.validate(given, place)
            for values in matches:
                values[param_name] = value
        return Config(self.name, self.source, self.description, stages)  # checked


def config_from_resolved(data: dict[str, Any]) -> Config:
    """The config :meth:`Config.resolved` described (every parameter set explicitly)."""
    return parse_config(
        {"name": data["name"], "description": data["description"], "stage": data["stages"]},
        str(data["source"]),
    )


def shipped_configs() -> dict[str, Path]:
    """The configurations shipped with vtrack, by name."""
    folder = resources.files("vtrack.configs")
    return {
        Path(entry.name).stem: Path(str(entry))
        for entry in folder.iterdir()
        if entry.name.endswith(".toml")
    }


def config_file(spec: str | os.PathLike[str]) -> Path:
    """The file a config ``spec`` names, as :func:`load_config` reads it: a shipped config's
    file for its name (``s2``), else the path given (not checked)."""
    return shipped_configs().get(os.fspath(spec), Path(spec))


def load_config(spec: str | Path | None = None) -> Config:
    """Load a shipped config by name (default: ``DEFAULT_CONFIG``) or a config file by path.

    A shipped name (``s2``) always means the shipped config, even when a file of that name is in
    the current folder: give such a file as a path (``./s2``) or with ``.toml``.
    """
    return config_and_text(spec)[0]


def config_and_text(spec: str | Path | None = None) -> tuple[Config, str]:
    """:func:`load_config`'s config and the text of its file, read once (``vtrack stages
    CONFIG --toml`` prints the text of the config it checked)."""
    spec = DEFAULT_CONFIG if spec is None else spec
    if not isinstance(spec, str | os.PathLike):
        raise TypeError(f"config: expected a shipped config name, a TOML file path or a "
                        f"vtrack.Config, got {type(spec).__name__}")
    if not os.fspath(spec).strip():  # ("" would be opened as the current folder)
        raise ConfigError(f"config: empty; give {CONFIG_HINT}")
    path = config_file(spec)
    where = str(spec)  # the config's source, whole: run.json records it (resume ignores it)
    named = cut(where)  # how a refusal's one line names a spec it could not read
    if not _is_file(path, named):
        kind = special_kind(path)
        if kind is not None:
            raise ConfigError(not_a_file(named, kind, "config"))
        if path.is_dir():
            raise ConfigError(f"{named}: is a folder, not a config file")
        elif path.suffix == ".toml" or "/" in str(spec):
            shipped = _shipped_meant(path)
            raise ConfigError(f"{named}: config file not found" + (
                f"; did you mean the shipped config {shipped!r} (named without a path or "
                ".toml)?" if shipped else ""))
        else:
            shipped = sorted(shipped_configs())
            raise ConfigError(
                f"{named}: no such config file or shipped config (shipped: {', '.join(shipped)})"
                f"{did_you_mean(str(spec), shipped)}"
            )
    try:
        text = read_text_bounded(path, CONFIG_BYTES, "config")
        data = tomllib.loads(text, parse_float=float_from_text)  # (1e400: named as written)
    except InputError as exc:
        raise ConfigError(str(exc).replace(str(path), named, 1)) from None
    except tomllib.TOMLDecodeError as exc:
        raise ConfigError(f"{named}: not valid TOML ({exc})") from None
    except RecursionError:  # tomllib reads nested arrays and tables recursively
        raise ConfigError(f"{named}: arrays or tables nested too deeply to read (a config's "
                          "values are numbers, text and true/false)") from None
    except ValueError:  # tomllib's int() of a decimal integer longer than Python converts
        raise ConfigError(f"{named}: an integer of more than {sys.get_int_max_str_digits()} "
                          "digits, too long to read") from None
    try:
        return parse_config(data, where, default_name=path.stem), text
    except ConfigError as exc:  # (its one line names a long path cut, its record keeps it whole)
        if named == where:
            raise
        raise ConfigError(str(exc).replace(where, named, 1)) from None


def _shipped_meant(path: Path) -> str | None:
    """The shipped config a missing config file most likely meant: its stem when that names
    one, the file has no extension or ``.toml`` and its folder is the current one (however
    written) or one named ``configs`` (``s0.toml``, ``./s0``, ``$PWD/s0.toml``,
    ``configs/robust.toml``); None for another folder's or another extension's file
    (``exp/robust.toml``, ``my_configs/robust.toml``, ``x/s0.json``: the user's own file,
    whose values the shipped one does not have)."""
    try:
        here = real_path(path.parent) == real_path(Path.cwd())  # (a looping link: no error)
    except OSError:  # (the current folder removed)
        here = False
    if path.suffix not in ("", ".toml") or not (here or path.parent.name == "configs"):
        return None
    return path.stem if path.stem in shipped_configs() else None


def _near_keys(unknown: list[str], keys: tuple[str, ...], present: Iterable[str]) -> str:
    """How a refusal of ``unknown`` keys ends: ``"; did you mean 'name'?"`` for one that is a
    near miss of one of ``keys`` (:func:`~vtrack.errors.close_names`) not already ``present`` in
    the file (``NAME`` beside ``name`` gets no guess); for several, each near miss with its
    guess (``"; did you mean 'name' for 'nmae', 'stage' for 'stages'?"``), the first
    :data:`~vtrack.errors.MOST_LISTED` and how many more; ``""`` when none is near."""
    taken = set(present)
    guesses = [guess_text(close) + (f" for {shown(key)}" if len(unknown) > 1 else "")
               for key in unknown
               if (close := [name for name in close_names(key, keys) if name not in taken])]
    return f"; did you mean {first_few(guesses)}?" if guesses else ""


def parse_config(data: dict[str, Any], where: str, default_name: str = "config") -> Config:
    """Validate a decoded TOML document (see the module docstring for its shape)."""
    keys = ("name", "description", "stage")
    unknown = sorted(set(data) - set(keys))
    if unknown:
        raise ConfigError(
            f"{where}: unknown top-level key(s) {first_few([shown(k) for k in unknown])} "
            f"(expected name, description, [[stage]]){_near_keys(unknown, keys, data)}"
        )
    raw_stages = data.get("stage")
    if isinstance(raw_stages, dict):  # [stage] (one bracket): a table, not a list of them
        raise ConfigError(f"{where}: stage is one table ([stage]), not a list of them: write "
                          "each stage as a [[stage]] table (two brackets), in the order of the "
                          "chain")
    if raw_stages is not None and not isinstance(raw_stages, list):
        raise ConfigError(f"{where}: stage = {shown(raw_stages)}: write each stage as a "
                          "[[stage]] table (name = \"hue\" ...), in the order of the chain")
    if not isinstance(raw_stages, list) or not raw_stages:
        raise ConfigError(f"{where}: no [[stage]] tables: a config is a chain of stages")
    stages: list[tuple[str, dict[str, Any]]] = []
    for position, table in enumerate(raw_stages, start=1):
        if not isinstance(table, dict):
            raise ConfigError(f"{where}: stage #{position} is not a [[stage]] table, got "
                              f"{shown(table)}")
        if "name" not in table:
            raise ConfigError(f"{where}: stage #{position} has no name")
        if not isinstance(table["name"], str):
            raise ConfigError(f"{where}: stage #{position}: name must be text (a stage's "
                              f"name, e.g. name = \"hue\"), got {shown(table['name'])}")
        stages.append((table["name"], {k: v for k, v in table.items() if k != "name"}))
    return Config(  # its values, name and chain are checked as it is made
        name=data.get("name", default_name),
        source=where,
        description=data.get("description", ""),
        stages=stages,
    )


def _is_file(path: Path, spec: str) -> bool:
    """Whether ``path`` is a file; ConfigError naming ``spec`` when the file system cannot
    say (a name too long for it, ...)."""
    try:
        return path.is_file()
    except OSError as exc:
        raise ConfigError(f"{spec}: cannot be read as a config file ({os_reason(exc)})") from None


def check_chain(config: Config) -> None:
    """Reject a chain in which a stage reads a context field no earlier stage provides (or whose
    value an earlier stage made stale, see :data:`~vtrack.stages.base.DERIVED`), and a chain
    that cannot track (:func:`_check_tracks`)."""
    check_stages(config._named, config.stage_classes(), [values for _, values in config.stages])


def check_stages(source: str, classes: list[type[Stage]], values: list[dict[str, Any]]) -> None:
    """:func:`check_chain` of a chain given as its stages' classes, in order, each with its
    parameter values (those set, or all of a built stage's): ConfigError naming ``source``."""
    _check_tracks(source, classes)
    available = set(PIPELINE_PROVIDES)
    before: list[str] = []
    for settings, cls in zip(values, classes, strict=True):
        missing = cls.requires - available
        if missing:
            raise ConfigError(
                f"{source}: stage '{cls.name}' needs {', '.join(sorted(missing))}, "
                f"which no earlier stage provides (check the order of the chain: "
                f"{_givers(sorted(missing), cls, settings, before, _records(classes))})"
            )
        problem = cls.chain_problem(settings, before)
        if problem:
            raise ConfigError(f"{source}: stage '{cls.name}': {problem}")
        before.append(cls.name)
        for provided in cls.provides:  # what an older value was computed from is stale now
            available -= DERIVED.get(provided, frozenset()) - cls.provides
        available |= cls.provides


def _givers(values: list[str], needing: type[Stage], settings: dict[str, Any],
            before: list[str], records: list[str]) -> str:
    """Which stages make each of ``values`` (shared values the stage ``needing``, with these
    parameter ``settings``, lacks after the stages ``before``), for a refusal of the chain:
    ``likelihood comes from background, backproject, ...; target_model from backproject`` (a
    stage that changes a value it needs, occlusion's measurement, is not where it comes from).
    A maker the chain would refuse is left out when another is not: one ``needing``'s own check
    (:meth:`~vtrack.stages.base.Stage.chain_problem`) refuses (meanshift_fixed's fixed comes
    from hue_bp_fixed, not kernel_meanshift_int, whose record is S2's), and one keeping a
    second fixed-point record (:func:`_records`) beside the chain's own ``records`` (anywhere
    in it, before or after ``needing``) or the makers named for an earlier value, all of
    which keep one (kalman_f32's measurement after hue_bp_fixed
    is not kernel_meanshift_int's). An earlier value's only maker counts as in the chain (the
    author adds it: kalman_f32 alone is told fixed comes from hue_bp_fixed, and measurement
    from the makers that can follow it); when all are refused, the refusal is not the maker's
    and each is named."""
    stages = all_stages()
    chain = list(before)  # and each earlier value's only maker: the author adds it
    # the stages keeping the chain's record, each set one of which will (the chain's own, or
    # the makers of an earlier value when all of them keep one)
    kept = [{name} for name in records]
    lines: list[str] = []
    for index, value in enumerate(values):
        made = [name for name, cls in stages.items() if value in cls.provides - cls.requires]
        accepted = [name for name in made
                    if not (_records([stages[name]]) and any(name not in k for k in kept))
                    and needing.chain_problem(settings, [*chain, name]) is None] or made
        if len(accepted) == 1:
            chain.append(accepted[0])
        if accepted and len(_records(stages[name] for name in accepted)) == len(accepted):
            kept.append(set(accepted))
        lines.append(f"{value} {'comes ' if index == 0 else ''}from "
                     f"{', '.join(accepted) or 'no stage'}")
    return "; ".join(lines)


def _records(classes: Iterable[type[Stage]]) -> list[str]:
    """The names of ``classes`` that keep a fixed-point record (provide ``fixed``, each of its
    own document's model, S0 or S2): a chain keeps one (:func:`_check_tracks`)."""
    return [cls.name for cls in classes if "fixed" in cls.provides]


def refuse_repeats(source: str, names: list[str]) -> None:
    """ConfigError naming ``source`` for a stage named twice in the chain ``names`` (one stage
    runs once a frame)."""
    for name, count in Counter(names).items():
        if count > 1:
            raise ConfigError(f"{source}: stage {shown(name)} appears {count} times; a chain "
                              "runs each stage once")


#: What a single-target stage sets: a chain that tracks several targets writes none of it.
SINGLE_TARGET_OUTPUTS = frozenset({"box", "measurement"})


def _check_tracks(source: str, classes: list[type[Stage]]) -> None:
    """ConfigError for a chain whose result would not be what it computes: a stage named twice
    (one stage runs once a frame); two stages keeping a fixed-point record (S0's and S2's,
    each reads its own back); a single-target chain in which no stage sets the box (it
    would report the first box on every frame), or a multi-target one with no stage, or two,
    setting the tracks; a multi-target chain with a stage of a single target (its box would be
    thrown away, or it would need a first box the chain refuses)."""
    names = [cls.name for cls in classes]
    refuse_repeats(source, names)
    records = _records(classes)
    if len(records) > 1:
        raise ConfigError(f"{source}: stages {' and '.join(records)} both keep the chain's "
                          "fixed-point record, each of its own document's model (S0, S2): "
                          "a chain computes one")
    if not any(cls.multi_target for cls in classes):
        if not any("box" in cls.provides for cls in classes):
            raise ConfigError(f"{source}: no stage of the chain ({' -> '.join(names)}) "
                              "tracks: none sets the target's box (e.g. meanshift, particle, "
                              "kernel_meanshift, robust_search, kalman) nor the tracks of "
                              "several (mht, kalman_tracks, byte_tracks)")
        return
    trackers = [cls.name for cls in classes if "tracks" in cls.provides]
    if len(trackers) > 1:
        raise ConfigError(f"{source}: stages {' and '.join(trackers)} both set the "
                          "tracks; a chain has one multi-target tracker")
    for cls in classes:
        single = sorted(cls.provides & SINGLE_TARGET_OUTPUTS)
        if cls.needs_init_box or single:
            why = "needs the target's first box" if cls.needs_init_box else \
                f"sets the {' and '.join(single)} of one target"
            raise ConfigError(f"{source}: stage '{cls.name}' {why}, but the chain "
                              f"tracks several targets ({trackers[0]}), whose result is the "
                              "tracks: use one kind of chain")
