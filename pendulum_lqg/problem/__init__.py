"""The declarations of the problem: each setting declared once — type, bounds, default, unit, help
text — on msgspec, and every front end derived from the declarations.

This package sits below ``core`` and ``policies`` and imports nothing of theirs.

==================  ===========================================================================
module              concept
==================  ===========================================================================
``declare``         the declaration of a setting (:func:`~pendulum_lqg.problem.declare.setting`),
                    the constrained types, and the one validation path
``errors``          the one adapter from msgspec's errors to ``FILE: key: expected …, got …``
``defaults``        the defaults of an episode, written once
``scenario``        :class:`~pendulum_lqg.problem.scenario.ScenarioSettings`: the scenario's settings
``env``             the Gymnasium environments' keyword layer (scenario, noise and env settings)
``experiment``      the experiment file's tables and grid routing, derived from the declarations
``study``           the analysis studies' parameter tables (``[margins]``, ``[roa]``)
``frontends``       the command line's flags, derived from the declarations
``generate``        writes the derived files (``python -m pendulum_lqg.problem.generate [--check]``)
==================  ===========================================================================
"""
