"""Tests of the widget callback of the Basseville & Zhang chapter."""

from __future__ import annotations

import matplotlib

matplotlib.use("Agg")

import numpy as np
import pytest

from fdi_lib.errors import ModelError
from fdi_lib.widgets.bz import bz_run, explore_bz


def test_callback_draws_three_panels_and_reuses_figure():
    fig = explore_bz()
    assert len(fig.axes) == 3
    theta_hat = np.asarray(fig.axes[0].lines[1].get_ydata())
    assert theta_hat.size == 300
    again = explore_bz(lam=0.9, delta=0.0, f_size=0.0, fig=fig)
    assert again is fig and len(fig.axes) == 3


def test_sliders_change_what_they_should():
    base = bz_run(0.95, 3e-4, 0.2)
    no_f = bz_run(0.95, 3e-4, 0.0)
    # f does not move the Kitanidis GLR (rejected) but does raise the RLS error energy
    assert np.allclose(base.sol1.glr.statistic, no_f.sol1.glr.statistic, equal_nan=True, atol=1e-9)
    assert np.nanmax(base.sol2.energy[200:]) > np.nanmax(no_f.sol2.energy[200:])
    # the forgetting factor changes the tracking only
    other = bz_run(0.8, 3e-4, 0.2)
    assert not np.allclose(other.sol2.rls.theta_hat, base.sol2.rls.theta_hat)


def test_bad_values():
    with pytest.raises(ModelError, match=r"lam: expected a forgetting factor in \(0, 1\], got 0"):
        explore_bz(lam=0)
    with pytest.raises(ModelError, match="delta, f_size: expected non-negative values"):
        explore_bz(f_size=-1.0)


def test_cached_rls_gains_give_solution2_exactly():
    # bz_run runs solution 2 step by step with the record's innovation, the regressor and the
    # RLS gains cached: the same result as solution2 on the record
    from fdi_lib.nonparametric import solution2
    from fdi_lib.reproduce.bz import SOL2
    from fdi_lib.reproduce.bz_setup import setup
    from fdi_lib.systems import bz_example as ex
    from fdi_lib.widgets.bz import _record

    model, kal = setup(SOL2["n_steps"])[:2]
    for lam, delta, f_size, seed in [(0.9, 3e-4, 0.2, 0), (1.0, 1e-3, 0.0, 1), (0.8, 0.0, 0.5, 0)]:
        run = bz_run(lam, delta, f_size, seed=seed)
        sim = _record(delta, f_size, seed)[2]
        alone = solution2(
            model,
            sim.y,
            sim.u,
            Psi=ex.PSI,
            lam=lam,
            energy_window=SOL2["energy_window"],
            energy_alpha=SOL2["energy_alpha"],
            start=SOL2["warmup"],
            kalman=kal,
        )
        for field in ("theta_hat", "errors", "prior_errors"):
            np.testing.assert_array_equal(getattr(run.sol2.rls, field), getattr(alone.rls, field))
        np.testing.assert_array_equal(run.sol2.regressor, alone.regressor)
        np.testing.assert_array_equal(run.sol2.energy, alone.energy)
        assert run.sol2.energy_alarm == alone.energy_alarm
        assert run.sol2.energy_threshold == alone.energy_threshold
    with pytest.raises(
        ModelError, match="rls: expected RLS gains for lam = 0.8, got gains for lam = 0.9"
    ):
        solution2(
            model,
            sim.y,
            sim.u,
            Psi=ex.PSI,
            lam=0.8,
            energy_window=SOL2["energy_window"],
            energy_alpha=SOL2["energy_alpha"],
            kalman=kal,
            rls=bz_run(0.9, 3e-4, 0.2).sol2.rls.gains,
        )
