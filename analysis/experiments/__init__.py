"""Experiments over many systems: the paper's parameter values and run sizes
(:mod:`~analysis.experiments.parameters`), the model registry (:mod:`~analysis.experiments.models`),
ensembles (:mod:`~analysis.experiments.ensemble`, :mod:`~analysis.experiments.iid`), the
attractor of each disorder realization (:mod:`~analysis.experiments.realizations`), and running
and keeping tasks (:mod:`~analysis.experiments.execution`, :mod:`~analysis.experiments.store`).

The modules are imported on use (each pulls in the compiled kernels it needs).
"""
