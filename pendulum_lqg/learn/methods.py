"""Every method ``pendulum-lqg train`` knows: its one-line description, its suite and budget, the
options that apply to it and the extra it needs. Light: nothing here imports numpy or torch."""

from __future__ import annotations

from dataclasses import dataclass

from pendulum_lqg.learn.deep import METHODS as SB3_METHODS

#: The install line of the ``rl`` extra, said by every SB3 method that misses it.
RL_EXTRA = "uv sync --extra rl, or pip install 'pendulum-lqg[rl]'"
#: ARS's default budget (``ARSSettings.steps``): what the committed runs of
#: ``experiments/agents/models`` used and docs/leaderboard.md gives.
ARS_STEPS = 200_000
#: The most env steps ``sysid-lqg``'s default recipe logs (``ClosedLoopSettings``): whole bursts
#: of 30 periods covering 10 000 open-loop steps (334 · 30 = 10 020), then two rounds of 30
#: episodes of at most 1 000 periods; episodes that fail end early, so a run logs at most this.
SYSID_LQG_STEPS = 70_020


@dataclass(frozen=True)
class MethodInfo:
    """One method: what it is, its default suite and env steps, the options it takes."""

    name: str
    what: str
    suite: str
    steps: int
    kind: str                        # "sb3", "ars", "clone", "sysid-lqg", "sysid-openloop"
    options: tuple[str, ...] = ()

    @property
    def extra(self) -> str | None:
        return "rl" if self.kind == "sb3" else None

    @property
    def plant_refusal(self) -> str | None:
        """Why the method does not train on a plant other than the cart-pole (``train --plant``),
        or ``None``: it reads the plant's sizes from the env (:data:`PLANT_REFUSALS`)."""
        return PLANT_REFUSALS.get(self.kind)


#: Why a kind of method trains on the cart-pole only (``train --plant``; every other kind, ARS,
#: reads the plant's n, p and m from its env: any plant of one input, the env's rule).
PLANT_REFUSALS = {
    "sb3": "its model is scored on the cart-pole's suites only (score --plant scores built-in "
           "policies and linear:FILE controllers)",
    "clone": "its teacher is sysid-lqg's model, the cart-pole's structured 4-state, "
             "2-output model",
    "sysid-lqg": "it identifies the cart-pole's structured 4-state model of y = [p, θ]",
    "sysid-openloop": "it identifies the cart-pole's structured 4-state model of y = [p, θ]",
}


_LINEAR = {
    "ars-history": MethodInfo("ars-history", "ARS V2-t from zero: a linear policy of the last 64 "
                              "(y, u) rows, observation normalisation", "lecture", ARS_STEPS, "ars",
                              ("frames", "alpha", "nu", "eval_every")),
    "ars-history-clone": MethodInfo("ars-history-clone", "ARS V2-t started from a least-squares "
                                    "clone (--init FILE, from ls-clone)", "lecture", ARS_STEPS, "ars",
                                    ("frames", "alpha", "nu", "eval_every", "init")),
    "ls-clone": MethodInfo("ls-clone", "least-squares clone (history of 64) of the identified "
                           "LQG's actions on closed-loop data", "lecture", 20_000, "clone",
                           ("frames",)),
    "sysid-lqg": MethodInfo("sysid-lqg", "closed-loop identification, then certainty-equivalent "
                            "LQG (one curve point per round)", "lecture", SYSID_LQG_STEPS,
                            "sysid-lqg"),
    "sysid-openloop": MethodInfo("sysid-openloop", "least squares from open-loop bursts, then LQG "
                                 "(the earlier sysid-lqg, kept as evidence)", "lecture", 1_000_000,
                                 "sysid-openloop"),
}
METHODS: dict[str, MethodInfo] = {
    **{name: MethodInfo(name, m.what, m.suite, m.steps, "sb3",
                        ("eval_every", "noise_scale")) for name, m in SB3_METHODS.items()},
    **_LINEAR,
}


def list_lines() -> list[str]:
    """One line per method: name, default suite, default env steps, the extra, what it is; then
    the methods that train on any plant (``--plant``)."""
    out = []
    for name, m in METHODS.items():
        steps = f"{'≤ ' if m.kind == 'sysid-lqg' else ''}{m.steps:,} steps"
        extra = f"[{m.extra}]" if m.extra else "-"
        out.append(f"{name:22s} {m.suite:11s} {steps:>15s}  {extra:5s} {m.what}")
    anywhere = [name for name, m in METHODS.items() if m.plant_refusal is None]
    out.append(f"--plant NAME|FILE (any plant of one input): {', '.join(anywhere)}")
    return out
