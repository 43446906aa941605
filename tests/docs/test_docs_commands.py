"""The commands and examples of README.md and docs/*.md run as written.

What is collected, from the fenced blocks of README.md and docs/*.md:

* every line of a ```` ```bash ```` / ```` ```console ```` block that calls ``pendulum-lqg``
  (``uv run pendulum-lqg …``, ``uv run --extra ray pendulum-lqg …`` or the bare console script;
  a ``$`` prompt, a trailing ``# comment`` and a shell redirection or pipe are dropped). Each is
  parsed by the command's own argument parser, so a flag that does not exist (``design --theta0``)
  fails here. The short ones also run, through the console script's own function
  (``pendulum_lqg.cli.main``, in this process: a subprocess would add only an interpreter's
  start-up, which ``tests/envs/test_envs.py`` and CI's smoke run test with the real console
  script) in a scratch folder: ``design``, ``--help`` / ``--version``, and ``run`` with
  ``--episodes`` ≤ 4; the test checks the exit status and a value in the output (the DLQR gain,
  the success count);
* a ```` ```python ```` block preceded by ``<!-- test -->`` runs as a script in a scratch folder;
  when the next fenced block is ```` ```text ```` (what the page says it prints), its output must
  equal that block;
* a ```` ```python ```` block preceded by ``<!-- file: NAME -->`` is a file the page tells the
  reader to save (a plug-in): it is written as ``NAME`` into the scratch folder of the commands,
  as are the files of ``cp SRC DST`` lines, and the repository's ``experiments/`` and ``models/``
  folders are linked there, so that a command naming them finds them.

README's commands and examples, the plain ``design``, ``--help`` and ``--version`` are the quick set
; the other pages' commands and examples are marked ``slow``. The selected commands run one
after the other and the examples two at a time, once per session (module fixtures), and each test
checks its own.
"""

from __future__ import annotations

import json
import os
import re
import shlex
import shutil
import subprocess
import sys
from dataclasses import dataclass
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[2]
PAGES = [ROOT / "README.md", *sorted((ROOT / "docs").glob("*.md"))]
#: a fenced block, with the HTML comment on the line before it (if any)
FENCE = re.compile(r"(?:^<!--\s*(?P<marker>[^>]*?)\s*-->\n)?^```(?P<lang>[\w-]*)\n(?P<body>.*?)^```\s*$",
                   re.M | re.S)
#: ``uv run [--extra X | --group X …] pendulum-lqg ARGS`` or ``pendulum-lqg ARGS``
COMMAND = re.compile(r"^(?:uv run(?:\s+--(?:extra|group)\s+\S+)*\s+)?pendulum-lqg(?:\s+(?P<args>.*))?$")
SHELL_OPERATORS = {">", ">>", "|", "&&", ";", "2>", "2>&1", "&"}
TIMEOUT_S = 300


@dataclass(frozen=True)
class Block:
    page: Path
    line: int
    lang: str
    marker: str
    body: str
    next_lang: str
    next_body: str

    @property
    def where(self) -> str:
        return f"{self.page.relative_to(ROOT)}:{self.line}"


def _blocks(page: Path) -> list[Block]:
    text = page.read_text(encoding="utf-8")
    found = list(FENCE.finditer(text))
    out = []
    for i, m in enumerate(found):
        nxt = found[i + 1] if i + 1 < len(found) else None
        # "the next block" only if nothing but a short sentence ("prints") lies between them
        gap = text[m.end():nxt.start()] if nxt else ""
        close = nxt is not None and len(gap.strip()) <= 80 and not nxt.group("marker")
        out.append(Block(page=page, line=text.count("\n", 0, m.start("lang")) + 1,
                         lang=m.group("lang"), marker=(m.group("marker") or "").strip(),
                         body=m.group("body"), next_lang=nxt.group("lang") if close else "",
                         next_body=nxt.group("body") if close else ""))
    return out


BLOCKS = [b for page in PAGES for b in _blocks(page)]


@dataclass(frozen=True)
class Command:
    where: str
    text: str
    argv: tuple[str, ...]

    @property
    def readme(self) -> bool:
        return self.where.startswith("README.md")


def _commands() -> list[Command]:
    out = []
    for block in BLOCKS:
        if block.lang not in ("bash", "console"):
            continue
        for offset, raw in enumerate(block.body.splitlines(), start=1):
            line = raw.strip()
            if line.startswith("$ "):
                line = line[2:].strip()
            words = shlex.split(line, comments=True)
            for i, word in enumerate(words):
                if word in SHELL_OPERATORS:
                    words = words[:i]
                    break
            m = COMMAND.match(" ".join(shlex.quote(w) for w in words))
            if m is None:
                continue
            argv = tuple(shlex.split(m.group("args") or ""))
            out.append(Command(f"{block.page.relative_to(ROOT)}:{block.line + offset}",
                               " ".join(words), argv))
    return out


COMMANDS = _commands()


def _is_short(cmd: Command) -> bool:
    argv = cmd.argv
    if not argv or "--help" in argv or "-h" in argv or "--version" in argv:
        return True
    if argv[0] == "design":
        return True
    if argv[0] == "run" and "--episodes" in argv:
        return int(argv[argv.index("--episodes") + 1]) <= 4
    return False


def _unique(commands: list[Command]) -> list[Command]:
    seen: dict[tuple[str, ...], Command] = {}
    for c in commands:                      # README first: its copy decides the speed mark
        seen.setdefault(c.argv, c)
    return list(seen.values())


def _quick(cmd: Command) -> bool:
    """README's commands, the plain ``design``, ``--help`` and ``--version``: the quick set."""
    return cmd.readme or cmd.argv == ("design",) or bool({"--help", "-h", "--version"} & set(cmd.argv))


def _params(commands: list[Command]) -> list:
    return [pytest.param(c, id=f"{c.where} {c.text}", marks=() if _quick(c) else pytest.mark.slow)
            for c in commands]


# ---- the commands -----------------------------------------------------------------------------------
def test_the_pages_have_commands_and_examples():
    assert len(COMMANDS) >= 40, [c.text for c in COMMANDS]
    assert any(b.marker == "test" for b in BLOCKS if b.page.name == "README.md")
    short = {c.argv[0] for c in COMMANDS if c.argv and _is_short(c)}
    assert {"design", "run"} <= short


@pytest.mark.parametrize("cmd", [pytest.param(c, id=f"{c.where} {c.text}") for c in COMMANDS])
def test_every_command_parses(cmd, capsys):
    """Each documented command line is accepted by the parser (flags exist, values convert)."""
    from pendulum_lqg.cli import build_parser

    try:
        build_parser().parse_args(list(cmd.argv))
    except SystemExit as exc:           # --help and --version exit 0; a parse error exits 2
        assert exc.code == 0, f"{cmd.where}: {cmd.text!r} is refused: {capsys.readouterr().err}"


def test_every_option_of_every_subcommand_is_documented():
    """Each option of each subcommand (``pendulum-lqg SUB --help``) appears in the README or docs."""
    import argparse

    from pendulum_lqg.cli import build_parser

    text = "\n".join(p.read_text(encoding="utf-8") for p in PAGES)
    parser = build_parser()
    subparsers = next(a for a in parser._actions if isinstance(a, argparse._SubParsersAction))
    documented = {c.argv[0] for c in COMMANDS if c.argv}
    assert set(subparsers.choices) <= documented, \
        f"subcommands without a documented command: {set(subparsers.choices) - documented}"
    missing = [f"{name} {opt}" for name, sub in subparsers.choices.items()
               for action in sub._actions for opt in action.option_strings
               if opt.startswith("--") and opt != "--help" and f"`{opt}" not in text
               and f" {opt}" not in text]
    assert not missing, f"options not documented: {missing}"


@pytest.fixture(scope="module")
def workdir(tmp_path_factory):
    """A scratch folder holding what the pages tell the reader to create or copy."""
    work = tmp_path_factory.mktemp("docs_commands")
    for name in ("experiments", "models"):
        (work / name).symlink_to(ROOT / name, target_is_directory=True)
    for block in BLOCKS:
        if block.marker.startswith("file:"):
            (work / block.marker.split(":", 1)[1].strip()).write_text(block.body, encoding="utf-8")
        if block.lang == "bash":
            for line in block.body.splitlines():
                words = shlex.split(line, comments=True)
                if len(words) == 3 and words[0] == "cp":
                    shutil.copy(work / words[1], work / words[2])
    return work


def _run_in_process(argv: tuple[str, ...], cwd: Path) -> subprocess.CompletedProcess:
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
    return subprocess.CompletedProcess(["pendulum-lqg", *argv], status, out.getvalue(),
                                       err.getvalue())


def _run(argv, cwd: Path) -> subprocess.CompletedProcess:
    env = {**os.environ, "COLUMNS": "120", "MUJOCO_GL": os.environ.get("MUJOCO_GL", "egl")}
    return subprocess.run(argv, cwd=cwd, capture_output=True, text=True, timeout=TIMEOUT_S, env=env)


def _selected(request, test_name: str, param: str) -> list:
    """The parameters ``param`` of the tests ``test_name`` that this session runs (after ``-m`` /
    ``-k`` selection), in order."""
    return [item.callspec.params[param] for item in request.session.items
            if getattr(item, "originalname", None) == test_name and hasattr(item, "callspec")]


def _run_all(jobs: dict, workers: int = 2) -> dict:
    """``_run(argv, cwd)`` of every job ``key → (argv, cwd)``, ``workers`` at a time. The pages'
    commands are independent processes, most of whose time is Python starting and importing:
    two at once keep both cores of a CI machine busy. Returns ``key → CompletedProcess``."""
    from concurrent.futures import ThreadPoolExecutor

    with ThreadPoolExecutor(max_workers=workers) as pool:
        futures = {key: pool.submit(_run, argv, cwd) for key, (argv, cwd) in jobs.items()}
        return {key: f.result() for key, f in futures.items()}


@pytest.fixture(scope="module")
def short_runs(request, workdir) -> dict:
    """The selected short commands, run in the scratch folder, by argv."""
    cmds = _selected(request, "test_short_commands_run", "cmd")
    return {c.argv: _run_in_process(c.argv, workdir) for c in cmds}


@pytest.mark.parametrize("cmd", _params(_unique([c for c in COMMANDS if _is_short(c)])))
def test_short_commands_run(cmd, short_runs):
    proc = short_runs[cmd.argv]
    out = proc.stdout
    assert proc.returncode == 0, f"{cmd.where}: {cmd.text!r} exited {proc.returncode}:\n{proc.stderr}"
    argv = cmd.argv
    if "--version" in argv:
        import pendulum_lqg

        assert out.strip() == f"pendulum-lqg {pendulum_lqg.__version__}"
    elif not argv or "--help" in argv or "-h" in argv:
        assert out.startswith("usage: pendulum-lqg"), out
    elif argv[0] == "design" and "--lti" in argv:          # a plant given as matrices
        if "--json" in argv:
            d = json.loads(out)
            assert len(d["K_dlqr"]) == len(d["inputs"]) and len(d["K_dlqr"][0]) == len(d["states"])
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
    elif "--json" in argv:                                 # run --episodes N --json
        n = int(argv[argv.index("--episodes") + 1])
        doc = json.loads(out)
        assert len(doc["episodes"]) == n and 0.0 <= doc["success_rate"] <= 1.0
        assert all(r["cost"] > 0 for r in doc["episodes"])
    else:                                                  # run --episodes N
        n = int(argv[argv.index("--episodes") + 1])
        m = re.search(r"success: (\d+)/(\d+) = ", out)
        assert m is not None and int(m.group(2)) == n, out
        assert re.search(r"J = .*?│\s+([-+0-9.e]+|–)", out), out


# ---- the Python examples -------------------------------------------------------------------------------
EXAMPLES = [b for b in BLOCKS if b.lang == "python" and b.marker == "test"]


@pytest.fixture(scope="module")
def example_runs(request, tmp_path_factory) -> dict:
    """The selected examples, each run as a script in a scratch folder of its own (two at a
    time), by page and line."""
    jobs = {}
    for block in _selected(request, "test_python_examples_run_and_print_what_the_page_says",
                           "block"):
        folder = tmp_path_factory.mktemp("example")
        script = folder / "example.py"
        script.write_text(block.body, encoding="utf-8")
        jobs[block.where] = ([sys.executable, str(script)], folder)
    return _run_all(jobs)


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
