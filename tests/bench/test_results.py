"""Results folders: --force empties only our folders, names are plain, resume verifies every unit."""

from __future__ import annotations

import json
from pathlib import Path

import pytest

from pendulum_lqg.bench.results import check_name, versions
from pendulum_lqg.cli import main
from pendulum_lqg.errors import ConfigError

SMALL = """
name = "small"
episodes = 4
seed = 3
chunk = 2
[scenario]
duration = 0.3
[grid]
policy = ["dlqr+kalman", "dlqr+luenberger"]
"""


def _bench(tmp_path: Path, *extra: str, text: str = SMALL, out: str | None = None) -> int:
    spec = tmp_path / "small.toml"
    spec.write_text(text)
    return main(["bench", str(spec), "--out", out or str(tmp_path / "out"), "--quiet", *extra])


def _err_line(capsys) -> str:
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1, err
    return err[0]


# ---- where results may go ------------------------------------------------------------------------
@pytest.mark.parametrize("name", ["", ".", "..", "../../x", "/abs/path", "a/b", "-rf", "x" * 101])
def test_experiment_names_must_be_plain(name):
    with pytest.raises(ConfigError, match=r"^name: expected a plain name"):
        check_name(name)


@pytest.mark.parametrize("name", ["..", "", "../../escape", "/tmp/abs"])
def test_a_bad_name_writes_and_deletes_nothing(tmp_path, monkeypatch, capsys, name):
    work = tmp_path / "work"
    (work / "results" / "other").mkdir(parents=True)
    keep = work / "results" / "other" / "keep.txt"
    keep.write_text("precious")
    (work / "beside.txt").write_text("precious")
    monkeypatch.chdir(work)
    spec = work / "bad.toml"
    spec.write_text(SMALL.replace('name = "small"', f"name = {json.dumps(name)}"))
    assert main(["bench", str(spec), "--quiet", "--force"]) == 2
    assert "name: expected a plain name" in _err_line(capsys)
    assert keep.read_text() == "precious" and (work / "beside.txt").exists()
    assert sorted(p.name for p in (work / "results").iterdir()) == ["other"]


def test_force_refuses_a_folder_that_is_not_ours(tmp_path, capsys):
    folder = tmp_path / "mine"
    folder.mkdir()
    (folder / "thesis.tex").write_text("precious")
    assert _bench(tmp_path, "--force", out=str(folder)) == 2
    assert "holds no pendulum_lqg spec.json" in _err_line(capsys)
    assert (folder / "thesis.tex").read_text() == "precious"


@pytest.mark.parametrize("where", ["cwd", "parent", "home"])
def test_force_never_empties_the_current_folder_a_parent_or_home(tmp_path, monkeypatch, capsys,
                                                                 where):
    project = tmp_path / "home" / "project"
    project.mkdir(parents=True)
    monkeypatch.setenv("HOME", str(tmp_path / "home"))
    monkeypatch.chdir(project)
    target = {"cwd": project, "parent": project.parent, "home": tmp_path / "home"}[where]
    (target / "spec.json").write_text(json.dumps({"fingerprint": "x", "name": "small"}))
    (project / "code.py").write_text("precious")
    assert _bench(tmp_path, "--force", out=str(target)) == 2
    assert "--force: refusing to empty" in _err_line(capsys)
    assert (project / "code.py").read_text() == "precious"


def test_out_pointing_at_a_file_and_record_at_a_file_are_refused_up_front(tmp_path, capsys):
    file = tmp_path / "notes.txt"
    file.write_text("x")
    assert _bench(tmp_path, out=str(file)) == 2
    assert _err_line(capsys).startswith("error: out: ") and file.read_text() == "x"
    assert _bench(tmp_path, "--record", str(file)) == 2
    assert "--record:" in _err_line(capsys)
    assert not (tmp_path / "out" / "units").exists() or not any((tmp_path / "out" / "units").iterdir())


def test_a_read_only_folder_is_a_one_line_error(tmp_path, capsys, monkeypatch):
    """A folder we may not write into (simulated: the tests run as root here, where a read-only
    mode does not stop writes) ends in one line naming it, exit 2."""
    import errno

    ro = tmp_path / "ro"
    real_mkdir = Path.mkdir

    def refuse(self, *args, **kwargs):
        if self.is_relative_to(ro):
            raise PermissionError(errno.EACCES, "Permission denied", str(self))
        return real_mkdir(self, *args, **kwargs)

    monkeypatch.setattr(Path, "mkdir", refuse)
    assert _bench(tmp_path, out=str(ro / "out")) == 2
    line = _err_line(capsys)
    assert "out: cannot write into" in line and "Permission denied" in line
    assert not ro.exists()


# ---- verified resume -----------------------------------------------------------------------------
def _complete(tmp_path: Path) -> tuple[Path, bytes]:
    assert _bench(tmp_path) == 0
    out = tmp_path / "out"
    return out, (out / "episodes.csv").read_bytes()


def _edit_value(path: Path) -> None:
    lines = path.read_text().splitlines()
    cells = lines[1].split(",")
    cells[-3] = "123.0"
    lines[1] = ",".join(cells)
    path.write_text("\n".join(lines) + "\n")


def _drop_row(path: Path) -> None:
    lines = path.read_text().splitlines()
    path.write_text("\n".join(lines[:-1]) + "\n")


def _cut_mid_row(path: Path) -> None:
    data = path.read_bytes()
    path.write_bytes(data[: len(data) - 25])


def _empty(path: Path) -> None:
    path.write_text("")


@pytest.mark.parametrize("damage", [_edit_value, _drop_row, _cut_mid_row, _empty])
def test_resume_recomputes_a_damaged_unit(tmp_path, capsys, damage):
    out, full = _complete(tmp_path)
    unit = sorted((out / "units").glob("*.csv"))[1]
    damage(unit)
    (out / "summary.json").unlink()
    capsys.readouterr()
    spec = tmp_path / "small.toml"
    assert main(["bench", str(spec), "--out", str(out), "--resume"]) == 0
    err = capsys.readouterr().err
    assert f"unit {unit.stem}:" in err and "recomputing it" in err
    assert (out / "episodes.csv").read_bytes() == full
    assert json.loads((out / "summary.json").read_text())["configurations"][0]["summary"][
        "episodes"] == 4


def test_resume_can_refuse_a_damaged_unit_naming_it(tmp_path, capsys):
    out, _ = _complete(tmp_path)
    unit = sorted((out / "units").glob("*.csv"))[0]
    _drop_row(unit)
    capsys.readouterr()
    assert _bench(tmp_path, "--resume", "--on-mismatch", "refuse") == 2
    line = _err_line(capsys)
    assert f"unit {unit.stem} fails its check" in line and "rows" in line


def test_resume_without_spec_json_does_not_mix_seeds(tmp_path, capsys):
    out, _ = _complete(tmp_path)                   # seed 3
    (out / "spec.json").unlink()
    for f in sorted((out / "units").glob("*.csv"))[2:]:
        f.unlink()                                 # half the units of seed 3 remain
    assert _bench(tmp_path, "--resume", "--seed", "4") == 0
    mixed = (out / "episodes.csv").read_bytes()
    fresh = tmp_path / "fresh"
    assert _bench(tmp_path, "--seed", "4", out=str(fresh)) == 0
    assert mixed == (fresh / "episodes.csv").read_bytes()


def test_units_from_another_configuration_are_not_trusted(tmp_path):
    out, full = _complete(tmp_path)
    units = sorted((out / "units").glob("*.csv"))
    # swap two units of different configurations, with their check records
    a, b = units[0], units[-1]
    for ext in (".csv", ".json"):
        pa, pb = a.with_suffix(ext), b.with_suffix(ext)
        ta, tb = pa.read_bytes(), pb.read_bytes()
        pa.write_bytes(tb)
        pb.write_bytes(ta)
    assert _bench(tmp_path, "--resume") == 0
    assert (out / "episodes.csv").read_bytes() == full


def test_spec_and_meta_record_versions_and_resume_across_a_change_is_refused(tmp_path, capsys):
    out, full = _complete(tmp_path)
    spec_json = json.loads((out / "spec.json").read_text())
    assert spec_json["versions"] == versions()
    assert set(versions()) == {"pendulum_lqg", "mujoco", "numpy", "scipy", "control"}
    assert json.loads((out / "meta.json").read_text())["versions"] == versions()
    spec_json["versions"]["mujoco"] = "3.0.0"
    (out / "spec.json").write_text(json.dumps(spec_json))
    capsys.readouterr()
    assert _bench(tmp_path, "--resume") == 2
    line = _err_line(capsys)
    assert "mujoco 3.0.0" in line and "--allow-version-change" in line
    assert _bench(tmp_path, "--resume", "--allow-version-change") == 0
    assert (out / "episodes.csv").read_bytes() == full


def test_a_full_disk_is_a_one_line_error_and_finished_units_stay(tmp_path, capsys, monkeypatch):
    import errno

    import pendulum_lqg.bench.results as results

    real = results.atomic_write
    calls = {"n": 0}

    def full_after_two(path, text):
        calls["n"] += 1
        if calls["n"] > 4:                        # spec.json, 1 unit (csv + record), …
            raise OSError(errno.ENOSPC, "No space left on device", str(path))
        real(path, text)

    monkeypatch.setattr(results, "atomic_write", full_after_two)
    assert _bench(tmp_path) == 2
    line = _err_line(capsys)
    assert "No space left on device" in line and line.startswith("error: cannot write")
    monkeypatch.setattr(results, "atomic_write", real)
    assert len(list((tmp_path / "out" / "units").glob("*.json"))) >= 1
    assert _bench(tmp_path, "--resume") == 0
