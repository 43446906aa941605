"""The data files the package ships: cart-pole models and experiment files.

The sources live in the repository's top-level ``models/`` and ``experiments/`` folders; the wheel
carries copies as package data under ``pendulum_lqg/_data/`` (``[tool.hatch.build.targets.wheel.
force-include]`` in ``pyproject.toml``). Both are read through :mod:`importlib.resources`, so an
installed package finds its files from any working directory, and a source checkout (an editable
install) uses the top-level folders directly.
"""

from __future__ import annotations

from importlib.resources import files
from pathlib import Path

from pendulum_lqg.errors import ConfigError

#: Kinds of shipped data: the folder name in the repository and under ``pendulum_lqg/_data``.
KINDS: tuple[str, ...] = ("models", "experiments")


def data_dir(kind: str) -> Path:
    """The folder holding the shipped ``kind`` files (``"models"`` or ``"experiments"``)."""
    if kind not in KINDS:
        raise ConfigError(f"kind: expected one of {', '.join(KINDS)}, got {kind!r}")
    package = Path(str(files("pendulum_lqg")))
    for candidate in (package / "_data" / kind, package.parent / kind):
        if candidate.is_dir():
            return candidate
    raise ConfigError(f"{kind}: the package data folder is missing (looked in "
                      f"{package / '_data' / kind} and {package.parent / kind}); reinstall "
                      "pendulum-lqg")


def model_path(name: str = "cartpole.xml") -> Path:
    """Path of a shipped model file (default the cart-pole of the benchmark)."""
    path = data_dir("models") / name
    if not path.is_file():
        raise ConfigError(f"model: no shipped model {name!r}; shipped: "
                          + ", ".join(sorted(p.name for p in data_dir("models").glob("*.xml"))))
    return path


def experiment_names() -> list[str]:
    """Names of the shipped experiment files (``bench NAME``)."""
    return sorted(p.stem for p in data_dir("experiments").glob("*.toml"))


def experiment_path(name: str) -> Path | None:
    """Path of the shipped experiment ``NAME.toml``, or ``None`` if there is none."""
    path = data_dir("experiments") / f"{name}.toml"
    return path if path.is_file() else None
