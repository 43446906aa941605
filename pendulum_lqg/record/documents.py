"""The Markdown documents of a recording: the run's configuration, each episode's outcome, the summary."""

from __future__ import annotations

import json
from collections.abc import Mapping, Sequence
from typing import TYPE_CHECKING, Any

import numpy as np

from pendulum_lqg.errors import ConfigError
from pendulum_lqg.model.plant import Plant
from pendulum_lqg.util.jsonio import plain

if TYPE_CHECKING:
    from pendulum_lqg.core.scenario import Scenario
    from pendulum_lqg.core.trajectory import Trajectory
    from pendulum_lqg.policies.lqg import Policy

# ---- episode selection ----------------------------------------------------------------------
def telling_episodes(rows: Sequence[Mapping[str, Any]]) -> dict[str, int]:
    """Pick the episodes worth recording from a sweep's episode rows.

    Among the successful episodes, the ``best`` (lowest cost), ``median`` (the lower median by
    cost) and ``worst`` (highest cost); among the failures, the ``first_failure`` (lowest episode
    number). Labels whose episode is missing are left out (e.g. no ``first_failure`` when all
    succeed); several labels may name the same episode.

    Parameters
    ----------
    rows : episode records with at least ``episode``, ``success`` and ``cost``
        (:data:`~pendulum_lqg.bench.sources.EPISODE_FIELDS`)

    Returns
    -------
    label → episode number, in the order best, median, worst, first_failure
    """
    for i, r in enumerate(rows):
        missing = [k for k in ("episode", "success", "cost") if k not in r]
        if missing:
            raise ConfigError(f"rows[{i}]: missing key {missing[0]!r}; telling_episodes needs "
                              "'episode', 'success' and 'cost'")
    ok = [r for r in rows if bool(r["success"]) and np.isfinite(float(r["cost"]))]
    ok.sort(key=lambda r: (float(r["cost"]), int(r["episode"])))
    out: dict[str, int] = {}
    if ok:
        out["best"] = int(ok[0]["episode"])
        out["median"] = int(ok[(len(ok) - 1) // 2]["episode"])
        out["worst"] = int(ok[-1]["episode"])
    failed = [int(r["episode"]) for r in rows if not bool(r["success"])]
    if failed:
        out["first_failure"] = min(failed)
    return out


# ---- formatting -----------------------------------------------------------------------------
def fmt(value: object) -> str:
    if isinstance(value, np.ndarray):
        if np.iscomplexobj(value):
            return "[" + ", ".join(fmt(complex(v)) for v in value.ravel()) + "]"
        return np.array2string(value, separator=", ", max_line_width=100,
                               formatter={"float_kind": lambda v: f"{v:.6g}"})
    if isinstance(value, complex):
        if abs(value.imag) < 1e-12:
            return f"{value.real:.6g}"
        return f"{value.real:.6g}{value.imag:+.6g}j"
    if isinstance(value, float):
        return f"{value:.6g}"
    return str(value)


def flatten(data: object, prefix: str = "") -> dict[str, Any]:
    """Nested mappings as ``{"a.b": value}`` (lists stay values)."""
    if not isinstance(data, Mapping):
        return {prefix: data}
    out: dict[str, Any] = {}
    for k, v in data.items():
        key = f"{prefix}.{k}" if prefix else str(k)
        if isinstance(v, Mapping) and v:
            out.update(flatten(v, key))
        else:
            out[key] = v
    return out


def config_markdown(plant: Plant, scenario: Scenario, policy: Policy,
                     config: Mapping[str, object]) -> str:
    info = policy.info
    lines = [f"# Run: {policy.name}", ""]
    if "seed" in config:
        lines.append(f"* **seed**: `{config['seed']}` (episode seeds: "
                     "`SeedSequence(seed, spawn_key=(episode,))`)")
    lines += [f"* **policy**: `{policy.name}`, u = sat(−K x̂), |u| ≤ {plant.u_max:g} N",
              f"* **control period**: {scenario.control_period:g} s, "
              f"physics step {plant.timestep:g} s", "", "## Gains and design poles", ""]
    for key, label in (("K", "controller gain K"), ("L", "observer gain L"),
                       ("controller_poles", "closed-loop controller poles (z)"),
                       ("observer_poles", "observer poles (z)"),
                       ("observer_poles_continuous", "observer poles (s)")):
        if key in info:
            lines += [f"**{label}**", "", "```", fmt(np.asarray(info[key])), "```", ""]
    for title, data in (("Configuration", config), ("Scenario", scenario.to_dict())):
        lines += [f"## {title}", "", "| key | value |", "|---|---|"]
        lines += [f"| {k} | `{json.dumps(v, default=str)}` |"
                  for k, v in flatten(plain(dict(data), nonfinite_as_string=True)).items()]
        lines.append("")
    lines += ["## Plant (read from the MJCF)", "", f"model: `{plant.path}`", "",
              "| parameter | value |", "|---|---|"]
    lines += [f"| {k} | {fmt(v)} |" for k, v in plant.parameters().items()]
    return "\n".join(lines) + "\n"


def outcome_title(tr: Trajectory) -> str:
    row = tr.row
    if bool(row.get("success", False)):
        return f"Episode {tr.episode}: success (cost J = {float(row['cost']):.4g})"  # type: ignore[arg-type]
    return (f"Episode {tr.episode}: FAILED, {row.get('failure_reason', '?')} at "
            f"t = {float(row.get('time_to_failure', np.nan)):.3f} s")  # type: ignore[arg-type]


def outcome_markdown(tr: Trajectory, label: str | None) -> str:
    lines = [f"# {outcome_title(tr)}", ""]
    if label:
        lines += [f"Recorded as: **{label}**", ""]
    lines += [f"* episode seed: `{tr.seed}`", "", "| metric | value |", "|---|---|"]
    lines += [f"| {k} | {fmt(v)} |" for k, v in tr.row.items()]
    return "\n".join(lines) + "\n"


def summary_markdown(trajectories: Sequence[Trajectory], labels: Mapping[int, str]) -> str:
    lines = ["# Recorded episodes", "",
             "| episode | label | seed | outcome | time to failure [s] | cost J |",
             "|---|---|---|---|---|---|"]
    for tr in trajectories:
        r = tr.row
        outcome = "success" if bool(r.get("success")) else f"failed: {r.get('failure_reason')}"
        lines.append(f"| {tr.episode} | {labels.get(tr.episode, '')} | {tr.seed} | {outcome} | "
                     f"{fmt(float(r.get('time_to_failure', np.nan)))} | "  # type: ignore[arg-type]
                     f"{fmt(float(r.get('cost', np.nan)))} |")  # type: ignore[arg-type]
    return "\n".join(lines) + "\n"
