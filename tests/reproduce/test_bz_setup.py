"""Tests of the cached data-independent quantities of the designed example (bz_setup)."""

from __future__ import annotations

import numpy as np
import pytest

from fdi_lib.glr import WindowedGLR, glr_window
from fdi_lib.models import fault_profile, step_family
from fdi_lib.nonparametric import solution1_glr, solution2, solution2_tracking
from fdi_lib.reproduce.bz_setup import (
    kalman_detector,
    kalman_regressor,
    kitanidis_detector,
    regressor_rls_gains,
    setup,
)
from fdi_lib.rls import rls_gains
from fdi_lib.signatures import fault_signature
from fdi_lib.simulate import simulate
from fdi_lib.systems import bz_example as ex

N = 120


def test_cached_regressor_and_rls_gains_are_fresh_bits_and_read_only():
    model, kal = setup(N)[:2]
    fresh = fault_signature(model, kal, fault_profile(model, Psi=ex.PSI)).on_innovation
    np.testing.assert_array_equal(kalman_regressor(N), fresh)
    g = rls_gains(fresh, kal.Sigma, lam=0.9)
    cached = regressor_rls_gains(N, 0.9)
    assert cached is regressor_rls_gains(N, 0.9) and cached.lam == 0.9
    np.testing.assert_array_equal(cached.L, g.L)
    np.testing.assert_array_equal(cached.P, g.P)
    for a in (kalman_regressor(N), cached.L, cached.P):
        with pytest.raises(ValueError, match="read-only"):
            a[0] = 0.0


def test_cached_setup_is_read_only_and_fresh_bits():
    """Every array of the shared model, gains and projection is read-only (a caller cannot change
    what the next one reads), and equal to a fresh computation."""
    from fdi_lib.filters import kalman_gains
    from fdi_lib.kitanidis import kitanidis_gains

    model, kal, kg, pred, T = setup(N)
    fresh = ex.bz_model(N)
    arrays = [T]
    for part in (model, kal, kg, pred):
        arrays += [v for v in vars(part).values() if isinstance(v, np.ndarray)]
    assert len(arrays) > 20
    for a in arrays:
        with pytest.raises(ValueError, match="read-only"):
            a.flat[0] = 0.0
    np.testing.assert_array_equal(model.F, fresh.F)
    np.testing.assert_array_equal(kal.K, kalman_gains(fresh).K)
    np.testing.assert_array_equal(kg.K, kitanidis_gains(fresh, ex.E).K)


def test_cached_detectors_give_the_statistics_of_fresh_ones():
    model, kal, kg, _, T = setup(N)
    eps = np.random.default_rng(3).standard_normal((4, N, model.p))
    det = kalman_detector(N, 10)
    assert det is kalman_detector(N, 10) and isinstance(det, WindowedGLR)
    a = glr_window(eps, model, kal, det.family, 10, shared=det, estimates=False)
    b = glr_window(eps, model, kal, step_family(model, Psi=ex.PSI), 10)
    np.testing.assert_array_equal(a.statistic, b.statistic)
    np.testing.assert_array_equal(a.onset, b.onset)
    kit = kitanidis_detector(N, 10)
    fresh = solution1_glr(model, E=ex.E, Psi=ex.PSI, window=10, kgains=kg, T=T)
    res = np.random.default_rng(4).standard_normal((3, N, fresh.gains.Sigma.shape[1]))
    a = glr_window(res, kit.model, kit.gains, kit.family, 10, shared=kit)
    b = glr_window(res, fresh.model, fresh.gains, fresh.family, 10, shared=fresh)
    np.testing.assert_array_equal(a.statistic, b.statistic)


def test_solution2_tracking_is_solution2_after_its_filter():
    from fdi_lib.filters import kalman_filter

    model, kal = setup(N)[:2]
    th = np.broadcast_to([0.06, -0.04], (N, 2))
    fault = fault_profile(model, Psi=ex.state_disturbance(np.zeros((N, 1)), th))
    s = simulate(
        model,
        rng=np.random.default_rng(5),
        controller=ex.controller(),
        size=3,
        fault=fault,
        theta=[1.0],
    )
    kw = dict(lam=0.95, energy_window=20, energy_alpha=1e-4, start=30)
    ref = solution2(model, s.y, s.u, Psi=ex.PSI, kalman=kal, **kw)
    eps = kalman_filter(model, s.y, s.u, gains=kal).innovations
    got = solution2_tracking(eps, kalman_regressor(N), kal, rls=regressor_rls_gains(N, 0.95), **kw)
    for field in ("theta_hat", "errors", "prior_errors"):
        np.testing.assert_array_equal(getattr(got.rls, field), getattr(ref.rls, field))
    np.testing.assert_array_equal(got.energy, ref.energy)
    np.testing.assert_array_equal(got.energy_alarm, ref.energy_alarm)
    assert got.energy_threshold == ref.energy_threshold
