"""Worlds made from a seed (``world: {generate: {kind: ..., seed: N}}``): obstacles as plain
shapes (shapes.py), the same for one seed on any machine (NumPy's PCG64 through
``Generator.random`` and ``Generator.integers``), written as an SDF world and turned into the
WorldPlan that loading that file gives (sdf.py). make.py makes them; each kind is one module
with a ``generate(rng, **params)`` returning its obstacles, the parameters validated before
(scenario/world_model.py).
"""
