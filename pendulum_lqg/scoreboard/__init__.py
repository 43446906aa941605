"""The scoreboard: suites on fixed seeds where any policy or agent meets the LQG reference.

=============  ================================================================================
module         concept
=============  ================================================================================
``suites``     :class:`~pendulum_lqg.scoreboard.suites.Suite`: a named, versioned challenge level
               (``experiments/suites/*.toml``) with its reference policy
``episodes``   playing a suite: a policy through the batch, a Gymnasium agent through the env
``score``      success rate, mean J and the optimality gap to the reference; the score file
``board``      a folder of score files as one Markdown table
``sb3``        stable-baselines3 models as Gymnasium agents (the ``rl`` extra)
=============  ================================================================================

``pendulum-lqg score POLICY`` / ``--agent REF`` and ``pendulum-lqg board DIR`` are the commands.
"""
