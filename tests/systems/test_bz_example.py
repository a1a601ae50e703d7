"""Tests of the designed example of the Basseville & Zhang chapter."""

from __future__ import annotations

import numpy as np
import pytest

from fdi_lib.errors import ModelError
from fdi_lib.kitanidis import kitanidis_gains
from fdi_lib.simulate import simulate
from fdi_lib.systems import bz_example as ex


def test_dimensions_and_rank_conditions():
    m = ex.bz_model(50)
    assert (m.n, m.p, m.l, m.n_steps) == (3, 3, 1, 50)
    assert np.linalg.matrix_rank(m.H[0] @ ex.E) == 1  # Kitanidis (iv)
    # p >= q + m: after rejecting E, the parametric directions stay visible
    assert m.p >= ex.E.shape[1] + ex.PSI.shape[1]
    # the 2x2 block is the Section 6.1 matrix with a_k in [0.4, 0.6]
    a = m.F[:, 0, 0]
    assert a.min() >= 0.4 - 1e-12 and a.max() <= 0.6 + 1e-12 and np.ptp(a) > 0.1
    assert np.allclose(m.F[:, :2, 1], [1.0, 1.2])
    kitanidis_gains(m, ex.E)  # does not raise


def test_closed_loop_is_stable_and_tracks_setpoint():
    m = ex.bz_model()
    sim = simulate(m, rng=np.random.default_rng(0), controller=ex.controller(), size=20)
    assert np.abs(sim.x).max() < 10
    assert abs(sim.y[:, 300:, 0].mean() - 1.0) < 0.05


def test_profiles():
    f = ex.nonparametric_profile(100, size=0.3, onset=40)
    assert (
        f.shape == (100, 1) and np.all(f[:40] == 0) and np.isclose(np.abs(f).max(), 0.3, atol=1e-3)
    )
    th = ex.parametric_path(100, theta=[1.0, 2.0], onset=10)
    assert np.all(th[:10] == 0) and np.all(th[10:] == [1.0, 2.0])
    ramp = ex.parametric_path(100, theta=[1.0, 0.0], onset=10, ramp=20)
    assert np.allclose(np.diff(ramp[:, 0])[10:29], 1 / 20) and ramp[-1, 0] == 1.0
    d = ex.drift_path(100, delta=1e-3, onset=5)
    inc = np.abs(np.diff(d, axis=0)).max(axis=1)
    assert np.allclose(inc[5:], 1e-3) and np.all(inc[:4] == 0)
    dist = ex.state_disturbance(f, th)
    assert dist.shape == (100, 3, 1) and np.allclose(dist[:, 0, 0], f[:, 0])


def test_bad_arguments():
    with pytest.raises(ModelError, match="n_steps: expected an integer >= 2, got 1"):
        ex.bz_model(1)
    with pytest.raises(ModelError, match="delta: expected a non-negative"):
        ex.drift_path(10, delta=-1.0, onset=0)
    with pytest.raises(ModelError, match="period: expected a positive"):
        ex.nonparametric_profile(10, size=1.0, onset=0, period=0)
    with pytest.raises(ModelError, match="ramp: expected a non-negative"):
        ex.parametric_path(10, theta=[1.0], onset=0, ramp=-2)
