"""The reference controller's memory: the time constants of its estimator's error modes.

    uv run python docs/leaderboard/estimator_memory.py    # → docs/leaderboard/estimator_memory.md

For each measurement suite's reference design (built as the suites build it:
:func:`~pendulum_lqg.policies.loading.build_policy` on the suite's nominal plant and scenario), the
eigenvalues ``z`` of its estimator's error dynamics (``policy.info["observer_poles"]``: for the
current-form Kalman filter the eigenvalues of ``(I − LC)Φ``; for ``kalman-delay`` those of the
delay-augmented filter, whose delay-line modes are at ``z ≈ 0``) and each mode's time constant
``τ = −T / ln|z|`` at the control period ``T``: an estimation error in that mode decays as
``e^{−t/τ}``, so the filter weighs a measurement ``τ/T`` samples old by ``e^{−1}`` relative to a
new one. Modes with ``|z| < 10⁻³`` (they forget within a sample) are counted, not listed.
"""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np

from pendulum_lqg.policies.loading import build_policy
from pendulum_lqg.scoreboard.suites import Suite, load_suite, suite_names

HERE = Path(__file__).resolve().parent
#: Below this |z| a mode forgets within one sample (the delay lines of kalman-delay).
FAST = 1e-3


def memory_rows() -> list[str]:
    lines = ["| suites | reference | T [s] | slow modes \\|z\\| | τ [s] | τ / T [samples] | "
             "modes with \\|z\\| < 10⁻³ |", "|---|---|---|---|---|---|---|"]
    designs: dict[tuple[str, str], list[str]] = {}
    for name in suite_names():
        suite = load_suite(name)
        if suite.observes_state:
            continue
        key = (suite.reference, design_key(suite))
        designs.setdefault(key, []).append(name)
    for (reference, _), names in designs.items():
        suite = load_suite(names[0])
        policy = build_policy(reference, plant=suite.plants()[1], scenario=suite.config.scenario)
        T = float(policy.info["dt"])
        z = np.sort(np.abs(np.asarray(policy.info["observer_poles"])))[::-1]
        slow = z[z >= FAST]
        tau = [-T / math.log(v) for v in slow]
        lines.append(f"| {', '.join(f'`{n}`' for n in names)} | `{reference}` | {T:g} | "
                     + ", ".join(f"{v:.4f}" for v in slow) + " | "
                     + ", ".join(f"{t:.2f}" for t in tau) + " | "
                     + ", ".join(f"{t / T:.0f}" for t in tau) + f" | {int((z < FAST).sum())} |")
    return lines


def design_key(suite: Suite) -> str:
    """What decides the reference's estimator besides its name: period, delays, nominal model."""
    s = suite.config.scenario
    return repr((s.control_period, s.measurement_delay, s.actuator_delay,
                 suite.config.model_path))


def main() -> None:
    text = "\n".join(memory_rows()) + (
        "\n\nThe estimator of each measurement suite's reference: its error modes' |z| and time "
        "constants τ = −T / ln|z| (made by `uv run python docs/leaderboard/estimator_memory.py`)."
        "\n")
    (HERE / "estimator_memory.md").write_text(text, encoding="utf-8")
    print(text, end="")


if __name__ == "__main__":
    main()
