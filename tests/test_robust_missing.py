"""The missing-data policy (fdi_lib.validation): a NaN measurement never hides a fault.

Each case is checked against an independent computation (a scalar loop written here,
with the missing sample simply left out), not against the library itself.
"""

from __future__ import annotations

import numpy as np
import pytest
import scipy.stats

from fdi_lib.errors import FDIError, NonFiniteError
from fdi_lib.filters import kalman_filter, kalman_gains
from fdi_lib.glr import first_alarm, glr_known_profile, glr_window
from fdi_lib.isolation import information
from fdi_lib.models import fault_profile, ltv_model, step_family
from fdi_lib.nonparametric import energy_statistic
from fdi_lib.signatures import fault_signature
from fdi_lib.simulate import simulate

N, ONSET, THETA = 200, 100, 3.0
THRESHOLD = float(scipy.stats.chi2.ppf(1 - 1e-6, 1))


def _setup(seed: int = 0):
    """Scalar model; a state step of size 3 at k = 100 first shows in eps_101."""
    m = ltv_model(F=[[0.9]], H=[[1.0]], Q=0.01, R=0.01, n_steps=N)
    k = np.arange(N)
    prof = fault_profile(m, Psi=(k >= ONSET).astype(float)[:, None, None])
    g = kalman_gains(m)
    sig = fault_signature(m, g, prof).on_innovation
    sim = simulate(m, rng=np.random.default_rng(seed), fault=prof, theta=[THETA])
    return m, g, sig, sim


def _glr_loop(eps, sigma, s, skip):
    """Known-profile GLR of a scalar model by a plain loop, leaving out the samples in ``skip``."""
    C = d = 0.0
    out = []
    for k in range(len(eps)):
        if k not in skip:
            C += s[k] ** 2 / sigma[k]
            d += s[k] * eps[k] / sigma[k]
        out.append(d * d / C if C > 0 else 0.0)
    return np.array(out)


def test_clean_record_alarms_at_101():
    m, g, sig, sim = _setup()
    eps = kalman_filter(m, sim.y, gains=g).innovations
    assert first_alarm(glr_known_profile(eps, g, sig).statistic, THRESHOLD) == ONSET + 1


@pytest.mark.parametrize("seed", [0, 1, 2])
def test_nan_innovation_does_not_hide_the_fault(seed):
    """Before the policy: l_k was NaN from k = 50 on and first_alarm returned -1 (fault missed)."""
    m, g, sig, sim = _setup(seed)
    eps = kalman_filter(m, sim.y, gains=g).innovations.copy()
    eps[50] = np.nan
    res = glr_known_profile(eps, g, sig)
    assert np.all(np.isfinite(res.statistic))
    expected = _glr_loop(eps[:, 0], g.Sigma[:, 0, 0], sig[:, 0, 0], skip={50})
    np.testing.assert_allclose(res.statistic, expected, rtol=1e-9, atol=1e-12)
    assert first_alarm(res.statistic, THRESHOLD) == ONSET + 1


def test_nan_innovation_in_one_realisation_only():
    """A batch where only realisation 1 misses sample 50: each row equals its own loop."""
    m, g, sig, _ = _setup()
    sims = simulate(m, rng=np.random.default_rng(5), size=3,
                    fault=fault_profile(m, Psi=(np.arange(N) >= ONSET).astype(float)[:, None, None]),
                    theta=[THETA])
    eps = kalman_filter(m, sims.y, gains=g).innovations.copy()
    eps[1, 50] = np.nan
    res = glr_known_profile(eps, g, sig)
    for b in range(3):
        expected = _glr_loop(eps[b, :, 0], g.Sigma[:, 0, 0], sig[:, 0, 0], skip={50} if b == 1 else set())
        np.testing.assert_allclose(res.statistic[b], expected, rtol=1e-9, atol=1e-12)
    assert list(first_alarm(res.statistic, THRESHOLD)) == [ONSET + 1] * 3


def test_missing_measurement_predicts_without_update():
    """y_50 = NaN: eps_50 is NaN (the marker), Xhat_51 = F Xhat_50, the fault is still found at 101."""
    m, g, sig, sim = _setup()
    y = sim.y.copy()
    y[50] = np.nan
    kf = kalman_filter(m, y, gains=g)
    # Independent scalar filter with the same gains.
    xh, eps, filt = 0.0, [], []
    for k in range(N):
        e = y[k, 0] - xh
        eps.append(e)
        xf = xh if np.isnan(e) else xh + g.K[k, 0, 0] * e
        filt.append(xf)
        xh = 0.9 * xf
    eps, filt = np.array(eps), np.array(filt)
    np.testing.assert_allclose(kf.x_filt[:, 0], filt, rtol=1e-12, atol=1e-14)
    np.testing.assert_allclose(kf.updated_residuals[:, 0], y[:, 0] - filt, rtol=1e-12, atol=1e-14, equal_nan=True)
    assert np.isnan(kf.innovations[50, 0]) and np.isnan(eps[50])
    assert np.count_nonzero(np.isnan(kf.innovations)) == 1
    np.testing.assert_allclose(kf.innovations[:, 0], eps, rtol=1e-12, atol=1e-14)
    assert kf.x_pred[51, 0] == pytest.approx(0.9 * kf.x_pred[50, 0], rel=1e-15)
    stat = glr_known_profile(kf.innovations, g, sig).statistic
    assert np.all(np.isfinite(stat))
    assert first_alarm(stat, THRESHOLD) == ONSET + 1


def test_infinite_measurement_is_an_error_naming_the_index():
    m, g, _, sim = _setup()
    y = sim.y.copy()
    y[42, 0] = np.inf
    with pytest.raises(NonFiniteError, match=r"y.*\(42, 0\)"):
        kalman_filter(m, y, gains=g)


def test_windowed_glr_skips_a_missing_sample():
    m, g, _, sim = _setup()
    eps = kalman_filter(m, sim.y, gains=g).innovations.copy()
    fam = step_family(m, Psi=[[1.0]])
    clean = glr_window(eps, m, g, fam, window=30)
    eps[50] = np.nan
    res = glr_window(eps, m, g, fam, window=30)
    defined = np.arange(N) >= clean.min_samples
    assert np.all(np.isfinite(res.statistic[defined]))
    # Windows that do not contain sample 50 are unchanged.
    far = np.arange(N) >= 50 + 30
    np.testing.assert_allclose(res.statistic[far], clean.statistic[far], rtol=1e-12)
    assert first_alarm(res.statistic, THRESHOLD) == first_alarm(clean.statistic, THRESHOLD) > ONSET


def test_windowed_glr_batch_with_different_missing_samples():
    m, g, _, _ = _setup()
    eps = np.random.default_rng(3).standard_normal((3, N, 1)) * np.sqrt(g.Sigma[:, 0, 0])[:, None]
    fam = step_family(m, Psi=[[1.0]])
    eps[0, 20] = np.nan
    eps[2, 70] = np.nan
    res = glr_window(eps, m, g, fam, window=15)
    for b in range(3):
        one = glr_window(eps[b], m, g, fam, window=15)
        np.testing.assert_allclose(res.statistic[b], one.statistic[...], rtol=1e-12, equal_nan=True)


def test_information_skips_a_missing_sample():
    m, g, sig, sim = _setup()
    eps = kalman_filter(m, sim.y, gains=g).innovations.copy()
    eps[120] = np.nan
    F, zeta = information(eps, sig, g, 101, 150)
    keep = [k for k in range(101, 150) if k != 120]
    s, sg = sig[keep, 0, 0], g.Sigma[keep, 0, 0]
    assert float(np.squeeze(F)) == pytest.approx(np.sum(s * s / sg), rel=1e-12)
    assert float(np.squeeze(zeta)) == pytest.approx(np.sum(s * eps[keep, 0] / sg), rel=1e-12)


def test_first_alarm_never_reads_nan_as_no_alarm():
    stat = np.array([np.nan, np.nan, 0.5, np.nan, 9.0])
    with pytest.raises(NonFiniteError, match=r"statistic.*3"):
        first_alarm(stat, 1.0)
    # A leading warm-up (statistic not defined yet) is allowed.
    assert first_alarm(np.array([np.nan, np.nan, 0.5, 9.0]), 1.0) == 3


def test_first_alarm_nan_threshold_is_an_error():
    with pytest.raises(FDIError, match="threshold"):
        first_alarm(np.zeros(5), np.nan)


def _energy_loop(z, w):
    out = np.full(len(z), np.nan)
    for k in range(w - 1, len(z)):
        out[k] = sum(z[j] ** 2 for j in range(k - w + 1, k + 1) if not np.isnan(z[j]))
    return out


@pytest.mark.parametrize("spike", [1e8, 1e10])
def test_energy_after_a_glitch(spike):
    """Before: window sums by differences of a running total; a 1e10 spike made the statistic 0 for
    the rest of the record and a 3 sigma fault 50,000 samples later was never detected."""
    n, w, fault_at = 50_200, 20, 50_100
    r = np.random.default_rng(0).standard_normal(n)
    r[100] = spike
    r[fault_at:] += 3.0
    L = np.ones((n, 1, 1))
    en = energy_statistic(r[:, None], L, w)
    ok = np.arange(n) >= 100 + w            # windows after the glitch has left
    tail = slice(fault_at - 500, n)
    np.testing.assert_allclose(en[tail], _energy_loop(r[tail.start - w + 1:], w)[w - 1:], rtol=1e-12)
    thr = float(scipy.stats.chi2.ppf(1 - 1e-4, w))
    alarm = first_alarm(np.where(ok, en, 0.0), thr)
    assert fault_at <= alarm < fault_at + w


def test_energy_skips_missing_samples():
    n, w = 300, 10
    r = np.random.default_rng(1).standard_normal((n, 1))
    r[37] = np.nan
    en = energy_statistic(r, np.ones((n, 1, 1)), w)
    assert np.all(np.isfinite(en[w - 1:]))
    np.testing.assert_allclose(en, _energy_loop(r[:, 0], w), rtol=1e-12, equal_nan=True)


def test_kitanidis_filter_predicts_without_update_on_a_missing_sample():
    from fdi_lib.kitanidis import kitanidis_filter, kitanidis_gains

    m = ltv_model(F=0.5 * np.eye(2), H=np.eye(2), Q=np.eye(2), R=np.eye(2), n_steps=20)
    kg = kitanidis_gains(m, [[1.0], [0.0]])
    y = np.random.default_rng(2).standard_normal((20, 2))
    y[7, 1] = np.nan                                     # one component missing: the whole sample is
    res = kitanidis_filter(m, y, gains=kg)
    assert np.isnan(res.innovations[7]).all() and np.count_nonzero(np.isnan(res.innovations)) == 2
    np.testing.assert_array_equal(res.x_filt[7], res.x_pred[7])       # no update
    np.testing.assert_allclose(res.x_pred[8], 0.5 * res.x_pred[7], rtol=1e-15)
    clean = kitanidis_filter(m, np.where(np.arange(20)[:, None] == 7, 0.0, y), gains=kg)
    np.testing.assert_allclose(res.x_filt[:7], clean.x_filt[:7], rtol=1e-15)


@pytest.mark.parametrize("bad", [np.nan, np.inf, -np.inf])
def test_check_finite_on_large_arrays_names_the_first_bad_index(bad):
    """Large arrays take a fast path (a finite sum); it must neither miss a bad value nor
    reject finite values whose sum overflows."""
    from fdi_lib.validation import check_finite

    x = np.full((70, 80), 1e308)  # the sum overflows, every value is finite
    check_finite(x, "x")
    x[[0, 33], [5, 7]] = [-np.inf, bad]  # with a NaN or an inf elsewhere
    with pytest.raises(NonFiniteError, match=r"x: expected finite values, got -inf at index \(0, 5\)"):
        check_finite(x, "x")
    y = np.zeros(10_000)
    y[9_999] = bad
    with pytest.raises(NonFiniteError, match=r"y: expected finite values, got .* at index \(9999,\)"):
        check_finite(y, "y")
