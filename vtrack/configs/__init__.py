"""The shipped tracker configs (``NAME.toml``) and the name of the default one.

:data:`DEFAULT_CONFIG` is the one place the default is named: ``vtrack run``/``vtrack batch``
(behaviour and ``--help``), ``vtrack.track`` and ``vtrack.Tracker`` all read it. This module
imports nothing, so ``--help`` stays cheap.
"""

#: The config used when none is given.
DEFAULT_CONFIG = "robust"

#: What a config is given as, for a message refusing an empty one (``--config ""``,
#: ``load_config("")``).
CONFIG_HINT = "a shipped config's name (vtrack stages lists them) or a TOML file"
