"""Issue 55's small things at the command line: one form of the saturated time on every plant."""

from __future__ import annotations

import json
import re
from pathlib import Path

import pytest

from pendulum_lqg.cli import main

ROOT = Path(__file__).resolve().parents[2]


def _saturated_cell(out: str) -> list[str]:
    line = next(x for x in out.splitlines() if "time saturated" in x)
    return re.split(r"\s*│\s*", line.strip("│ "))


def test_time_saturated_is_a_percentage_on_every_plant(tmp_path, capsys):
    """A matrix plant printed the saturated time as a share (0.8), the cart-pole as a percentage
    (80): both print "time saturated [% of the episode]" and the percentage now."""
    lti = tmp_path / "di_sat.toml"
    lti.write_text((ROOT / "experiments" / "lti" / "double_integrator.toml").read_text()
                   + "force_limit = 0.5\n", encoding="utf-8")
    runs = {"lti": ["run", "--lti", str(lti), "--episodes", "4", "--duration", "2"],
            "cart-pole": ["run", "--episodes", "4", "--duration", "2", "--force-limit", "1.5"]}
    for args in runs.values():
        assert main([*args, "--json"]) == 0
        share = json.loads(capsys.readouterr().out)["summary"]["saturated_fraction"]["mean"]
        assert 0.05 < share < 1.0
        assert main(args) == 0
        label, cell = _saturated_cell(capsys.readouterr().out)
        assert label == "time saturated [% of the episode]"
        assert float(cell.split(" ± ")[0]) == pytest.approx(100 * share, rel=1e-3)
