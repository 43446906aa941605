"""Learning controllers from data: identification, random search and deep RL, behind
``pendulum-lqg train METHOD``.

The deep-RL methods need the ``rl`` extra (stable-baselines3, sb3-contrib, torch), imported only
inside the functions that train them; identification and random search need nothing beyond the
package's own dependencies.

================  ========================================================================
module            concept
================  ========================================================================
``methods``       every method, its options and extra
``train``         one run, every input checked first
``runs``          a run's names, seeds, folder (and its lock), stop and progress
``checkpoint``    the checkpoint ``--resume`` continues, checked before any work
``curve``         the learning curve
``deep``          the SB3 methods (the ``rl`` extra)
``ars``           augmented random search over a y/u history
``openloop``      ``sysid-openloop``: identification from open-loop bursts
``closed_loop``   closed-loop identification and the certainty-equivalent LQG design, over the
                  prediction-error fit of :mod:`pendulum_lqg.design.pem`
``sysid_lqg``     ``sysid-lqg`` over ``closed_loop``
``clone``         ``ls-clone``: a least-squares clone of the identified LQG
``price``         the price of not knowing the model: score and gap against the data budget
``pilot``         the pilots that chose the baselines' settings (``python -m``)
``noise_ladder``  RL models and the LQG reference at four noise scales (``python -m``)
``figures``       comparisons across training runs (``python -m``)
================  ========================================================================
"""
