"""The simulation core: one noisy closed loop behind every front end (CLI, benchmarks, envs, recordings).

Data flow::

    runner.run_episodes ─► loop.Simulator ─► physics (one backend) + rules ─► metrics ─► rows
         (shards, seeds,     measure → act →    mujoco_batch / mujoco_step /   streamed per
          trajectories)      advance → rules    linear                         episode

======================  =====================================================================
module                  concept
======================  =====================================================================
``scenario``            :class:`~pendulum_lqg.core.scenario.Scenario`: the control problem
``scenario_fields``     its declared settings as dataclass fields (generated, do not edit)
``rules``               the rules of a control period, each one function (below)
``period``              the period buffer the physics, the rules and the metrics share
``physics/``            the backends behind :class:`~pendulum_lqg.core.physics.base.Physics`
``sensing``             delays, sample losses, actuator lag, randomised models (per row)
``loop``                :class:`~pendulum_lqg.core.loop.Simulator`: measure → act → advance
``runner``              :func:`~pendulum_lqg.core.runner.run_episodes`: batches, shards
``protocol``            the typed policy protocol the loop drives
``noise``, ``seeding``  noise with units from per-episode generators; the episodes' seeds
``metrics``             streamed per-episode metrics and their aggregates
``trajectory``          full trajectories, on request
======================  =====================================================================

The rules, each defined once in :mod:`pendulum_lqg.core.rules` and called by every path (batch,
single env, vector env):

* saturation — :func:`~pendulum_lqg.core.rules.saturate`;
* a non-finite force fails its episode — :func:`~pendulum_lqg.core.rules.nonfinite_forces`;
* the failure rule — :func:`~pendulum_lqg.core.rules.detect_failure`, with its fast check
  :func:`~pendulum_lqg.core.rules.all_inside` on the bounds of
  :func:`~pendulum_lqg.core.rules.failure_bounds`;
* the period cost — :func:`~pendulum_lqg.core.rules.period_integrals` (and
  :func:`~pendulum_lqg.core.rules.period_cost`, its unmasked sum);
* the state noise — :func:`~pendulum_lqg.core.rules.end_of_period`.
"""
