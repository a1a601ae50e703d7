"""Smoke and contract tests of the bz-* reproductions at reduced trial counts."""

from __future__ import annotations

import matplotlib

matplotlib.use("Agg")

import numpy as np
import pytest
import scipy.stats

from fdi_lib.reproduce.registry import get, reproduce


@pytest.fixture(scope="module")
def results():
    return {
        rid: reproduce(rid, seed=1, trials=12)
        for rid in ("bz-whiteness", "bz-solution1", "bz-solution2")
    }


def test_registered_with_documented_keys(results):
    for rid, res in results.items():
        rep = get(rid)
        assert rep.default_trials is None and rep.plot is not None  # the paper has no Monte Carlo
        doc = rep.func.__doc__
        for key in res.headline:
            if not key.endswith("_ci"):
                assert key.split("_ci")[0] in doc or key in doc, (rid, key)
        js = res.to_json_dict()
        assert js["id"] == rid and js["settings"]["trials"] == 12
        fig = rep.plot(res)
        assert len(fig.axes) >= 2


def test_whiteness_headline(results):
    h = results["bz-whiteness"].headline
    assert h["lag1_corr_theory"] < -0.05  # the closed form is clearly non-zero
    lo, hi = h["lag1_corr_empirical_ci"]
    assert lo < h["lag1_corr_theory"] < hi
    assert h["cov_rel_error_kitanidis"] < 0.1 and h["cov_rel_error_reduced"] < 0.1
    # the white residuals reject at about the 5 % level: their intervals hold 0.05
    for name in ("kalman", "reduced_f"):
        lo, hi = h[f"lb_reject_rate_{name}_ci"]
        assert lo <= 0.05 <= hi, (name, lo, hi)
        assert h[f"ks_pvalue_{name}"] > 0.001, name


def test_solution_headlines(results):
    h1 = results["bz-solution1"].headline
    assert h1["glr_detection_rate_theta"] > 0.8 and h1["glr_detection_rate_theta_with_f"] > 0.8
    assert h1["glr_mean_delay_theta"] == h1["glr_mean_delay_theta_with_f"]  # f rejected exactly
    assert h1["glr_alarm_rate_f_only"] == h1["glr_false_alarm_rate"]
    assert h1["nonparametric_detection_rate_f"] > 0.8
    h2 = results["bz-solution2"].headline
    assert len(h2["tracking_rmse"]) == len(h2["lambdas"]) == 4
    assert all(r > 0.8 for r in h2["detection_rate"])
    assert all(0 < e < 0.05 for e in h2["tracking_rmse"])


def test_same_results_for_any_job_count():
    a = reproduce("bz-solution2", seed=3, trials=4, jobs=1)
    b = reproduce("bz-solution2", seed=3, trials=4, jobs=2)
    assert a.headline == b.headline
    np.testing.assert_array_equal(a.data["mean_err_f"][0], b.data["mean_err_f"][0])


def test_updated_residual_is_free_of_f_white_and_singular(results):
    """Zhang 2021's updated residual (I - H L) eps: T H E = 0, closed-form lag covariance zero
    (while the innovation's is not), covariance of rank p - q; Monte Carlo agrees."""
    from fdi_lib.nonparametric import kitanidis_lag_covariance
    from fdi_lib.reproduce.bz import projected_lag_covariance, updated_residual_projection
    from fdi_lib.reproduce.bz_setup import setup
    from fdi_lib.systems import bz_example as ex

    model, _, kg, _, _ = setup(200)
    T = updated_residual_projection(model, kg)
    assert np.abs(T[1:] @ model.H[1:] @ ex.E).max() < 1e-10
    assert np.abs(projected_lag_covariance(model, kg, T, 1)).max() < 1e-12 * np.abs(kg.Sigma).max()
    assert np.abs(projected_lag_covariance(model, kg, T, 3)).max() < 1e-12 * np.abs(kg.Sigma).max()
    assert np.abs(kitanidis_lag_covariance(model, kg, 1)).max() > 0.05 * np.abs(kg.Sigma).max()
    S = T @ kg.Sigma @ np.swapaxes(T, 1, 2)
    assert all(np.linalg.matrix_rank(S[k], tol=1e-10) == model.p - ex.E.shape[1] for k in (5, 100))
    h = results["bz-whiteness"].headline
    assert h["updated_f_change"] < 1e-10
    assert h["updated_cov_rank"] == model.p - ex.E.shape[1]
    assert h["lag1_corr_updated_max"] < 2 * h["lag1_corr_updated_halfwidth"]
    # the maximum is over the pairs of components with non-zero variance (here p - 1 of them)
    assert h["lag1_corr_updated_entries"] == (model.p - 1) ** 2
    assert h["lag1_corr_updated_bonferroni_z"] == pytest.approx(
        scipy.stats.norm.ppf(1 - 0.05 / (2 * h["lag1_corr_updated_entries"])), rel=1e-12
    )
    # the entry of the largest |correlation| has a half-width at most the largest one
    assert (
        h["lag1_corr_updated_zmax"]
        >= 1.96 * h["lag1_corr_updated_max"] / h["lag1_corr_updated_halfwidth"]
    )
    assert abs(h["lag1_corr_theory"]) > 5 * h["lag1_cov_updated_theory_max"] + 0.05


def test_reader_tables(results):
    from fdi_lib.reproduce.views.bz import LABELS
    from fdi_lib.reproduce.views.bz import headline_table, solution2_table

    r1 = results["bz-solution1"]
    keys = [k for k in LABELS if k in r1.headline]
    t = headline_table(r1, keys)
    assert [label for label, _ in t.rows] == [LABELS[k] for k in keys]
    text = str(t)
    assert "_" not in text.split("note:")[0]  # no raw keys
    assert "%" in dict(t.rows)[LABELS["glr_false_alarm_rate"]][0]
    t2 = solution2_table(results["bz-solution2"])
    assert t2.columns == ("λ = 0.9", "λ = 0.95", "λ = 0.98", "λ = 0.995")


@pytest.mark.parametrize("shape, lags", [((6, 120, 3), 10), ((4, 37, 1), 5), ((3, 550, 2), 10)])
def test_ljung_box_pvalues_equal_statsmodels(shape, lags):
    """The vectorised Ljung-Box p-values are statsmodels' acorr_ljungbox, bit for bit (white,
    trending and correlated series)."""
    from statsmodels.stats.diagnostic import acorr_ljungbox

    from fdi_lib.reproduce.bz import ljung_box_pvalues

    rng = np.random.default_rng(shape[1])
    series = 3.0 * rng.standard_normal(shape) + 1.0
    series[..., 0] = 0.05 * np.cumsum(series[..., 0], axis=1)  # strongly correlated
    ours = ljung_box_pvalues(series, lags)
    ref = np.array(
        [
            [
                float(acorr_ljungbox(series[i, :, j], lags=[lags])["lb_pvalue"].iloc[0])
                for j in range(shape[2])
            ]
            for i in range(shape[0])
        ]
    )
    np.testing.assert_array_equal(ours, ref)
    assert ours[:, 0].max() < 1e-6 and ours.shape == shape[::2]
