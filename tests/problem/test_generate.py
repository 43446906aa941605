"""The generated files (env keywords, CLI flags, docs tables) are those the declarations give."""

from __future__ import annotations

from pendulum_lqg.problem.generate import main


def test_the_generated_files_are_up_to_date(capsys):
    assert main(["--check"]) == 0, capsys.readouterr().err
