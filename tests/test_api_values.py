"""The library's values as a user gives them in Python: numbers too large to write as text,
NumPy scalars, a config given beside a RunRequest, a Config changed after its check. Each is
one ConfigError (or TypeError) naming the value, never a traceback from deep inside."""

from __future__ import annotations

from pathlib import Path

import pytest

import vtrack
from vtrack.errors import ConfigError
from vtrack.scenes import make_scene

#: An integer Python will not turn into text (more than 4300 digits): a message that shows it
#: with ``repr`` raises ValueError instead of saying what is wrong.
HUGE = 10**5000


def _frames(count: int = 10) -> list:
    """A few BGR frames of a target on a plain background."""
    scene = make_scene("smooth", seed=1, width=96, height=72, frames=count, fps=30.0)
    return list(scene.frames())


@pytest.mark.parametrize("make", [
    lambda: list(vtrack.track(_frames(), "s0", (10, 10, 20, 20), seed=HUGE)),
    lambda: vtrack.Tracker("s0", seed=HUGE),
    lambda: vtrack.RunRequest(input="c.mp4", out_dir=Path("out"),
                              config=vtrack.load_config("s0"), seed=HUGE),
])
def test_a_seed_too_long_to_write_is_refused_naming_seed_and_its_range(make) -> None:
    with pytest.raises(ConfigError) as caught:
        make()
    assert str(caught.value) == ("seed an integer of more than 4000 digits: must be a whole "
                                 "number from 0 to 4294967295")


@pytest.mark.parametrize("make", [
    lambda box: list(vtrack.track(_frames(), "s0", box)),
    lambda box: vtrack.RunRequest(input="c.mp4", out_dir=Path("out"),
                                  config=vtrack.load_config("s0"), init_box=box),
])
def test_a_first_box_with_a_number_too_long_to_write_is_refused_naming_init_box(make) -> None:
    with pytest.raises(ConfigError) as caught:
        make((HUGE, 1, 20, 20))
    assert str(caught.value) == ("init_box: (an integer of more than 4000 digits, 1, 20, 20): "
                                 "a number beyond a float's range (x, y, w, h are pixels of "
                                 "the frame)")
    with pytest.raises(ConfigError, match=r"^init_box: expected \(x, y, w, h\) numbers, got "
                                          r"\[an integer of more than 4000 digits, 'a'\]$"):
        make([HUGE, "a"])
