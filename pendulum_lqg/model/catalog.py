"""The plants a user names: the shipped family (``models/NAME.toml``), the cart-pole, and any
plant file.

``--plant NAME|FILE`` (and the experiment key ``plant``, the env keyword ``plant``) is resolved
here, once for every front end:

* ``cartpole`` — the benchmark's MuJoCo cart-pole (:mod:`pendulum_lqg.model.plant`);
* a shipped NAME (``double-cartpole``, …; ``_`` and ``-`` alike) — ``models/NAME.toml``, a plant
  file of an MJCF model (:mod:`pendulum_lqg.model.mjcf`);
* a FILE — a plant file: with a ``model`` key any MuJoCo model, else a plant given as matrices
  (:mod:`pendulum_lqg.model.lti`, TOML or ``.npz``).
"""

from __future__ import annotations

from pathlib import Path
from typing import Any

from pendulum_lqg.errors import ConfigError

#: The plant of the benchmark's lecture tasks.
CARTPOLE = "cartpole"


def shipped_plants() -> dict[str, Path]:
    """``{NAME: plant file}`` of the family shipped in ``models/`` (NAME with ``-``)."""
    from pendulum_lqg.util.resources import data_dir

    return {p.stem.replace("_", "-"): p for p in sorted(data_dir("models").glob("*.toml"))}


def plant_names() -> list[str]:
    """Every name ``--plant`` takes: the cart-pole and the shipped family."""
    return [CARTPOLE, *shipped_plants()]


def is_cartpole(ref: str | Path | None) -> bool:
    """``ref`` names the benchmark's cart-pole (``None``: the default plant)."""
    return ref is None or str(ref).replace("_", "-") == CARTPOLE


def plant_path(ref: str | Path, *, what: str = "plant") -> Path:
    """The plant file ``ref`` names: a shipped NAME's, else the file itself (a relative path not
    found here is looked up among the shipped files, as the docs write them)."""
    from pendulum_lqg.util.resources import find_file

    text = str(ref)
    if not text.strip():
        raise ConfigError(f"{what}: expected a plant name ({', '.join(plant_names())}) or a plant "
                          f"file (.toml, .npz), got {text!r}")
    shipped = shipped_plants().get(text.replace("_", "-"))
    if shipped is not None and Path(text).suffix == "":
        return shipped
    path = Path(text) if Path(text).is_file() else find_file(text)
    if not path.is_file():
        raise ConfigError(f"{what}: expected a plant name ({', '.join(plant_names())}) or a plant "
                          f"file (.toml, .npz), got {text!r}: no such plant or file")
    return path


def load_named_plant(ref: str | Path | None, *, what: str = "plant") -> Any:
    """The plant ``ref`` names (module docstring): a
    :class:`~pendulum_lqg.model.interface.SimulatedPlant`."""
    if is_cartpole(ref):
        from pendulum_lqg.model.plant import load_plant

        return load_plant()
    assert ref is not None
    return load_plant_at(plant_path(ref, what=what))


def load_plant_at(path: str | Path) -> Any:
    """The plant of the plant file ``path``: with a ``model`` key a MuJoCo plant
    (:func:`~pendulum_lqg.model.mjcf.load_plant_file`), else a plant given as matrices
    (:func:`~pendulum_lqg.model.lti.lti_from_mapping`)."""
    from pendulum_lqg.model.lti import lti_from_mapping, read_plant_data

    resolved, data, where = read_plant_data(path)
    if "model" in data:
        from pendulum_lqg.model.mjcf import load_plant_file

        return load_plant_file(resolved, data)
    return lti_from_mapping(data, name=resolved.name.split(".")[0], path=resolved, where=where)
