"""Instructions executed per env step, vector step or closed-loop run, counted by Valgrind.

Wall and CPU time on a shared VM vary between runs by more than a small change of the code moves
them; the number of instructions a piece of Python executes does not vary at all. This script
runs one workload under ``valgrind --tool=callgrind`` with counting switched on only around the
timed part (after imports, set-up and a warm-up), so two versions of the package can be compared
to the instruction:

* ``env`` — ``--steps`` calls of ``env.step`` of ``pendulum_lqg/CartPoleLQG-v0`` with a fixed force
  of 0.1 N from the upright at rest (the state is put back before each step, so every step does
  the same work): what the single env's Python costs on top of its 10 physics steps;
* ``vector`` — ``--steps`` steps of the native vector env (64 envs) driven by the LQG agent;
* ``loop`` — one ``run_episodes`` of ``--episodes`` DLQR + Kalman episodes of 2 s, one thread;
* ``import`` — ``import pendulum_lqg.cli`` once, in a fresh interpreter (what every command pays
  before it parses its arguments; bytecode already compiled);
* ``design`` — ``pendulum-lqg design`` once, the package's imports included, its output
  discarded; numpy and ``scipy.linalg`` are imported before the count starts and BLAS is held to
  one thread through threadpoolctl's API (OpenBLAS's idle threads spin while they wait, so with
  two of them the count followed the machine's load by billions).

The last two run once (no warm-up: a module is imported once) with ``PYTHONHASHSEED=0`` so that
two runs of one version count the same set-ups, after compiling the package's bytecode (an edited
module left uncompiled would count the compiler, several times the import itself).

Instructions are not time — a cache miss costs more than an add — but a difference in
instructions of the Python around the physics is a difference in work. ``--tree`` runs another
checkout's package (a ``git worktree`` of an older version) with this environment's libraries.

Usage::

    uv run python benchmarks/instructions.py env [--steps 1000] [--tree PATH]
    uv run python benchmarks/instructions.py vector [--steps 100]
    uv run python benchmarks/instructions.py loop [--episodes 64]
    uv run python benchmarks/instructions.py import [--tree PATH]
    uv run python benchmarks/instructions.py design [--tree PATH]
    uv run python benchmarks/instructions.py env --public   # DIRECT_CALL off: the public rollout
    uv run python benchmarks/instructions.py env --out env.callgrind   # keep the profile, then
    callgrind_annotate --inclusive=yes env.callgrind | head -60         # per-function counts

It needs ``valgrind`` on the PATH (``apt-get install valgrind``), and ``design`` threadpoolctl (in the
dev group); a run takes a minute or two.
"""

from __future__ import annotations

import argparse
import importlib.util
import os
import re
import shutil
import subprocess
import sys
import tempfile
from collections.abc import Callable
from pathlib import Path

#: Ceiling of --steps (env or vector steps counted under Valgrind, about 50× slower than native).
MAX_STEPS = 10**6


def workload(kind: str, count: int, public: bool = False) -> None:
    """Run the workload, counting only its timed part (called inside Valgrind)."""
    def counting(on: bool) -> None:
        subprocess.run(["callgrind_control", "-i", "on" if on else "off", str(os.getpid())],
                       capture_output=True, check=False)

    if kind in ("import", "design"):
        once(kind, counting)
        return
    import gymnasium as gym
    import numpy as np

    import pendulum_lqg

    if kind == "env":
        env = gym.make(pendulum_lqg.ENV_ID)
        env.reset(seed=1)
        sim = env.unwrapped._sim
        if public:                      # the public Batch.rollout instead of DIRECT_CALL's core
            sim._physics.direct_call = False
        action = np.array([0.1])

        def run(n: int) -> None:
            for _ in range(n):
                sim.x[...] = 0.0
                sim.period[0] = 0
                env.step(action)
    elif kind == "vector":
        from pendulum_lqg import LQGAgent
        vec = gym.make_vec(pendulum_lqg.ENV_ID, num_envs=64)
        agent = LQGAgent(vec)
        obs = [vec.reset(seed=1)[0]]
        agent.reset()

        def run(n: int) -> None:
            for _ in range(n):
                obs[0] = vec.step(agent.act(obs[0]))[0]
    else:
        from pendulum_lqg import Scenario, run_episodes
        from pendulum_lqg.model.plant import load_plant
        from pendulum_lqg.policies.lqg import DesignSpec, design_policy
        plant, sc = load_plant(), Scenario(duration=2.0)
        policy = design_policy(plant, sc.control_period, sc.noise, DesignSpec("dlqr", "kalman"))

        def run(n: int) -> None:
            run_episodes(plant, sc, policy, seed=0, episodes=range(n), nthread=1)
    run(max(1, count // 10))                                    # warm-up, not counted
    counting(True)
    run(count)
    counting(False)


def once(kind: str, counting: Callable[[bool], None]) -> None:
    """``import pendulum_lqg.cli`` or one ``pendulum-lqg design``, counted whole, once."""
    import contextlib
    import importlib
    import io

    if kind == "design":
        # the libraries both versions load, loaded first; then every BLAS they loaded on one
        # thread, so that no idle BLAS thread spins inside the count (threadpoolctl limits the
        # libraries already loaded: hence after the imports)
        importlib.import_module("numpy")
        importlib.import_module("scipy.linalg")
        from threadpoolctl import threadpool_limits
        threadpool_limits(limits=1, user_api="blas")
    counting(True)
    cli = importlib.import_module("pendulum_lqg.cli")
    if kind == "design":
        with contextlib.redirect_stdout(io.StringIO()):
            cli.main(["design"])
    counting(False)


def inner(argv: list[str]) -> None:
    """The workload inside Valgrind (``--inner``): it imports nothing of the package before the
    workload does, so that ``--tree`` may name a checkout of any version."""
    ap = argparse.ArgumentParser()
    ap.add_argument("kind")
    ap.add_argument("--steps", type=int)
    ap.add_argument("--episodes", type=int, default=64)
    ap.add_argument("--public", action="store_true")
    ap.add_argument("--inner", action="store_true")
    args = ap.parse_args(argv)
    workload(args.kind, args.episodes if args.kind == "loop"
             else args.steps or (1000 if args.kind == "env" else 100), args.public)


def main(argv: list[str] | None = None) -> None:
    from pendulum_lqg.errors import ConfigError
    from pendulum_lqg.util.files import output_file, replacing
    from pendulum_lqg.util.limits import MAX_BATCH_EPISODES
    from pendulum_lqg.util.scripts import ScriptParser, int_in

    ap = ScriptParser(description=__doc__.splitlines()[0])
    ap.add_argument("kind", choices=["env", "vector", "loop", "import", "design"])
    ap.add_argument("--steps", type=int_in(1, MAX_STEPS), default=None,
                    help="env or vector steps (1000 / 100)")
    ap.add_argument("--episodes", type=int_in(1, MAX_BATCH_EPISODES), default=64,
                    help="loop: episodes")
    ap.add_argument("--tree", default=None, help="a checkout whose pendulum_lqg to run")
    ap.add_argument("--public", action="store_true",
                    help="env: the period through the public Batch.rollout, not DIRECT_CALL's "
                         "direct call of its C++ core (the two counted against each other)")
    ap.add_argument("--out", default=None,
                    help="keep callgrind's profile in this file (for callgrind_annotate)")
    ap.add_argument("--inner", action="store_true", help=argparse.SUPPRESS)
    args = ap.parse_args(argv)
    count = 1 if args.kind in ("import", "design") else args.episodes if args.kind == "loop" \
        else (args.steps or (1000 if args.kind == "env" else 100))
    out = None if args.out is None else output_file("--out", args.out, what="callgrind profile")
    if args.tree and not (Path(args.tree) / "pendulum_lqg").is_dir():
        raise ConfigError(f"--tree: expected a checkout holding pendulum_lqg/, got {args.tree!r}")
    if args.kind == "design" and importlib.util.find_spec("threadpoolctl") is None:
        raise ConfigError("instructions design: threadpoolctl is not installed (the dev group "
                          "has it: uv sync)")
    if shutil.which("valgrind") is None:
        raise ConfigError("instructions: valgrind is not on the PATH (apt-get install valgrind)")
    env = dict(os.environ, MUJOCO_GL=os.environ.get("MUJOCO_GL", "egl"))
    if args.tree:
        env["PYTHONPATH"] = os.path.abspath(args.tree)
    if args.kind in ("import", "design"):        # the same dict and set orders in both versions
        env["PYTHONHASHSEED"] = "0"
        # the package's bytecode compiled first (as an install does), so that neither version's
        # count holds the compiler: PYTHONDONTWRITEBYTECODE keeps an edited module uncompiled
        tree = Path(args.tree or Path(__file__).resolve().parents[1]) / "pendulum_lqg"
        subprocess.run([sys.executable, "-m", "compileall", "-q", str(tree)], capture_output=True,
                       check=False)
    with tempfile.TemporaryDirectory() as tmp:
        # callgrind writes its profile itself: into the temporary folder, then moved whole to --out
        profile = f"{tmp}/callgrind.out"
        cmd = ["valgrind", "--tool=callgrind", "--instr-atstart=no",
               f"--callgrind-out-file={profile}", sys.executable, os.path.abspath(__file__),
               args.kind, "--inner", "--steps", str(count), "--episodes", str(count),
               *(["--public"] if args.public else [])]
        done = subprocess.run(cmd, env=env, capture_output=True, text=True, check=False)
        found = re.search(r"I\s+refs:\s+([\d,]+)", done.stderr)
        if done.returncode != 0 or found is None:
            last = (done.stderr.strip().splitlines() or ["no output"])[-1]
            raise ConfigError(f"instructions: the valgrind run failed (exit status "
                              f"{done.returncode}): {last}")
        if out is not None:
            with replacing(out, where="--out", what="callgrind profile") as kept:
                shutil.copyfile(profile, kept)
    total = int(found.group(1).replace(",", ""))
    what = {"env": "env.step", "vector": "vector step (64 envs, with the agent)",
            "loop": "episode (2 s, DLQR + Kalman, one thread)",
            "import": "import pendulum_lqg.cli", "design": "pendulum-lqg design"}[args.kind]
    via = " through the public Batch.rollout" if args.public else ""
    print(f"{args.kind}: {total / count / 1e3:,.1f} k instructions per {what}{via} "
          f"({total:,} over {count}; package from {args.tree or 'this checkout'})")


if __name__ == "__main__":
    if "--inner" in sys.argv[1:]:
        inner(sys.argv[1:])
    else:
        from pendulum_lqg.util.scripts import run_script

        run_script(main)
