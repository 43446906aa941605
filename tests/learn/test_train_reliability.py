"""``pendulum-lqg train`` against issue 55's reliability attack: its run folder locked as
``bench``'s, ``--force`` replacing links and never their targets, a blank ``--out`` refused,
``sysid-lqg`` checkpointed every round, checkpoints and ``--init`` files checked at the boundary,
FIFOs never read, ceilings on ``--steps`` and a folder that cannot be written refused before any
work, a temporary file never left behind, and ``--noise-scale`` named as itself. Every test is
named after the issue's item it covers; none needs torch."""

from __future__ import annotations

import errno
import json
import os
import sys
from pathlib import Path

import pytest
from conftest import run_cli

from pendulum_lqg.cli import main
from pendulum_lqg.learn.runs import Stopped
from pendulum_lqg.learn.train import prepare, run

ROOT = Path(__file__).resolve().parents[2]


def _one_line(status, err, needle):
    assert status == 2, err
    assert "Traceback" not in err and len(err.strip().splitlines()) == 1, err
    assert err.startswith("error: ") and needle in err, err


def _stopped_ars(out, *, seed=0, steps=3000):
    """An ARS run stopped (as by Ctrl-C) after its first curve point past 0: its checkpoint."""
    box = {}

    def log(line):
        if ", success " in line and not line.split(": ", 1)[1].startswith("0 steps"):
            box["ctx"].stop.requested = True

    box["ctx"] = ctx = prepare("ars-history", seed=seed, steps=steps, out=out,
                               options={"eval_every": 1000}, log=log)
    with pytest.raises(Stopped):
        run(ctx)
    assert (Path(out) / f"ars-history-seed{seed}-checkpoint.json").is_file()
    return Path(out) / f"ars-history-seed{seed}-checkpoint.json"


@pytest.fixture
def identification(monkeypatch):
    from stand_ins import closed_loop_module

    calls: list[dict] = []
    monkeypatch.setitem(sys.modules, "pendulum_lqg.learn.closed_loop", closed_loop_module(calls))
    return calls


@pytest.fixture
def rl_installed(monkeypatch):
    """The SB3 methods' extra taken as installed: what is checked before it is imported."""
    monkeypatch.setattr("pendulum_lqg.learn.train.check_extra", lambda info: None)


# ---- 1. the run folder's lock ------------------------------------------------------------------

def _stopped_sysid_lqg(out):
    """A ``sysid-lqg`` run into ``out`` stopped at its first progress line (as Ctrl-C would):
    its checkpoint and the identification's episodes are on disk."""
    box = {}

    def log(line):
        box["ctx"].stop.requested = True

    box["ctx"] = ctx = prepare("sysid-lqg", seed=0, out=out, log=log)
    with pytest.raises(Stopped):
        run(ctx)

def test_item01_train_locks_its_run_folder(capsys, tmp_path, few_curve_episodes):
    """Two runs of one method and seed into one --out, a --force during a run and two --resume
    of one checkpoint: the second is refused with bench's line, and loses nothing."""
    held = prepare("ars-history", seed=0, steps=500, out=tmp_path)     # a run under way
    busy = f"--out: {tmp_path} (ars-history-seed0) is being written by another run (pid {os.getpid()})"
    try:
        status, err = run_cli(capsys, ["train", "ars-history", "--steps", "500", "--out",
                                       str(tmp_path)])
        _one_line(status, err, busy)
        (tmp_path / "ars-history-seed0-checkpoint.json").write_text("the run's own")
        status, err = run_cli(capsys, ["train", "ars-history", "--steps", "500", "--out",
                                       str(tmp_path), "--force"])
        _one_line(status, err, busy)
        assert (tmp_path / "ars-history-seed0-checkpoint.json").read_text() == "the run's own"
        (tmp_path / "ars-history-seed0-checkpoint.json").unlink()
        assert run(held) and not (tmp_path / ".ars-history-seed0.lock").exists()
    finally:
        held.folder.release()
    # two --resume of one checkpoint
    out = tmp_path / "resumed"
    _stopped_ars(out)
    capsys.readouterr()                                   # the stopped run's progress lines
    first = prepare("ars-history", seed=0, steps=3000, out=out, resume=True,
                    options={"eval_every": 1000})
    try:
        status, err = run_cli(capsys, ["train", "ars-history", "--steps", "3000", "--eval-every",
                                       "1000", "--out", str(out), "--resume"])
        _one_line(status, err, "is being written by another run (pid ")
    finally:
        first.folder.release()
    assert main(["train", "ars-history", "--steps", "3000", "--eval-every", "1000", "--out",
                 str(out), "--resume"]) == 0
    assert sorted(p.name for p in out.iterdir()) == ["ars-history-seed0-curve.csv",
                                                     "ars-history-seed0.json"]
    # another seed into the same folder is another run: not refused
    other = prepare("ars-history", seed=1, steps=500, out=tmp_path)
    other.folder.release()


# ---- 2. --force replaces a link, never its target ----------------------------------------------
def test_item02_train_force_replaces_symlinked_run_files_not_their_targets(tmp_path,
                                                                          few_curve_episodes):
    committed = tmp_path / "committed"
    committed.mkdir()
    for name in ("ars-history-seed0.json", "ars-history-seed0-curve.csv"):
        (committed / name).write_text("a committed model")
    out = tmp_path / "runs"
    out.mkdir()
    for name in ("ars-history-seed0.json", "ars-history-seed0-curve.csv"):
        (out / name).symlink_to(committed / name)
    assert main(["train", "ars-history", "--steps", "500", "--out", str(out), "--force"]) == 0
    for name in ("ars-history-seed0.json", "ars-history-seed0-curve.csv"):
        assert (committed / name).read_text() == "a committed model"
        assert not (out / name).is_symlink() and (out / name).stat().st_size > 0
    # bench --force removes through the very same function
    from pendulum_lqg.bench import results
    from pendulum_lqg.util.files import remove_entry

    assert results.remove_entry is remove_entry


# ---- 3. a blank --out ----------------------------------------------------------------------------
@pytest.mark.parametrize("blank", ["", "  "])
def test_item03_train_blank_out_is_refused(capsys, tmp_path, monkeypatch, blank):
    monkeypatch.chdir(tmp_path)
    status, err = run_cli(capsys, ["train", "ars-history", "--steps", "500", "--out", blank])
    _one_line(status, err, f"--out: expected a folder for the run, got {blank!r}")
    assert list(tmp_path.iterdir()) == []


# ---- 12. sysid-lqg checkpointed every round ------------------------------------------------------
def _digest(folder):
    """The run's files, the wall times left out (they differ between two runs)."""
    out = {}
    for p in sorted(folder.iterdir()):
        if p.suffix == ".json":
            doc = json.loads(p.read_text())
            doc["training"].pop("wall_seconds")
            out[p.name] = doc
        elif p.suffix == ".csv":
            rows = [r.split(",") for r in p.read_text().splitlines()]
            out[p.name] = [r[:1] + r[2:] for r in rows]
        else:
            out[p.name] = p.read_bytes()
    return out


@pytest.mark.parametrize("stop_at", ["identification", "curve"])
def test_item12_sysid_lqg_checkpoints_each_round(tmp_path, capsys, identification,
                                                  few_curve_episodes, stop_at):
    """A stop during the identification (after its first stage) or between curve points leaves
    a checkpoint; --resume continues it to the files of an uninterrupted run."""
    assert main(["train", "sysid-lqg", "--seed", "4", "--out", str(tmp_path / "whole")]) == 0
    box = {}

    def log(line):
        if (stop_at == "identification" and line.startswith("stand-in")) or (
                stop_at == "curve" and line.startswith("sysid-lqg-seed4: 10,000 steps")):
            box["ctx"].stop.requested = True

    out = tmp_path / "stopped"
    box["ctx"] = ctx = prepare("sysid-lqg", seed=4, out=out, log=log)
    with pytest.raises(Stopped) as stop:
        run(ctx)
    assert out / "sysid-lqg-seed4-checkpoint.json" in stop.value.wrote
    saved = json.loads((out / "sysid-lqg-seed4-checkpoint.json").read_text())
    if stop_at == "identification":
        assert saved["identification"]["stage"] == 0 and saved["rounds"] is None
        assert (out / "sysid-lqg-seed4-checkpoint-data.npz").is_file()
    else:
        assert saved["points"] == 1 and len(saved["rounds"]) == 2
    assert main(["train", "sysid-lqg", "--seed", "4", "--out", str(out), "--resume"]) == 0
    assert _digest(out) == _digest(tmp_path / "whole")
    resumed = [c for c in identification if "resumed_after" in c]
    assert resumed == ([{"suite": "lecture", "root": 504_000, "steps": None, "resumed_after": 0}]
                       if stop_at == "identification" else [])


# ---- 14. checkpoints checked at the boundary ------------------------------------------------------
def _edit(key_path, value):
    def edit(doc):
        *parents, last = key_path
        for k in parents:
            doc = doc[k]
        doc[last] = value
    return edit


@pytest.mark.parametrize(("damage", "needle"), [
    (lambda text: text[:len(text) // 2], "is not valid JSON"),                    # truncated
    (lambda text: "\x00\xff" + text, "is not valid JSON"),                        # damaged
    (lambda text: "[1, 2, 3]", "expected a table (JSON object)"),                 # foreign
    (lambda text: json.dumps({"score_version": 1}), "settings: missing"),         # foreign
    (_edit(("state", "steps"), 10**12), "state.steps: expected fewer than 3,000"),
    (_edit(("state", "steps"), "many"), "state.steps: expected a non-negative integer"),
    (_edit(("state", "M"), [0.0]), "state.M: expected a list of 192"),
    (_edit(("state", "m2"), None), "state.m2: expected a list of 192"),
    (_edit(("state", "rng"), {"bit_generator": "PCG64", "state": {"state": -1, "inc": 1},
                              "has_uint32": 0, "uinteger": 0}), "state.rng.state.state: expected"),
    (_edit(("state", "rng", "bit_generator"), "MT19937"), "state.rng.bit_generator: expected"),
    (_edit(("state", "log"), [0, 0]), "state.log: expected a list of 3"),
    (_edit(("points",), 10**6), "points: expected at most"),
    (_edit(("settings", "alpha"), 0.5), "settings: expected the run's settings"),
    (_edit(("suite",), "another"), "suite: written on another suite"),
])
def test_item14_train_resume_validates_its_checkpoint(capsys, tmp_path, few_curve_episodes,
                                                      damage, needle):
    path = _stopped_ars(tmp_path)
    capsys.readouterr()                                   # the stopped run's progress lines
    text = path.read_text()
    if damage.__name__ == "edit":
        doc = json.loads(text)
        damage(doc)
        text = json.dumps(doc)
    else:
        text = damage(text)
    path.write_text(text, encoding="utf-8", errors="surrogateescape")
    status, err = run_cli(capsys, ["train", "ars-history", "--steps", "3000", "--eval-every",
                                   "1000", "--out", str(tmp_path), "--resume"])
    _one_line(status, err, f"--resume: {path}")
    assert needle in err, err
    assert path.read_text(encoding="utf-8", errors="surrogateescape") == text   # left as it is


@pytest.mark.parametrize(("name", "content", "needle"), [
    ("ars-history-seed0-curve.csv", "not,a,curve\n", "-curve.csv: expected the header"),
    ("ars-history-seed0-curve.csv", None, "-curve.csv: line 2: env_steps: expected a count"),
])
def test_item14_train_resume_validates_the_curve_beside_its_checkpoint(
        capsys, tmp_path, few_curve_episodes, name, content, needle):
    _stopped_ars(tmp_path)
    capsys.readouterr()                                   # the stopped run's progress lines
    path = tmp_path / name
    if content is None:
        lines = path.read_text().splitlines()
        content = "\n".join([lines[0], "x" + lines[1], *lines[2:]]) + "\n"
    path.write_text(content)
    status, err = run_cli(capsys, ["train", "ars-history", "--steps", "3000", "--eval-every",
                                   "1000", "--out", str(tmp_path), "--resume"])
    _one_line(status, err, needle)


@pytest.mark.parametrize(("edit", "needle"), [
    (_edit(("identification", "stage"), "x"), "identification.stage: expected"),
    (_edit(("identification", "rng"), []), "identification.rng: expected a table"),
    (_edit(("identification", "results"), []), "identification.results: expected 1"),
    (_edit(("steps",), 10**12), "steps: written for --steps"),
    (_edit(("seed",), 7), "seed: written for --seed 7"),
    (None, "-checkpoint-data.npz: not a .npz file"),
])
def test_item14_sysid_lqg_resume_validates_its_checkpoint(capsys, tmp_path, identification,
                                                          few_curve_episodes, edit, needle):
    _stopped_sysid_lqg(tmp_path)
    path = tmp_path / "sysid-lqg-seed0-checkpoint.json"
    if edit is None:
        (tmp_path / "sysid-lqg-seed0-checkpoint-data.npz").write_bytes(b"PK\x03\x04 truncated")
    else:
        doc = json.loads(path.read_text())
        edit(doc)
        path.write_text(json.dumps(doc))
    status, err = run_cli(capsys, ["train", "sysid-lqg", "--out", str(tmp_path), "--resume"])
    _one_line(status, err, "--resume: ")
    assert needle in err, err


# ---- 15. --init files' training keys -------------------------------------------------------------
@pytest.mark.parametrize(("training", "needle"), [
    ({"samples": "many"}, "training.samples: expected a non-negative integer, got 'many'"),
    ({"samples": 2.5}, "training.samples: expected a non-negative integer"),
    ([1, 2], "training: expected a table"),
    ({"budget": [1]}, "training.budget: expected a table"),
    ({"budget": {"steps": "x"}}, "training.budget.steps: expected a non-negative integer"),
])
def test_item15_init_file_with_wrongly_typed_training_keys_is_refused(capsys, tmp_path,
                                                                      training, needle):
    from pendulum_lqg.scoreboard.linear import controller_file

    size = 3 * 64
    doc = controller_file("history", {"frames": 64, "weights": [0.0] * size, "bias": 0.0,
                                      "mean": [0.0] * size, "std": [1.0] * size},
                          action_scale=1.0, env={}, method="ls-clone", seed=0,
                          training=training)
    init = tmp_path / "clone.json"
    init.write_text(json.dumps(doc))
    status, err = run_cli(capsys, ["train", "ars-history-clone", "--init", str(init), "--steps",
                                   "500", "--out", str(tmp_path / "o")])
    _one_line(status, err, f"--init: {init}: {needle}")
    assert not (tmp_path / "o").exists()


# ---- 16. FIFOs as checkpoint files --------------------------------------------------------------
@pytest.mark.parametrize("fifo", ["-checkpoint.zip", "-checkpoint-vecnormalize.pkl",
                                  "-checkpoint-replay.pkl"])
def test_item16_a_fifo_as_an_sb3_checkpoint_is_refused(capsys, tmp_path, rl_installed, fifo):
    """The FIFO is refused before SB3 (or torch) is imported: nothing here needs them."""
    from pendulum_lqg.scoreboard.suites import load_suite

    name = "sac-history-seed0"
    (tmp_path / f"{name}-checkpoint.json").write_text(json.dumps(
        {"algo": "SAC", "steps": 1000, "points": 0, "suite": load_suite("lecture").fingerprint(),
         "wall_seconds": 1.0}))
    for suffix in ("-checkpoint.zip", "-checkpoint-vecnormalize.pkl"):
        (tmp_path / f"{name}{suffix}").write_bytes(b"a stand-in")
    (tmp_path / f"{name}{fifo}").unlink(missing_ok=True)
    os.mkfifo(tmp_path / f"{name}{fifo}")
    status, err = run_cli(capsys, ["train", "sac-history", "--out", str(tmp_path), "--resume"])
    _one_line(status, err, f"--resume: {tmp_path / (name + fifo)} is a FIFO (named pipe); "
                           "expected a regular file")


def test_item16_a_fifo_as_the_sysid_lqg_data_is_refused(capsys, tmp_path, identification,
                                                        few_curve_episodes):
    _stopped_sysid_lqg(tmp_path)
    data = tmp_path / "sysid-lqg-seed0-checkpoint-data.npz"
    data.unlink()
    os.mkfifo(data)
    status, err = run_cli(capsys, ["train", "sysid-lqg", "--out", str(tmp_path), "--resume"])
    _one_line(status, err, f"--resume: {data} is a FIFO (named pipe); expected a regular file")


# ---- 17. ceilings on --steps ----------------------------------------------------------------------
@pytest.mark.parametrize(("args", "needle"), [
    (["ls-clone", "--steps", "10000000000"], "--steps: expected at most 208,333 for ls-clone"),
    (["ls-clone", "--frames", "1024", "--steps", "20000"],
     "--steps: expected at most 13,020 for ls-clone"),
    (["sysid-openloop", "--steps", "10000000000"],
     "--steps: expected at most 10,000,000 for sysid-openloop"),
    (["sysid-lqg", "--steps", "10000000000"], "--steps: expected at most 1,000,000 for sysid-lqg"),
])
def test_item17_huge_steps_are_refused_before_any_work(capsys, tmp_path, identification, args,
                                                       needle):
    status, err = run_cli(capsys, ["train", *args, "--out", str(tmp_path / "o")])
    _one_line(status, err, needle)
    assert identification == [] and not (tmp_path / "o").exists()


def test_item17_the_ceilings_are_documented():
    from pendulum_lqg.learn.train import CLONE_MAX_VALUES, METHOD_MAX_STEPS

    text = (ROOT / "docs" / "leaderboard.md").read_text()
    paragraph = text.split("**`--steps` has a ceiling", 1)[1].split("\n\n", 1)[0]
    for number in (*METHOD_MAX_STEPS.values(), CLONE_MAX_VALUES):
        assert f"{number:,}".replace(",", " ") in paragraph, number


# ---- 19. a folder that cannot be written; no temporary file left ------------------------------
def test_item19_train_into_an_unwritable_folder_is_refused_before_any_work(capsys, tmp_path):
    if os.geteuid() == 0:
        out = Path("/proc/self")                  # root writes any mode: a folder of the kernel's
    else:
        out = tmp_path / "read-only"
        out.mkdir()
        out.chmod(0o555)
    status, err = run_cli(capsys, ["train", "ars-history", "--steps", "500", "--out", str(out)])
    _one_line(status, err, f"--out: cannot write into {out} (")
    assert "steps, success" not in err                           # nothing trained


def test_item19_an_sb3_checkpoint_write_that_fails_leaves_no_temporary_file(tmp_path):
    """A file-size limit (EFBIG) while SB3 writes: the error is the user's file's, and neither
    a temporary file nor a half checkpoint is left."""
    from types import SimpleNamespace

    from pendulum_lqg.learn import deep
    from pendulum_lqg.learn.runs import RunContext

    def save(path):
        Path(path).write_bytes(b"half a model")
        raise OSError(errno.EFBIG, "File too large", path)

    ctx = RunContext(method="ppo-history", seed=0, suite=None, out=tmp_path)
    model = SimpleNamespace(save=save, num_timesteps=10)
    with pytest.raises(OSError) as exc:
        deep._checkpoint(ctx, model, SimpleNamespace(save=save), SimpleNamespace(points=[]))
    assert exc.value.errno == errno.EFBIG
    assert exc.value.filename == str(tmp_path / "ppo-history-seed0-checkpoint.zip")
    assert list(tmp_path.iterdir()) == []


# ---- 22. --noise-scale named as itself; -0.0 is 0 ------------------------------------------------
def test_item22_noise_scale_errors_name_the_flag_and_minus_zero_is_zero(capsys, tmp_path,
                                                                        rl_installed):
    status, err = run_cli(capsys, ["train", "ppo-history", "--noise-scale", "1e300", "--out",
                                   str(tmp_path / "o")])
    _one_line(status, err, "--noise-scale: expected at most 1e+12")
    assert "[env]" not in err and "suite" not in err
    names = set()
    for value in ("0", "-0.0", "0.0", "-0"):
        ctx = prepare("ppo-history", seed=0, out=tmp_path / value, options={"noise_scale": value})
        ctx.folder.release()
        names.add(ctx.name)
    assert names == {"ppo-history-noise0-seed0"}


# ---- the small things ---------------------------------------------------------------------------
def test_train_list_budgets_agree_with_the_docs(capsys):
    """The methods table of docs/leaderboard.md gives each method's default budget as --list
    does (ARS: 200 000, what the committed runs used; sysid-lqg: what its default recipe logs at
    most, 70 020)."""
    from pendulum_lqg.learn.ars import ARSSettings
    from pendulum_lqg.learn.closed_loop import ClosedLoopSettings
    from pendulum_lqg.learn.methods import METHODS

    assert main(["train", "--list"]) == 0
    lines = {line.split()[0]: line for line in capsys.readouterr().out.splitlines()}
    table = {}
    text = (ROOT / "docs" / "leaderboard.md").read_text()
    methods = text.split("| method | algorithm | what the policy sees | env steps | envs |", 1)[1]
    for row in methods.split("\n\n", 1)[0].splitlines():
        cells = [c.strip() for c in row.split("|")]
        if len(cells) == 7 and cells[1].strip("`") in METHODS and (
                cells[4][:1].isdigit() or cells[4][:1] == "≤"):
            table[cells[1].strip("`")] = cells[4]
    assert {"ars-history", "ars-history-clone", "sysid-lqg", "ppo-history"} <= set(table), table
    assert ARSSettings().steps == METHODS["ars-history"].steps == 200_000
    s = ClosedLoopSettings()
    most = -(-s.open_loop_steps // s.burst) * s.burst + s.rounds * s.episodes * 1000
    assert METHODS["sysid-lqg"].steps == most == 70_020
    for name, cell in table.items():
        steps = METHODS[name].steps
        assert f"{steps:,}".replace(",", " ") in cell, (name, cell, steps)
        assert f"{steps:,}" in lines[name], lines[name]


def test_scores_folder_of_the_documented_score_command_is_ignored_by_git():
    assert "/scores/" in (ROOT / ".gitignore").read_text().splitlines()


def test_sb3_logger_writes_into_the_run_folder_not_the_system_temp(tmp_path):
    pytest.importorskip("stable_baselines3")
    import tempfile

    from pendulum_lqg.learn.deep import METHODS as SB3
    from pendulum_lqg.learn.deep import _log_into, build
    from pendulum_lqg.scoreboard.suites import load_suite

    before = {p.name for p in Path(tempfile.gettempdir()).glob("SB3-*")}
    model, _ = build(SB3["ppo-lecture"], 0, load_suite("lecture"))
    _log_into(model, tmp_path)
    model.learn(total_timesteps=64)
    assert {p.name for p in Path(tempfile.gettempdir()).glob("SB3-*")} == before
