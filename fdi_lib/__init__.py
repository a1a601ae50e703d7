"""``fdi_lib``: statistical and set-based fault detection and isolation for LTV/LPV systems.

The library behind *fdi-book*. Modules: :mod:`~fdi_lib.models` (LTV/LPV containers),
:mod:`~fdi_lib.simulate`, :mod:`~fdi_lib.filters` (Kalman), :mod:`~fdi_lib.signatures`
(fault signatures), :mod:`~fdi_lib.glr` (GLR tests), :mod:`~fdi_lib.isolation` (minmax),
:mod:`~fdi_lib.reproduce` (the papers' figures and tables).

Missing and non-finite data (stated in full in :mod:`fdi_lib.validation`): a NaN measurement
is a missing sample, handled explicitly (the filters predict without updating, the GLR and
energy sums skip it, the statistics stay finite) or reported by a typed error naming the
argument and the first bad index; any other non-finite input is a typed
:class:`~fdi_lib.errors.FDIError`.
"""

__version__ = "0.1.0"
