"""Full trajectories of episodes, kept only on request (recordings, plots)."""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np


@dataclass
class Trajectory:
    """One episode's trajectory (kept only when a caller asks, e.g. for a recording).

    Control-rate arrays have one row per control sample ``n`` (time ``t[n]``); ``states`` holds the
    physics-rate states with times ``t_physics``. The shapes are the cart-pole's; an LTI plant's
    (:class:`~pendulum_lqg.model.interface.Layout`) have its ``n_x`` states and ``p`` outputs in
    place of 4 and 2, and ``y_true = C x``.

    Attributes
    ----------
    t : (N,) sample times [s]; x : (N, 4) true state at the sample; y : (N, 2) noisy measurement;
    y_true : (N, 2) noise-free measurement; u : (N,) applied force; x_hat : (N, 4) estimate used;
    x_prior : (N, 4) a-priori estimate; innovation : (N, 2); P : (N, 4, 4) a-posteriori covariance
    of x̂ − x at each sample, from the filter's start where its estimator gives one
    (``error_covariances``), else what the estimator holds (nan if it has none); cost : (N,)
    running cost at the end of each period;
    t_physics : (N·k,), states : (N·k, 4); u_policy : (N,) the force the policy asked for, before
    saturation (``u`` is that force saturated to ±u_max)
    """

    episode: int
    seed: int
    t: np.ndarray
    x: np.ndarray
    y: np.ndarray
    y_true: np.ndarray
    u: np.ndarray
    x_hat: np.ndarray
    x_prior: np.ndarray
    innovation: np.ndarray
    P: np.ndarray
    cost: np.ndarray
    t_physics: np.ndarray
    states: np.ndarray
    row: dict[str, object] = field(default_factory=dict)
    u_policy: np.ndarray | None = None



class TrajectoryLog:
    """Per-period snapshots of the running rows, split per episode at the end."""

    def __init__(self) -> None:
        self.frames: list[dict[str, np.ndarray]] = []

    def add(self, ids: np.ndarray, **arrays: np.ndarray) -> None:
        self.frames.append({"ids": ids.copy(), **{k: np.array(v) for k, v in arrays.items()}})

    def split(self, n: int, seeds: list[int], rows: list[dict[str, object]],
              C: np.ndarray | None = None) -> list[Trajectory]:
        """One :class:`Trajectory` per episode; ``C`` the measurement matrix (``None``: the
        cart-pole's ``y = [p, θ]``)."""
        out = []
        for e in range(n):
            parts: dict[str, list[np.ndarray]] = {}
            for fr in self.frames:
                hit = np.nonzero(fr["ids"] == e)[0]
                if hit.size == 0:
                    continue
                i = hit[0]
                for key, arr in fr.items():
                    if key != "ids":
                        parts.setdefault(key, []).append(arr[i] if arr.ndim and arr.shape[0] ==
                                                         fr["ids"].shape[0] else arr)
            stack = {k: np.array(v) for k, v in parts.items()}
            cost = np.cumsum(stack["cost"])
            states = stack["states"].reshape(-1, stack["states"].shape[-1])
            k = stack["states"].shape[1]
            h = (stack["t"][1] - stack["t"][0]) / k if stack["t"].size > 1 else np.nan
            t_phys = (stack["t"][:, None] + h * np.arange(1, k + 1)[None, :]).ravel()
            out.append(Trajectory(
                episode=e, seed=seeds[e], t=stack["t"], x=stack["x"], y=stack["y"],
                y_true=stack["x"][:, :2] if C is None else stack["x"] @ C.T, u=stack["u"],
                x_hat=stack["x_hat"],
                x_prior=stack["x_prior"], innovation=stack["innovation"], P=stack["P"],
                cost=cost, t_physics=t_phys, states=states, row=rows[e],
                u_policy=stack.get("u_policy")))
        return out




def estimator_snapshot(est: object | None, x_hat: np.ndarray | None, n: int, nx: int = 4,
                       ny: int = 2) -> dict[str, np.ndarray]:
    """The estimator intermediates a recording logs: ``x_hat`` and the estimator ``est``'s
    (:attr:`~pendulum_lqg.core.protocol.OptionalMembers.estimator`) ``x_prior``, ``innovation``
    and ``P``, nan where there are none; ``nx``, ``ny`` the lengths of x and y."""
    nan_x = np.full((n, nx), np.nan)
    P = getattr(est, "P", None)
    return {"x_hat": x_hat if x_hat is not None else nan_x,
            "x_prior": getattr(est, "x_prior", nan_x),
            "innovation": getattr(est, "innovation", np.full((n, ny), np.nan)),
            "P": np.broadcast_to(P if P is not None else np.full((nx, nx), np.nan), (n, nx, nx))}


