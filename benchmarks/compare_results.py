"""Compare two results folders file by file: which CSVs are byte-identical, the largest relative
difference of their numbers, and whether any outcome (success, failure reason, episode, seed)
differs.

    uv run python benchmarks/compare_results.py results_small /tmp/regenerated

Floats from two machines agree to a tolerance, not bit for bit (another CPU makes OpenBLAS round
its products differently); outcomes must be identical. Relative differences are taken against
max(|a|, |b|, 1e-12), so numbers that are zero up to rounding (1e-17 against 0) do not dominate.
"""

from __future__ import annotations

import csv
import math
from pathlib import Path

from pendulum_lqg.errors import ConfigError
from pendulum_lqg.util.scripts import ScriptParser, run_script

OUTCOMES = ("success", "failure_reason", "episode", "seed", "config")


def compare(a: Path, b: Path) -> int:
    differing_outcomes = 0
    for f in sorted(a.rglob("*.csv")):
        g = b / f.relative_to(a)
        if not g.is_file():
            print(f"{f.relative_to(a)}: missing in {b}")
            continue
        if f.read_bytes() == g.read_bytes():
            print(f"{f.relative_to(a)}: byte-identical")
            continue
        with f.open(newline="") as fa, g.open(newline="") as fb:
            ra, rb = list(csv.DictReader(fa)), list(csv.DictReader(fb))
        worst, differ, total, outcomes = 0.0, 0, 0, abs(len(ra) - len(rb))
        if len(ra) != len(rb):
            print(f"{f.relative_to(a)}: {len(ra)} rows here, {len(rb)} in {b}")
        for x, y in zip(ra, rb, strict=False):
            for key, va in x.items():
                vb = y.get(key)
                if key in OUTCOMES:
                    outcomes += va != vb
                    continue
                try:
                    fa, fb = float(va), float(vb)
                except (TypeError, ValueError):
                    outcomes += va != vb
                    continue
                total += 1
                if fa != fb and not (math.isnan(fa) and math.isnan(fb)):
                    differ += 1
                    worst = max(worst, abs(fa - fb) / max(abs(fa), abs(fb), 1e-12))
        differing_outcomes += outcomes
        print(f"{f.relative_to(a)}: {differ} of {total} numbers differ, worst relative "
              f"{worst:.2e}; outcomes differing: {outcomes}")
    return differing_outcomes


def main(argv: list[str] | None = None) -> int:
    ap = ScriptParser(description=__doc__.splitlines()[0])
    ap.add_argument("a", type=Path, help="a results folder")
    ap.add_argument("b", type=Path, help="the results folder to compare it with")
    args = ap.parse_args(argv)
    for name, folder in (("a", args.a), ("b", args.b)):
        if not folder.is_dir():
            raise ConfigError(f"{name}: expected a results folder, got {str(folder)!r} "
                              f"({'not a folder' if folder.exists() else 'no such folder'})")
    return 1 if compare(args.a, args.b) else 0


if __name__ == "__main__":
    run_script(main)
