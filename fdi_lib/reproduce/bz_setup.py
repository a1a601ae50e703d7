"""The data-independent quantities of the designed example of :mod:`fdi_lib.reproduce.bz`, cached.

Filter gains, the projection, the regressor of solution 2, its RLS gains for each forgetting
factor and the windowed GLR detectors of solution 1 depend on the setting (the record length,
``lambda``, the window), not on the records: the Monte Carlo chunks of ``bz-solution1`` and
``bz-solution2`` and the chapter's explorable (:mod:`fdi_lib.widgets.bz`) compute each once per
process and share it. Every array they return (the model's, the gains', the projection, the
regressor) is read-only, so a caller cannot change what the next one reads.
"""

from __future__ import annotations

import dataclasses
import functools
from typing import Any

import numpy as np

from fdi_lib.filters import KalmanGains, kalman_gains
from fdi_lib.glr import WindowedGLR
from fdi_lib.kitanidis import KitanidisGains, kitanidis_gains
from fdi_lib.models import LTVModel, fault_profile, step_family
from fdi_lib.nonparametric import kitanidis_predictor_gains, rejection_projection, solution1_glr
from fdi_lib.rls import RLSGains, rls_gains
from fdi_lib.signatures import fault_signature
from fdi_lib.systems import bz_example as ex

__all__ = [
    "setup",
    "kalman_regressor",
    "regressor_rls_gains",
    "kitanidis_detector",
    "kalman_detector",
]


@functools.lru_cache(maxsize=4)
def setup(n_steps: int) -> tuple[LTVModel, KalmanGains, KitanidisGains, KalmanGains, np.ndarray]:
    """``(model, kalman, kitanidis, kitanidis_predictor, T)`` for the example (cached, data
    independent; every array read-only)."""
    model = ex.bz_model(n_steps)
    kg = kitanidis_gains(model, ex.E)
    out = (
        model,
        kalman_gains(model),
        kg,
        kitanidis_predictor_gains(model, ex.E, kg),
        rejection_projection(model, kg),
    )
    for part in out:
        _read_only(part)
    return out


def _read_only(a: Any) -> Any:
    """``a`` with its array (an array) or every array field (a dataclass) made read-only."""
    if isinstance(a, np.ndarray):
        a.flags.writeable = False
    else:
        for field in dataclasses.fields(a):
            value = getattr(a, field.name)
            if isinstance(value, np.ndarray):
                value.flags.writeable = False
    return a


@functools.lru_cache(maxsize=4)
def kalman_regressor(n_steps: int) -> np.ndarray:
    """Solution 2's regressor ``H_k Gamma_k`` ``(N, p, m)`` with the Kalman gain (``Psi_k`` from
    ``k = 0``), as :func:`fdi_lib.nonparametric.solution2` computes it; read-only."""
    model, kal = setup(n_steps)[:2]
    return _read_only(fault_signature(model, kal, fault_profile(model, Psi=ex.PSI)).on_innovation)


@functools.lru_cache(maxsize=16)
def regressor_rls_gains(n_steps: int, lam: float) -> RLSGains:
    """The RLS gains of solution 2 (:func:`fdi_lib.rls.rls_gains` of :func:`kalman_regressor` and
    the Kalman ``Sigma_k``) for the forgetting factor ``lam``; arrays read-only."""
    return _read_only(rls_gains(kalman_regressor(n_steps), setup(n_steps)[1].Sigma, lam=lam))


@functools.lru_cache(maxsize=4)
def kitanidis_detector(n_steps: int, window: int) -> WindowedGLR:
    """Solution 1's windowed GLR on the projected Kitanidis residual
    (:func:`fdi_lib.nonparametric.solution1_glr`), its signatures and informations computed once."""
    model, _, kg, _, T = setup(n_steps)
    return solution1_glr(model, E=ex.E, Psi=ex.PSI, window=window, kgains=kg, T=T)


@functools.lru_cache(maxsize=4)
def kalman_detector(n_steps: int, window: int) -> WindowedGLR:
    """The same windowed GLR on the standard Kalman innovation (the step family of ``Psi``), which
    solution 1 is compared with."""
    model, kal = setup(n_steps)[:2]
    return WindowedGLR(model, kal, step_family(model, Psi=ex.PSI), window)
