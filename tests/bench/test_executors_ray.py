"""Sweeps on Ray: byte-identical to the local executor, node loss, interrupt + resume, failures.

Ray starts only in this module (a local instance per test that needs one, or a
``ray.cluster_utils.Cluster``); without the ``ray`` extra these tests are skipped and
``--executor ray`` is a one-line error (the last test checks that in any case).
"""

from __future__ import annotations

import os
import signal
import subprocess
import sys
import time
from pathlib import Path

import pytest
from conftest import interruptible_cli

from pendulum_lqg.bench.experiments import load_spec, parse_spec
from pendulum_lqg.bench.sweep import run_sweep
from pendulum_lqg.cli import main

HERE = Path(__file__).parents[1]
PLUGINS = HERE / "plugins" / "lqg_plugins.py"


def _files(folder: Path) -> tuple[bytes, bytes]:
    return (folder / "episodes.csv").read_bytes(), (folder / "summary.json").read_bytes()


@pytest.fixture(scope="module")
def local_results(tmp_path_factory) -> Path:
    """``bench lecture --episodes 20`` on the local executor, the reference."""
    out = tmp_path_factory.mktemp("local") / "lecture"
    assert main(["bench", "lecture", "--episodes", "20", "--out", str(out), "--quiet"]) == 0
    return out


@pytest.fixture
def ray_module():
    ray = pytest.importorskip("ray")
    yield ray
    if ray.is_initialized():
        ray.shutdown()


@pytest.mark.slow
def test_local_ray_with_2_cpus_is_byte_identical(ray_module, local_results, tmp_path, capsys):
    from pendulum_lqg.bench.executors import RayExecutor

    out = tmp_path / "ray"
    executor = RayExecutor(num_cpus=2)
    assert executor.max_in_flight == 4
    spec = load_spec("lecture").with_overrides(episodes=20)
    result = run_sweep(spec, out, executor=executor, progress=False)
    assert result.complete and result.units_run == 10
    assert _files(out) == _files(local_results)
    assert not ray_module.is_initialized()          # the instance started for the run is gone
    # (the command line's --executor ray: the interrupted-sweep and failing-unit tests below)


@pytest.mark.slow
def test_two_node_cluster_losing_a_node_mid_sweep_completes_identically(ray_module, tmp_path):
    from ray.cluster_utils import Cluster

    from pendulum_lqg.bench.executors import RayExecutor

    spec = load_spec("lecture").with_overrides(episodes=20)
    spec = parse_spec({**spec.source, "chunk": 5}, name="lecture")       # 40 units of 5 episodes
    assert main(["bench", "lecture", "--episodes", "20", "--out", str(tmp_path / "ref"),
                 "--quiet"]) == 0  # (chunking does not change the rows; checked below)
    cluster = Cluster(initialize_head=True, head_node_args={"num_cpus": 0})
    try:
        cluster.add_node(num_cpus=1)
        doomed = cluster.add_node(num_cpus=1)
        ray_module.init(address=cluster.address)
        cluster.wait_for_nodes()

        class LosesANode(RayExecutor):
            def run(self, units):
                for i, outcome in enumerate(super().run(units)):
                    if i == 1:
                        cluster.remove_node(doomed)        # tasks on it are lost and retried
                    yield outcome

        executor = LosesANode(address=cluster.address)
        assert executor.max_in_flight == 4
        result = run_sweep(spec, tmp_path / "cluster", executor=executor, progress=False)
        assert result.complete and result.units_total == 40
        alive = [n for n in ray_module.nodes() if n["Alive"] and n["Resources"].get("CPU")]
        assert len(alive) == 1
    finally:
        ray_module.shutdown()
        cluster.shutdown()
    assert _files(tmp_path / "cluster") == _files(tmp_path / "ref")


@pytest.mark.slow
def test_interrupted_ray_sweep_resumes_to_identical_results(ray_module, local_results, tmp_path):
    out = tmp_path / "interrupted"
    cmd = interruptible_cli("bench", "lecture", "--episodes", "20", "--out", out, "--quiet",
                            "--executor", "ray")
    proc = subprocess.Popen(cmd, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    deadline = time.monotonic() + 120
    while time.monotonic() < deadline and len(list((out / "units").glob("*.csv"))) < 2:
        time.sleep(0.05)
    os.kill(proc.pid, signal.SIGINT)
    _, err = proc.communicate(timeout=120)
    assert proc.returncode == 130, err
    saved = len(list((out / "units").glob("*.csv")))
    assert 2 <= saved < 10 and not (out / ".lock").exists()
    assert "--resume" in err and "--executor ray" in err and "--episodes 20" in err
    assert main(["bench", "lecture", "--episodes", "20", "--out", str(out), "--quiet",
                 "--resume", "--executor", "ray"]) == 0
    assert _files(out) == _files(local_results)


@pytest.mark.slow
def test_a_unit_that_keeps_failing_is_reported_and_the_rest_finishes(ray_module, tmp_path,
                                                                     capsys):
    toml = tmp_path / "mixed.toml"
    toml.write_text(f'name = "mixed"\nepisodes = 4\nseed = 1\n[scenario]\nduration = 1.0\n'
                    f'[grid]\npolicy = ["dlqr+kalman", "{PLUGINS}:raises"]\n')
    out = tmp_path / "mixed"
    assert main(["bench", str(toml), "--out", str(out), "--quiet", "--executor", "ray"]) == 1
    err = capsys.readouterr().err
    assert "error: work unit c001_e000000-000004 failed: PluginError" in err
    assert "1/2 work units failed" in err and "--resume" in err
    assert [p.name for p in (out / "units").glob("*.csv")] == ["c000_e000000-000004.csv"]
    assert not (out / "episodes.csv").exists()


def test_without_ray_the_executor_is_a_one_line_error(monkeypatch, tmp_path, capsys):
    monkeypatch.setitem(sys.modules, "ray", None)          # `import ray` raises ImportError
    assert main(["bench", "lecture", "--episodes", "2", "--out", str(tmp_path / "x"),
                 "--executor", "ray"]) == 2
    err = capsys.readouterr().err.strip().splitlines()[-1]
    assert err == ("error: --executor ray: Ray is not installed; install the extra: pip install "
                   "'pendulum-lqg[ray]' (in a checkout: uv run --extra ray pendulum-lqg …)")
    assert main(["bench", "lecture", "--address", "auto", "--out", str(tmp_path / "y")]) == 2
    assert "--address: only with --executor ray" in capsys.readouterr().err


def test_an_address_where_nothing_listens_fails_at_once_with_one_line(tmp_path, capsys):
    import socket

    from conftest import assert_one_line_error, run_cli

    with socket.socket() as held:                   # bound, never listening: refused, and no
        held.bind(("127.0.0.1", 0))                 # other process can take the port meanwhile
        address = f"127.0.0.1:{held.getsockname()[1]}"
        t = time.perf_counter()
        status, err = run_cli(capsys, ["bench", "lecture", "--episodes", "2", "--out",
                                       str(tmp_path / "o"), "--executor", "ray",
                                       "--address", address])
        assert time.perf_counter() - t < 60
    assert_one_line_error(status, err, f"--address: no Ray cluster answers at {address} "
                                       "(Connection refused within 10 s)")
    assert not (tmp_path / "o").exists()
    for bad in ("nowhere", "host:port", "10.0.0.1:99999"):
        status, err = run_cli(capsys, ["bench", "lecture", "--out", str(tmp_path / "o"),
                                       "--executor", "ray", "--address", bad])
        assert_one_line_error(status, err, "--address: expected 'auto' or HOST:PORT")
