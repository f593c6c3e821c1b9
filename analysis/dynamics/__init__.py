"""Dynamics of one forced oscillator with hysteresis: Lyapunov spectra
(:mod:`~analysis.dynamics.lyapunov`), attractor dimensions (:mod:`~analysis.dynamics.dimensions`),
bifurcation diagrams (:mod:`~analysis.dynamics.bifurcation`) and the statistics of their
measurements (:mod:`~analysis.dynamics.statistics`).

The modules are imported on use (each pulls in the compiled kernels it needs).
"""
