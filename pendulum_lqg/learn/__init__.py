"""Learning controllers from data: identification, random search and deep RL, behind
``pendulum-lqg train METHOD``.

The deep-RL methods need the ``rl`` extra (stable-baselines3, sb3-contrib, torch), imported only
inside the functions that train them; identification and random search need nothing beyond the
package's own dependencies.

Modules: ``methods`` (every method, its options and extra), ``train`` (one run, every input checked
first), ``runs`` (a run's names, seeds, folder, stop and progress), ``curve`` (the learning curve),
``deep`` (the SB3 methods), ``ars`` (random search), ``openloop`` (``sysid-openloop``),
``closed_loop`` (closed-loop identification and the certainty-equivalent LQG design, over the
prediction-error fit of :mod:`pendulum_lqg.design.pem`), ``sysid_lqg`` (``sysid-lqg`` over
``closed_loop``), ``clone`` (``ls-clone``), ``price`` (the price of not knowing the model: the
identified controller's score and gap against its data budget), ``pilot``, ``noise_ladder`` and
``figures`` (``python -m pendulum_lqg.learn.X``).
"""
