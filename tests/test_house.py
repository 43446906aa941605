"""The shape of the package: no import cycles, and the simulation core imports no design code."""

from __future__ import annotations

import ast
import subprocess
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
PKG = ROOT / "pendulum_lqg"


def _module_name(path: Path) -> str:
    name = ".".join(path.relative_to(ROOT).with_suffix("").parts)
    return name.removesuffix(".__init__")


def _imports(path: Path, name: str, modules: set[str]) -> set[str]:
    """pendulum_lqg modules imported anywhere in ``path`` (function-level imports included,
    ``if TYPE_CHECKING:`` blocks excluded: they never run)."""
    found: set[str] = set()

    class Visitor(ast.NodeVisitor):
        def visit_If(self, node: ast.If) -> None:
            if "TYPE_CHECKING" in ast.unparse(node.test):
                for child in node.orelse:
                    self.visit(child)
                return
            self.generic_visit(node)

        def visit_ImportFrom(self, node: ast.ImportFrom) -> None:
            module = node.module or ""
            if node.level:
                module = name.rsplit(".", node.level)[0] + (f".{module}" if module else "")
            for alias in node.names:
                full = f"{module}.{alias.name}"
                found.add(full if full in modules else module)

        def visit_Import(self, node: ast.Import) -> None:
            found.update(alias.name for alias in node.names)

    Visitor().visit(ast.parse(path.read_text(encoding="utf-8")))
    return {m for m in found if m in modules and m != name}


def test_no_import_cycles_between_modules():
    files = {_module_name(p): p for p in PKG.rglob("*.py")}
    graph = {m: _imports(p, m, set(files)) - {"pendulum_lqg"} for m, p in files.items()}
    state: dict[str, int] = {}          # 1 on the stack, 2 done
    cycles: list[list[str]] = []

    def visit(m: str, stack: list[str]) -> None:
        state[m] = 1
        for d in sorted(graph[m]):
            if state.get(d) == 1:
                cycles.append([*stack[stack.index(d):], d])
            elif d not in state:
                visit(d, [*stack, d])
        state[m] = 2

    for m in sorted(graph):
        if m not in state:
            visit(m, [m])
    assert not cycles, " ; ".join(" -> ".join(c) for c in cycles)


def test_env_and_sim_import_no_design_code_or_python_control():
    code = ("import sys, pendulum_lqg.env, pendulum_lqg.sim; "
            "print(sorted(m for m in ('control', 'scipy', 'slycot', 'cvxpy', "
            "'pendulum_lqg.design', 'pendulum_lqg.linearize', 'pendulum_lqg.policy') "
            "if m in sys.modules))")
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, cwd=ROOT,
                         check=True).stdout.strip()
    assert out == "[]", out
