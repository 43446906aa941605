"""pendulum_lqg.learn.noise_ladder without the rl extra: the reference scored at each noise scale
is what ``score --noise-scale`` writes, and the figure's table is the median and quartiles of the
runs in each group; its outputs follow the command line's rule (a device, a FIFO, an existing file
without --force: one line, exit 2, nothing written)."""

from __future__ import annotations

import json
from pathlib import Path

import pytest

from pendulum_lqg.cli import main
from pendulum_lqg.learn import noise_ladder

ROOT = Path(__file__).resolve().parents[2]


@pytest.fixture(scope="module")
def ladder():
    return noise_ladder


def test_the_ladder_scores_are_the_score_commands_files_and_make_a_table(ladder, tmp_path,
                                                                          capsys):
    folder = tmp_path / "ladder"
    assert ladder.main(["score", "--scales", "0", "1", "--episodes", "3",
                        "--scores", str(folder)]) == 0
    assert sorted(p.name for p in folder.iterdir()) == ["reference-at0.json", "reference-at1.json"]
    assert main(["score", "dlqr+kalman", "--suite", "lecture", "--episodes", "3",
                 "--noise-scale", "0", "--out", str(tmp_path / "cli.json")]) == 0
    assert (folder / "reference-at0.json").read_bytes() == (tmp_path / "cli.json").read_bytes()
    # two runs of a method trained at the suite's noise, three of one trained on the ladder
    base = json.loads((folder / "reference-at1.json").read_text())
    for k, (success, score) in enumerate([(0.2, 0.1), (0.6, 0.5)]):
        doc = {**base, "policy": f"sb3:m{k}.zip", "kind": "agent", "method": "ppo-history",
               "seed": k}
        doc["suites"]["lecture"].update(success_rate=success, score_mean=score)
        (folder / f"m{k}-at1.json").write_text(json.dumps(doc))
    for k, success in enumerate([0.1, 0.3, 0.9]):
        doc = {**base, "policy": f"sb3:n{k}.zip", "kind": "agent",
               "method": "ppo-history-noise1", "seed": k}
        doc["suites"]["lecture"].update(success_rate=success, score_mean=success / 2)
        (folder / f"n{k}-at1.json").write_text(json.dumps(doc))
    table = ladder.ladder_table(folder, "lecture")
    assert sorted(table) == ["LQG reference (dlqr+kalman)",
                             "ppo-history (trained at the scored noise)",
                             "ppo-history (trained at the suite's noise)"]
    assert sorted(table["LQG reference (dlqr+kalman)"]) == [0.0, 1.0]
    text = ladder.markdown(table, "lecture")
    row = next(line for line in text.splitlines() if "suite's noise" in line)
    assert row.endswith("| 2 |  | 40 % [30, 50], 0.30 [0.20, 0.40] |")    # median, quartiles
    row = next(line for line in text.splitlines() if "scored noise" in line)
    assert row.endswith("| 3 |  | 30 % [20, 60], 0.15 [0.10, 0.30] |")
    capsys.readouterr()
    assert ladder.main(["figure", "--scores", str(folder),
                        "--figure", str(tmp_path / "fig" / "ladder.png")]) == 0
    assert (tmp_path / "fig" / "ladder.png").stat().st_size > 10_000
    assert (tmp_path / "fig" / "ladder.md").read_text() == text


def _one_line_exit_2(capsys, status, needle):
    err = capsys.readouterr().err
    assert status == 2, err
    assert "Traceback" not in err and len(err.strip().splitlines()) == 1, err
    assert err.startswith("error: ") and needle in err, err


@pytest.fixture(scope="module")
def ladder_scores(tmp_path_factory):
    folder = tmp_path_factory.mktemp("ladder")
    assert noise_ladder.main(["score", "--scales", "0", "1", "--episodes", "2",
                              "--scores", str(folder)]) == 0
    return folder


def test_noise_ladder_figure_refuses_a_device(ladder_scores, capsys):
    status = noise_ladder.main(["figure", "--scores", str(ladder_scores), "--figure",
                                "/dev/null"])
    _one_line_exit_2(capsys, status, "/dev/null is a character device")


def test_noise_ladder_figure_refuses_a_fifo(ladder_scores, tmp_path, capsys):
    import os

    fifo = tmp_path / "ladder.png"
    os.mkfifo(fifo)
    status = noise_ladder.main(["figure", "--scores", str(ladder_scores), "--figure", str(fifo)])
    _one_line_exit_2(capsys, status, "is a FIFO")


def test_noise_ladder_replaces_a_figure_only_with_force(ladder_scores, tmp_path, capsys):
    figure = tmp_path / "ladder.png"
    figure.write_bytes(b"mine")
    status = noise_ladder.main(["figure", "--scores", str(ladder_scores), "--figure", str(figure)])
    _one_line_exit_2(capsys, status, "exists; give --force")
    assert figure.read_bytes() == b"mine"
    assert noise_ladder.main(["figure", "--scores", str(ladder_scores), "--figure", str(figure),
                              "--force"]) == 0
    assert figure.read_bytes()[:4] == b"\x89PNG"
    assert not [p for p in tmp_path.iterdir() if p.name.startswith(".")]     # no temp left


def test_noise_ladder_score_refuses_to_replace_score_files(ladder_scores, capsys):
    before = (ladder_scores / "reference-at0.json").read_bytes()
    status = noise_ladder.main(["score", "--scales", "0", "--episodes", "2",
                                "--scores", str(ladder_scores)])
    _one_line_exit_2(capsys, status, "reference-at0.json exists; give --force")
    assert (ladder_scores / "reference-at0.json").read_bytes() == before


def test_noise_ladder_library_error_is_one_line(tmp_path, capsys):
    status = noise_ladder.main(["score", "--suite", "no-such-suite", "--scores", str(tmp_path)])
    _one_line_exit_2(capsys, status, "no-such-suite")
