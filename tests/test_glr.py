"""GLR tests of Zhang & Basseville (2014), Section 4, against independent computations."""

import numpy as np
import pytest
import scipy.stats

from conftest import make_random_ltv
from fdi_lib import glr
from fdi_lib.errors import ModelError, ShapeError
from fdi_lib.filters import kalman_filter, kalman_gains
from fdi_lib.glr import WindowedGLR, first_alarm, glr_known_profile, glr_window, quadratic_form
from fdi_lib.models import fault_profile, impulse_family, step_family
from fdi_lib.signatures import fault_signature
from fdi_lib.simulate import simulate
from fdi_lib.systems import zb2014_unstable as ex


def test_known_profile_glr_equals_brute_force_least_squares():
    rng = np.random.default_rng(0)
    m = make_random_ltv(rng, n=3, p=2, n_steps=30)
    prof = fault_profile(m, Psi=rng.standard_normal((30, 3, 2)))
    sim = simulate(m, rng=rng, fault=prof, theta=[0.5, -1.0])
    g = kalman_gains(m)
    eps = kalman_filter(m, sim.y, sim.u, gains=g).innovations
    S = fault_signature(m, g, prof).on_innovation
    res = glr_known_profile(eps, g, S)
    for k in (3, 10, 29):
        # Stack the whitened regression explicitly and solve it with lstsq.
        W = [np.linalg.cholesky(np.linalg.inv(g.Sigma[j])).T for j in range(k + 1)]
        X = np.vstack([W[j] @ S[j] for j in range(k + 1)])
        z = np.concatenate([W[j] @ eps[j] for j in range(k + 1)])
        theta, *_ = np.linalg.lstsq(X, z, rcond=None)
        lr = z @ z - np.sum((z - X @ theta) ** 2)  # 2 log LR = RSS(0) - RSS(theta_hat)
        np.testing.assert_allclose(res.statistic[k], lr, rtol=1e-9)
        np.testing.assert_allclose(res.theta_hat[k], theta, rtol=1e-8)


def _naive_window(eps, model, gains, family, w, s):
    """Per-onset triple loop straight from (31)-(36): for each k, each r, sum over j.

    A sample whose innovation has a NaN is missing: it is left out of both sums.
    """
    N = model.n_steps
    kept = [j for j in range(N) if not np.isnan(eps[j]).any()]
    stat = np.full(N, np.nan)
    onset = np.full(N, -1)
    for k in range(N):
        best = -np.inf
        for r in range(max(0, k - w + 1), k - s + 1):
            prof = family.profile(r)
            S = fault_signature(model, gains, prof).on_innovation
            C = sum(S[j].T @ np.linalg.solve(gains.Sigma[j], S[j]) for j in kept if j <= k)
            d = sum(S[j].T @ np.linalg.solve(gains.Sigma[j], eps[j]) for j in kept if j <= k)
            val = d @ np.linalg.pinv(C) @ d
            if val > best:
                best, onset[k] = val, r
        if best > -np.inf:
            stat[k] = best
    return stat, onset


@pytest.mark.parametrize("kind", ["step", "impulse"])
def test_windowed_glr_equals_naive_triple_loop(kind):
    rng = np.random.default_rng(1)
    m = make_random_ltv(rng, n=2, p=1, n_steps=25)
    g = kalman_gains(m)
    if kind == "step":
        fam = step_family(
            m, Psi=rng.standard_normal((25, 2, 2)), Phi=rng.standard_normal((25, 1, 2))
        )
    else:
        fam = impulse_family(m)
    sim = simulate(m, rng=rng, fault=fam.profile(12), theta=[1.0, 2.0])
    eps = kalman_filter(m, sim.y, sim.u, gains=g).innovations
    fast = glr_window(eps, m, g, fam, window=8, min_samples=2)
    stat, onset = _naive_window(eps, m, g, fam, 8, 2)
    np.testing.assert_allclose(fast.statistic, stat, rtol=1e-9, equal_nan=True)
    np.testing.assert_array_equal(fast.onset, onset)
    # Missing samples (NaN) are left out of the sums, online and batched, for every window
    # that contains them (the information precomputed for the window is corrected).
    eps[[13, 15]] = np.nan
    stat, onset = _naive_window(eps, m, g, fam, 8, 2)
    for res in (
        glr_window(eps, m, g, fam, window=8, min_samples=2),
        glr_window(np.stack([eps, eps]), m, g, fam, window=8, min_samples=2),
    ):
        np.testing.assert_allclose(
            res.statistic[..., 14:],
            np.broadcast_to(stat[14:], res.statistic[..., 14:].shape),
            rtol=1e-9,
        )
        np.testing.assert_array_equal(
            res.onset[..., 14:], np.broadcast_to(onset[14:], res.onset[..., 14:].shape)
        )


def test_online_updates_equal_batch_and_realisations_are_independent():
    m = ex.unstable_model(120)
    g = kalman_gains(m)
    fam = impulse_family(m)
    sim = simulate(
        m,
        rng=np.random.default_rng(2),
        controller=ex.controller(),
        size=3,
        fault=fam.profile(60),
        theta=[2.0, 0.0],
    )
    eps = kalman_filter(m, sim.y, sim.u, gains=g).innovations
    batch = glr_window(eps, m, g, fam, window=30)
    online = WindowedGLR(m, g, fam, window=30)
    for k in range(120):
        l_k, r_k, *_ = online.update(eps[1, k])
        np.testing.assert_allclose(l_k, batch.statistic[1, k], rtol=1e-12, equal_nan=True)
        assert r_k == batch.onset[1, k]
    single = glr_window(eps[2], m, g, fam, window=30)
    np.testing.assert_allclose(single.statistic, batch.statistic[2], rtol=1e-12, equal_nan=True)


def test_many_realisations_equal_online_updates_bit_for_bit():
    """More realisations than the block evaluation takes (_RECORD_MAX_BATCH): glr_window steps one
    detector sample by sample and fills each sample's outputs as one row; the same bits as
    WindowedGLR.update on every realisation, with a sample dropped in all of them and start=."""
    m = ex.unstable_model(120)
    g = kalman_gains(m)
    fam = impulse_family(m)
    sim = simulate(
        m,
        rng=np.random.default_rng(7),
        controller=ex.controller(),
        size=6,
        fault=fam.profile(60),
        theta=[2.0, 0.0],
    )
    eps = kalman_filter(m, sim.y, sim.u, gains=g).innovations
    eps[:, 75] = np.nan  # dropped in every realisation: one detector, C_k(r) corrected
    assert eps.shape[0] > glr._RECORD_MAX_BATCH
    res = glr_window(eps, m, g, fam, window=30, start=40)
    online = WindowedGLR(m, g, fam, window=30, batch_shape=(6,))
    keys = ("statistic", "onset", "theta_hat", "C_hat", "d_hat")
    for k in range(120):
        out = online.update(eps[:, k], statistics=k >= 40)
        for key, value in zip(keys, out):
            np.testing.assert_array_equal(getattr(res, key)[:, k], value, err_msg=f"{key} at {k}")
    assert np.all(np.isnan(res.statistic[:, :40])) and np.all(res.onset[:, :40] == -1)
    assert np.all(np.isfinite(res.statistic[:, 40:]))
    for key in keys:  # the layout of a result (realisations first), contiguous
        assert getattr(res, key).flags.c_contiguous


def test_shared_detector_gives_the_same_results_for_every_batch():
    """glr_window(..., shared=det) reuses det's noise-independent arrays: same results as a detector
    built for each batch (bit for bit), batches independent of each other, NaN groups included."""
    m = ex.unstable_model(120)
    g = kalman_gains(m)
    fam = impulse_family(m)
    sim = simulate(
        m,
        rng=np.random.default_rng(5),
        controller=ex.controller(),
        size=7,
        fault=fam.profile(60),
        theta=[2.0, 0.0],
    )
    eps = kalman_filter(m, sim.y, sim.u, gains=g).innovations
    det = WindowedGLR(m, g, fam, window=30)
    eps_nan = eps.copy()
    eps_nan[2, 70] = np.nan  # a second missing-sample pattern: grouped evaluation
    for batch in (eps[0], eps[:3], eps, eps_nan):
        ref = glr_window(batch, m, g, fam, window=30)
        for _ in range(2):  # a second use of det starts afresh
            res = glr_window(batch, m, g, fam, window=30, shared=det)
            for key in ("statistic", "onset", "theta_hat", "C_hat", "d_hat"):
                np.testing.assert_array_equal(getattr(res, key), getattr(ref, key))
    assert det.k == 0  # the template itself is never advanced
    other = WindowedGLR(m, g, fam, window=20)
    with pytest.raises(
        ModelError, match="shared: expected a WindowedGLR built with the same model"
    ):
        glr_window(eps, m, g, fam, window=30, shared=other)
    with pytest.raises(ModelError, match="shared: expected a WindowedGLR"):
        glr_window(eps, m, kalman_gains(m), fam, window=30, shared=det)


@pytest.mark.parametrize("size", [None, 3, 7])
def test_start_leaves_later_statistics_unchanged(size):
    """glr_window(..., start=s): nan / -1 before s, the same outputs as without from s on (record
    evaluation for a few realisations, sample by sample for more, grouped with missing samples)."""
    m = ex.unstable_model(90)
    g = kalman_gains(m)
    fam = impulse_family(m)
    sim = simulate(
        m,
        rng=np.random.default_rng(8),
        controller=ex.controller(),
        size=size,
        fault=fam.profile(50),
        theta=[3.0, 0.0],
    )
    eps = kalman_filter(m, sim.y, sim.u, gains=g).innovations
    cases = [eps]
    if size == 7:
        nan = eps.copy()
        nan[1, 20] = np.nan
        cases.append(nan)
    for e in cases:
        full = glr_window(e, m, g, fam, window=25)
        part = glr_window(e, m, g, fam, window=25, start=40)
        for key, undefined in (
            ("statistic", np.nan),
            ("onset", -1),
            ("theta_hat", np.nan),
            ("C_hat", np.nan),
            ("d_hat", np.nan),
        ):
            a, b = getattr(part, key), getattr(full, key)
            np.testing.assert_array_equal(
                a[..., 40:, *([slice(None)] * (a.ndim - e.ndim + 1))],
                b[..., 40:, *([slice(None)] * (b.ndim - e.ndim + 1))],
            )
            before = a.reshape(*e.shape[:-2], 90, -1)[..., :40, :]
            assert np.all(np.isnan(before)) if undefined is np.nan else np.all(before == -1)
        assert np.any(np.isfinite(full.statistic[..., 30:40]))  # the masked samples had values
    with pytest.raises(ModelError, match=r"start: expected an integer in \[0, 90\], got 91"):
        glr_window(eps, m, g, fam, window=25, start=91)


def test_known_profile_statistic_is_chi2_m_under_no_fault():
    """Calibration: l_k ~ chi2(m) under H0 (4000 seeded runs, KS test at the last sample)."""
    rng = np.random.default_rng(3)
    m = make_random_ltv(rng, n=3, p=1, n_steps=40)
    prof = fault_profile(m, Psi=rng.standard_normal((40, 3, 3)))  # m = 3 faults > p = 1 sensor
    g = kalman_gains(m)
    S = fault_signature(m, g, prof).on_innovation
    sim = simulate(m, rng=np.random.default_rng(4), size=4000)
    eps = kalman_filter(m, sim.y, sim.u, gains=g).innovations
    stat = glr_known_profile(eps, g, S).statistic[:, -1]
    assert scipy.stats.kstest(stat, scipy.stats.chi2(3).cdf).pvalue > 0.01
    # ...and it is not chi2(2) or chi2(4): the test can fail.
    assert scipy.stats.kstest(stat, scipy.stats.chi2(2).cdf).pvalue < 1e-6
    assert scipy.stats.kstest(stat, scipy.stats.chi2(4).cdf).pvalue < 1e-6


def test_pseudo_inverse_handles_a_singular_information():
    C = np.array([[1.0, 1.0], [1.0, 1.0]])
    d = np.array([2.0, 2.0])
    stat, theta = quadratic_form(C, d)
    np.testing.assert_allclose(stat, 4.0)  # d^T C^+ d with C^+ = C / 4
    np.testing.assert_allclose(theta, [1.0, 1.0])


def test_first_alarm():
    stat = np.array([[np.nan, 1.0, 5.0, 2.0, 9.0], [0.0, 0.0, 0.0, 0.0, 0.0]])
    np.testing.assert_array_equal(first_alarm(stat, 4.0), [2, -1])
    np.testing.assert_array_equal(first_alarm(stat, 4.0, start=3), [4, -1])


def test_bad_arguments():
    m = ex.unstable_model(20)
    g = kalman_gains(m)
    fam = impulse_family(m)
    with pytest.raises(ModelError, match=r"window: expected an integer in \[1, 20\], got 0"):
        WindowedGLR(m, g, fam, window=0)
    with pytest.raises(ModelError, match=r"min_samples: expected an integer in \[0, 4\], got 5"):
        WindowedGLR(m, g, fam, window=5, min_samples=5)
    with pytest.raises(
        ShapeError, match=r"innovations: expected shape \(\.\.\., 20, 1\), got \(19, 1\)"
    ):
        glr_window(np.zeros((19, 1)), m, g, fam, window=5)
    det = WindowedGLR(m, g, fam, window=5, batch_shape=(4,))
    with pytest.raises(ShapeError, match=r"eps_k: expected shape \(4, 1\), got \(1,\)"):
        det.update(np.zeros(1))
    with pytest.raises(ShapeError, match=r"signature: expected shape \(20, 1, m\)"):
        glr_known_profile(np.zeros((20, 1)), g, np.zeros((20, 2, 2)))
    # no parameter at all (m = 0): a shape error, not numpy's empty reduction
    with pytest.raises(ShapeError, match=r"signature: expected shape \(20, 1, m\) with m >= 1"):
        glr_known_profile(np.zeros((20, 1)), g, np.zeros((20, 1, 0)))
    with pytest.raises(ShapeError, match=r"C, d: expected shapes .* with m >= 1, got \(3, 0, 0\)"):
        quadratic_form(np.zeros((3, 0, 0)), np.zeros((3, 0)))


def test_an_information_below_the_smallest_normal_number_is_none():
    """An eigenvalue of C that is positive but subnormal would give an infinite 1 / lambda (an
    overflow): it is below the cut-off, the statistic 0 and the estimate 0, finite, without a
    warning; the smallest normal one is still inverted."""
    tiny = np.finfo(float).tiny
    for lam, inverted in ((tiny / 4, False), (5e-324, False), (tiny, True), (1.0, True)):
        with np.errstate(over="raise", divide="raise", invalid="raise"):
            stat, theta = quadratic_form(np.array([[[lam]]]), np.array([[1e-160]]))
        assert np.isfinite(stat).all() and np.isfinite(theta).all()
        assert (stat[0] > 0) == inverted and (theta[0, 0] > 0) == inverted


@pytest.mark.parametrize(
    "kind, m_faults, batch", [("step", 3, 1), ("step", 2, 6), ("impulse", 2, 3), ("step", 5, 2)]
)
def test_windowed_glr_estimates_equal_brute_force(kind, m_faults, batch):
    """Statistic, onset, theta_hat = C^+ d, C and d at the estimated onset, from scratch per (k, r),
    for single records and batches (both evaluation orders of glr_window), m = 2 (closed-form
    rotation), 3 (Jacobi sweeps) and 5 (LAPACK) fault directions."""
    rng = np.random.default_rng(7)
    N, w, s = 22, 7, 1
    m = make_random_ltv(rng, n=3, p=2, n_steps=N)
    g = kalman_gains(m)
    if kind == "step":
        fam = step_family(
            m, Psi=rng.standard_normal((N, 3, m_faults)), Phi=rng.standard_normal((N, 2, m_faults))
        )
    else:
        fam = impulse_family(m)
        m_faults = fam.m
    theta = np.zeros(m_faults)
    theta[0] = 1.5
    sim = simulate(m, rng=rng, fault=fam.profile(9), theta=theta, size=batch)
    eps = kalman_filter(m, sim.y, sim.u, gains=g).innovations
    fast = glr_window(eps, m, g, fam, window=w, min_samples=s)
    for b in range(batch):
        for k in range(N):
            best, arg = -np.inf, None
            for r in range(max(0, k - w + 1), k - s + 1):
                S = fault_signature(m, g, fam.profile(r)).on_innovation
                C = sum(S[j].T @ np.linalg.solve(g.Sigma[j], S[j]) for j in range(r, k + 1))
                d = sum(S[j].T @ np.linalg.solve(g.Sigma[j], eps[b, j]) for j in range(r, k + 1))
                val = d @ np.linalg.pinv(C, rcond=1e-10, hermitian=True) @ d
                if val > best:
                    best, arg = val, (r, C, d)
            if arg is None:
                assert np.isnan(fast.statistic[b, k]) and fast.onset[b, k] == -1
                continue
            r, C, d = arg
            scale = max(1.0, abs(best))
            assert abs(fast.statistic[b, k] - best) <= 1e-9 * scale
            assert fast.onset[b, k] == r
            np.testing.assert_allclose(
                fast.C_hat[b, k], C, rtol=1e-10, atol=1e-12 * np.abs(C).max()
            )
            np.testing.assert_allclose(
                fast.d_hat[b, k], d, rtol=1e-10, atol=1e-12 * np.abs(d).max()
            )
            th = np.linalg.pinv(C, rcond=1e-10, hermitian=True) @ d
            np.testing.assert_allclose(
                fast.theta_hat[b, k], th, rtol=1e-7, atol=1e-9 * np.abs(th).max()
            )


@pytest.mark.parametrize("size", [2, 6])
def test_statistics_alone_are_those_with_the_estimates(size):
    """glr_window(..., estimates=False): the same statistics and onsets, bit for bit, without
    theta_hat, C_hat, d_hat (None), by blocks (few realisations), sample by sample (many), per group
    of missing samples, and with per-realisation profiles; estimates="scores": also d_hat, bit for
    bit."""
    m = ex.unstable_model(120)
    g = kalman_gains(m)
    fam = impulse_family(m)
    sim = simulate(
        m,
        rng=np.random.default_rng(9),
        controller=ex.controller(),
        size=size,
        fault=fam.profile(60),
        theta=[2.0, 0.0],
    )
    eps = kalman_filter(m, sim.y, sim.u, gains=g).innovations
    eps_nan = eps.copy()
    eps_nan[1, 70] = np.nan  # two missing-sample patterns: grouped evaluation
    own = step_family(m, Psi=np.random.default_rng(1).standard_normal((size, 120, m.n, 1)))
    for e, f in ((eps, fam), (eps_nan, fam), (eps, own)):
        full = glr_window(e, m, g, f, window=30, start=40)
        alone = glr_window(e, m, g, f, window=30, start=40, estimates=False)
        assert alone.theta_hat is None and alone.C_hat is None and alone.d_hat is None
        assert alone.statistic.tobytes() == full.statistic.tobytes()
        assert alone.onset.tobytes() == full.onset.tobytes()
        scores = glr_window(e, m, g, f, window=30, start=40, estimates="scores")
        assert scores.theta_hat is None and scores.C_hat is None
        for key in ("statistic", "onset", "d_hat"):
            assert getattr(scores, key).tobytes() == getattr(full, key).tobytes(), key


def test_information_is_the_estimates_information_at_the_estimated_onset():
    """WindowedGLR.information(k, r_hat_k) is glr_window's C_hat, bit for bit, at every sample where
    an onset is estimated (a shared family, sample by sample and by blocks); it refuses what it
    cannot give: per-realisation profiles, an onset outside the window or too recent, floats."""
    m = ex.unstable_model(120)
    g = kalman_gains(m)
    fam = step_family(m, Phi=np.eye(m.p))
    det = WindowedGLR(m, g, fam, window=30)
    for size in (2, 6):
        sim = simulate(m, rng=np.random.default_rng(size), controller=ex.controller(), size=size)
        eps = kalman_filter(m, sim.y, sim.u, gains=g).innovations
        res = glr_window(eps, m, g, fam, window=30, shared=det)
        b, k = np.nonzero(res.onset >= 0)
        assert b.size > 100
        got = det.information(k, res.onset[b, k])
        assert got.tobytes() == res.C_hat[b, k].tobytes()
    with pytest.raises(ModelError, match=r"r = 100 at k = 100 \(index \(1,\)\)"):
        det.information([100, 100], [95, 100])  # s = 1: the newest onset has no sample yet
    with pytest.raises(ModelError, match="r = 70 at k = 100"):
        det.information(100, 70)
    with pytest.raises(ModelError, match="expected integers"):
        det.information(100.0, 95)
    own = step_family(m, Psi=np.ones((2, 120, m.n, 1)))
    with pytest.raises(ModelError, match="per-realisation profiles"):
        WindowedGLR(m, g, own, window=30, batch_shape=(2,)).information(100, 95)
    with pytest.raises(ModelError, match="estimates: expected True, False or 'scores'"):
        glr_window(eps, m, g, fam, window=30, estimates="C")
