"""Local executor vs Ray on one machine: the same sweep, side by side, in one run.

    uv run python benchmarks/executor_benchmark.py [--experiment mismatch] [--episodes 20] [--rounds 2]

Runs the sweep (default ``mismatch`` at 20 episodes per configuration: 100 configurations = 100
work units of 20 ten-second episodes) alternately on the local executor (one process, the rollout
of each unit on every core) and on a local Ray instance (one task per core, one rollout thread
each), checks that both give byte-identical ``episodes.csv`` and ``summary.json``, and prints work
units per second (median of the rounds) and Ray's start-up time. Needs the ``ray`` extra.
"""

from __future__ import annotations

import os
import statistics
import tempfile
import time
from pathlib import Path

from pendulum_lqg.bench.executors import LocalExecutor, RayExecutor
from pendulum_lqg.bench.experiments import load_spec
from pendulum_lqg.bench.sweep import run_sweep
from pendulum_lqg.util.limits import MAX_SCORE_EPISODES
from pendulum_lqg.util.scripts import ScriptParser, int_in, requires, run_script

#: Ceiling of the alternating rounds.
MAX_ROUNDS = 100


def main(argv: list[str] | None = None) -> None:
    ap = ScriptParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--experiment", default="mismatch")
    ap.add_argument("--episodes", type=int_in(1, MAX_SCORE_EPISODES), default=20,
                    help="episodes per configuration")
    ap.add_argument("--rounds", type=int_in(1, MAX_ROUNDS), default=2)
    args = ap.parse_args(argv)
    requires("ray", needed_for="the Ray executor", install="the ray extra: uv sync --extra ray")
    spec = load_spec(args.experiment).with_overrides(episodes=args.episodes)
    n_units = len(spec.units())
    cpus = len(os.sched_getaffinity(0))
    rates: dict[str, list[float]] = {"local": [], "ray": []}
    startups: list[float] = []
    outputs: dict[str, bytes] = {}
    with tempfile.TemporaryDirectory() as tmp:
        for r in range(args.rounds):
            for name in ("local", "ray"):
                t0 = time.perf_counter()
                executor = LocalExecutor() if name == "local" else RayExecutor(num_cpus=cpus)
                t_ready = time.perf_counter()
                out = Path(tmp) / f"{name}{r}"
                run_sweep(spec, out, executor=executor, progress=False)
                t_end = time.perf_counter()
                if name == "ray":
                    startups.append(t_ready - t0)
                rates[name].append(n_units / (t_end - t_ready))
                data = (out / "episodes.csv").read_bytes() + (out / "summary.json").read_bytes()
                assert outputs.setdefault(name, data) == data
    identical = outputs["local"] == outputs["ray"]
    local, ray = (statistics.median(rates[k]) for k in ("local", "ray"))
    print(f"{spec.name}: {n_units} work units × {spec.episodes} episodes of "
          f"{spec.configurations[0].scenario.get('duration', 10.0)} s, {cpus} CPUs, "
          f"{args.rounds} alternating rounds (medians)")
    print(f"  local executor (1 process, {cpus} rollout threads): {local:7.2f} units/s")
    print(f"  Ray, local instance ({cpus} tasks × 1 thread):     {ray:7.2f} units/s  "
          f"(+ {statistics.median(startups):.1f} s start-up, not counted)")
    print(f"  ratio Ray / local: {ray / local:.2f}; results byte-identical: {identical}")


if __name__ == "__main__":
    run_script(main)
