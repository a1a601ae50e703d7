"""fdi_lib: statistical and set-based fault detection and isolation for LTV/LPV systems.

The library behind *fdi-book*. Modules: :mod:`~fdi_lib.models` (LTV/LPV containers),
:mod:`~fdi_lib.simulate`, :mod:`~fdi_lib.filters` (Kalman), :mod:`~fdi_lib.signatures`
(fault signatures), :mod:`~fdi_lib.glr` (GLR tests), :mod:`~fdi_lib.isolation` (minmax),
:mod:`~fdi_lib.reproduce` (the papers' figures and tables).
"""

__version__ = "0.1.0"
