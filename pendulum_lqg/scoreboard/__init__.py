"""The scoreboard: suites on fixed seeds where any policy or agent meets the LQG reference.

================  ================================================================================
module            concept
================  ================================================================================
``suites``        :class:`~pendulum_lqg.scoreboard.suites.Suite`: a named, versioned challenge level
                  (``experiments/suites/*.toml``) with its reference policy
``lti_suite``     a suite of a plant given as matrices (``score POLICY --suite FILE``)
``episodes``      playing a suite: a policy through the batch, a Gymnasium agent through the env
``score``         success rate, mean J and the optimality gap to the reference; the score file
``board``         a folder of score files as one Markdown table
``sb3``           stable-baselines3 models as Gymnasium agents (the ``rl`` extra)
``sb3_record``    the training record of your own stable-baselines3 model, from the command line
``sb3_batch``     a stable-baselines3 model scored batched in the native vector env
``sb3_vec``       stable-baselines3's ``VecEnv`` over the native vector env (training)
``obs_design``    what an RL agent's network sees, the same in training and scoring
``linear``        linear controllers of a y/u history as files (``--agent linear:FILE``)
``stats``         the failure-aware score and its aggregates across training runs
``exact``         the exact stationary J and gap of a linear controller on the plant's linearisation
================  ================================================================================

``pendulum-lqg score POLICY`` / ``--agent REF`` and ``pendulum-lqg board DIR`` are the commands.
"""
