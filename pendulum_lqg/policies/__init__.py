"""The runtime policies (``reset(n)`` / ``act(y)``, batched) and the closed-loop theory beside them.

==================  ====================================================================
module              concept
==================  ====================================================================
``spec``            :class:`~pendulum_lqg.policies.spec.DesignSpec`: the design choices of a built-in policy
``lqg``             ``design_policy``: a controller plus an estimator, the built-in LQG policies
``observers``       the observers of the built-in policies, one builder per name
``estimators``      runtime state estimators, vectorised over a batch of episodes
``loading``         bring your own controller: :class:`PolicyContext` and plug-in loading
``lti``             the built-in policies on a plant given as matrices
``control_io``      python-control in and out: a plant from a ``StateSpace``, designs back as ones
``closed_loop``     a linear policy's closed loop on a sampled linear plant, as matrices
``episode_theory``  the expected RMS over one episode from x₀ and x̂₀ (mean and covariance propagated)
``theory``          the stationary closed loop in closed form, beside the simulation
==================  ====================================================================
"""
