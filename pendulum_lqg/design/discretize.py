"""Exact sampled-data discretisation: ZOH plant, integrated noise, and sampled quadratic cost.

All three are Van Loan matrix exponentials (C. F. Van Loan, "Computing integrals involving the matrix
exponential", IEEE TAC 1978). Forward Euler is provided for comparison only (first-order accurate).
"""

from __future__ import annotations

import numpy as np
from numpy.typing import ArrayLike
from scipy.linalg import expm

from pendulum_lqg.design.checks import as_matrix, as_positive, as_square, as_weight, design_function


@design_function('A and dt')
def zoh(A: ArrayLike, B: ArrayLike, dt: float) -> tuple[np.ndarray, np.ndarray]:
    r"""Zero-order-hold discretisation.

    .. math:: \Phi = e^{AT}, \qquad \Gamma = \int_0^T e^{As}\,ds\,B

    Parameters
    ----------
    A : (n, n) array
    B : (n, m) array
    dt : float, sample period T [s]

    Returns
    -------
    Phi : (n, n) array
    Gamma : (n, m) array
    """
    A = as_square("A", A)
    n = A.shape[0]
    B = as_matrix("B", B, (n, None))
    dt = as_positive("dt", dt)
    m = B.shape[1]
    block = np.zeros((n + m, n + m))
    block[:n, :n], block[:n, n:] = A, B
    E = expm(block * dt)
    return E[:n, :n], E[:n, n:]


@design_function('A and dt')
def euler(A: ArrayLike, B: ArrayLike, dt: float) -> tuple[np.ndarray, np.ndarray]:
    r"""Forward-Euler discretisation :math:`\Phi \approx I + AT`, :math:`\Gamma \approx BT`.

    Only first-order accurate; this is what a hand-written loop does, kept for comparison.
    """
    A = as_square("A", A)
    n = A.shape[0]
    B = as_matrix("B", B, (n, None))
    dt = as_positive("dt", dt)
    return np.eye(n) + A * dt, B * dt


@design_function('A, W and dt')
def process_noise_covariance(A: ArrayLike, G: ArrayLike, W: ArrayLike, dt: float) -> np.ndarray:
    r"""Covariance of the state increment over one period from continuous white noise.

    For :math:`\dot x = Ax + Gw` with spectral density :math:`E\{w(t)w(s)^T\} = W\delta(t-s)`:

    .. math:: Q_d = \int_0^T e^{As} G W G^T e^{A^Ts}\,ds

    Parameters
    ----------
    A : (n, n) array
    G : (n, q) array, noise input matrix
    W : (q, q) array, spectral density [units² · s]
    dt : float, sample period [s]

    Returns
    -------
    Qd : (n, n) array, per-sample covariance
    """
    A = as_square("A", A)
    n = A.shape[0]
    G = as_matrix("G", G, (n, None))
    W = as_weight("W", W, G.shape[1], definite=False)
    dt = as_positive("dt", dt)
    block = np.zeros((2 * n, 2 * n))
    block[:n, :n] = -A
    block[:n, n:] = G @ W @ G.T
    block[n:, n:] = A.T
    E = expm(block * dt)
    Phi = E[n:, n:].T
    Qd = Phi @ E[:n, n:]
    return 0.5 * (Qd + Qd.T)


@design_function('A, Q, R and dt')
def sampled_cost(A: ArrayLike, B: ArrayLike, Q: ArrayLike, R: ArrayLike, dt: float, *,
                 N: ArrayLike | None = None) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    r"""Exact discrete weights of a continuous quadratic cost under zero-order hold.

    With :math:`u` held over each period, :math:`\int_{nT}^{(n+1)T} x^TQx + u^TRu\,dt =
    x_n^T Q_d x_n + 2 x_n^T N_d u_n + u_n^T R_d u_n`, so a ``dlqr`` with these weights minimises
    exactly the continuous cost a simulation measures (Franklin, Powell & Workman, §9.4.4). A
    cross term ``N`` (n, m) of the continuous cost ``∫ xᵀQx + 2xᵀNu + uᵀRu dt`` enters the same
    integral (default none).

    Returns
    -------
    Qd : (n, n), Rd : (m, m), Nd : (n, m)
    """
    A = as_square("A", A)
    n = A.shape[0]
    B = as_matrix("B", B, (n, None))
    m = B.shape[1]
    Q = as_weight("Q", Q, n, definite=False)
    R = as_weight("R", R, m, definite=False)
    dt = as_positive("dt", dt)
    F = np.zeros((n + m, n + m))
    F[:n, :n], F[:n, n:] = A, B
    Qz = np.zeros((n + m, n + m))
    Qz[:n, :n], Qz[n:, n:] = Q, R
    if N is not None:
        Qz[:n, n:] = as_matrix("N", N, (n, m))
        Qz[n:, :n] = Qz[:n, n:].T
    k = n + m
    block = np.zeros((2 * k, 2 * k))
    block[:k, :k] = -F.T
    block[:k, k:] = Qz
    block[k:, k:] = F
    E = expm(block * dt)
    W = E[k:, k:].T @ E[:k, k:]
    W = 0.5 * (W + W.T)
    return W[:n, :n], W[n:, n:], W[:n, n:]


@design_function('the poles and dt')
def c2d_poles(poles: ArrayLike, dt: float) -> np.ndarray:
    """Map continuous poles to the z-plane, ``z = e^{sT}``."""
    dt = as_positive("dt", dt)
    return np.exp(np.asarray(poles, dtype=complex) * dt)

