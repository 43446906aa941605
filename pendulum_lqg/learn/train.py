"""``pendulum-lqg train METHOD --seed S``: one run, every input checked before any training.

:func:`train` is the library's entry (the command calls it): the method named, the numbers in
range, the options that apply to the method, the extra it needs installed, the suite loadable and
the run folder fit to write in (a folder or a new path; its run files replaced only with
``force``, continued only with ``resume`` where a checkpoint exists) — each a one-line
:class:`~pendulum_lqg.errors.ConfigError` naming the option — then the method's trainer.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from pathlib import Path
from typing import Any

from pendulum_lqg.errors import ConfigError
from pendulum_lqg.learn.methods import METHODS, RL_EXTRA, MethodInfo
from pendulum_lqg.learn.runs import (
    RunContext,
    check_out_folder,
    clear_run,
    default_out,
    out_folder,
)

#: Ceilings checked before training: env steps of one run and the history length (3K inputs).
MAX_STEPS, MAX_FRAMES = 10**10, 1024
#: ``--steps`` ceilings of the methods whose memory grows with the budget (the others keep a
#: fixed memory: SB3's rollouts and replay buffer, ARS's policy and statistics): the
#: identifications hold every logged sample for their fits (about 15 and 10 times their defaults).
METHOD_MAX_STEPS = {"sysid-lqg": 1_000_000, "sysid-openloop": 10_000_000}
#: ``ls-clone`` holds ``--steps`` histories of ``3·K`` values for its fit: at most this many values
#: (320 MB; 208,333 samples at the default K = 64).
CLONE_MAX_VALUES = 40_000_000
CHECKPOINT = "-checkpoint.json"


def _integer(flag: str, value: Any, low: int, high: int) -> int:
    """``value`` as an integer in ``[low, high]`` (a string from the command line accepted)."""
    try:
        number = int(str(value), 10) if not isinstance(value, bool) else None
    except ValueError:
        number = None
    if number is None or not low <= number <= high:
        raise ConfigError(f"{flag}: expected an integer from {low:,} to {high:,}, got {value!r}")
    return number


def _real(flag: str, value: Any, *, positive: bool) -> float:
    try:
        number = float(value)
    except (TypeError, ValueError):
        number = math.nan
    if not math.isfinite(number) or number < 0 or (positive and number == 0):
        raise ConfigError(f"{flag}: expected a finite number {'> 0' if positive else '≥ 0'}, "
                          f"got {value!r}")
    return number + 0.0                         # -0.0 is 0: one value, one run name


def max_steps(info: MethodInfo, frames: int | None = None) -> int:
    """The largest ``--steps`` of ``info`` (:data:`METHOD_MAX_STEPS`, :data:`CLONE_MAX_VALUES`)."""
    if info.kind == "clone":
        from pendulum_lqg.learn.clone import FRAMES

        return CLONE_MAX_VALUES // (3 * (frames or FRAMES))
    return METHOD_MAX_STEPS.get(info.kind, MAX_STEPS)


def check_steps(info: MethodInfo, steps: Any, frames: int | None) -> int | None:
    """``--steps`` within the method's documented ceiling (:func:`max_steps`), before any work."""
    if steps is None:
        return None
    number = _integer("--steps", steps, 1, MAX_STEPS)
    ceiling = max_steps(info, frames)
    if number > ceiling:
        why = (f"the fit holds --steps × 3·K history values, at most {CLONE_MAX_VALUES:,}; K = "
               f"{frames or 64}" if info.kind == "clone" else
               "the identification holds every logged sample for its fits")
        raise ConfigError(f"--steps: expected at most {ceiling:,} for {info.name} ({why}), got "
                          f"{number:,}")
    return number


def _training_suite(name: str, noise_scale: float | None) -> Any:
    """The suite ``name`` with ``--noise-scale`` applied; a scale the env refuses is blamed on the
    flag, not on the suite's ``[env]``."""
    from pendulum_lqg.errors import PendulumLQGError
    from pendulum_lqg.scoreboard.suites import load_suite

    loaded = load_suite(name)
    try:
        return loaded.with_noise_scale(noise_scale)
    except PendulumLQGError as exc:
        if noise_scale is None:
            raise
        said = str(exc)
        said = said.split("noise_scale: ", 1)[1] if "noise_scale: " in said else said
        raise ConfigError(f"--noise-scale: {said}") from None


def check_options(info: MethodInfo, options: dict[str, Any]) -> dict[str, Any]:
    """The method's options checked: each given one applies to the method, and is in range."""
    given = {k: v for k, v in options.items() if v is not None}
    for key in given:
        if key not in info.options:
            takes = ", ".join("--" + o.replace("_", "-") for o in info.options) or "none"
            raise ConfigError(f"--{key.replace('_', '-')}: does not apply to {info.name} (its "
                              f"options: {takes})")
    out: dict[str, Any] = {}
    for key, value in given.items():
        if key == "frames":
            out[key] = _integer("--frames", value, 1, MAX_FRAMES)
        elif key == "eval_every":
            out[key] = _integer("--eval-every", value, 1, MAX_STEPS)
        elif key in ("alpha", "nu"):
            out[key] = _real(f"--{key}", value, positive=True)
        elif key == "noise_scale":
            out[key] = _real("--noise-scale", value, positive=False)
        elif key == "init":
            out[key] = Path(value)
    return out


def check_extra(info: MethodInfo) -> None:
    """The libraries an SB3 method imports, installed, or one line saying which extra to add."""
    import importlib.util

    if info.extra is None:
        return
    needed = ["torch", "stable_baselines3"] + (["sb3_contrib"] if "Recurrent" in info.what else [])
    missing = [lib for lib in needed if importlib.util.find_spec(lib) is None]
    if missing:
        raise ConfigError(f"{info.name}: needs the {info.extra} extra ({', '.join(missing)} not "
                          f"installed): {RL_EXTRA}")


def train(method: str, *, seed: Any, suite: str | None = None, steps: Any = None,
          out: str | Path | None = None, force: bool = False, resume: bool = False,
          options: dict[str, Any] | None = None,
          log: Callable[[str], None] | None = None,
          plant: str | Path | None = None) -> tuple[RunContext, list[Path]]:
    """Check everything, then train run ``seed`` of ``method``; the run's context and the files
    written. ``options``: ``frames``, ``alpha``, ``nu``, ``eval_every``, ``noise_scale``,
    ``init`` (those the method takes; :data:`~pendulum_lqg.learn.methods.METHODS`); ``plant``:
    a plant NAME or FILE to train on (its own suite, :func:`plant_training_suite`)."""
    ctx = prepare(method, seed=seed, suite=suite, steps=steps, out=out, force=force,
                  resume=resume, options=options, log=log, plant=plant)
    return ctx, run(ctx)


def plant_training_suite(info: MethodInfo, plant: str | Path, suite: str | None) -> Any:
    """The suite a run of ``info`` on ``plant`` trains on: the plant's own suite
    (:func:`~pendulum_lqg.scoreboard.lti_suite.plant_suite`, the one ``score --plant`` scores
    on), its env checked; one line ``--plant: …`` where the method or the plant cannot."""
    from pendulum_lqg.envs.config import EnvConfig
    from pendulum_lqg.errors import PendulumLQGError
    from pendulum_lqg.scoreboard.lti_suite import plant_suite

    if suite is not None:
        raise ConfigError(f"--plant: {str(plant)!r} trains on its own suite; --suite {suite} "
                          "names another: give one")
    if info.plant_refusal is not None:
        raise ConfigError(f"--plant: {info.name} trains on the cart-pole only: "
                          f"{info.plant_refusal}")
    loaded = plant_suite(plant)
    try:
        EnvConfig.from_keywords(loaded.env)           # the env of one input, the env's rule
    except PendulumLQGError as exc:
        said = str(exc).removeprefix("plant: ")
        raise ConfigError(f"--plant: {info.name} trains on the env: {said}") from None
    return loaded


def prepare(method: str, *, seed: Any, suite: str | None = None, steps: Any = None,
            out: str | Path | None = None, force: bool = False, resume: bool = False,
            options: dict[str, Any] | None = None,
            log: Callable[[str], None] | None = None,
            plant: str | Path | None = None) -> RunContext:
    """The run's context, every input checked (nothing trained, nothing written)."""
    from pendulum_lqg.learn.deep import method_name
    from pendulum_lqg.model.catalog import is_cartpole

    info = METHODS.get(method)
    if info is None:
        raise ConfigError(f"method: expected one of {', '.join(METHODS)}, got {method!r} "
                          "(pendulum-lqg train --list)")
    seed = _integer("--seed", seed, 0, 10**6)
    opts = check_options(info, options or {})
    steps = check_steps(info, steps, opts.get("frames"))
    if force and resume:
        raise ConfigError("--resume: give either --force (start again) or --resume, not both")
    if resume and out is None:
        raise ConfigError("--resume: needs the --out DIR of the run to continue")
    folder = out_folder(out) if out is not None else None
    if is_cartpole(plant):
        check_extra(info)
        loaded = _training_suite(suite or info.suite, opts.get("noise_scale"))
    else:
        loaded = plant_training_suite(info, str(plant), suite)
    if "init" in opts:                     # the clone ARS starts from, read at the boundary now
        from pendulum_lqg.learn.ars import ARSSettings, history_inputs, load_start

        opts["start"] = load_start(opts["init"], opts.get("frames") or ARSSettings().frames,
                                   history_inputs(loaded))
    name = method_name(method, opts.get("noise_scale"))
    folder = folder or default_out(name, seed)
    held = check_out_folder(folder, f"{name}-seed{seed}", force=force, resume=resume,
                            checkpoint=CHECKPOINT)
    try:
        ctx = RunContext(method=name, seed=seed, suite=loaded, out=folder, steps=steps,
                         eval_every=opts.get("eval_every", 50_000), resume=resume, options=opts,
                         folder=held)
        ctx.options["kind"], ctx.options["base"] = info.kind, method
        if log is not None:
            ctx.log = log
        if resume:
            from pendulum_lqg.learn.checkpoint import read_checkpoint

            ctx.checkpoint = read_checkpoint(ctx)
    except BaseException:
        held.abandon()
        raise
    return ctx


def run(ctx: RunContext) -> list[Path]:
    """Train the prepared run (:func:`prepare`), holding its folder's lock until it ends. A run
    started again (``--force``) first removes the files of the run it replaces, checkpoints too
    (:func:`~pendulum_lqg.learn.runs.clear_run`: a symbolic link is removed, never its target),
    so that nothing of the old run is mixed into the new one and a later ``--resume`` can only
    continue it."""
    if ctx.folder is None:                      # a context made by hand: hold the folder now
        from pendulum_lqg.learn.runs import RunFolder

        ctx.folder = RunFolder(ctx.out, ctx.name)
        ctx.folder.open()
    try:
        if ctx.resume and ctx.checkpoint is None:
            from pendulum_lqg.learn.checkpoint import read_checkpoint

            ctx.checkpoint = read_checkpoint(ctx)
        if not ctx.resume:
            clear_run(ctx.out, ctx.name)
        return _train(ctx)
    finally:
        ctx.folder.release()


def _train(ctx: RunContext) -> list[Path]:
    kind = ctx.options["kind"]
    if kind == "sb3":
        from pendulum_lqg.learn.deep import METHODS as SB3
        from pendulum_lqg.learn.deep import train_sb3

        return train_sb3(ctx, SB3[ctx.options["base"]])
    if kind == "ars":
        from pendulum_lqg.learn.ars import train_ars

        return train_ars(ctx)
    if kind == "clone":
        from pendulum_lqg.learn.clone import train_clone

        return train_clone(ctx)
    if kind == "sysid-lqg":
        from pendulum_lqg.learn.sysid_lqg import train_sysid_lqg

        return train_sysid_lqg(ctx)
    from pendulum_lqg.learn.openloop import train_openloop

    return train_openloop(ctx)
