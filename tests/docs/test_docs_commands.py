"""Every command and example that README.md and docs/**/*.md show runs, as written or reduced.

What is collected, from the fenced blocks of README.md and every page under docs/:

* **every line** of a ```` ```bash ```` / ```` ```console ```` / ```` ```sh ```` block (a ``$``
  prompt and a trailing ``# comment`` dropped): a *documented command*. Each one is, by its text,

  - run as written: ``pendulum-lqg …`` (bare, or after ``uv run [--extra X | --group X |
    --with X]``) through the console script's own function (:func:`pendulum_lqg.cli.main`, in this
    process: a subprocess would add only an interpreter's start-up, which ``tests/envs`` and the
    wheel's smoke run test with the real console script); ``python …`` / ``uv run python …`` as a
    subprocess of this interpreter; ``cp SRC DST`` by copying;
  - run in the reduced form :data:`REDUCED` gives it, with the reason (a bench of 200 episodes, a
    timing of seven rounds, a training run);
  - run only where the ``rl`` extra is installed (:data:`NEEDS_RL`: torch), reduced as well;
  - or not run, for the reason :data:`NOT_RUN` gives (an install, a server, the whole site).

  A documented command that is none of these fails :func:`test_every_documented_command_is_run_or_listed`,
  and so does a training run (``pendulum-lqg train …``, ``python benchmarks/train_*.py …``) that
  no table gives a budget, and an entry of the tables that no page shows any more.
* the commands run in a scratch folder per page, in the page's order (a ``report`` finds what the
  ``bench`` above it wrote), beside copies of the checkout's ``experiments/``, ``models/``,
  ``benchmarks/`` and ``docs/leaderboard/`` (a script that writes next to itself writes into the
  copy); :func:`test_the_commands_leave_the_checkout_as_it_was` checks ``git status``;
* what a command prints is checked: when the page shows its output (a ```` ```text ```` block right
  after the command's block, introduced by at most a short sentence ending in ``:``), every line of
  that block appears in the output, in order (machine paths of the model file aside); a file the
  comment names after ``→`` must have been written; ``design`` / ``run`` / ``--version`` /
  ``--help`` are checked for their values (the DLQR gain, the success count);
* a ```` ```python ```` block preceded by ``<!-- test -->`` runs as a script in a scratch folder;
  when the next fenced block is ```` ```text ```` (what the page says it prints), its output must
  equal that block;
* a ```` ```python ```` block preceded by ``<!-- file: NAME -->`` is a file the page tells the
  reader to save (a plug-in): it is written as ``NAME`` into the page's scratch folder.

README's commands and examples, and every command whose page runs only cheap commands up to it
(``design``, ``--help``, ``--version``, ``run`` of at most 4 episodes), are the quick set; the rest
is marked ``slow``. A selected command runs its page's commands up to it, once per session.
"""

from __future__ import annotations

import importlib.util
import json
import os
import re
import shlex
import shutil
import subprocess
import sys
import time
import tomllib
from dataclasses import dataclass
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[2]
PAGES = [ROOT / "README.md",
         *sorted(p for p in (ROOT / "docs").rglob("*.md") if "_build" not in p.parts)]
#: a fenced block, with the HTML comment on the line before it (if any)
#: (the info string is anything after the backticks: ```{include} FILE``` is a block too, so that
#: its closing fence is not taken for an opening one)
FENCE = re.compile(r"(?:^<!--\s*(?P<marker>[^>]*?)\s*-->\n)?^```(?P<lang>[^`\n]*)\n(?P<body>.*?)^```\s*$",
                   re.M | re.S)
SHELL_LANGS = {"bash", "console", "sh", "shell"}
#: ``uv run [--extra X | --group X | --with X …]``: the prefix that runs a command in the project
UV_RUN = re.compile(r"^uv run(?:\s+--(?:extra|group|with)\s+\S+)*\s+")
SHELL_OPERATORS = {">", ">>", "|", "&&", ";", "2>", "2>&1", "&"}
TIMEOUT_S = 300
HAS_TORCH = importlib.util.find_spec("torch") is not None
#: a training run: never run as written (its budget is minutes to hours), only through a table
TRAINING = re.compile(r"^(?:pendulum-lqg train\b(?!.*--(?:list|help))|python benchmarks/train_\w+\.py\b"
                      r"(?!.*--(?:list|help)))")

# ---- what is not run as written ----------------------------------------------------------------------
_BENCH = "bench of 200 episodes per configuration: 2 episodes of 1 s on each grid axis's first two values"
_TIMING = "a timing of several rounds: one short round (the numbers are not checked, the script is)"
#: documented command → (the command run instead, why). A ``bench NAME`` runs the reduced copy of
#: ``experiments/NAME.toml`` that :func:`reduced_experiment` writes (``reduced/NAME.toml``).
REDUCED: dict[str, tuple[str, str]] = {
    "uv run pendulum-lqg bench lecture": ("pendulum-lqg bench reduced/lecture.toml --quiet", _BENCH),
    "pendulum-lqg bench lecture": ("pendulum-lqg bench reduced/lecture.toml --quiet", _BENCH),
    "uv run pendulum-lqg bench margins --out results_small/margins --force":
        ("pendulum-lqg bench reduced/margins.toml --out results_small/margins --force --quiet",
         "13 weights × 4000 frequencies: 2 weights, 200 frequencies"),
    "uv run pendulum-lqg bench roa --episodes 20 --out results_small/roa --force":
        ("pendulum-lqg bench reduced/roa.toml --out results_small/roa --force --quiet",
         "a bisection per policy and a 25 × 25 map: 2 policies, a coarse bisection, a 3 × 3 map"),
    "uv run pendulum-lqg bench sample_period --episodes 2 --out results_small/sample_period --force":
        ("pendulum-lqg bench reduced/sample_period.toml --out results_small/sample_period --force --quiet",
         "144 configurations: " + _BENCH),
    "uv run pendulum-lqg bench mismatch --episodes 4 --out results_small/mismatch --force":
        ("pendulum-lqg bench reduced/mismatch.toml --out results_small/mismatch --force --quiet",
         "100 configurations: " + _BENCH),
    "uv run pendulum-lqg bench noise --episodes 20 --out results_small/noise --force":
        ("pendulum-lqg bench reduced/noise.toml --out results_small/noise --force --quiet", _BENCH),
    "uv run pendulum-lqg bench lecture_unbounded":
        ("pendulum-lqg bench reduced/lecture_unbounded.toml --quiet", _BENCH),
    "uv run pendulum-lqg bench double_cartpole --episodes 200":
        ("pendulum-lqg bench reduced/double_cartpole.toml --quiet", _BENCH),
    "uv run pendulum-lqg bench double_integrator --episodes 200":
        ("pendulum-lqg bench reduced/double_integrator.toml --quiet", _BENCH),
    "uv run pendulum-lqg bench observers": ("pendulum-lqg bench reduced/observers.toml --quiet", _BENCH),
    "uv run pendulum-lqg bench lecture_linear":
        ("pendulum-lqg bench reduced/lecture_linear.toml --quiet", _BENCH),
    "uv run pendulum-lqg bench plugins": ("pendulum-lqg bench reduced/plugins.toml --quiet", _BENCH),
    "uv run pendulum-lqg bench delay": ("pendulum-lqg bench reduced/delay.toml --quiet", _BENCH),
    "uv run pendulum-lqg bench lecture --record recordings/":
        ("pendulum-lqg bench reduced/lecture.toml --record recordings/ --quiet", _BENCH),
    "uv run pendulum-lqg run --plant experiments/lti/double_integrator.toml --episodes 200 --duration 50":
        ("pendulum-lqg run --plant experiments/lti/double_integrator.toml --episodes 4 --duration 1",
         "200 episodes of 50 s: 4 of 1 s"),
    "pendulum-lqg score --agent experiments/agents/zero_force.py:make --suite lecture --episodes 2":
        ("pendulum-lqg score --agent experiments/agents/zero_force.py:make --suite lecture "
         "--episodes 2", "as written (the agent's fall ends each episode early)"),
    "uv run pendulum-lqg score dlqr+luenberger --suite lecture --suite lossy --out scores/dlqr+luenberger.json":  # noqa: E501 (a documented line, as the page shows it)
        ("pendulum-lqg score dlqr+luenberger --suite lecture --suite lossy --episodes 2 "
         "--out scores/dlqr+luenberger.json", "100 episodes per suite: 2"),
    "uv run pendulum-lqg score dlqr+kalman --suite lecture --suite lossy --out scores/dlqr+kalman.json":
        ("pendulum-lqg score dlqr+kalman --suite lecture --suite lossy --episodes 2 "
         "--out scores/dlqr+kalman.json", "100 episodes per suite: 2"),
    "uv run pendulum-lqg score dlqr+luenberger --suite experiments/lti/two_mass_suite.toml":
        ("pendulum-lqg score dlqr+luenberger --suite experiments/lti/two_mass_suite.toml "
         "--episodes 4", "100 episodes of the LTI suite: 4"),
    "uv run pendulum-lqg perf --repeats 3":
        ("pendulum-lqg perf --repeats 1 --episodes 8 --duration 1", _TIMING),
    "uv run python benchmarks/env_benchmark.py --repeats 5":
        ("python benchmarks/env_benchmark.py --repeats 1 --steps 200 --blocks 2", _TIMING),
    "uv run python benchmarks/env_benchmark.py --repeats 7":
        ("python benchmarks/env_benchmark.py --repeats 1 --steps 200 --blocks 2", _TIMING),
    "uv run python benchmarks/env_benchmark.py --repeats 3 --steps 5000":
        ("python benchmarks/env_benchmark.py --repeats 1 --steps 200 --blocks 2", _TIMING),
    "uv run python benchmarks/vector_benchmark.py --repeats 5":
        ("python benchmarks/vector_benchmark.py --repeats 1 --steps 20 --blocks 2 --num-envs 4",
         _TIMING),
    "uv run python benchmarks/vector_benchmark.py --repeats 3 --steps 300":
        ("python benchmarks/vector_benchmark.py --repeats 1 --steps 20 --blocks 2 --num-envs 4",
         _TIMING),
    "uv run python benchmarks/instructions.py env":
        ("python benchmarks/instructions.py env --steps 20",
         "1000 steps under valgrind's callgrind: 20 (the count is not checked, the script is)"),
    "uv run python experiments/record_demo.py --out /tmp/recordings":
        ("python experiments/record_demo.py --out recordings",
         "writes into the scratch folder, not a shared /tmp"),
    "pendulum-lqg score --agent linear:experiments/agents/models/ars-history-seed0.json --suite all --out docs/leaderboard/scores/rl_ars-history-seed0.json":  # noqa: E501 (as the page shows it)
        ("pendulum-lqg score --agent linear:experiments/agents/models/ars-history-seed0.json "
         "--suite all --episodes 2 --out docs/leaderboard/scores/rl_ars-history-seed0.json",
         "7 suites × 100 episodes: 2 each"),
    "pendulum-lqg train sysid-lqg --seed 0 --out runs/sysid":
        ("pendulum-lqg train sysid-lqg --seed 0 --steps 20000 --out runs/sysid",
         "the default recipe logs about 70 000 steps: a budget of 20 000"),
    "pendulum-lqg score --agent linear:runs/sysid/sysid-lqg-seed0.json --suite lecture":
        ("pendulum-lqg score --agent linear:runs/sysid/sysid-lqg-seed0.json --suite lecture "
         "--episodes 4", "100 episodes: 4"),
    "pendulum-lqg train sysid-lqg --seed 0 --suite delayed --out runs/delayed":
        ("pendulum-lqg train sysid-lqg --seed 0 --suite delayed --steps 20000 --out runs/delayed",
         "the default recipe logs about 70 000 steps: a budget of 20 000"),
    "pendulum-lqg train ars-history --seed 0 --out runs/linear":
        ("pendulum-lqg train ars-history --seed 0 --steps 400 --eval-every 200 --out runs/linear",
         "a training run of 300 000 env steps: 400"),
    "pendulum-lqg train sysid-openloop --seed 0 --out runs/linear":
        ("pendulum-lqg train sysid-openloop --seed 0 --steps 5000 --out runs/linear",
         "1 000 000 logged steps: 5 000"),
    "uv run pendulum-lqg train ars-history --plant double-cartpole --out runs/double":
        ("pendulum-lqg train ars-history --plant double-cartpole --steps 2000 --eval-every 1000 "
         "--out runs/double", "a training run of 200 000 env steps: 2 000"),
    "pendulum-lqg train ls-clone --seed 0 --out runs/clone":
        ("pendulum-lqg train ls-clone --seed 0 --steps 2000 --out runs/clone",
         "20 000 closed-loop samples of the fit: 2 000 (the identification it clones runs whole)"),
    "pendulum-lqg train ars-history-clone --seed 0 --init runs/clone/ls-clone-seed0.json --out runs/clone":
        ("pendulum-lqg train ars-history-clone --seed 0 --init runs/clone/ls-clone-seed0.json "
         "--steps 400 --eval-every 200 --out runs/clone", "a training run of 300 000 env steps: 400"),
    "uv run python -m pendulum_lqg.learn.price run --out docs/leaderboard/price.csv --force":
        ("python -m pendulum_lqg.learn.price run --suites lecture --seeds 0 --budgets 5000 "
         "--out price.csv", "80 identifications of up to 500 000 steps: one of 5 000, into the "
         "scratch folder (the figure below reads the committed CSV)"),
}
#: commands that need the ``rl`` extra (torch, stable-baselines3): documented command → the
#: reduced form run where torch is installed (skipped, with this reason, where it is not)
NEEDS_RL: dict[str, str] = {
    "python -m pendulum_lqg.learn.noise_ladder score experiments/agents/models/ppo-history-seed*.zip --scores docs/leaderboard/noise_ladder --force":  # noqa: E501 (a documented line, as the page shows it)
        "python -m pendulum_lqg.learn.noise_ladder score experiments/agents/models/ppo-history-seed0.zip "
        "--episodes 2 --scores scores/ladder --force",
    "python -m pendulum_lqg.learn.noise_ladder score --matched experiments/agents/models/ppo-history-noise*-seed*.zip --scores docs/leaderboard/noise_ladder --force":  # noqa: E501 (a documented line, as the page shows it)
        "python -m pendulum_lqg.learn.noise_ladder score --matched "
        "experiments/agents/models/ppo-history-noise0.25-seed0.zip --episodes 2 --scores scores/ladder "
        "--force",
    "pendulum-lqg train ppo-history --seed 3 --out runs/ppo-history-seed3":
        "pendulum-lqg train ppo-history --seed 3 --steps 256 --eval-every 128 --out runs/ppo-history-seed3",
    "pendulum-lqg train ppo-history --seed 3 --steps 4000 --eval-every 2000":
        "pendulum-lqg train ppo-history --seed 3 --steps 256 --eval-every 128",
    "pendulum-lqg train ppo-history --seed 0 --noise-scale 0.25 --out runs/ladder":
        "pendulum-lqg train ppo-history --seed 0 --noise-scale 0.25 --steps 256 --eval-every 128 "
        "--out runs/ladder",
    "pendulum-lqg score --agent sb3:experiments/agents/models/ppo-history-seed3.zip --suite all --out rl_ppo-history-seed3.json":  # noqa: E501 (a documented line, as the page shows it)
        "pendulum-lqg score --agent sb3:experiments/agents/models/ppo-history-seed3.zip --suite lecture "
        "--episodes 2 --out rl_ppo-history-seed3.json",
    "uv run pendulum-lqg score --agent sb3:experiments/agents/models/ppo-history-seed0.zip --suite lecture":
        "pendulum-lqg score --agent sb3:experiments/agents/models/ppo-history-seed0.zip --suite lecture "
        "--episodes 2",
}
_INSTALL = "installs into the environment the tests run in (CI installs the wheel in a fresh one)"
_PERF_OLD = ("performance.md's comparison with 0.4.1 and 0.3.4, run on git worktrees of those "
             "versions (their own environments); each of this version's commands in it is run "
             "below in its own block")
#: documented command → why the test does not run it
#: docs/architecture.md's count of an import (the validation library's choice)
_VALGRIND = "PYTHONHASHSEED=0 valgrind --tool=callgrind --callgrind-out-file=/dev/null /tmp/pv/bin/python"

NOT_RUN: dict[str, str] = {
    **dict.fromkeys(["uv run python benchmarks/instructions.py env --public",
                     "uv run python benchmarks/instructions.py vector",
                     "uv run python benchmarks/instructions.py loop"],
                    "an instruction count under valgrind, whose start-up alone costs tens of "
                    "seconds: `instructions.py env --steps 20` runs the script's valgrind path; "
                    "these change only the workload it counts"),
    **dict.fromkeys([
        "uv venv /tmp/pv && VIRTUAL_ENV=/tmp/pv uv pip install --compile-bytecode pydantic msgspec",
        *(f"{_VALGRIND} -c \"{code}\"" for code in (
            "pass", "from msgspec import Struct, Meta, convert",
            "from pydantic import BaseModel, Field, TypeAdapter"))],
        "the library choice's measurement: a scratch environment with pydantic, which the project "
        "does not depend on, downloaded from the package index"),
    "uv sync --compile-bytecode": _INSTALL,
    "uv sync --group docs": _INSTALL,
    "uv build --wheel": "builds the wheel into dist/ of the checkout (CI's package job builds it)",
    "pip install dist/*.whl": _INSTALL,
    "pip install 'dist/pendulum_lqg-0.5.0-py3-none-any.whl[ray]'": _INSTALL,
    "pip install 'dist/pendulum_lqg-0.5.0-py3-none-any.whl[rl]'": _INSTALL,
    "pip install torch --index-url https://download.pytorch.org/whl/cpu": _INSTALL + " (from an index)",
    "uv pip install torch --index-url https://download.pytorch.org/whl/cpu": _INSTALL + " (from an index)",
    "uv pip install stable-baselines3 sb3-contrib": _INSTALL + " (from an index)",
    "uv run pytest": "the test suite itself",
    "uv run --group docs sphinx-build -W -b html docs docs/_build/html":
        "builds the whole site (CI's docs job); the tutorials it executes run in test_notebooks.py",
    "cd pendulum_lqg": "the reader's checkout",
    "cd any/folder": "the reader's own folder (the commands after it run in the page's scratch folder)",
    "uv run --with jupyterlab --with jupytext jupyter lab docs/tutorials/":
        "starts a Jupyter server; test_notebooks.py checks that it loads jupytext, that jupytext "
        "reads each tutorial as a notebook, and runs every tutorial",
    "uv run rerun --web-viewer luenberger.rrd": "starts the Rerun web viewer (a server)",
    "uv run rerun luenberger.rrd": "opens the Rerun viewer (a window)",
    "uv run --extra ray pendulum-lqg bench lecture --executor ray":
        "starts a local Ray instance; tests/bench/test_executors_ray.py runs bench --executor ray on one",
    "ray start --head --port 6379": "starts a Ray cluster's head (a server)",
    "ray start --address HEAD_HOST:6379": "joins a Ray cluster on another machine",
    "pendulum-lqg bench mismatch --executor ray --address auto": "needs a running Ray cluster",
    "uv run python benchmarks/leaderboard.py --out docs/leaderboard --force":
        "rescores the committed leaderboard (18 entries × 7 suites × 100 episodes) and has no "
        "budget option; it calls score_entry, which the score commands of the same page run",
    "python benchmarks/leaderboard.py --rl --out docs/leaderboard --force":
        "rescores every committed RL model (the rl extra; 7 suites × 100 episodes each) and has "
        "no budget option; score --agent sb3:… runs the same scoring (NEEDS_RL)",
    "uv run python benchmarks/instructions.py env --tree ../v034": _PERF_OLD,
    **dict.fromkeys([
        "git worktree add ../v041 34aa814 && git worktree add ../v034 00f1037",
        "(cd ../v041 && uv sync --locked --compile-bytecode); (cd ../v034 && uv sync --locked "
        "--compile-bytecode)",
        "for t in . ../v041 ../v034; do for k in env vector loop; do",
        "uv run python benchmarks/instructions.py $k --tree $t; done; done",
        "for r in 1 2 3; do for t in . ../v041 ../v034; do",
        '(cd $t && .venv/bin/python -m pendulum_lqg.cli perf --repeats 3 | grep "ratio closed"); '
        "done; done",
        "for r in 1 2 3; do",
        '.venv/bin/python benchmarks/env_benchmark.py --repeats 3 | grep "ratio:"',
        '(cd ../v041 && .venv/bin/python benchmarks/env_benchmark.py --repeats 3 | grep "ratio:")',
        "(cd ../v034 && PYTHONPATH=. .venv/bin/python experiments/env_benchmark.py --repeats 3 | "
        'grep "ratio:")',
        "done",
        '.venv/bin/python benchmarks/vector_benchmark.py --repeats 3 | grep "native / bare"',
        "(cd ../v041 && .venv/bin/python benchmarks/vector_benchmark.py --repeats 3 | grep "
        '"native / bare")',
        "(cd ../v034 && PYTHONPATH=. .venv/bin/python experiments/vector_benchmark.py --repeats 3 | "
        'grep "native / bare")',
        "for t in . ../v041 ../v034; do for r in 1 2 3; do",
        '(cd $t && /usr/bin/time -f "%e s import" .venv/bin/python -c "import pendulum_lqg.policy")',
        '(cd $t && /usr/bin/time -f "%e s design" .venv/bin/python -m pendulum_lqg.cli design '
        ">/dev/null)",
        "done; done",
        '.venv/bin/python -X importtime -c "import pendulum_lqg.cli" 2>&1 | grep -E '
        '"control|cvxpy|scipy.signal|matplotlib"',
    ], _PERF_OLD),
    'uv run pytest -q | tail -1; uv run pytest -q -m "not slow" | tail -1': "the test suite itself, timed",
}
#: grid axes, episodes and duration of a reduced experiment (:func:`reduced_experiment`); a study's
#: own table, or a grid that must keep a value, is cut here, by experiment and table
#: the score files of ``reduced/scores``: the reference and two runs of two methods
REDUCED_SCORES = ("dlqr+kalman.json", "rl_ppo-history-seed0.json", "rl_ppo-history-seed1.json",
                  "rl_ars-history-seed0.json", "rl_ars-history-seed1.json")
REDUCED_GRID_VALUES = 2
REDUCED_EPISODES = 2
REDUCED_DURATION_S = 1.0
REDUCED_TABLES = {"margins": {"margins": {"q": [1.0, 10.0], "n_omega": 200, "nyquist_points": 20}},
                  "roa": {"roa": {"map_theta": [-1.2, 1.2, 3], "map_theta_dot": [-3.0, 3.0, 3],
                                  "tolerance": 0.3}},
                  # the report draws each scale against the other at 1: the nominal plant stays
                  "mismatch": {"grid": {"pole_mass_scale": [1.0, 2.0], "pole_length_scale": [1.0, 2.0]}}}


@dataclass(frozen=True)
class Block:
    page: Path
    line: int
    lang: str
    marker: str
    body: str
    next_lang: str
    next_body: str
    #: the sentence between this block and the next, when it is short
    gap: str

    @property
    def where(self) -> str:
        return f"{self.page.relative_to(ROOT)}:{self.line}"


def _blocks(page: Path) -> list[Block]:
    text = page.read_text(encoding="utf-8")
    found = list(FENCE.finditer(text))
    out = []
    for i, m in enumerate(found):
        nxt = found[i + 1] if i + 1 < len(found) else None
        gap = text[m.end():nxt.start()].strip() if nxt else ""
        # "the next block" only if nothing but a short sentence ("prints", "On this machine:")
        close = nxt is not None and not nxt.group("marker") and (
            len(gap) <= 80 or (len(gap) <= 400 and gap.endswith(":")))
        out.append(Block(page=page, line=text.count("\n", 0, m.start("lang")) + 1,
                         lang=m.group("lang").strip(), marker=(m.group("marker") or "").strip(),
                         body=m.group("body"), next_lang=nxt.group("lang").strip() if close else "",
                         next_body=nxt.group("body") if close else "", gap=gap if close else ""))
    return out


BLOCKS = [b for page in PAGES for b in _blocks(page)]


@dataclass(frozen=True)
class Command:
    """One documented command line: where it is, its text (the key of the tables) and, when the
    test runs it, the argv it runs."""

    page: str
    where: str
    text: str
    comment: str
    #: the ``text`` block that the page says this command prints (the last line of its block)
    shows: str

    @property
    def readme(self) -> bool:
        return self.page == "README.md"

    @property
    def run_as(self) -> str | None:
        """The command line the test runs, or None when it is not run here."""
        if self.text in NOT_RUN:
            return None
        if self.text in NEEDS_RL:
            return NEEDS_RL[self.text] if HAS_TORCH else None
        if self.text in REDUCED:
            return REDUCED[self.text][0]
        return None if TRAINING.match(UV_RUN.sub("", self.text)) else self.text

    @property
    def kind(self) -> str:
        """``cli`` (pendulum-lqg), ``python``, ``cp``, or ``?`` (no rule runs it)."""
        return _kind(self.run_as or self.text)[0]


def _words(line: str) -> list[str]:
    try:
        return shlex.split(line, comments=True)
    except ValueError:
        return line.split()


def _kind(text: str) -> tuple[str, list[str], str | None]:
    """``(kind, argv, stdout file)`` of a command line: ``pendulum-lqg ARGS`` → ``("cli", ARGS)``,
    ``python ARGS`` → ``("python", ARGS)``, ``cp A B`` → ``("cp", [A, B])``; a ``> FILE`` at the
    end is where its output goes. Anything else (pipes, loops, other programs): ``("?", …)``."""
    words = _words(UV_RUN.sub("", text))
    redirect = None
    if len(words) >= 2 and words[-2] == ">":
        words, redirect = words[:-2], words[-1]
    if any(w in SHELL_OPERATORS for w in words) or not words:
        return "?", words, redirect
    if words[0] == "pendulum-lqg":
        return "cli", words[1:], redirect
    if words[0] == "python":
        return "python", words[1:], redirect
    if words[0] == "cp" and len(words) == 3:
        return "cp", words[1:], redirect
    return "?", words, redirect


def _commands() -> list[Command]:
    out = []
    for block in BLOCKS:
        if block.lang not in SHELL_LANGS:
            continue
        lines = [(offset, raw.strip()) for offset, raw in enumerate(block.body.splitlines(), 1)]
        lines = [(o, line[2:].strip() if line.startswith("$ ") else line) for o, line in lines]
        lines = [(o, line) for o, line in lines if _words(line)]
        for i, (offset, line) in enumerate(lines):
            m = re.search(r"\s+#(?:\s+(.*))?$", line)
            last = i == len(lines) - 1
            out.append(Command(page=str(block.page.relative_to(ROOT)),
                               where=f"{block.page.relative_to(ROOT)}:{block.line + offset}",
                               text=" ".join(line[:m.start()].split() if m else line.split()),
                               comment=(m.group(1) or "") if m else "",
                               shows=block.next_body if last and block.next_lang == "text" else ""))
    return out


COMMANDS = _commands()
CLI_COMMANDS = [c for c in COMMANDS if _kind(c.text)[0] == "cli"]
(GYM_AGENT,) = [c for c in COMMANDS if "experiments/gym_lqg_agent.py" in c.text]


def _is_short(cmd: Command) -> bool:
    kind, argv, _ = _kind(cmd.run_as or "")
    if kind == "cp" or cmd.run_as is None:
        return True
    if kind != "cli":
        return False
    if not argv or "--help" in argv or "-h" in argv or "--version" in argv or argv[0] == "design":
        return True
    if argv[0] == "run" and "--episodes" in argv and "--duration" not in argv:
        return int(argv[argv.index("--episodes") + 1]) <= 4
    return False


def _quick(cmd: Command) -> bool:
    """README's commands, and a command whose page runs only short ones up to it."""
    if cmd.readme:
        return True
    page = [c for c in COMMANDS if c.page == cmd.page]
    return all(_is_short(c) for c in page[:page.index(cmd) + 1])


def _skip_reason(cmd: Command) -> str | None:
    if cmd.text in NOT_RUN:
        return f"not run: {NOT_RUN[cmd.text]}"
    if cmd.run_as is None and cmd.text not in NEEDS_RL:
        return "a training run without a reduced form: see test_every_documented_command_is_run_or_listed"
    if cmd.text in NEEDS_RL and not HAS_TORCH:
        return "needs the rl extra (torch is not installed)"
    return None


def _param(cmd: Command):
    marks = [] if _quick(cmd) else [pytest.mark.slow]
    if (reason := _skip_reason(cmd)) is not None:
        marks.append(pytest.mark.skip(reason=reason))
    return pytest.param(cmd, id=f"{cmd.where} {cmd.text}", marks=marks)


# ---- the tables --------------------------------------------------------------------------------------
def test_the_pages_have_commands_and_examples():
    assert len(COMMANDS) >= 100, [c.text for c in COMMANDS]
    assert any(b.marker == "test" for b in BLOCKS if b.page.name == "README.md")
    assert {"design", "run", "bench", "score", "board", "report", "theory"} <= {
        _kind(c.run_as)[1][0] for c in COMMANDS if c.run_as and c.kind == "cli" and _kind(c.run_as)[1]}


def test_every_documented_command_is_run_or_listed():
    """A documented command runs (as written, reduced, or with the rl extra) or is in NOT_RUN with
    its reason; every entry of the tables is a command some page shows."""
    unknown = [f"{c.where}: {c.text}" for c in COMMANDS
               if c.text not in NOT_RUN and _kind(c.run_as or c.text)[0] == "?"]
    assert not unknown, ("documented commands that are neither run nor listed in NOT_RUN "
                         f"(add a rule, a REDUCED form or a NOT_RUN reason): {unknown}")
    training = [f"{c.where}: {c.text}" for c in COMMANDS if TRAINING.match(UV_RUN.sub("", c.text))
                and c.text not in REDUCED and c.text not in NEEDS_RL and c.text not in NOT_RUN]
    assert not training, ("training commands run as written (give each a tiny budget in REDUCED, "
                          f"or in NEEDS_RL when it needs torch): {training}")
    shown = {c.text for c in COMMANDS}
    stale = sorted((set(REDUCED) | set(NEEDS_RL) | set(NOT_RUN)) - shown)
    assert not stale, f"table entries that no page shows any more: {stale}"
    both = (set(REDUCED) & set(NOT_RUN)) | (set(NEEDS_RL) & (set(REDUCED) | set(NOT_RUN)))
    assert not both, f"in two tables: {both}"
    for text, reduced in [*((t, r) for t, (r, _) in REDUCED.items()), *NEEDS_RL.items()]:
        assert _kind(reduced)[0] in ("cli", "python"), f"{text!r} → {reduced!r} cannot run"


def test_a_command_whose_output_is_shown_runs_as_written():
    """The output a page prints can be compared only with the command it shows."""
    reduced = [c.where for c in COMMANDS if c.shows and c.text in REDUCED]
    assert not reduced, f"a page shows the output of a command the test reduces: {reduced}"


def test_every_experiment_script_is_documented_and_run():
    """Each ``experiments/*.py`` is run by a documented command: a script, or a plug-in loaded by
    ``--policy`` / ``--agent``."""
    run = " ".join(c.run_as for c in COMMANDS if c.run_as)
    missing = [p.name for p in sorted((ROOT / "experiments").glob("*.py"))
               if f"experiments/{p.name}" not in run]
    assert not missing, f"experiments/ scripts that no documented command runs: {missing}"


@pytest.mark.parametrize("cmd", [pytest.param(c, id=f"{c.where} {c.text}") for c in CLI_COMMANDS])
def test_every_command_parses(cmd, capsys):
    """Each documented ``pendulum-lqg`` line is accepted by the parser (flags exist, values convert)."""
    from pendulum_lqg.cli import build_parser

    try:
        build_parser().parse_args(_kind(cmd.text)[1])
    except SystemExit as exc:           # --help and --version exit 0; a parse error exits 2
        assert exc.code == 0, f"{cmd.where}: {cmd.text!r} is refused: {capsys.readouterr().err}"


def test_every_option_of_every_subcommand_is_documented():
    """Each option of each subcommand (``pendulum-lqg SUB --help``) appears in the README or docs."""
    import argparse

    from pendulum_lqg.cli import build_parser

    text = "\n".join(p.read_text(encoding="utf-8") for p in PAGES)
    parser = build_parser()
    subparsers = next(a for a in parser._actions if isinstance(a, argparse._SubParsersAction))
    documented = {_kind(c.text)[1][0] for c in CLI_COMMANDS if _kind(c.text)[1]}
    assert set(subparsers.choices) <= documented, \
        f"subcommands without a documented command: {set(subparsers.choices) - documented}"
    missing = [f"{name} {opt}" for name, sub in subparsers.choices.items()
               for action in sub._actions for opt in action.option_strings
               if opt.startswith("--") and opt != "--help" and f"`{opt}" not in text
               and f" {opt}" not in text]
    assert not missing, f"options not documented: {missing}"


# ---- the scratch folders -----------------------------------------------------------------------------
def reduced_experiment(name: str) -> dict:
    """``experiments/NAME.toml`` cut to a test's budget: :data:`REDUCED_EPISODES` episodes of
    :data:`REDUCED_DURATION_S` s, the first :data:`REDUCED_GRID_VALUES` values of each grid axis,
    and a table's values replaced as :data:`REDUCED_TABLES` says; the name (and so the results folder)
    unchanged, a relative plant file made absolute."""
    doc = tomllib.loads((ROOT / "experiments" / f"{name}.toml").read_text(encoding="utf-8"))
    doc["episodes"] = REDUCED_EPISODES
    for key in ("lti_file", "plant"):           # a plant file (a shipped NAME has no suffix)
        if key in doc and Path(doc[key]).suffix:
            doc[key] = str(ROOT / "experiments" / doc[key])
    if "study" not in doc:
        doc.setdefault("scenario", {})["duration"] = REDUCED_DURATION_S
    doc["grid"] = {k: v[:REDUCED_GRID_VALUES] for k, v in doc.get("grid", {}).items()}
    for table, values in REDUCED_TABLES.get(name, {}).items():
        doc[table].update(values)
    return doc


def _toml(doc: dict) -> str:
    """A TOML file of scalars, arrays and one level of tables (JSON's literals are TOML's)."""
    def value(v) -> str:
        if isinstance(v, float) and v in (float("inf"), -float("inf")):
            return "inf" if v > 0 else "-inf"
        if isinstance(v, list):
            return "[" + ", ".join(value(x) for x in v) + "]"
        return json.dumps(v)
    top = [f"{k} = {value(v)}" for k, v in doc.items() if not isinstance(v, dict)]
    tables = [f"\n[{k}]\n" + "\n".join(f"{kk} = {value(vv)}" for kk, vv in v.items())
              for k, v in doc.items() if isinstance(v, dict)]
    return "\n".join(top) + "\n" + "\n".join(tables) + "\n"


@pytest.fixture(scope="module")
def snapshot(tmp_path_factory) -> Path:
    """A copy of the checkout's folders that the commands read, and that scripts writing next to
    themselves (``benchmarks/*.py``, ``docs/leaderboard/*.py``) write into; the reduced
    experiments in ``reduced/``."""
    snap = tmp_path_factory.mktemp("checkout")
    skip = shutil.ignore_patterns("__pycache__", "_build")
    for name in ("experiments", "models", "benchmarks", "docs/leaderboard"):
        shutil.copytree(ROOT / name, snap / name, ignore=skip)
    (snap / "reduced").mkdir()
    names = {Path(_kind(r)[1][1]).stem for r, _ in REDUCED.values()
             if _kind(r)[1][:1] == ["bench"] and _kind(r)[1][1].startswith("reduced/")}
    for name in names:
        (snap / "reduced" / f"{name}.toml").write_text(_toml(reduced_experiment(name)),
                                                       encoding="utf-8")
    (snap / "reduced" / "scores").mkdir()
    for name in REDUCED_SCORES:
        shutil.copy(ROOT / "docs" / "leaderboard" / "scores" / name, snap / "reduced" / "scores")
    return snap


def _page_folder(page: str, snapshot: Path, root: Path) -> Path:
    """The scratch folder of one page: links to the snapshot, and the files the page tells the
    reader to save (``<!-- file: NAME -->``)."""
    work = root / re.sub(r"\W", "_", page)
    work.mkdir()
    for name in ("experiments", "models", "benchmarks", "docs", "reduced"):
        (work / name).symlink_to(snapshot / name, target_is_directory=True)
    for block in BLOCKS:
        if str(block.page.relative_to(ROOT)) == page and block.marker.startswith("file:"):
            (work / block.marker.split(":", 1)[1].strip()).write_text(block.body, encoding="utf-8")
    return work


def _run_in_process(argv: list[str], cwd: Path) -> subprocess.CompletedProcess:
    """``pendulum-lqg ARGV`` run in ``cwd`` by the console script's function, in this process,
    with its exit status, stdout and stderr as a subprocess would give them."""
    import contextlib
    import io

    from pendulum_lqg.cli import main

    out, err = io.StringIO(), io.StringIO()
    with pytest.MonkeyPatch.context() as mp, contextlib.redirect_stdout(out), \
            contextlib.redirect_stderr(err):
        mp.chdir(cwd)
        mp.setenv("COLUMNS", "120")
        try:
            status = main(list(argv))
        except SystemExit as exc:             # --help and --version exit through argparse
            status = exc.code if isinstance(exc.code, int) else 0 if exc.code is None else 2
        except Exception:                     # a traceback: this command's test fails, not all
            import traceback

            err.write(traceback.format_exc())
            status = 1
    return subprocess.CompletedProcess(["pendulum-lqg", *argv], status, out.getvalue(),
                                       err.getvalue())


def _run(argv, cwd: Path) -> subprocess.CompletedProcess:
    env = {**os.environ, "COLUMNS": "120", "MUJOCO_GL": os.environ.get("MUJOCO_GL", "egl")}
    try:
        return subprocess.run(argv, cwd=cwd, capture_output=True, text=True, timeout=TIMEOUT_S,
                              env=env)
    except subprocess.TimeoutExpired as exc:    # this command's test fails, not all
        return subprocess.CompletedProcess(argv, -9, str(exc.stdout), f"timed out: {exc}")


def run_command(text: str, cwd: Path) -> subprocess.CompletedProcess:
    """Run one command line (:func:`_kind`) in ``cwd``; a ``> FILE`` gets its stdout."""
    kind, argv, redirect = _kind(text)
    if kind == "cli":
        proc = _run_in_process(argv, cwd)
    elif kind == "python":
        proc = _run([sys.executable, *argv], cwd)
    elif kind == "cp":
        shutil.copy(cwd / argv[0], cwd / argv[1])
        proc = subprocess.CompletedProcess(["cp", *argv], 0, "", "")
    else:
        raise AssertionError(f"no rule runs {text!r}")
    if redirect is not None:
        (cwd / redirect).write_text(proc.stdout, encoding="utf-8")
    return proc


def _selected(request, test_name: str, param: str) -> list:
    """The parameters ``param`` of the tests ``test_name`` that this session runs (after ``-m`` /
    ``-k`` selection), in order."""
    return [item.callspec.params[param] for item in request.session.items
            if getattr(item, "originalname", None) == test_name and hasattr(item, "callspec")]


@pytest.fixture(scope="module")
def git_status_before() -> str:
    return _git_status()


def _git_status() -> str:
    return subprocess.run(["git", "status", "--porcelain", "--untracked-files=all"], cwd=ROOT,
                          capture_output=True, text=True, check=True).stdout


@pytest.fixture(scope="module")
def command_runs(request, snapshot, tmp_path_factory, git_status_before) -> dict:
    """Each page's commands, up to its last selected one, in order, in the page's scratch
    folder: ``where → (CompletedProcess, start time)``."""
    selected = _selected(request, "test_documented_command", "cmd")
    if any(getattr(item, "originalname", None) == "test_documented_example_gym_lqg_agent_runs"
           for item in request.session.items):
        selected.append(GYM_AGENT)
    root = tmp_path_factory.mktemp("pages")
    runs: dict = {}
    for page in dict.fromkeys(c.page for c in selected):
        on_page = [c for c in COMMANDS if c.page == page]
        last = max(on_page.index(c) for c in selected if c.page == page)
        work = _page_folder(page, snapshot, root)
        done: dict[str, tuple] = {}          # a command the page shows twice runs once
        for cmd in on_page[:last + 1]:
            if cmd.run_as is not None and cmd.run_as not in done:
                start = time.time()
                done[cmd.run_as] = (run_command(cmd.run_as, work), start, work)
            if cmd.run_as is not None:
                runs[cmd.where] = done[cmd.run_as]
    return runs


#: A number written as d.de-NN with NN ≥ 10: a rounding residue (the separation principle's
#: eigenvalue mismatch, say), whose digits depend on the machine's BLAS kernels, not on the code.
ROUNDOFF = re.compile(r"\b\d(?:\.\d+)?e-(?:1\d|[2-9]\d)\b")


def _lines(text: str) -> list[str]:
    """Lines without trailing blanks, with a model file's folder dropped (it is the machine's) and
    rounding residues written as one token (floats from another machine are not compared bit
    for bit; a residue must still be one, below 1e-9)."""
    return [ROUNDOFF.sub("<roundoff>", re.sub(r"\S*/models/", "models/", line.rstrip()))
            for line in text.splitlines() if line.strip()]


def _check_output(cmd: Command, proc: subprocess.CompletedProcess) -> None:
    argv = _kind(cmd.run_as or "")[1]
    out = proc.stdout
    if cmd.shows:                          # every line the page shows, in order
        got = iter(_lines(out))
        missing = [line for line in _lines(cmd.shows) if not any(g == line for g in got)]
        assert not missing, f"{cmd.where}: the page shows lines it does not print: {missing}\n{out}"
    if cmd.kind == "cli" and argv:
        if "--version" in argv:
            import pendulum_lqg

            assert out.strip() == f"pendulum-lqg {pendulum_lqg.__version__}"
        elif "--help" in argv or "-h" in argv:
            assert out.startswith("usage: pendulum-lqg"), out
        elif argv[0] == "design" and _plant_file(argv):     # a plant file's plant
            if "--json" in argv:
                d = json.loads(out)
                assert len(d["K_dlqr"]) == len(d["inputs"])
                assert len(d["K_dlqr"][0]) == len(d["states"])
            else:
                assert "Discrete LQR" in out and "Separation principle" in out, out
        elif argv[0] == "design" and "--json" in argv:
            K = json.loads(out)["K_dlqr"]
            assert len(K) == 1 and len(K[0]) == 4 and all(abs(k) > 0 for k in K[0])
        elif argv[0] == "design":
            m = re.search(r"Discrete LQR.*?\n\s*\[([^\]]+)\]", out, re.S)
            assert m is not None, out
            gain = [float(v) for v in m.group(1).split()]
            assert len(gain) == 4 and gain[1] < -1.0, gain     # θ gain: push towards the fall
        elif argv[0] == "run" and "--json" in argv:
            n = int(argv[argv.index("--episodes") + 1])
            doc = json.loads(out)
            assert len(doc["episodes"]) == n and 0.0 <= doc["success_rate"] <= 1.0
            assert all(r["cost"] > 0 for r in doc["episodes"])
        elif argv[0] == "run" and not _plant_file(argv):
            n = int(argv[argv.index("--episodes") + 1]) if "--episodes" in argv else 100
            m = re.search(r"success: (\d+)/(\d+) = ", out)
            assert m is not None and int(m.group(2)) == n, out
        else:
            assert out.strip() or proc.stderr.strip(), f"{cmd.where}: prints nothing to check"
    elif cmd.kind == "python" and "-c" not in argv:
        assert out.strip() or proc.stderr.strip(), f"{cmd.where}: prints nothing to check"


def _plant_file(argv: list[str]) -> bool:
    """The command plays a plant other than the cart-pole (``--plant NAME|FILE``, ``--lti``)."""
    for flag in ("--plant", "--lti"):
        if flag in argv and argv[argv.index(flag) + 1] not in ("cartpole",):
            return True
    return False


@pytest.mark.parametrize("cmd", [_param(c) for c in COMMANDS])
def test_documented_command(cmd, command_runs):
    """The command (or its reduced form) exits 0, prints what the page shows, and writes the
    file its comment names after ``→``."""
    proc, start, work = command_runs[cmd.where]
    assert proc.returncode == 0, (f"{cmd.where}: {cmd.run_as!r} exited {proc.returncode}:\n"
                                  f"{proc.stdout[-2000:]}\n{proc.stderr[-4000:]}")
    _check_output(cmd, proc)
    if cmd.text not in REDUCED and (m := re.search(r"→\s*(\.?/?[\w./-]+/[\w.-]+)", cmd.comment)):
        path = work / m.group(1).removeprefix("./")
        assert path.exists() and path.stat().st_mtime >= start - 1, \
            f"{cmd.where}: {path} was not written"


def test_documented_example_gym_lqg_agent_runs(command_runs):
    """``experiments/gym_lqg_agent.py`` (docs/gymnasium.md) runs as written and prints exactly the
    page's output: the Gymnasium loop's episodes are the benchmark's."""
    assert GYM_AGENT.shows and GYM_AGENT.run_as == GYM_AGENT.text
    proc = command_runs[GYM_AGENT.where][0]
    assert proc.returncode == 0, proc.stderr
    assert _lines(proc.stdout) == _lines(GYM_AGENT.shows)
    assert proc.stdout.rstrip().endswith("identical episode by episode: True")


def test_the_commands_leave_the_checkout_as_it_was(command_runs, git_status_before):
    """Whatever the commands wrote, they wrote into the scratch folders (the last test of the
    module: the fixtures have run every selected command)."""
    assert _git_status() == git_status_before


# ---- the Python examples -------------------------------------------------------------------------------
EXAMPLES = [b for b in BLOCKS if b.lang == "python" and b.marker == "test"]


@pytest.fixture(scope="module")
def example_runs(request, tmp_path_factory) -> dict:
    """The selected examples, each run as a script in a scratch folder of its own (two at a
    time), by page and line."""
    from concurrent.futures import ThreadPoolExecutor

    jobs = {}
    for block in _selected(request, "test_python_examples_run_and_print_what_the_page_says",
                           "block"):
        folder = tmp_path_factory.mktemp("example")
        script = folder / "example.py"
        script.write_text(block.body, encoding="utf-8")
        jobs[block.where] = ([sys.executable, str(script)], folder)
    with ThreadPoolExecutor(max_workers=2) as pool:
        futures = {key: pool.submit(_run, argv, cwd) for key, (argv, cwd) in jobs.items()}
        return {key: f.result() for key, f in futures.items()}


@pytest.mark.parametrize("block", [
    pytest.param(b, id=b.where, marks=() if b.page.name == "README.md" else pytest.mark.slow)
    for b in EXAMPLES])
def test_python_examples_run_and_print_what_the_page_says(block, example_runs):
    proc = example_runs[block.where]
    assert proc.returncode == 0, f"{block.where}:\n{proc.stderr}"
    if block.next_lang == "text":
        assert proc.stdout.strip() == block.next_body.strip(), f"{block.where}: printed\n{proc.stdout}"
    else:
        assert proc.stdout.strip(), f"{block.where}: prints nothing to check"
