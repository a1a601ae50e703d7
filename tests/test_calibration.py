import numpy as np
import pytest

from fdi_lib.calibration import glr_null_calibration, minmax_null_calibration
from fdi_lib.errors import ModelError
from fdi_lib.models import fault_profile
from fdi_lib.systems.random_ltv import random_ltv_model


@pytest.fixture(scope="module")
def setting():
    rng = np.random.default_rng(5)
    model = random_ltv_model(rng, n=3, p=1, n_steps=40)  # one sensor...
    fault = fault_profile(model, Psi=rng.standard_normal((40, 3, 2)))  # ...two faults
    return model, fault


def test_glr_null_is_chi2_m_and_the_level_holds(setting):
    model, fault = setting
    cal = glr_null_calibration(model, fault, n_runs=3000, seed=1, alpha=0.05)
    assert cal.dof == 2 and cal.statistics.shape == (3000,)
    assert cal.ks_pvalue > 0.01
    assert cal.rejection_ci[0] <= 0.05 <= cal.rejection_ci[1]


def test_minmax_null_ignores_the_nuisance(setting):
    model, fault = setting
    cal = minmax_null_calibration(model, fault, [0], [0.0, 5.0], n_runs=3000, seed=2, alpha=0.05)
    assert cal.dof == 1 and cal.ks_pvalue > 0.01
    assert cal.rejection_ci[0] <= 0.05 <= cal.rejection_ci[1]


def test_same_results_for_one_and_two_jobs(setting):
    model, fault = setting
    a = glr_null_calibration(model, fault, n_runs=64, seed=3, jobs=1)
    b = glr_null_calibration(model, fault, n_runs=64, seed=3, jobs=2)
    np.testing.assert_array_equal(a.statistics, b.statistics)


def test_bad_arguments(setting):
    model, fault = setting
    with pytest.raises(ModelError, match=r"theta: the tested components a=\[0\] must be zero"):
        minmax_null_calibration(model, fault, [0], [1.0, 0.0], n_runs=10, seed=0)
    with pytest.raises(ModelError, match=r"n_runs: expected an integer >= 2, got 1"):
        glr_null_calibration(model, fault, n_runs=1, seed=0)
