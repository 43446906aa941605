"""A report on corrupt results names the file and the key."""

from __future__ import annotations

import json

import pytest
from conftest import assert_one_line_error, run_cli

from pendulum_lqg.errors import ConfigError


def _results_folder(tmp_path, study=None, summary=None, spec=None):
    folder = tmp_path / "res"
    folder.mkdir()
    src = {"study": study} if study else {}
    (folder / "spec.json").write_text(spec if spec is not None
                                      else json.dumps({"name": "r", "spec": src}))
    (folder / "summary.md").write_text("| a |\n|---|\n| 1 |\n")
    if study == "margins":
        (folder / "nyquist.csv").write_text("loop,re,im\nLQ (continuous),0.1,0.2\n")
        (folder / "ltr.csv").write_text("measurement,q,phase_margin_deg,min_return_difference,"
                                        "disk_margin\nfull,1,60,1,0.5\n")
    if summary is not None:
        (folder / "summary.json").write_text(summary)
    return folder


@pytest.mark.parametrize(("study", "spec", "summary", "message"), [
    (None, '{"name": "r", "spec": {', None, "spec.json is not valid JSON"),
    (None, "[1, 2]", None, "spec.json: expected a JSON object, got list"),
    (None, '{"name": "r", "spec": {"grid": 5}}', None,
     "spec.json: key 'spec.grid': expected an object, got 5"),
    (None, '{"name": "r", "spec": {"grid": {"noise_scale": 1}}}', None,
     "spec.json: key 'spec.grid.noise_scale': expected a list, got 1"),
    (None, '{"name": 5}', None, "spec.json: key 'name': expected a string, got 5"),
    (None, '{"name": "../../x"}', None, "spec.json: key 'name': expected a plain name"),
    ("margins", None, '{"loops": ', "summary.json is not valid JSON"),
    ("margins", None, '{"loops": "x"}', "summary.json: key 'loops': expected a list"),
    ("margins", None, '{"loops": [{"loop": "LQ (c)", "phase_margin_deg": "60"}]}',
     "summary.json: key 'loops[0].phase_margin_deg': expected a number, got '60'"),
    ("roa", None, "\xff", "summary.json is not valid JSON"),
    ("roa", None, '{"params": {"map_theta": "a"}}',
     "summary.json: key 'params.map_theta': expected a list"),
    ("roa", None, "", "summary.json is not valid JSON"),
])
def test_report_on_corrupt_results_names_the_file(tmp_path, capsys, study, spec, summary,
                                                   message):
    folder = _results_folder(tmp_path, study, summary, spec)
    status, err = run_cli(capsys, ["report", str(folder), "--out", str(tmp_path / "rep")])
    assert_one_line_error(status, err, "results: ")
    assert message in err and str(folder) in err, err


def test_report_json_reader_from_the_python_api(tmp_path):
    from pendulum_lqg.analysis.report import make_report

    folder = _results_folder(tmp_path, "roa", summary='{"params": 1}')
    (folder / "summary.json").write_bytes(b'{"params": "\xff"}')
    with pytest.raises(ConfigError, match=r"^results: .*summary.json is not UTF-8 text"):
        make_report([folder], tmp_path / "rep")
