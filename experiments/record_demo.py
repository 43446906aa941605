"""Record a failing Luenberger and a succeeding Kalman episode of the lecture scenario; time it.

    uv run python experiments/record_demo.py [--out DIR] [--screenshot]

Writes ``DIR/luenberger.rrd`` (dlqr + Luenberger, episode 0 of seed 0: runs off the track) and
``DIR/kalman.rrd`` (dlqr + Kalman, same episode: succeeds), default ``DIR = /tmp/pendulum_lqg_rec``;
verifies them with ``rerun rrd verify`` and prints the time to record each (best of 5 calls, and
the first call, which also imports rerun). A 10 s episode is 10 000 physics samples and 1 000
control samples.

``--screenshot`` also renders each recording in a headless Rerun viewer
(``rerun.experimental.ViewerClient``) and saves ``docs/recording.png`` (Kalman) and
``docs/recording_failure.png`` (Luenberger). The headless viewer needs a Vulkan adapter: on a box
without a GPU install Mesa's software one (Debian: ``apt-get install mesa-vulkan-drivers``).
"""

from __future__ import annotations

import argparse
import time
from pathlib import Path

from pendulum_lqg.core.runner import run_episodes
from pendulum_lqg.core.scenario import Scenario
from pendulum_lqg.model.plant import load_plant
from pendulum_lqg.policies.lqg import DesignSpec, design_policy
from pendulum_lqg.record import read_recording, record_episodes, verify_recording

SEED, EPISODE = 0, 0
DOCS = Path(__file__).resolve().parent.parent / "docs"


def screenshot(rrd: Path, png: Path, *, port: int = 9877, settle: float = 6.0) -> None:
    """Open ``rrd`` in a headless viewer and save what its blueprint shows to ``png``."""
    from rerun.experimental import ViewerClient

    viewer = ViewerClient.spawn(headless=True, port=port, hide_welcome_screen=True)
    try:
        time.sleep(3.0)
        viewer.open(str(rrd))
        time.sleep(settle)   # let the software rasteriser draw every view
        png.parent.mkdir(parents=True, exist_ok=True)
        viewer.save_screenshot(str(png))
    finally:
        viewer.quit()


def main(out: Path, shots: bool) -> None:
    plant, scenario = load_plant(), Scenario()
    for observer in ("luenberger", "kalman"):
        spec = DesignSpec(controller="dlqr", observer=observer)
        policy = design_policy(plant, scenario.control_period, scenario.noise, spec)
        t0 = time.perf_counter()
        res = run_episodes(plant, scenario, policy, seed=SEED, episodes=[EPISODE], trajectory=True)
        t_sim = time.perf_counter() - t0
        assert res.trajectories is not None
        tr = res.trajectories[0]
        path = out / f"{observer}.rrd"
        config = {"seed": SEED, "controller": "dlqr", "observer": observer, "episodes": [EPISODE],
                  "scenario": "lecture"}
        times = []
        for _ in range(5):
            stats = record_episodes([tr], plant=plant, scenario=scenario, policy=policy,
                                    config=config, path=path)
            times.append(stats.seconds)
        check = verify_recording(path)
        contents = read_recording(path)
        print(f"{observer:10s} episode {EPISODE}: {tr.row['failure_reason'] or 'success'} "
              f"(t_end {tr.t_physics[-1]:.3f} s, {tr.t_physics.size} physics / {tr.t.size} "
              f"control samples); simulate {t_sim:.3f} s; record best {min(times):.3f} s, "
              f"first {times[0]:.3f} s (send calls {stats.seconds_logging:.3f} s); "
              f"{stats.rows} rows, {stats.entities} entities, {stats.bytes / 1e6:.2f} MB; "
              f"rrd verify ok={check.ok}; {len(contents.entity_paths)} entity paths read back")
        if shots:
            name = "recording.png" if observer == "kalman" else "recording_failure.png"
            screenshot(path, DOCS / name)
            print(f"  screenshot: {DOCS / name}")


if __name__ == "__main__":
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--out", type=Path, default=Path("/tmp/pendulum_lqg_rec"))
    parser.add_argument("--screenshot", action="store_true")
    args = parser.parse_args()
    main(args.out, args.screenshot)
