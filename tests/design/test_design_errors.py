"""Bad matrices given to the designs: one-line errors naming the argument, never a raw solver
exception, a silently truncated complex matrix or an inf/NaN design (random garbage included)."""

from __future__ import annotations

import warnings

import msgspec
import numpy as np
import pytest

from pendulum_lqg import design
from pendulum_lqg.errors import DesignError, PendulumLQGError, ShapeError

A_DI = np.array([[0.0, 1.0], [0.0, 0.0]])
B_DI = np.array([[0.0], [1.0]])
C_DI = np.array([[1.0, 0.0]])


def test_complex_matrices_are_refused_not_cut_to_their_real_part():
    with pytest.raises(ShapeError, match=r"^A: expected a real matrix, got complex entries"):
        design.lqr(A_DI + 0j, B_DI, np.eye(2), 1.0)
    with pytest.raises(ShapeError, match=r"^Q: expected a real matrix, got complex entries"):
        design.lqr(A_DI, B_DI, np.eye(2) * (1 + 1e-3j), 1.0)
    with pytest.raises(ShapeError, match=r"^B: expected a real matrix"):
        design.zoh(A_DI, [[0.0], [1j]], 0.1)
    with pytest.raises(ShapeError, match=r"^C: expected a real matrix"):
        design.luenberger(A_DI, [[1.0, 0.5j]], [-1.0, -2.0])
    with pytest.raises(DesignError, match=r"^dt: expected a finite positive number"):
        design.zoh(A_DI, B_DI, np.complex128(0.1))


def test_overflowing_results_raise_instead_of_returning_inf():
    with pytest.raises(DesignError, match=r"^zoh: the result is not finite"):
        design.zoh(np.eye(2) * 1e3, B_DI, 10.0)           # e^{10⁴}
    with pytest.raises(DesignError, match=r"^euler: the result is not finite"):
        design.euler(np.full((2, 2), 1e300), B_DI, 1e10)
    with pytest.raises(DesignError, match=r"^finite_horizon_dlqr: the result is not finite"):
        design.finite_horizon_dlqr(np.eye(2) * 1e100, np.ones((2, 1)), np.eye(2), 1.0,
                                   np.eye(2), 10)


def test_a_finite_horizon_too_long_to_hold_is_refused_at_once():
    import time

    from pendulum_lqg.util.limits import MAX_RICCATI_FLOATS

    Phi, Gamma = np.array([[1.0, 0.01], [0.0, 1.0]]), np.array([[0.0], [0.01]])
    t = time.perf_counter()
    with pytest.raises(DesignError, match=r"^horizon: at most 4,999,999 \(steps for n = 2 "
                                          r"states: P keeps \(horizon \+ 1\)·n² floats, at most "
                                          r"20,000,000\), got 100,000,000$"):
        design.finite_horizon_dlqr(Phi, Gamma, np.eye(2), 1.0, np.eye(2), horizon=10**8)
    assert time.perf_counter() - t < 1.0          # refused, not allocated (P would be 3.2 GB)
    n4 = MAX_RICCATI_FLOATS // 16 - 1             # the cart-pole's 4 states: 1 249 999 steps
    with pytest.raises(DesignError, match=f"^horizon: at most {n4:,} "):
        design.finite_horizon_dlqr(np.eye(4), np.ones((4, 1)), np.eye(4), 1.0, np.eye(4),
                                   horizon=n4 + 1)
    assert design.finite_horizon_dlqr(Phi, Gamma, np.eye(2), 1.0, np.eye(2),
                                      horizon=3).K.shape == (3, 1, 2)


def test_raw_solver_errors_are_wrapped_naming_the_function():
    # a CARE whose Hamiltonian has eigenvalues on the imaginary axis: scipy raises LinAlgError
    with pytest.raises(DesignError, match=r"^Q: the cost does not weight the mode\(s\)"):
        design.lqr(A_DI, B_DI, np.zeros((2, 2)), 1.0)
    with pytest.raises(DesignError, match=r"^lqr: no solution for these data \(LinAlgError"):
        design.lqr(A_DI, B_DI, np.eye(2), 1e300)
    with pytest.raises(DesignError, match=r"^dkalman: no solution for these data"):
        design.dkalman([[1.0, 0.1], [0.0, 1.0]], np.eye(2), C_DI, np.eye(2) * 1e300, 1.0)


_SPECIALS = (np.nan, np.inf, -np.inf, 1e300, -1e300, 1e-300, 0.0)


def _garbage(rng, shape):
    """A random matrix of ``shape`` that is often wrong: non-finite entries, huge or tiny scales,
    complex entries, zeros, a wrong rank, or not a matrix at all."""
    kind = rng.integers(10)
    if kind == 0:
        return ["abc", None, [[1.0, 2.0], [3.0]], {"a": 1}][rng.integers(4)]
    if kind == 1:
        return np.zeros(shape)
    M = rng.normal(size=shape) * 10.0 ** rng.integers(-3, 4)
    if kind == 2 and M.size:
        M.flat[rng.integers(M.size)] = rng.choice(_SPECIALS)
    elif kind == 3:
        M = M * rng.choice([1e150, 1e300, 1e-300])
    elif kind == 4:
        M = M + 1j * rng.normal(size=shape) * rng.choice([1.0, 1e-12])
    elif kind == 5 and M.ndim == 2 and min(M.shape) > 1:
        M[:, 0] = M[:, 1]                       # rank deficient
    elif kind == 6:
        M = M @ M.T if M.ndim == 2 and M.shape[0] == M.shape[1] else M
    return M


def non_finite_arrays(result, path="result"):
    """Paths of the arrays and numbers in ``result`` (result record, tuple, array) that hold
    nan/inf."""
    if isinstance(result, msgspec.Struct):
        return [q for f in msgspec.structs.fields(result)
                for q in non_finite_arrays(getattr(result, f.name), f"{path}.{f.name}")]
    if isinstance(result, np.ndarray):
        return [] if result.dtype.kind not in "fc" or np.all(np.isfinite(result)) else [path]
    if isinstance(result, float | complex):
        return [] if np.isfinite(result) else [path]
    if isinstance(result, tuple | list):
        return [q for i, v in enumerate(result) for q in non_finite_arrays(v, f"{path}[{i}]")]
    return []


def _random_call(rng):
    n, m, p = int(rng.integers(0, 5)), int(rng.integers(1, 3)), int(rng.integers(1, 3))
    if rng.random() < 0.15:                     # wrong shapes
        m, p = m + 1, p + 1
    A = _garbage(rng, (n, n))
    B = _garbage(rng, (n, m) if rng.random() < 0.9 else (n + 1, m))
    C = _garbage(rng, (p, n))
    Q = _garbage(rng, (n, n)) if rng.random() < 0.5 else np.eye(n)
    R = _garbage(rng, (m, m)) if rng.random() < 0.5 else np.eye(m)
    W, V = Q, _garbage(rng, (p, p)) if rng.random() < 0.5 else np.eye(p)
    choices = [-1.0, -2.0, -0.5, -3.0, np.nan, 1e300, -1 + 1j, -1 - 1j]
    poles = [choices[k] for k in rng.integers(len(choices), size=int(rng.integers(0, 6)))]
    dt = [0.01, 0.1, 1.0, 100.0, 0.0, -1.0, np.nan, 1e300, 1j, "x"][rng.integers(10)]
    calls = {
        "lqr": lambda: design.lqr(A, B, Q, R),
        "dlqr": lambda: design.dlqr(A, B, Q, R, alpha=[1.0, 1.5, 1e300][rng.integers(3)]),
        "kalman": lambda: design.kalman(A, B, C, W, V),
        "dkalman": lambda: design.dkalman(A, B, C, W, V),
        "kalman_tv": lambda: design.kalman_tv(A, B, C, W, V, Q, int(rng.integers(1, 30))),
        "zoh": lambda: design.zoh(A, B, dt),
        "euler": lambda: design.euler(A, B, dt),
        "sampled_cost": lambda: design.sampled_cost(A, B, Q, R, dt),
        "process_noise_covariance": lambda: design.process_noise_covariance(A, B, W, dt),
        "finite_horizon_dlqr": lambda: design.finite_horizon_dlqr(A, B, Q, R, Q,
                                                                  int(rng.integers(1, 30))),
        "luenberger": lambda: design.luenberger(A, C, poles),
        "dluenberger": lambda: design.dluenberger(A, C, poles, dt=[None, 0.1][rng.integers(2)]),
        "ackermann": lambda: design.ackermann(A, C, poles),
        "reduced_order_observer": lambda: design.reduced_order_observer(A, B, C, poles),
        "lqg": lambda: design.lqg(A, B, C, _garbage(rng, (m, n)), _garbage(rng, (n, p))),
        "structure": lambda: design.structure(A, B, C),
        "augment_delays": lambda: design.augment_delays(
            A, B, C, measurement_delay=int(rng.integers(0, 3)),
            actuator_delay=int(rng.integers(0, 3))),
    }
    name = str(rng.choice(sorted(calls)))
    return name, calls[name]


def test_a_result_record_holding_nan_is_refused_and_the_checker_sees_inside_it():
    """The results are msgspec Structs: the design layer's finiteness check (and this file's
    helper, which the garbage test below relies on) look inside them, nested records included."""
    from pendulum_lqg.design.checks import design_function
    from pendulum_lqg.design.lqg import LQGResult
    from pendulum_lqg.design.lqr import LQRResult

    bad = LQRResult(K=np.array([[1.0, np.nan]]), P=np.eye(2), poles=np.array([-1.0, -2.0]),
                    discrete=False)
    assert non_finite_arrays(bad) == ["result.K"]
    assert non_finite_arrays((1.0, [bad])) == ["result[1][0].K"]

    @design_function("Q and R")
    def returns(value):
        return value

    with pytest.raises(DesignError, match=r"^returns: the result is not finite .*Q and R$"):
        returns(bad)
    with pytest.raises(DesignError, match=r"^returns: the result is not finite"):
        returns(LQGResult(A_cl=np.eye(2), poles=np.array([np.inf, 1.0]),
                          controller_poles=np.ones(1), observer_poles=np.ones(1),
                          separation_error=0.0))
    good = msgspec.structs.replace(bad, K=np.array([[1.0, 2.0]]))
    assert returns(good) is good and non_finite_arrays(good) == []


def test_random_garbage_raises_only_pendulum_lqg_errors_and_returns_only_finite_arrays():
    rng = np.random.default_rng(17)
    outcomes = {"ok": 0, "refused": 0}
    for i in range(300):
        name, call = _random_call(rng)
        try:
            with warnings.catch_warnings():
                warnings.simplefilter("error", np.exceptions.ComplexWarning)
                result = call()
        except PendulumLQGError as exc:
            assert "\n" not in str(exc), (i, name, str(exc))
            outcomes["refused"] += 1
        except Exception as exc:
            pytest.fail(f"call {i} ({name}) raised {type(exc).__name__}: {exc}")
        else:
            bad = non_finite_arrays(result)
            assert not bad, (i, name, bad)
            outcomes["ok"] += 1
    assert outcomes["ok"] >= 20 and outcomes["refused"] >= 100, outcomes


def test_the_lmi_designs_wrap_solver_errors():
    with pytest.raises(DesignError, match=r"^decay: expected a real number"):
        design.lmi_observer(A_DI, C_DI, decay="fast")
    with pytest.raises(ShapeError, match=r"^A: expected a real matrix, got complex"):
        design.h2_filter(A_DI * 1j, np.eye(2), C_DI, np.eye(2), 1.0)
    for W in (np.eye(2) * 1e300, np.zeros((2, 2))):
        try:
            res = design.hinf_filter(A_DI, np.eye(2), C_DI, W, 1.0)
        except PendulumLQGError:
            continue
        assert np.all(np.isfinite(res.L))


# ---- 3. experiment files -------------------------------------------------------------------------
