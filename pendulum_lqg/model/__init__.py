"""The plants: the MuJoCo cart-pole (its MJCF the one source of its parameters) and plants as matrices.

=============  ========================================================================
module         concept
=============  ========================================================================
``plant``      the MuJoCo cart-pole: loading with overrides, named read-outs, ``x = [p, θ, ṗ, θ̇]``
``linearize``  the cart-pole's continuous ``(A, B, C, D)`` about the upright, by finite differences
``lti``        any linear plant given as matrices (TOML or ``.npz``), sampled at T
=============  ========================================================================
"""
