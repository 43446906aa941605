"""Start-up of ``pendulum-lqg design`` against the imports it cannot avoid, paired.

    uv run python benchmarks/startup.py [--rounds 9]

Starts three whole processes in turn, round after round (bytecode cached, output discarded):

* ``python -c pass`` — the interpreter alone;
* ``python -c "import numpy, mujoco, scipy.linalg, scipy.signal"`` — the libraries whose public
  functions the design calls (MuJoCo to read and linearise the model, ``scipy.linalg`` for the
  matrix exponential and the Riccati equations, ``scipy.signal.place_poles`` for the two
  Luenberger observers);
* ``pendulum-lqg design`` — the console script next to this interpreter.

It prints each one's median wall time with its range, the median of the per-round ratios
design / libraries (the machine's drift cancels in a pair: a ratio near 1 says the command costs
little beyond importing its libraries), and where one design run's imports go: ``-X importtime``
self times, each charged to the library whose import brought the module in (see
:func:`import_shares`). ``-X importtime`` slows every import, so the breakdown is given as
shares, not seconds.
"""

from __future__ import annotations

import os
import statistics
import subprocess
import sys
import time
from pathlib import Path

from pendulum_lqg.errors import ConfigError
from pendulum_lqg.util.scripts import ScriptParser, int_in, run_script

#: Ceiling of the alternating rounds.
MAX_ROUNDS = 100
#: The groups import time is charged to: the package's own modules and the libraries it calls
#: (``scipy`` after its two subpackages: SciPy's common core, whichever subpackage loads it).
GROUPS = ("pendulum_lqg", "scipy.signal", "scipy.linalg", "scipy", "mujoco", "numpy")
LIBRARIES = "import numpy, mujoco, scipy.linalg, scipy.signal"


def group_of(module: str) -> str | None:
    """The group ``module`` belongs to by name, or None (``scipy.signal._ltisys`` → ``scipy.signal``)."""
    for g in GROUPS:
        if module == g or module.startswith(g + "."):
            return g
    return None


def import_shares(importtime: str) -> dict[str, int]:
    """Microseconds of self time per group (and ``other``) from ``python -X importtime`` output.

    A module is charged to the outermost library import that brought it in — ``scipy.stats`` and
    ``numpy.ma`` to ``scipy.signal``, which loads them — so that a library's share is what its
    first import cost on top of what was loaded before it. Modules no library brought in go to
    their own group by name, else to ``pendulum_lqg`` if the package imported them (``argparse``,
    ``json``), else to ``other``. The lines come children first, each indented two spaces per
    level below the import that caused it: read backwards they are in pre-order, and a stack of
    (level, group) gives each module its ancestors.
    """
    rows = []
    for line in importtime.splitlines():
        if not line.startswith("import time:") or "|" not in line:
            continue
        head, _cumulative, name = line.split("|", 2)
        try:
            us = int(head.removeprefix("import time:").strip())
        except ValueError:          # the header line: "self [us] | cumulative | imported package"
            continue
        level = (len(name) - len(name.lstrip(" ")) - 1) // 2
        rows.append((level, name.strip(), us))
    totals = {g: 0 for g in (*GROUPS, "other")}
    stack: list[tuple[int, str | None]] = []
    for level, name, us in reversed(rows):
        while stack and stack[-1][0] >= level:
            stack.pop()
        parent = stack[-1][1] if stack else None
        if parent is not None and parent != "pendulum_lqg":
            group: str | None = parent            # inside a library's import: that library's
        else:
            group = group_of(name) or parent
        stack.append((level, group))
        totals[group or "other"] += us
    return totals


def wall(cmd: list[str]) -> float:
    """Seconds from the start of ``cmd`` to its exit (stdout and stderr discarded)."""
    t0 = time.perf_counter()
    subprocess.run(cmd, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL, check=True)
    return time.perf_counter() - t0


def main(argv: list[str] | None = None) -> None:
    ap = ScriptParser(description=__doc__.splitlines()[0])
    ap.add_argument("--rounds", type=int_in(1, MAX_ROUNDS), default=9,
                    help="alternating rounds (default 9)")
    args = ap.parse_args(argv)
    script = Path(sys.executable).with_name("pendulum-lqg")
    if not script.exists():
        raise ConfigError(f"startup: no console script at {script} (install the package: uv sync)")
    commands = {
        "python -c pass": [sys.executable, "-c", "pass"],
        f'python -c "{LIBRARIES}"': [sys.executable, "-c", LIBRARIES],
        "pendulum-lqg design": [str(script), "design"],
    }
    for cmd in commands.values():   # warm-up: page cache and bytecode, not counted
        wall(cmd)
    times: dict[str, list[float]] = {k: [] for k in commands}
    for _ in range(args.rounds):
        for name, cmd in commands.items():
            times[name].append(wall(cmd))
    names = list(commands)
    ratios = [d / lib for d, lib in zip(times[names[2]], times[names[1]], strict=True)]
    print(f"start-up, {args.rounds} alternating rounds, wall s: median (range); "
          f"{os.cpu_count()} CPUs, bytecode cached")
    for name in names:
        t = times[name]
        print(f"  {name:<60} {statistics.median(t):6.3f}  ({min(t):.3f}–{max(t):.3f})")
    print(f"  ratio design / its libraries' imports: {statistics.median(ratios):.3f} "
          f"(rounds {min(ratios):.3f}–{max(ratios):.3f})")
    done = subprocess.run([sys.executable, "-X", "importtime", str(script), "design"],
                          stdout=subprocess.DEVNULL, stderr=subprocess.PIPE, text=True, check=True)
    shares = import_shares(done.stderr)
    total = sum(shares.values())
    print("imports of one design run, share of -X importtime self time by the group that "
          "imported them:")
    print("  " + ", ".join(f"{g} {100 * us / total:.0f} %"
                           for g, us in sorted(shares.items(), key=lambda kv: -kv[1]) if us))


if __name__ == "__main__":
    run_script(main)
