"""Design and run flags that used to end in a traceback or never end: one line, exit 2."""

from __future__ import annotations

import pytest
from conftest import assert_one_line_error, run_cli


# ---- 1. design / run flags that used to end in a traceback or never end ------------------------
@pytest.mark.parametrize(("argv", "name", "detail"), [
    (["design", "--q", "0,0,0,0"], "Q:", "no stabilising LQR"),
    (["design", "--r", "1e300"], "lqr:", "check the scaling of Q and R"),
    (["design", "--w", "1e300"], "kalman:", "check the scaling of W and V"),
    (["design", "--w", "0,0,0,0"], "W:", "no stabilising Kalman filter"),
    (["design", "--dt", "100"], "control_period:", "expected at most 1 s"),
    (["design", "--dt", "1e5"], "control_period:", "expected at most 1 s"),
    (["run", "--duration", "1e308", "--episodes", "1"], "duration:", "at most 1e+08 control"),
    (["run", "--duration", "2e6", "--episodes", "1"], "duration:", "at most 1e+08 control"),
])
def test_design_and_run_flags_end_in_one_line_errors(capsys, argv, name, detail):
    status, err = run_cli(capsys, argv)
    assert_one_line_error(status, err, name)
    assert detail in err, err
