"""The data files the package ships: cart-pole models and experiment files.

The sources live in the repository's top-level ``models/`` and ``experiments/`` folders; the wheel
carries copies as package data under ``pendulum_lqg/_data/`` (``[tool.hatch.build.targets.wheel]``'s
``include`` and ``sources`` in ``pyproject.toml``): the model, the experiment, suite and LTI files
and the example plug-ins and agents, but not the trained models (``experiments/agents/models``,
``experiments/agents/pilot``). Both are read through :mod:`importlib.resources`, so an installed
package finds its files from any working directory, and a source checkout (an editable install)
uses the top-level folders directly. :func:`find_file` is the one rule by which a path a user
gives (``experiments/plugin_lqg.py``, as the docs write it) falls back to the shipped copy.
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


#: Why a trained model (``sb3:``/``linear:``) named by a path may be missing: the wheel leaves them out.
TRAINED_MODELS_NOTE = ("trained models are not shipped in the wheel; give the path of a model "
                       "file, e.g. in a source checkout's experiments/agents/models/")


def find_file(path: str | Path, base_dir: Path | None = None) -> Path:
    """A user's file path made absolute: the first of ``base_dir / path``, the current folder's
    ``path`` and the shipped copy that is a file, else the first of these (for the caller's "no
    file" error). The shipped copy of ``experiments/X`` (as the docs write it, from a checkout's
    root) or of a bare ``X`` is ``X`` in the shipped experiments folder, so that the paths the
    docs show work from an installed wheel in any folder. An absolute path is returned as given."""
    path = Path(path).expanduser()
    if path.is_absolute():
        return path
    relative = Path(*path.parts[1:]) if path.parts[:1] == ("experiments",) else path
    candidates = [base_dir / path] if base_dir is not None else []
    candidates += [Path.cwd() / path]
    if relative.parts:
        candidates.append(data_dir("experiments") / relative)
    return next((c for c in candidates if c.is_file()), candidates[0]).resolve()
