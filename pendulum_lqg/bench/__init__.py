"""Experiments: typed specs of a grid of scenarios, split into work units, run and kept on disk.

================  ==============================================================================
module            concept
================  ==============================================================================
``experiments``   :class:`~pendulum_lqg.bench.experiments.ExperimentSpec` (``experiments/*.toml``)
                  and its :class:`~pendulum_lqg.bench.experiments.WorkUnit` s
``study_params``  the parameter tables of the studies an experiment may name (margins, ROA)
``lti``           experiments on a plant given as matrices (``lti_file = "…"``)
``sources``       where a configuration's plant comes from: the cart-pole's MJCF or an ``lti_file``
``results``       results folders: written incrementally and atomically, resumable
``sweep``         :func:`~pendulum_lqg.bench.sweep.run_sweep`: an experiment's units on an executor
``executors``     where the units run: in this process, or as Ray tasks
``perf``          throughput of the closed loop against bare MuJoCo physics (``pendulum-lqg perf``)
================  ==============================================================================

``pendulum-lqg bench FILE|NAME`` and ``pendulum-lqg perf`` are the commands.
"""
