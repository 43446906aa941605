"""The versions a result carries: the package's, the results schema's and the libraries' that
compute the numbers. Imports nothing of the package and no third-party library, so anything — the
CLI's ``--version``, a results folder, a score file — can read them at no cost."""

from __future__ import annotations

__version__ = "0.5.0"

#: Version of the results schema (``summary.json``, ``episodes.csv``); see docs/results.md.
SCHEMA_VERSION = 1

#: Libraries whose versions change the numbers; a resume across a change of any is refused.
VERSIONED = ("mujoco", "numpy", "scipy", "control")


def versions() -> dict[str, str]:
    """pendulum_lqg's version and those of :data:`VERSIONED` (read from package metadata, nothing
    imported)."""
    from importlib import metadata

    out = {"pendulum_lqg": __version__}
    for lib in VERSIONED:
        try:
            out[lib] = metadata.version(lib)
        except metadata.PackageNotFoundError:
            out[lib] = "absent"
    return out
