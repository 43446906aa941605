"""The shape of the package: no import circle between modules or between packages (function-level
and ``TYPE_CHECKING`` imports included), no private name imported from another module, no file over
600 lines and no function over 60, no private API of MuJoCo or numpy, a top level of packages and
a few named utilities, and a start-up that loads no heavy library."""

from __future__ import annotations

import ast
import re
import subprocess
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
PKG = ROOT / "pendulum_lqg"


def _module_name(path: Path) -> str:
    name = ".".join(path.relative_to(ROOT).with_suffix("").parts)
    return name.removesuffix(".__init__")


def _imports(path: Path, name: str, modules: set[str]) -> set[str]:
    """pendulum_lqg modules imported anywhere in ``path``: function-level imports and
    ``if TYPE_CHECKING:`` blocks included (a circle through type-only imports is still a circle
    in the design, and breaks the day one of them is needed at run time)."""
    found: set[str] = set()

    for module, alias in _import_froms(path, name):
        full = f"{module}.{alias}"
        found.add(full if full in modules else module)
    for node in ast.walk(ast.parse(path.read_text(encoding="utf-8"))):
        if isinstance(node, ast.Import):
            found.update(alias.name for alias in node.names)
    return {m for m in found if m in modules and m != name}


def _import_froms(path: Path, name: str) -> list[tuple[str, str]]:
    """``(module, name)`` of every ``from module import name`` in ``path`` (relative imports
    resolved), wherever it stands."""
    out = []
    package = name if path.name == "__init__.py" else name.rsplit(".", 1)[0]
    for node in ast.walk(ast.parse(path.read_text(encoding="utf-8"))):
        if isinstance(node, ast.ImportFrom):
            module = node.module or ""
            if node.level:
                base = package.rsplit(".", node.level - 1)[0] if node.level > 1 else package
                module = base + (f".{module}" if module else "")
            out.extend((module, alias.name) for alias in node.names)
    return out


def _modules() -> dict[str, Path]:
    return {_module_name(p): p for p in PKG.rglob("*.py")}


def _find_cycles(graph: dict[str, set[str]]) -> list[list[str]]:
    """Every back edge of a depth-first walk of ``graph``, as the circle it closes."""
    state: dict[str, int] = {}          # 1 on the stack, 2 done
    cycles: list[list[str]] = []

    def visit(m: str, stack: list[str]) -> None:
        state[m] = 1
        for d in sorted(graph.get(m, ())):
            if state.get(d) == 1:
                cycles.append([*stack[stack.index(d):], d])
            elif d not in state:
                visit(d, [*stack, d])
        state[m] = 2

    for m in sorted(graph):
        if m not in state:
            visit(m, [m])
    return cycles


def test_no_import_cycles_between_modules():
    files = _modules()
    graph = {m: _imports(p, m, set(files)) - {"pendulum_lqg"} for m, p in files.items()}
    cycles = _find_cycles(graph)
    assert not cycles, " ; ".join(" -> ".join(c) for c in cycles)


def _unit(module: str) -> str:
    """The package (or top-level module) ``module`` belongs to: ``pendulum_lqg.core.loop`` →
    ``pendulum_lqg.core``; the root is its own unit."""
    return ".".join(module.split(".")[:2])


def package_graph(files: dict[str, Path]) -> dict[str, set[str]]:
    """Which package imports which (every import of every module of it, lazy and type-only ones
    included; the root's lazy public names are imports of their modules under ``TYPE_CHECKING``)."""
    graph: dict[str, set[str]] = {}
    for m, p in files.items():
        deps = {_unit(d) for d in _imports(p, m, set(files) | {"pendulum_lqg"})}
        graph.setdefault(_unit(m), set()).update(deps - {_unit(m)})
    return graph


def test_no_import_cycles_between_packages():
    """Packages form layers: a circle between two packages (``bench`` ↔ ``analysis``) means
    neither can be read, tested or replaced without the other."""
    cycles = _find_cycles(package_graph(_modules()))
    assert not cycles, " ; ".join(" -> ".join(c) for c in cycles)


def test_the_package_cycle_check_sees_a_lazy_import_circle():
    """The check itself: a function-level import that closes a circle is found."""
    files = _modules()
    graph = package_graph(files)
    graph["pendulum_lqg.core"].add("pendulum_lqg.bench")        # bench imports core already
    assert any(c[0] == c[-1] for c in _find_cycles(graph))


def test_nothing_imports_the_package_root():
    """The root re-exports every layer (lazily), so a module that imported it would close a
    circle; modules import the real path (``pendulum_lqg.version``, ``pendulum_lqg.envs.registration``)."""
    files = _modules()
    hits = sorted(m for m, p in files.items() if m != "pendulum_lqg"
                  and "pendulum_lqg" in _imports(p, m, set(files) | {"pendulum_lqg"}))
    assert not hits, hits


def _private_imports(files: dict[str, Path]) -> list[str]:
    """Imports of a private name from another module (``from a import _b``), and of a private
    module from outside its package (``from pendulum_lqg.design._checks import …`` in ``policies``)."""
    hits = []
    for m, p in files.items():
        for module, alias in _import_froms(p, m):
            if not module.startswith("pendulum_lqg") or module == m:
                continue
            if alias.startswith("_") and not alias.startswith("__"):
                hits.append(f"{m}: from {module} import {alias}")
            private = [i for i, part in enumerate(module.split(".")) if part.startswith("_")]
            if private and not m.startswith(".".join(module.split(".")[:private[0]]) + "."):
                hits.append(f"{m}: from {module} import {alias}")
    return hits


def test_no_private_name_is_imported_from_another_module():
    hits = _private_imports(_modules())
    assert not hits, "\n".join(hits)


def test_the_private_import_check_sees_one(tmp_path):
    """The check itself, on a module written for it."""
    fake = tmp_path / "probe.py"
    fake.write_text("from pendulum_lqg.core.loop import _helper\n", encoding="utf-8")
    assert _private_imports({"pendulum_lqg.probe": fake}) == [
        "pendulum_lqg.probe: from pendulum_lqg.core.loop import _helper"]


def test_no_module_is_longer_than_600_lines():
    long = {str(p.relative_to(ROOT)): n for p in PKG.rglob("*.py")
            if (n := len(p.read_text(encoding="utf-8").splitlines())) > 600}
    assert not long, long


#: Private APIs of MuJoCo and numpy (``Batch``'s C++ core and private methods, numpy's C einsum).
PRIVATE_API = re.compile(r"\._b\.|batch\._[a-z]|c_einsum|_multiarray_umath|numpy\._core|np\._core"
                         r"|mujoco\._[a-z]|_DIRECT_BATCH")

#: The one private API kept, because a paired measurement shows it is worth more than 3 % of the
#: path it serves (``benchmarks/env_benchmark.py``'s ``direct / public`` line; docs/performance.md):
#: the held-force period calling ``Batch.rollout``'s C++ core, and the batch's own error check.
JUSTIFIED = {("pendulum_lqg/core/physics/mujoco_batch.py",
              "nfail = self.batch._b.rollout(rows.ids, self.k, None, spec, rows.records)"),
             ("pendulum_lqg/core/physics/mujoco_batch.py", "self.batch._check(rows.ids, nfail)")}


def test_the_package_uses_no_private_api_of_mujoco_or_numpy():
    code = ((str(p.relative_to(ROOT)), line.split("#")[0].strip()) for p in sorted(PKG.rglob("*.py"))
            for line in p.read_text(encoding="utf-8").splitlines())      # comments may name them
    hits = {(f, line) for f, line in code if PRIVATE_API.search(line)}
    assert hits == JUSTIFIED, "\n".join(f"{f}: {line}" for f, line in sorted(hits ^ JUSTIFIED))


def test_the_rules_of_a_period_are_defined_once_in_core_rules():
    """A tripwire only: no function named like one of the rules (saturation, the failure rule, the
    cost, the state noise) is defined outside ``core/rules.py``. It checks names, not behaviour;
    the behaviour is what tests/core/test_loop.py and tests/envs/test_envs.py compare bit for bit
    across the batch, the single env and the vector env."""
    definitions = {"saturate", "nonfinite_forces", "failure_bounds", "all_inside", "detect_failure",
                   "period_cost", "period_cost_of", "period_integrals", "end_of_period"}
    where: dict[str, list[str]] = {}
    for p in PKG.rglob("*.py"):
        for node in ast.walk(ast.parse(p.read_text(encoding="utf-8"))):
            if isinstance(node, ast.FunctionDef) and node.name.lstrip("_") in definitions:
                where.setdefault(node.name.lstrip("_"), []).append(str(p.relative_to(ROOT)))
    where = {name: sorted(set(files)) for name, files in where.items()}   # @overload stubs
    assert where == {d: ["pendulum_lqg/core/rules.py"] for d in definitions}, where


def test_envs_and_core_import_no_design_code_or_python_control():
    code = ("import sys, pendulum_lqg.envs, pendulum_lqg.core.runner; "
            "print(sorted(m for m in ('control', 'scipy', 'slycot', 'cvxpy', "
            "'pendulum_lqg.design', 'pendulum_lqg.model.linearize', 'pendulum_lqg.policies.lqg') "
            "if m in sys.modules))")
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, cwd=ROOT,
                         check=True).stdout.strip()
    assert out == "[]", out


#: Libraries that cost seconds to import (python-control pulls in scipy.signal, scipy.stats and
#: matplotlib.pyplot): only the functions that need them import them.
HEAVY = ("control", "cvxpy", "scipy.signal", "scipy.stats", "matplotlib", "torch", "ray")


def test_start_up_imports_no_heavy_library():
    """A fresh interpreter that imports the package, every CLI module, the envs and the agent, and
    designs the default policy (what ``gym.make``, a Ray worker or ``pendulum-lqg run`` does),
    has loaded none of :data:`HEAVY`; a design that does need one (a pole placement) loads it."""
    code = (
        "import sys, pendulum_lqg, pendulum_lqg.cli, pendulum_lqg.cli.commands, "
        "pendulum_lqg.cli.design, pendulum_lqg.cli.parser, pendulum_lqg.envs, pendulum_lqg.envs.agent, "
        "pendulum_lqg.policies.lqg, pendulum_lqg.design\n"
        "from pendulum_lqg.model.plant import load_plant\n"
        "from pendulum_lqg.policies.lqg import DesignSpec, design_policy\n"
        "from pendulum_lqg.core.noise import NoiseModel\n"
        "design_policy(load_plant(), 0.01, NoiseModel(), DesignSpec('dlqr', 'kalman'))\n"
        f"print(sorted(m for m in {HEAVY!r} if m in sys.modules))\n"
        "from pendulum_lqg.design import luenberger\n"
        "luenberger([[0.0, 1.0], [0.0, 0.0]], [[1.0, 0.0]], [-1.0, -2.0])\n"
        "print('scipy.signal' in sys.modules)\n"
    )
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, cwd=ROOT,
                         timeout=120)
    assert out.returncode == 0, out.stderr
    assert out.stdout.split() == ["[]", "True"], out.stdout + out.stderr


def test_no_function_is_longer_than_60_lines():
    long = {}
    for p in sorted(PKG.rglob("*.py")):
        for node in ast.walk(ast.parse(p.read_text(encoding="utf-8"))):
            if isinstance(node, ast.FunctionDef | ast.AsyncFunctionDef):
                n = node.end_lineno - node.lineno + 1            # type: ignore[operator]
                key = f"{p.relative_to(ROOT)}:{node.name}"
                if n > 60:
                    long[key] = n
    assert not long, long


#: The top level of the package: its packages, and these small modules (docs/architecture.md
#: names each): the errors, the CLI's numpy-free names, the versions, and the two deprecated
#: 0.3 import paths kept for the 0.6 series.
TOP_LEVEL_MODULES = {"__init__.py", "errors.py", "names.py", "version.py", "sim.py", "agent.py"}


def test_the_top_level_holds_packages_and_a_few_named_modules():
    modules = {p.name for p in PKG.glob("*.py")}
    assert modules == TOP_LEVEL_MODULES
    text = (ROOT / "docs" / "architecture.md").read_text(encoding="utf-8")
    assert all(f"`{m}`" in text for m in TOP_LEVEL_MODULES - {"__init__.py"})
    packages = {p.parent.name for p in PKG.glob("*/__init__.py")}
    assert all(f"`{p}/`" in text for p in packages), packages


def _packages() -> list[Path]:
    """Every package folder below the root (``core/physics`` included), sorted."""
    return sorted(p.parent for p in PKG.rglob("__init__.py") if p.parent != PKG)


def _package_modules(package: Path) -> set[str]:
    """The modules of ``package`` as a table names them: ``name`` for a file, ``name/`` for a
    sub-package."""
    files = {f.stem for f in package.glob("*.py") if f.stem != "__init__"}
    return files | {d.name + "/" for d in package.iterdir() if (d / "__init__.py").is_file()}


def _docstring_module_table(package: Path) -> set[str]:
    """The ``name`` cells of the first column of the package docstring's reST table whose header
    is ``module``."""
    doc = ast.get_docstring(ast.parse((package / "__init__.py").read_text(encoding="utf-8"))) or ""
    lines = doc.splitlines()
    for i, line in enumerate(lines[1:], 1):
        if line.split()[:1] == ["module"] and lines[i - 1].startswith("="):
            width = len(lines[i - 1].split()[0])
            names: set[str] = set()
            for row in lines[i + 2:]:
                if row.startswith("="):
                    return names
                names.update(re.findall(r"``([^`]+)``", row[:width + 1]))
    return set()


def test_each_package_lists_exactly_its_modules():
    """Each package's ``__init__`` docstring has a ``module`` table, and docs/architecture.md's
    module index a row, naming exactly the package's modules — a new or removed module fails here
    until both say so."""
    text = (ROOT / "docs" / "architecture.md").read_text(encoding="utf-8")
    index = text[text.index("## Module index"):]
    rows = dict(re.findall(r"^\| `([a-z_/]+)/` \| (.*) \|$", index, flags=re.M))
    for package in _packages():
        rel = package.relative_to(PKG).as_posix()
        modules = _package_modules(package)
        assert _docstring_module_table(package) == modules, rel
        assert set(re.findall(r"`([^`]+)`", rows.get(rel, ""))) == modules, rel
    assert set(rows) == {p.relative_to(PKG).as_posix() for p in _packages()}


def test_the_module_table_reader_sees_a_missing_module(tmp_path):
    package = tmp_path / "pkg"
    package.mkdir()
    (package / "__init__.py").write_text('"""P.\n\n=======  ====\nmodule   what\n=======  ====\n'
                                         '``a``    A\n=======  ====\n"""\n')
    (package / "a.py").write_text("")
    assert _docstring_module_table(package) == _package_modules(package) == {"a"}
    (package / "b.py").write_text("")
    assert _docstring_module_table(package) != _package_modules(package)


#: Test folders that mirror no package: the documentation's commands and tutorials, and the
#: plug-in fixtures the policy tests load.
TEST_FOLDERS_OF_NO_PACKAGE = {"docs", "plugins", "data"}


def test_the_tests_mirror_the_package():
    """``tests/<package>/test_<module>[_<topic>].py`` (``<module>`` a module of the package or the
    package's own name), ``tests/benchmarks/test_<script>…`` for the scripts; at the top only this
    file. Every package has its test folder."""
    tests = ROOT / "tests"
    scripts = {p.stem for p in (ROOT / "benchmarks").glob("*.py")} | {"benchmarks"}
    for path in sorted(tests.rglob("test_*.py")):
        rel = path.relative_to(tests)
        if rel.parts[0] in TEST_FOLDERS_OF_NO_PACKAGE or rel == Path("test_architecture.py"):
            continue
        package = PKG.joinpath(*rel.parts[:-1])
        if rel.parts[0] == "benchmarks":
            names = scripts
        else:
            assert (package / "__init__.py").is_file(), f"{rel}: no package pendulum_lqg/{rel.parent}"
            names = {m.rstrip("/") for m in _package_modules(package)} | {package.name}
        stem = path.stem.removeprefix("test_")
        assert any(stem == n or stem.startswith(n + "_") for n in names), \
            f"{rel}: named for none of {sorted(names)}"
    missing = {q.parent.name for q in PKG.glob("*/__init__.py") if not (tests / q.parent.name).is_dir()}
    assert not missing, f"packages without a test folder: {sorted(missing)}"


def test_the_plant_is_a_type_not_a_flag():
    """The core, the bench and the analyses ask a plant through its interface
    (:class:`pendulum_lqg.model.interface.SimulatedPlant`) and a configuration through its plant
    source (:mod:`pendulum_lqg.bench.sources`), never through a flag of which kind it is."""
    flag = re.compile(r"is_lti|lti_file is not None")
    hits = [f"{p.relative_to(ROOT)}:{i}" for p in sorted(PKG.rglob("*.py"))
            for i, line in enumerate(p.read_text(encoding="utf-8").splitlines(), 1)
            if flag.search(line)]
    assert not hits, hits


#: The concrete plants: the layers that run any plant (core/, policies/) ask none of them.
CONCRETE_PLANTS = ("pendulum_lqg.model.plant", "pendulum_lqg.model.linearize",
                   "pendulum_lqg.model.mjcf", "pendulum_lqg.model.mjcf_linear",
                   "pendulum_lqg.model.catalog")


def _concrete_plant_imports(paths: list[Path]) -> list[str]:
    modules = set(_modules())
    return [f"{p.relative_to(ROOT)} imports {m}" for p in paths
            for m in sorted(_imports(p, _module_name(p), modules)) if m in CONCRETE_PLANTS]


def test_core_and_policies_ask_the_plant_interface_not_a_concrete_plant():
    """``core/`` and ``policies/`` ask a plant through :mod:`pendulum_lqg.model.interface` only
    (and read a scenario's :mod:`pendulum_lqg.model.overrides`): no import of the cart-pole's
    ``model/plant.py`` or ``model/linearize.py`` (nor of a plant file's modules), at module or
    function level, type-only imports included."""
    paths = sorted([*(PKG / "core").rglob("*.py"), *(PKG / "policies").rglob("*.py")])
    assert len(paths) > 20
    assert _concrete_plant_imports(paths) == []


def test_the_concrete_plant_check_sees_a_function_level_import(tmp_path):
    bad = PKG / "core" / "_probe_concrete_import.py"
    bad.write_text("def f():\n    from pendulum_lqg.model.linearize import linearize\n"
                   "    return linearize\n", encoding="utf-8")
    try:
        assert _concrete_plant_imports([bad]) == [
            "pendulum_lqg/core/_probe_concrete_import.py imports pendulum_lqg.model.linearize"]
    finally:
        bad.unlink()
