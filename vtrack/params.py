"""Stage parameters, declared once.

Every stage lists its parameters as :class:`Param` objects. That single declaration drives config
validation (:meth:`Param.validate`), ``--set stage.param=value`` parsing (:meth:`Param.parse`),
``vtrack stages`` and the generated parameter docs (:meth:`Param.describe`).
"""

from __future__ import annotations

import math
import reprlib
from dataclasses import dataclass
from numbers import Integral
from typing import Any

from vtrack.errors import ConfigError, is_real, number_text, quoted, real_or_nan

#: The longest time a run's start or span takes in seconds (``--start Ts``, ``--frames Ts``,
#: RunRequest's ``start_s`` and ``max_s``): a year, so a frame number fits any rate.
MAX_SECONDS = 366 * 24 * 3600  # (an int: written 31622400 in messages, not 3.16224e+07)

#: The largest frame number and frame count a run takes (``--start N``, ``--frames N``,
#: RunRequest's ``start`` and ``max_frames``): a year at the highest frame rate (10,000 a
#: second) is 3.2e11 frames.
MAX_FRAME_NUMBER = 10**12

#: The longest wait a run or batch takes (``--follow``, ``--worker-timeout``,
#: ``--scheduler-timeout``, RunRequest's ``ffmpeg.follow_s``): a day.
MAX_WAIT_S = 24 * 3600.0

#: The range of a network input's timeout (``--timeout``, RunRequest's ``ffmpeg.timeout_s``).
MIN_TIMEOUT_S, MAX_TIMEOUT_S = 0.1, 3600.0

#: The highest x264 ``crf`` (``--crf``, RunRequest's ``crf``): 0 is lossless, 51 the worst.
MAX_CRF = 51

#: The largest seed of the stochastic stages (NumPy seeds 0 .. 2**32 - 1 as given, like
#: ``numpy.random.seed``): ``--seed`` and ``seed=`` take 0 .. MAX_SEED.
MAX_SEED = 2**32 - 1

#: The largest first track id a multi-target run takes (``--first-id``, RunRequest's and
#: ``vtrack.Tracker``'s ``first_track_id``; the smallest is 1): 2**53, up to which a double
#: holds every whole number, so tools that read a ``tracks.csv``'s numbers as doubles
#: (MATLAB, pandas, JavaScript) read its ids exactly. It is also the largest id a run
#: numbers: one whose new track would need an id past it stops there
#: (:class:`~vtrack.stages.detect.TrackIds`).
MAX_TRACK_ID = 2**53


def check_seed(seed: object) -> int:
    """``seed`` if it is a whole number from 0 to :data:`MAX_SEED`; ConfigError otherwise."""
    return check_whole("seed", seed, 0, MAX_SEED)


def check_whole(name: str, value: object, least: int, most: int, meaning: str = "") -> int:
    """``value`` as an ``int`` if it is a whole number (a NumPy one too; not a bool) from
    ``least`` to ``most``; ConfigError naming ``name`` otherwise (``meaning``, when given, says
    in brackets what the number is)."""
    if isinstance(value, bool) or not isinstance(value, Integral) \
            or not least <= value <= most:
        said = f" ({meaning})" if meaning else ""
        raise ConfigError(f"{name} {shown(value)}: must be a whole number from {least} to "
                          f"{most}{said}")
    return int(value)


def check_flag(value: object, name: str) -> bool:
    """``value`` as a bool if it is True or False (NumPy's too) or the whole number 1 or 0 (a
    NumPy one too: Python's and C's way to write them); ConfigError naming ``name`` otherwise:
    a string such as ``"no"`` is true to Python, not the answer given, and 2 no clear one."""
    numpy_bool = type(value).__module__ == "numpy" and type(value).__name__ in ("bool", "bool_")
    one_or_zero = isinstance(value, Integral) and value in (0, 1)
    if not (isinstance(value, bool) or numpy_bool or one_or_zero):  # (NumPy not imported here)
        raise ConfigError(f"{name} {shown(value)}: must be True or False (or the integers 1 "
                          "or 0)")
    return bool(value)


def checked_seconds(name: str, value: object, least: float, most: float, above: bool,
                    meaning: str = "") -> float:
    """``value`` as a float if it is a real number of seconds from ``least`` (``above``: more
    than it) to ``most``; ConfigError naming the field ``name`` otherwise (``meaning`` ends the
    message)."""
    seconds = real_or_nan(value)
    if not ((seconds > least if above else seconds >= least) and seconds <= most):
        bound = f"above {least:g}" if above else f"from {least:g}"
        raise ConfigError(f"{name} {shown(value)}: must be a time in seconds {bound} to "
                          f"{_number(most)}{meaning}")
    return seconds


#: The speed/size presets of the x264 and x265 encoders, fastest first (``vtrack scene
#: --preset``; the annotated video's ``vtrack run --preset`` and RunRequest's ``preset``: the
#: slower ones make a run slower, which an offline file may afford).
X264_PRESETS = ("ultrafast", "superfast", "veryfast", "faster", "fast", "medium", "slow",
                "slower", "veryslow", "placebo")


_TYPE_NAMES = {int: "integer", float: "number", bool: "true/false", str: "string"}
_A_TYPE = {int: "an integer", float: "a number", bool: "true or false", str: "a string"}


@dataclass(frozen=True)
class Param:
    """One parameter: its name, Python type, default, one-line help and optional constraints."""

    name: str
    type: type
    default: Any
    help: str
    choices: tuple[Any, ...] | None = None
    min: float | None = None
    max: float | None = None

    def __post_init__(self) -> None:
        """A numeric parameter must declare its valid range: every value a user can give is
        then one the stage can run with in bounded time and memory (README, value ranges)."""
        numeric = self.type in (int, float) and self.choices is None
        if numeric and (self.min is None or self.max is None):
            raise TypeError(f"parameter {self.name!r}: a number must declare min and max")
        if self.min is not None and self.max is not None and self.min > self.max:
            raise TypeError(f"parameter {self.name!r}: min {self.min} > max {self.max}")

    def range_text(self) -> str:
        """The declared range as people write it (``0 to 1000``); empty for a parameter without
        one (non-numeric, or numeric with choices: ``__post_init__`` requires both bounds of the
        others)."""
        if self.min is None or self.max is None:
            return ""
        return f"{_number(self.min)} to {_number(self.max)}"

    def allowed_text(self) -> str:
        """What a number of this parameter must be, for a message: ``in the range 0 to 1``,
        or ``one of 1, 3, 5`` for one with choices."""
        if self.range_text():
            return f"in the range {self.range_text()}"
        return "one of " + ", ".join(repr(c) for c in self.choices or ())

    def wanted_text(self) -> str:
        """What a value of this parameter must be, for a message refusing one of another type:
        its type and its declared range or choices (``an integer in the range 1 to 100``,
        ``a string, one of 'full', 'opencv'``), so that one line says all of it."""
        kind = _A_TYPE[self.type]
        if self.range_text():
            return f"{kind} {self.allowed_text()}"
        return f"{kind}, {self.allowed_text()}" if self.choices is not None else kind

    def validate(self, value: Any, where: str) -> Any:
        """Return ``value`` as this parameter's type, or raise ConfigError naming ``where``.

        ``where`` names the place the value came from, e.g. ``"configs/s0.toml: stage 'kalman'"``.
        A NumPy scalar or 0-d array counts as its Python value (``np.int64(5)``, ``np.True_``;
        an array of other shapes is refused, ``[150]`` too), a whole
        number (:class:`~numbers.Integral`) as an ``int`` and any real number
        (:func:`~vtrack.errors.is_real`: an int, ``Fraction``, ``Decimal``) as a ``float`` for a
        number; nothing else is converted (a string is not a number, nor True the number 1).
        """
        if type(value).__module__ == "numpy" and getattr(value, "shape", None) == ():
            value = value.item()  # (a NumPy scalar or 0-d array; NumPy is not imported here)
        if self.type is int and isinstance(value, Integral) and not isinstance(value, bool):
            value = int(value)
        if self.type is float and is_real(value) and not isinstance(value, BeyondFloat):
            try:
                value = float(value)
            except OverflowError:  # beyond any float, so beyond the range too
                raise ConfigError(f"{where}: parameter '{self.name}' must be in the range "
                                  f"{self.range_text()}, got {shown(value)}") from None
            except ValueError:  # (Decimal('sNaN'): not finite, refused below)
                value = math.nan
        wrong_bool = self.type is not bool and isinstance(value, bool)
        if wrong_bool or not isinstance(value, self.type):
            raise ConfigError(
                f"{where}: parameter '{self.name}' must be {self.wanted_text()}, got "
                f"{shown(value)}"
            )
        if self.type is float and not math.isfinite(value):
            raise ConfigError(f"{where}: parameter '{self.name}' must be {self.allowed_text()}, "
                              f"got {_not_finite(value)}")
        if self.type is float:
            value += 0.0  # -0.0 is 0.0 (NumPy's uniform(-x, x) refuses x = -0.0)
        if self.type is str and "\x00" in value:
            raise ConfigError(f"{where}: parameter '{self.name}' must not contain a NUL "
                              "character")
        if self.choices is not None and value not in self.choices:
            options = ", ".join(repr(c) for c in self.choices)
            raise ConfigError(
                f"{where}: parameter '{self.name}' must be one of {options}, got {shown(value)}"
            )
        too_low = self.min is not None and value < self.min
        if too_low or (self.max is not None and value > self.max):
            raise ConfigError(
                f"{where}: parameter '{self.name}' must be in the range {self.range_text()}, "
                f"got {_number(value)}"
            )
        return value

    def parse(self, text: str, where: str) -> Any:
        """Parse a command-line string (``--set``) into this parameter's type, then validate it."""
        value: Any = text
        try:
            if self.type is bool:
                lowered = text.strip().lower()
                if lowered not in ("true", "false", "1", "0", "yes", "no", "on", "off"):
                    raise ValueError(text)
                value = lowered in ("true", "1", "yes", "on")
            elif self.type is int:
                digits = text.strip().lstrip("+-")
                if len(digits) > 4000 and digits.isdigit():  # more than Python reads as an int
                    raise ConfigError(f"{where}: parameter '{self.name}' must be "
                                      f"{self.allowed_text()}, got a {len(digits)}-digit "
                                      "integer")
                value = int(text)
            elif self.type is float:
                value = float_from_text(text)
        except ValueError:
            raise ConfigError(
                f"{where}: parameter '{self.name}' must be {self.wanted_text()}, got "
                f"{shown(text)}"
            ) from None
        return self.validate(value, where)

    def describe(self) -> str:
        """One line for ``vtrack stages`` and the docs: name, type, default, help, constraints."""
        extra = []
        if self.choices is not None:
            extra.append("one of " + "|".join(str(c) for c in self.choices))
        if self.min is not None or self.max is not None:
            extra.append(f"range {self.range_text()}")
        tail = f" ({'; '.join(extra)})" if extra else ""
        return (f"{self.name} ({_TYPE_NAMES[self.type]}, default "
                f"{self.value_text(self.default)}): {self.help}{tail}")

    def value_text(self, value: Any) -> str:
        """A value of this parameter as a config file writes it (``true``, ``1.5``)."""
        return str(value).lower() if self.type is bool else repr(value)


class BeyondFloat(float):
    """A number written too large for a float (``1e400``, 400 nines, in a config file or a
    ``--set``): infinite as a float, and named in messages as what it was written as."""

    def __repr__(self) -> str:
        return "a number beyond a float's range"


def float_from_text(text: str) -> float:
    """The float ``text`` writes (ValueError if it writes none, as ``float``): a number too
    large for a float (``1e400``, not ``inf``) as a :class:`BeyondFloat`. Config files are read
    with it (``tomllib``'s ``parse_float``), as ``--set`` values are."""
    value = float(text)
    if math.isinf(value) and "inf" not in text.lower():
        return BeyondFloat(value)
    return value


def _not_finite(value: float) -> str:
    """A value that is not a finite number, as a message says what is wrong with it."""
    if isinstance(value, BeyondFloat):
        return repr(value)
    return f"{value!r}, not a number" if math.isnan(value) else f"{value!r}, not a finite number"


#: Digits of the longest integer a message spells out in full ("an integer of 25 digits").
_SHOWN_DIGITS = 20
#: Integers from this far are "of more than 4000 digits" (Python turns at most 4300 into text).
_COUNTED_DIGITS = 4000


def _number(value: float) -> str:
    """A bound or value for messages and docs: ``5``, ``0.25``, ``1e+06``, ``1e-09``; every
    digit a value needs to differ from a bound it breaks (``10.000000000000002``)."""
    if isinstance(value, int) and not isinstance(value, bool):
        if abs(value) >= 10**_COUNTED_DIGITS:  # (a TOML 0xfff... of 5000 digits)
            return f"an integer of more than {_COUNTED_DIGITS} digits"
        text = str(value)
        digits = len(text.lstrip("-"))
        return text if digits <= _SHOWN_DIGITS else f"an integer of {digits} digits"
    return number_text(value)


class _ShortRepr(reprlib.Repr):
    """``repr`` cut short, an integer written by :func:`_number` also inside a list or a table
    (the built-in ``repr`` of a 5000-digit one raises ValueError)."""

    def repr_int(self, x: int, level: int) -> str:
        return _number(x)

    def repr_str(self, x: str, level: int) -> str:
        """A long string cut on its characters, then quoted as :func:`~vtrack.errors.quoted`
        quotes it (a byte that is not UTF-8 as ``\\xff``, as usage messages say it): reprlib
        cuts the quoted text, which can split an escape (``\\\\udcff`` typed, cut to a lone
        ``\\udcff``: a byte the user never gave)."""
        if len(x) <= self.maxstring:
            text = quoted(x)
            if len(text) <= self.maxstring:
                return text
        keep = max(0, (self.maxstring - 5) // 2)  # (two quote marks and the ...)
        text = quoted(x[:keep] + "..." + x[len(x) - keep:])
        while len(text) > self.maxstring and keep > 1:
            # an escape takes up to 10 characters (\U0001f600): a character fewer each side
            # shortens the text by 2 to 20
            keep = max(1, keep - max(1, (len(text) - self.maxstring) // 20))
            text = quoted(x[:keep] + "..." + x[len(x) - keep:])
        return text


_SHORT = _ShortRepr()
_SHORT.maxstring = _SHORT.maxother = 80


def shown(value: object) -> str:
    """A value a user gave, for a one-line message: an integer as :func:`_number` writes it
    (a 5000-digit one is not spelt out), anything else as its ``repr`` cut to about 80
    characters (``'aaaa...aaaa'``, ``[1, 2, 3, 4, 5, 6, ...]``): a 1 MB string in a config
    file is not echoed whole; a NumPy array but a 0-d one by its shape (its ``repr`` takes
    lines)."""
    if isinstance(value, int) and not isinstance(value, bool):
        return _number(value)
    if type(value).__module__ == "numpy" and getattr(value, "shape", ()) != ():
        return f"a NumPy array of shape {value.shape}"  # type: ignore[attr-defined]
    return _SHORT.repr(value)
