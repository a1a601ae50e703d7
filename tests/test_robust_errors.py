"""Every bad input listed in issue 15 raises a typed fdi_lib error naming the argument.

Each case: the call, the error class, and a pattern with the argument name and the
expected / actual value (and the index or step for non-finite data and divergence).
"""

from __future__ import annotations

import numpy as np
import pytest

from fdi_lib.errors import CovarianceError, FDIError, ModelError, NonFiniteError, ShapeError
from fdi_lib.filters import kalman_filter, kalman_gains
from fdi_lib.glr import first_alarm, glr_window
from fdi_lib.isolation import minmax_isolation, minmax_statistic
from fdi_lib.kitanidis import kitanidis_gains, residual_signature
from fdi_lib.models import fault_profile, ltv_model, step_family
from fdi_lib.montecarlo import binomial_ci, run_monte_carlo, trial_seeds
from fdi_lib.nonparametric import energy_statistic, energy_threshold
from fdi_lib.rls import rls_gains, rls_track
from fdi_lib.sets import Polytope
from fdi_lib.sets.svo import SetValuedObserver
from fdi_lib.simulate import simulate
from fdi_lib.sparse import lasso_path, least_squares_on_support, regression_data

M1 = ltv_model(F=[[0.9]], H=[[1.0]], Q=1.0, R=1.0, n_steps=10)
M2 = ltv_model(F=0.5 * np.eye(2), H=np.eye(2), Q=np.eye(2), R=np.eye(2), n_steps=10)
G1 = kalman_gains(M1)
LONG = kalman_gains(ltv_model(F=[[0.9]], H=[[1.0]], Q=1.0, R=1.0, n_steps=20))
FAM = step_family(M1, Psi=[[1.0]])
X = np.random.default_rng(0).standard_normal((12, 3))
Y = X @ np.array([1.0, 0.0, -2.0])


def _nan_at(shape, index):
    a = np.ones(shape)
    a[index] = np.nan
    return a


CASES = {
    # glr.first_alarm: start is not Python slicing; NaN threshold; NaN after a finite value
    "first_alarm start=-3": (
        lambda: first_alarm(np.zeros(5), 1.0, start=-3),
        ModelError,
        r"start: expected an integer in \[0, 5\], got -3",
    ),
    "first_alarm start=True": (
        lambda: first_alarm(np.zeros(5), 1.0, start=True),
        ModelError,
        r"start: expected an integer, got True",
    ),
    "first_alarm threshold=nan": (
        lambda: first_alarm(np.zeros(5), np.nan),
        NonFiniteError,
        r"threshold: expected a finite number, got nan",
    ),
    "first_alarm NaN statistic": (
        lambda: first_alarm(np.array([1.0, np.nan, 2.0]), 5.0),
        NonFiniteError,
        r"statistic: expected finite values after the warm-up, got nan at index \(1,\)",
    ),
    # nonparametric
    "energy_threshold window=0": (
        lambda: energy_threshold(0, 1, 0.01),
        ModelError,
        r"window: expected a positive integer, got 0",
    ),
    "energy_threshold alpha=nan": (
        lambda: energy_threshold(5, 1, np.nan),
        NonFiniteError,
        r"alpha",
    ),
    "energy_statistic bad Sigma_chol": (
        lambda: energy_statistic(np.zeros((10, 1)), -np.ones((10, 1, 1)), 3),
        ModelError,
        r"Sigma_chol: expected lower-triangular factors",
    ),
    "energy_statistic inf residual": (
        lambda: energy_statistic(_inf((10, 1), (4, 0)), np.ones((10, 1, 1)), 3),
        NonFiniteError,
        r"residuals: .* at index \(4, 0\)",
    ),
    # isolation
    "minmax non-symmetric F": (
        lambda: minmax_statistic([[2.0, 1.0], [0.0, 2.0]], [1.0, 1.0], [0]),
        CovarianceError,
        r"F: expected a symmetric matrix, got asymmetry 1",
    ),
    "minmax indefinite F": (
        lambda: minmax_statistic([[1.0, 2.0], [2.0, 1.0]], [1.0, 1.0], [0]),
        CovarianceError,
        r"F: expected a positive semi-definite matrix, got smallest eigenvalue -1",
    ),
    "minmax NaN zeta": (
        lambda: minmax_statistic(np.eye(2), [np.nan, 1.0], [0]),
        NonFiniteError,
        r"zeta: .* at index \(0,\)",
    ),
    "minmax a=[1.5]": (
        lambda: minmax_statistic(np.eye(2), [1.0, 1.0], [1.5]),
        ModelError,
        r"a: expected an integer",
    ),
    "minmax_isolation alpha=1.5": (
        lambda: minmax_isolation(np.eye(2), np.ones(2), [[0]], alpha=1.5),
        ModelError,
        r"alpha: expected a probability in \(0, 1\), got 1.5",
    ),
    # filters: x0 of length 1 (was broadcast), NaN x0, gains of a longer model
    "kalman x0 length 1": (
        lambda: kalman_filter(M2, np.zeros((10, 2)), x0=[0.0]),
        ShapeError,
        r"x0: expected shape \(2,\), got \(1,\)",
    ),
    "kalman x0 NaN": (
        lambda: kalman_filter(M1, np.zeros(10), x0=[np.nan]),
        NonFiniteError,
        r"x0: expected finite values, got nan at index \(0,\)",
    ),
    "kalman gains of a longer model": (
        lambda: kalman_filter(M1, np.zeros(10), gains=LONG),
        ShapeError,
        r"gains: expected gains with K of shape \(10, 1, 1\).*\(20, 1, 1\)",
    ),
    # Riccati divergence: a typed error naming the step (was scipy's "must not contain infs")
    "Riccati diverged": (
        lambda: kalman_gains(ltv_model(F=[[1e200]], H=[[1.0]], Q=1.0, R=1.0, n_steps=5)),
        NonFiniteError,
        r"model: the Riccati recursion diverged .* step 1",
    ),
    "Kitanidis diverged": (
        lambda: kitanidis_gains(
            ltv_model(F=1e200 * np.eye(2), H=np.eye(2), Q=np.eye(2), R=np.eye(2), n_steps=5),
            E=[[1.0], [0.0]],
        ),
        NonFiniteError,
        r"model: the Kitanidis covariance recursion diverged .* step 1",
    ),
    # glr
    "glr_window window > N": (
        lambda: glr_window(np.zeros((10, 1)), M1, G1, FAM, window=11),
        ModelError,
        r"window: expected an integer in \[1, 10\], got 11",
    ),
    "glr_window inf innovation": (
        lambda: glr_window(_inf((10, 1), (3, 0)), M1, G1, FAM, window=4),
        NonFiniteError,
        r"innovations: .* at index \(3, 0\)",
    ),
    # sparse
    "lasso_path max_size=0": (
        lambda: lasso_path(X, Y, max_size=0),
        ModelError,
        r"max_size: expected a positive integer, got 0",
    ),
    "lasso_path max_size=-2": (
        lambda: lasso_path(X, Y, max_size=-2),
        ModelError,
        r"max_size: expected a positive integer, got -2",
    ),
    "lasso_path NaN y": (
        lambda: lasso_path(X, _nan_at(12, 7)),
        NonFiniteError,
        r"y: .* at index \(7,\)",
    ),
    "least_squares support=[-1]": (
        lambda: least_squares_on_support(X, Y, [-1]),
        ModelError,
        r"support: expected an integer in \[0, 2\], got -1",
    ),
    "least_squares support=[0, 0]": (
        lambda: least_squares_on_support(X, Y, [0, 0]),
        ModelError,
        r"support: expected distinct column indices",
    ),
    "regression_data NaN": (
        lambda: regression_data(_nan_at((5, 1), (2, 0)), np.ones((5, 1, 2))),
        NonFiniteError,
        r"residuals: .* at index \(2, 0\)",
    ),
    # sets
    "SVO margin=-1": (
        lambda: SetValuedObserver(Polytope.box([-1], [1]), margin=-1),
        ModelError,
        r"margin: expected a non-negative relative inflation in \[0, inf\], got -1",
    ),
    "SVO X0 not a polytope": (
        lambda: SetValuedObserver(np.eye(2)),
        ModelError,
        r"X0: expected a Polytope",
    ),
    # simulate / models
    "simulate theta=NaN": (
        lambda: simulate(
            M1, rng=np.random.default_rng(0), fault=fault_profile(M1, Psi=[[1.0]]), theta=[np.nan]
        ),
        NonFiniteError,
        r"theta: .* at index \(0,\)",
    ),
    "simulate size=1.5": (
        lambda: simulate(M1, rng=np.random.default_rng(0), size=1.5),
        ModelError,
        r"size: expected an integer, got 1.5",
    ),
    "ltv_model n_steps=True": (
        lambda: ltv_model(F=[[0.9]], H=[[1.0]], Q=1.0, R=1.0, n_steps=True),
        ModelError,
        r"n_steps: expected an integer, got True",
    ),
    # rls
    "rls indefinite Sigma": (
        lambda: rls_gains(np.ones((5, 1, 1)), -np.ones((5, 1, 1)), lam=0.9),
        CovarianceError,
        r"Sigma: expected a positive definite matrix, got smallest eigenvalue -1 at step 0",
    ),
    "rls NaN Sigma": (
        lambda: rls_gains(np.ones((5, 1, 1)), _nan_at((5, 1, 1), (3, 0, 0)), lam=0.9),
        NonFiniteError,
        r"Sigma: .* at index \(3, 0, 0\)",
    ),
    "rls non-symmetric Sigma": (
        lambda: rls_gains(
            np.ones((5, 2, 1)), np.broadcast_to([[1.0, 0.5], [0.0, 1.0]], (5, 2, 2)), lam=0.9
        ),
        CovarianceError,
        r"Sigma: expected a symmetric matrix, got asymmetry 0.5 at step 0",
    ),
    "rls indefinite P0": (
        lambda: rls_gains(np.ones((5, 1, 1)), np.ones((5, 1, 1)), lam=0.9, P0=[[-1.0]]),
        CovarianceError,
        r"P0: expected a positive semi-definite matrix",
    ),
    "rls NaN P0": (
        lambda: rls_gains(np.ones((5, 1, 1)), np.ones((5, 1, 1)), lam=0.9, P0=[[np.nan]]),
        NonFiniteError,
        r"P0: .* at index \(0, 0\)",
    ),
    "rls theta0 shape": (
        lambda: rls_track(
            np.zeros((5, 1)), np.ones((5, 1, 2)), np.ones((5, 1, 1)), lam=0.9, theta0=[0.0]
        ),
        ShapeError,
        r"theta0: expected shape \(2,\), got \(1,\)",
    ),
    "rls NaN innovation": (
        lambda: rls_track(_nan_at((5, 1), (2, 0)), np.ones((5, 1, 1)), np.ones((5, 1, 1)), lam=0.9),
        NonFiniteError,
        r"innovations: .* at index \(2, 0\)",
    ),
    "residual_signature NaN": (
        lambda: residual_signature(M1, G1, Psi=_nan_at((10, 1, 1), (6, 0, 0))),
        NonFiniteError,
        r"Psi: .* at index \(6, 0, 0\)",
    ),
    # Monte Carlo: seeds and levels
    "seed -1": (
        lambda: trial_seeds(-1, 3),
        ModelError,
        r"seed: expected a non-negative integer, got -1",
    ),
    "seed 'abc'": (
        lambda: trial_seeds("abc", 3),
        ModelError,
        r"seed: expected an integer, got 'abc'",
    ),
    "seed 1.5": (
        lambda: run_monte_carlo(lambda s: {}, 3, seed=1.5),
        ModelError,
        r"seed: expected an integer, got 1.5",
    ),
    "binomial_ci level=1.5": (
        lambda: binomial_ci(3, 10, level=1.5),
        ModelError,
        r"level: expected a probability in \(0, 1\), got 1.5",
    ),
}


def _inf(shape, index):
    a = np.zeros(shape)
    a[index] = np.inf
    return a


@pytest.mark.parametrize("case", sorted(CASES))
def test_bad_input_raises_a_typed_error(case):
    call, err, pattern = CASES[case]
    with pytest.raises(err, match=pattern) as info:
        call()
    assert isinstance(info.value, FDIError)
