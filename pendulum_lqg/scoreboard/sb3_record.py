"""The training record of your own stable-baselines3 model, written from the command line.

``score --agent sb3:MODEL.zip`` rebuilds the observation design the model was trained on from the
record beside it, ``MODEL.json`` (format: :mod:`pendulum_lqg.scoreboard.sb3`). The runs of
``pendulum-lqg train`` write it; a plain ``model.save("MODEL")`` does not, and this command
writes it from what you trained on::

    python -m pendulum_lqg.scoreboard.sb3_record MODEL.zip --algo PPO \\
        [--observation-mode state] [--frame-stack K] [--past-actions] [--estimator kalman] \\
        [--normalize-action] [--method NAME --seed S] [--force]

The record is checked by the same schema the scorer reads it with before it is written (one line
naming the flag, exit 2), written atomically, and an existing record is replaced only with
``--force``. The zip is not opened (no torch needed): its path names the record. A model trained
under ``VecNormalize`` also needs its statistics, ``obs_norm`` (``mean``, ``var``, ``clip``,
``epsilon`` of the stacked observation), which a plain ``model.save`` does not keep: add them to
the record by hand.
"""

from __future__ import annotations

import json
from pathlib import Path
from typing import Any

from pendulum_lqg.boundary.schemas import ALGORITHMS, ESTIMATORS, MAX_FRAME_STACK, training_record
from pendulum_lqg.errors import ConfigError
from pendulum_lqg.names import OBSERVATION_MODES
from pendulum_lqg.util.files import atomic_write, output_file
from pendulum_lqg.util.scripts import ScriptParser, int_in, script_status

PROG = "python -m pendulum_lqg.scoreboard.sb3_record"


def record(args: Any) -> dict[str, Any]:
    """The record of the parsed flags (the keys :func:`training_record` reads)."""
    out: dict[str, Any] = {"algo": args.algo, "frame_stack": args.frame_stack,
                           "past_actions": args.past_actions,
                           "normalize_action": args.normalize_action, "obs_norm": None,
                           "env": {"observation_mode": args.observation_mode}}
    if args.estimator is not None:
        out["estimator"] = args.estimator
    out.update({k: getattr(args, k) for k in ("method", "seed") if getattr(args, k) is not None})
    return out


def write_record(model: Path, doc: dict[str, Any], *, force: bool) -> Path:
    """Write ``doc`` beside ``model`` (``MODEL.json``) after checking it as the scorer will."""
    if model.suffix != ".zip":
        raise ConfigError(f"model: expected the path of a stable-baselines3 zip (MODEL.zip), got "
                          f"{str(model)!r}")
    path = output_file("record", model.with_suffix(".json"), what="training record")
    if path.exists() and not force:
        raise ConfigError(f"record: {path} exists; give --force to replace it")
    text = json.dumps(doc, indent=2) + "\n"
    tmp = path.with_name(f".{path.name}.check")
    try:                              # the scorer's own schema, on the very bytes to be written
        tmp.write_text(text, encoding="utf-8")
        training_record(tmp, where_text="record")
    finally:
        tmp.unlink(missing_ok=True)
    atomic_write(path, text)
    return path


def main(argv: list[str] | None = None) -> int:
    return script_status(lambda: _main(argv))


def _main(argv: list[str] | None) -> int:
    ap = ScriptParser(prog=PROG, description=__doc__.splitlines()[0])
    ap.add_argument("model", type=Path, help="the model zip (model.save's file), MODEL.zip")
    ap.add_argument("--algo", required=True, choices=tuple(ALGORITHMS),
                    help="the algorithm's class the model loads with")
    ap.add_argument("--observation-mode", choices=OBSERVATION_MODES, default="measurement",
                    help="the env's observation_mode it was trained on (default measurement)")
    ap.add_argument("--frame-stack", type=int_in(1, MAX_FRAME_STACK), default=1,
                    help="frames of the history it saw, newest last (default 1: none)")
    ap.add_argument("--past-actions", action="store_true",
                    help="each frame is [observation, previous action]")
    ap.add_argument("--estimator", choices=ESTIMATORS, default=None,
                    help="frames of the reference Kalman filter's x̂ instead of y")
    ap.add_argument("--normalize-action", action="store_true",
                    help="trained on actions in [−1, 1] (normalize_action=True)")
    ap.add_argument("--method", default=None, help="the run's method name (optional)")
    ap.add_argument("--seed", type=int_in(0), default=None, help="its training seed (optional)")
    ap.add_argument("--force", action="store_true", help="replace an existing record")
    args = ap.parse_args(argv)
    path = write_record(args.model, record(args), force=args.force)
    print(f"wrote {path}; score it with: pendulum-lqg score --agent sb3:{args.model}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
