"""The scripts' command-line contract (pendulum_lqg.util.scripts): each way a script can end is
one line and a documented exit status."""

from __future__ import annotations

import pytest

from pendulum_lqg.errors import ConfigError
from pendulum_lqg.util.scripts import ScriptParser, int_in, number, requires, run_script


def _ends(main, capsys):
    with pytest.raises(SystemExit) as done:
        run_script(main)
    return done.value.code, capsys.readouterr().err


def _raise(exc):
    def main():
        raise exc
    return main


@pytest.mark.parametrize(("exc", "status", "line"), [
    (ConfigError("--out: nope"), 2, "error: --out: nope"),
    (OSError(27, "File too large", "pic.png"), 2, "error: cannot write or read pic.png: File too large"),
    (KeyboardInterrupt(), 130, "interrupted: stopped by Ctrl-C before the script finished"),
])
def test_run_script_ends_in_one_line(capsys, exc, status, line):
    code, err = _ends(_raise(exc), capsys)
    assert (code, err.strip()) == (status, line)


def test_run_script_passes_main_status(capsys):
    assert _ends(lambda: 1, capsys) == (1, "")
    assert _ends(lambda: None, capsys) == (0, "")


def test_a_bug_keeps_its_traceback():
    with pytest.raises(ZeroDivisionError):
        run_script(_raise(ZeroDivisionError("a bug")))


@pytest.mark.parametrize(("argv", "line"), [
    (["--n", "0"], "error: --n: expected an integer from 1 to 10, got '0'"),
    (["--n", "1e3"], "error: --n: expected an integer from 1 to 10, got '1e3'"),
    (["--x", "-1"], "error: --x: expected a finite positive number, got '-1'"),
    (["--x", "nan"], "error: --x: expected a finite positive number, got 'nan'"),
])
def test_script_parser_errors_are_one_line_exit_2(capsys, argv, line):
    ap = ScriptParser()
    ap.add_argument("--n", type=int_in(1, 10), default=1)
    ap.add_argument("--x", type=number(positive=True), default=1.0)
    with pytest.raises(SystemExit) as done:
        ap.parse_args(argv)
    assert done.value.code == 2
    assert capsys.readouterr().err.strip() == line


def test_requires_names_what_needs_the_module_and_how_to_install_it():
    with pytest.raises(ConfigError, match=r"^the test needs no_such_module_xyz, which is not "
                                          r"installed \(.*\); install the x extra$"):
        requires("no_such_module_xyz", needed_for="the test", install="the x extra")
    assert requires("json", needed_for="-", install="-").dumps([1]) == "[1]"
