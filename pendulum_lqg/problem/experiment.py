"""The experiment file's tables, derived from the declarations: the ``[scenario]`` keys (the
settings declared with the front end ``"file"``), the ``[grid]`` keys routed to the scenario
(declared ``grid=True``), and the file's run settings (:class:`RunSettings`).
"""

from __future__ import annotations

from typing import Annotated

import msgspec

from pendulum_lqg.problem.declare import NonNegativeInt, PositiveInt, declared, setting
from pendulum_lqg.problem.scenario import ScenarioSettings

_FILE = ("file",)


class RunSettings(msgspec.Struct, frozen=True, kw_only=True):
    """The experiment file's top-level numbers."""

    episodes: Annotated[PositiveInt, setting(
        "episodes per configuration (--episodes overrides)", fronts=_FILE)] = 100
    seed: Annotated[NonNegativeInt, setting(
        "the run's seed (--seed overrides)", fronts=_FILE)] = 0
    chunk: Annotated[PositiveInt, setting(
        "episodes per work unit (one batch of run_episodes)", fronts=_FILE)] = 250


_SCENARIO = [d for d in declared(ScenarioSettings) if "file" in d.fronts]

#: The keys of the ``[scenario]`` table (``randomize``: its own declaration, a table of ranges).
SCENARIO_KEYS: tuple[str, ...] = (*(d.name for d in _SCENARIO), "randomize")
#: The ``[grid]`` keys that set a scenario setting of each configuration.
SCENARIO_GRID_KEYS: tuple[str, ...] = tuple(d.name for d in _SCENARIO if d.grid)
#: The run settings by name.
RUN_SETTINGS = {d.name: d for d in declared(RunSettings)}
