"""Dynamics of one forced oscillator with hysteresis: Lyapunov spectra
(:mod:`~analysis.dynamics.lyapunov`) and their memory directions
(:mod:`~analysis.dynamics.memory`), attractor dimensions (:mod:`~analysis.dynamics.dimensions`;
the attractor's Kaplan–Yorke dimension where neutral memory distorts the full-space one:
:mod:`~analysis.dynamics.attractor_dimension`),
bifurcation diagrams (:mod:`~analysis.dynamics.bifurcation`), the statistics of their
measurements (:mod:`~analysis.dynamics.statistics`), where one start ends
(:mod:`~analysis.dynamics.attractors`) and basins of attraction (:mod:`~analysis.dynamics.basins`,
:mod:`~analysis.dynamics.basin_map`), periodic orbits (:mod:`~analysis.dynamics.periodic_orbits`)
and their continuation (:mod:`~analysis.dynamics.continuation`; the stable stretch of a branch:
:mod:`~analysis.dynamics.stable_range`). Shared by them, once each: the
period of a section (:mod:`~analysis.dynamics.periods`), Floquet multipliers
(:mod:`~analysis.dynamics.floquet`), Newton's method (:mod:`~analysis.dynamics.newton`).

The modules are imported on use (each pulls in the compiled kernels it needs).
"""
