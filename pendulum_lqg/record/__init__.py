"""Rerun recordings of episodes: 3-D scene, time series, estimator internals and a blueprint.

=============  ========================================================================
module         concept
=============  ========================================================================
``writer``     :func:`record_episodes`: every episode's samples as columns, the blueprint
``scene``      the MJCF geometry as Rerun archetypes
``documents``  the Markdown panels: configuration, outcomes, summary
``reader``     :func:`read_recording`, :func:`verify_recording`
=============  ========================================================================

:func:`record_episodes` turns the :class:`~pendulum_lqg.core.trajectory.Trajectory` objects that
``run_episodes(..., trajectory=True)`` returns into one Rerun recording (a ``.rrd`` file and/or a
spawned viewer). Nothing here runs the simulation: the closed loop stays in :mod:`pendulum_lqg.core`,
and a run without ``--record`` never imports this module's heavy dependency (``rerun`` is imported
inside the functions that need it), so recording off costs nothing in the loop.

Every sample goes through ``RecordingStream.send_columns`` (one call per entity per episode); only the
static geometry, styles and text documents use ``log``.

Entity tree (one recording, each episode under its own prefix ``/episode_NNNN``; all times on the
``sim_time`` timeline, in seconds from the episode start):

=====================================  ==========================================================
``/config``                            the run: configuration, scenario, plant parameters, seed,
                                       gains and design poles (Markdown, static)
``/summary``                           one table row per recorded episode (Markdown, static)
``/episode_NNNN/outcome``              success or failure reason and time, cost and metrics
``/episode_NNNN/events``               a ``TextLog`` entry at the failure time
``…/world/<geom>``                     world geoms from the MJCF (floor, rail, rail stops)
``…/world/track_limits``               the failure limits ``±track_limit`` of the cart centre
``…/world/cart``                       cart body, translated by the true ``p`` (physics rate);
                                       its geoms below it
``…/world/cart/pole``                  pole body, rotated by the true ``θ`` about the hinge axis
``…/world/estimate[/pole]``            translucent ghost of the estimated pose ``x̂`` (control rate)
``…/world/failure``                    a labelled point where the episode failed
``…/state/<x>/true``                   true ``p, θ, ṗ, θ̇`` at the physics rate
``…/state/<x>/estimate``               ``x̂`` at the control rate (held between samples)
``…/state/<p|theta>/measured``         noisy measurements ``y`` (points)
``…/control/u``, ``…/control/limits``  applied force and the saturation limits ``±u_max``
``…/cost/J``                           running cost ``J(t)``, 0 at ``t = 0``
``…/estimation/error/<x>``             ``x̂ − x`` and, when the filter has a covariance, ``±2σ``
                                       from ``P`` (a-posteriori)
``…/estimation/innovation/<p|theta>``  innovations ``y − C x̄``
=====================================  ==========================================================

The estimate ghost and the ``estimation`` group are left out for the true-state "observer".

The blueprint sent with the recording has one tab per episode (the first :data:`MAX_EPISODE_TABS`):
the 3-D view above the outcome / configuration / event documents on the left, the four state plots
in the middle, control, cost and estimator plots on the right; plus an overview tab (θ and J of every
episode) and the episode table when more than one episode is recorded.
"""

from pendulum_lqg.record.documents import telling_episodes
from pendulum_lqg.record.reader import (
    RecordingContents,
    VerifyResult,
    read_column,
    read_recording,
    rerun_executable,
    verify_recording,
)
from pendulum_lqg.record.writer import (
    MAX_EPISODE_TABS,
    SPAWN_FLUSH_TIMEOUT,
    TIMELINE,
    VIEWER_PORT,
    VIEWER_WAIT,
    RecordingStats,
    episode_prefix,
    physics_samples,
    record_episodes,
)

__all__ = ["MAX_EPISODE_TABS", "SPAWN_FLUSH_TIMEOUT", "TIMELINE", "VIEWER_PORT", "VIEWER_WAIT",
           "RecordingContents", "RecordingStats", "VerifyResult", "episode_prefix", "physics_samples",
           "read_column", "read_recording", "record_episodes", "rerun_executable", "telling_episodes",
           "verify_recording"]
