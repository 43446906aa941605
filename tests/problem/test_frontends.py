"""Every declared setting reaches its front ends without a hand edit: the env's typed keywords, the
experiment file's table and its docs, the ``run`` / ``theory`` help; and a flag's value is checked
by its declaration (issue 44: derived, not written)."""

from __future__ import annotations

import typing

import pytest

from pendulum_lqg.bench import experiments
from pendulum_lqg.cli.parser import build_parser
from pendulum_lqg.envs.keywords import EnvKeywords
from pendulum_lqg.envs.single import CartPoleLQGEnv
from pendulum_lqg.problem.declare import declared
from pendulum_lqg.problem.env import EnvSettings, env_keywords
from pendulum_lqg.problem.generate import ROOT
from pendulum_lqg.problem.scenario import ScenarioSettings

SETTINGS = declared(ScenarioSettings) + declared(EnvSettings)


def _help(command: str) -> str:
    parser = build_parser()
    sub = next(a for a in parser._actions if a.dest == "command")
    return sub.choices[command].format_help()


@pytest.mark.parametrize("setting", SETTINGS, ids=lambda d: d.name)
def test_each_declared_setting_reaches_its_front_ends(setting):
    if "env" in setting.fronts:
        signature = typing.get_type_hints(CartPoleLQGEnv.__init__)
        assert setting.name in typing.get_type_hints(EnvKeywords)
        assert typing.Unpack[EnvKeywords] == signature["config"]
        assert f"`{setting.name}`" in (ROOT / "docs/_generated/env-keywords.md").read_text()
    if "file" in setting.fronts:
        assert setting.name in experiments.SCENARIO_KEYS
        assert f"`{setting.name}`" in (ROOT / "docs/_generated/scenario-keys.md").read_text()
        assert "_generated/scenario-keys.md" in (ROOT / "docs/experiment-files.md").read_text()
    for command in ("run", "theory"):
        if command in setting.fronts:
            assert setting.flag in _help(command)
    if setting.grid:
        assert setting.name in experiments.GRID_KEYS


def test_the_env_keywords_are_the_declared_ones():
    assert list(typing.get_type_hints(EnvKeywords)) == [d.name for d in env_keywords()]


def test_the_docs_pages_include_the_generated_tables():
    assert "_generated/env-keywords.md" in (ROOT / "docs/gymnasium.md").read_text()
    assert "_generated/cli-flags.md" in (ROOT / "docs/closed-loop.md").read_text()


@pytest.mark.parametrize(("argv", "message"), [
    (["run", "--dropout", "1"], "argument --dropout: expected a probability in [0, 1), got '1'"),
    (["run", "--theta-max", "-1"], "argument --theta-max: expected a positive number or inf"),
    (["theory", "--burn-in", "x"], "argument --burn-in: expected a finite number ≥ 0, got 'x'"),
])
def test_a_flag_is_checked_by_its_declaration(capsys, argv, message):
    with pytest.raises(SystemExit) as exc:
        build_parser().parse_args(argv)
    assert exc.value.code == 2
    assert message in capsys.readouterr().err


def test_flags_read_their_declared_types():
    args = build_parser().parse_args(["run", "--theta-max", "inf", "--dropout", "0.25"])
    assert args.theta_max == float("inf") and args.dropout == 0.25


#: The env's own keywords that no declaration holds (actions, rendering), in its docstring's table.
ENV_OWN_KEYWORDS = {"normalize_action", "render_mode", "width", "height"}


def _docstring_arguments() -> dict[str, str]:
    """The env docstring's Arguments table (what ``help(env)`` shows): keyword → default cell."""
    doc = CartPoleLQGEnv.__doc__ or ""
    table = doc[doc.index("## Arguments"):].split("\n\n")[1]
    rows: dict[str, str] = {}
    for line in table.splitlines()[2:]:                       # after the header and its rule
        cells = [c.strip() for c in line.strip().strip("|").split("|")]
        names, default = cells[0], cells[2]
        for name in names.split(","):
            rows[name.strip().strip("`")] = default
    return rows


def test_the_env_docstring_table_agrees_with_the_declarations():
    """The docstring's table is written by hand (it carries footnotes a generated table cannot),
    so it may lag behind: every keyword it names must be declared, and a default it writes as one
    literal must be the declaration's. The complete list is the generated one (``EnvKeywords``,
    docs/_generated/env-keywords.md), which the docstring points to: a new setting needs no row."""
    import ast

    rows = _docstring_arguments()
    by_name = {d.name: d for d in env_keywords()}
    assert not set(rows) - set(by_name) - ENV_OWN_KEYWORDS, "undeclared keywords in the docstring"
    assert "EnvKeywords" in (CartPoleLQGEnv.__doc__ or "")
    checked = 0
    for name, cell in rows.items():
        d = by_name.get(name)
        literal = cell.split()[0]
        if d is None or not (literal.startswith("`") and literal.endswith("`")) or "," in cell:
            continue                                 # "see above", "bundled XML", a pair …
        value = ast.literal_eval(literal.strip("`"))
        if isinstance(d.default, tuple) or (d.default is None and value is not None):
            continue                                 # a vector, or a default derived from others
        assert value == d.default, f"{d.name}: docstring {cell!r}, declared {d.default!r}"
        checked += 1
    assert checked >= 12, checked
