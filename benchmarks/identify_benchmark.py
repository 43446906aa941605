"""How long closed-loop identification of one seed takes (data, fits, design; no scoring).

::

    uv run python benchmarks/identify_benchmark.py                       # lecture, seed 0, default recipe
    uv run python benchmarks/identify_benchmark.py --suite delayed --seed 3 --steps 20000

Runs :func:`~pendulum_lqg.learn.closed_loop.identify_closed_loop` once per ``--repeat`` (the same
seed: the same episodes and fits every time) and prints, per repeat, the wall time with the logged
and stepped env steps, then the median. The data come from the native vector env on one physics
thread; the fits are numpy. Measure on a quiet machine: the time is shared with whatever else runs.
"""

from __future__ import annotations

import statistics
import time

from pendulum_lqg.util.scripts import ScriptParser, int_in, run_script


def main(argv: list[str] | None = None) -> int:
    ap = ScriptParser(description=__doc__.splitlines()[0])
    ap.add_argument("--suite", default="lecture", help="suite name or file (default lecture)")
    ap.add_argument("--seed", type=int_in(0, 10**6), default=0,
                    help="data seed S: root 500 000 + 1000·S")
    ap.add_argument("--steps", type=int_in(1, 10**8), default=None,
                    help="logged env-step budget (default: the default recipe)")
    ap.add_argument("--repeat", type=int_in(1, 100), default=1, help="runs (default 1)")
    args = ap.parse_args(argv)

    from pendulum_lqg.learn.closed_loop import identify_closed_loop
    from pendulum_lqg.scoreboard.suites import load_suite

    suite = load_suite(args.suite)
    times = []
    for i in range(args.repeat):
        t0 = time.perf_counter()
        final = identify_closed_loop(suite, root=500_000 + 1000 * args.seed, steps=args.steps)[-1]
        times.append(time.perf_counter() - t0)
        print(f"run {i + 1}: {times[-1]:.1f} s ({final.logged_steps:,} logged, "
              f"{final.stepped_steps:,} stepped env steps)", flush=True)
    print(f"identification of {suite.name} seed {args.seed}: median {statistics.median(times):.1f} s "
          f"over {len(times)} run(s)")
    return 0


if __name__ == "__main__":
    run_script(main)
