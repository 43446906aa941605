"""The plants: the MuJoCo cart-pole (its MJCF the one source of its parameters) and plants as matrices.

==============  ==============================================================================
module          concept
==============  ==============================================================================
``interface``   ``SimulatedPlant``, what every plant is (``Layout``, limits, models)
``overrides``   what a scenario changes of the cart-pole's model: overrides, randomisation
``plant``       the MuJoCo cart-pole: loading with overrides, read-outs, ``x = [p, θ, ṗ, θ̇]``
``linearize``   the cart-pole's continuous ``(A, B, C, D)`` by finite differences
``lti``         any linear plant given as matrices (TOML or ``.npz``), sampled at T
``lti_layout``  the ``Layout`` of a plant given as matrices (names, x₀, noise, weights)
``mjcf``        any MuJoCo model as a plant: the plant file, its checks, its simulators
``mjcf_linear`` a MuJoCo model's linearisation about its equilibrium (continuous and FD)
``catalog``     the plants a user names: ``--plant NAME|FILE``, the shipped family
==============  ==============================================================================
"""
