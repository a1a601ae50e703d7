"""Reproductions of Zhang & Basseville (2014), Section 6.1 (Figs. 1-4)."""

import numpy as np
import pytest

from fdi_lib.reproduce import reproduce
from fdi_lib.reproduce.zb2014 import (
    ONSETS,
    gamma_lower_bound,
    gamma_norm_peaks,
    single_entry_readings,
    unstable_run,
)
from fdi_lib.systems import zb2014_unstable as ex


def test_fig1_gamma_bounded_and_decaying():
    res = reproduce("zb2014-fig1")
    for r in map(str, ONSETS):
        assert (
            1.0 <= res.headline["gamma_norm_max"][r] < 3.0
        )  # bounded (the paper's "< 1": see book)
        assert res.headline["gamma_norm_final"][r] < 1e-50
    # Onsets after the Kalman transient all give the same (steady-state) peak, ||F(I - KH)||_2.
    assert res.headline["gamma_norm_max"]["101"] == pytest.approx(
        res.headline["gamma_norm_max"]["301"], rel=1e-9
    )


def test_fig2_alpha_grows_like_the_unstable_mode():
    res = reproduce("zb2014-fig2")
    for r in map(str, ONSETS):
        assert res.headline["alpha_log10_slope"][r] == pytest.approx(np.log10(1.2), rel=1e-6)
    finals = [res.headline["alpha_log10_norm_final"][str(r)] for r in ONSETS]
    np.testing.assert_allclose(np.diff(finals), -100 * np.log10(1.2), rtol=1e-3)


@pytest.mark.parametrize("rid, size", [("zb2014-fig3", 4.0), ("zb2014-fig4", 1.5)])
def test_fig3_fig4_detect_and_locate_the_impulse(rid, size):
    res = reproduce(rid, seed=0)
    h = res.headline
    assert h["glr_max_after_fault"] > 5 * h["glr_max_before_fault"]
    assert 201 <= h["glr_argmax_time"] <= 301
    assert abs(h["onset_estimate"] - 201) <= 2
    assert h["theta_estimate"][0] == pytest.approx(size, abs=0.6)


def test_detection_over_seeds_is_robust():
    """Not tuned to one seed: the larger fault is located within 2 samples for 10 seeds."""
    for seed in range(10):
        run = unstable_run(theta=(4.0, 0.0), seed=seed)
        k = int(np.nanargmax(run.glr.statistic))
        assert abs(run.glr.onset[k] - 201) <= 2


def test_plot_functions_draw_the_figures():
    import matplotlib

    matplotlib.use("Agg")
    from fdi_lib.reproduce import get

    for rid, n_axes in [
        ("zb2014-fig1", 2),
        ("zb2014-fig2", 1),
        ("zb2014-fig3", 2),
        ("zb2014-fig4", 2),
    ]:
        rep = get(rid)
        fig = rep.plot(rep())
        assert len(fig.axes) == n_axes
        assert all(ax.lines for ax in fig.axes), f"{rid}: an empty panel"
    fig1 = get("zb2014-fig1").plot(get("zb2014-fig1")())
    assert len(fig1.axes[0].lines) == len(ONSETS) + 1  # one curve per onset + the paper's bound
    # zoom: ||Gamma_k||, ||Gamma_k e_1||, the bound 1 and the floor ||F e_2||
    assert len(fig1.axes[1].lines) == 4


def _gamma_by_hand(F, r, n_steps=ex.N_STEPS):
    """Independent Kalman + signature recursion for an impulse at r (plain loops, no fdi_lib)."""
    P = ex.Q.copy()
    H, R, Q = ex.H, ex.R, ex.Q
    Gamma = np.zeros((2, 2))
    norms, e1 = [], []
    for k in range(n_steps):
        norms.append(np.linalg.norm(Gamma, 2))
        e1.append(np.linalg.norm(Gamma[:, 0]))
        S = H @ P @ H.T + R
        K = P @ H.T @ np.linalg.inv(S)
        A = F @ (np.eye(2) - K @ H)
        Gamma = A @ Gamma + (np.eye(2) if k == r - 1 else 0.0)
        P = A @ P @ F.T + Q  # = F (I - KH) P F^T + Q
    return np.array(norms), np.array(e1)


def test_fig1_bound_from_the_unobserved_column():
    """H e2 = 0, so ||Gamma_{r+1}|| >= ||F e2|| = sqrt(1 + 1.2^2) whatever P0, Q, R."""
    assert gamma_lower_bound() == pytest.approx(np.hypot(1.0, 1.2), rel=1e-15)
    h = reproduce("zb2014-fig1").headline
    assert h["gamma_lower_bound"] == pytest.approx(1.5620499351813308, rel=1e-12)
    for r in map(str, ONSETS):
        assert h["gamma_norm_max"][r] >= h["gamma_lower_bound"] - 1e-12
        # the column excited by theta = [theta_1, 0]: Gamma_r e1 = e1, then it only decays
        assert h["gamma_e1_norm_max"][r] == pytest.approx(1.0, abs=1e-12)
    assert h["unstable_eigenvalue"] == pytest.approx(1.2, rel=1e-12)
    # a different P0, Q or R does not lift the floor: the bound does not involve them
    for scale in (1e-3, 1e3):
        F = ex.F
        P = ex.Q * scale
        K = P @ ex.H.T / (ex.H @ P @ ex.H.T + ex.R * scale)
        assert np.linalg.norm(F @ (np.eye(2) - K @ ex.H), 2) >= np.hypot(1.0, 1.2) - 1e-12


def test_fig1_norms_match_an_independent_recursion():
    peaks = gamma_norm_peaks(ex.F, onsets=(1, 101))
    for r in (1, 101):
        norms, e1 = _gamma_by_hand(ex.F, r)
        np.testing.assert_allclose(
            peaks["gamma"][str(r)][:300], norms[:300], rtol=1e-9, atol=1e-300
        )
        np.testing.assert_allclose(
            peaks["gamma_e1"][str(r)][:300], e1[:300], rtol=1e-9, atol=1e-300
        )


def test_single_entry_readings_of_the_quoted_eigenvalue():
    lam = ex.QUOTED_UNSTABLE_EIGENVALUE
    readings = {t.entry: t for t in single_entry_readings()}
    # F12 of a triangular matrix does not change its eigenvalues: three readings only
    assert sorted(readings) == ["F11", "F21", "F22"]
    assert readings["F11"].value == pytest.approx(lam, rel=1e-12)
    assert readings["F22"].value == pytest.approx(lam, rel=1e-12)
    assert readings["F21"].value == pytest.approx((0.5 - lam) * (1.2 - lam), rel=1e-9)
    for t in readings.values():
        assert np.min(np.abs(t.eigenvalues - lam)) < 1e-9
        assert t.gamma_norm_max > 1.0  # none keeps the paper's bound
    # F22 = 1.2808: peak 1.95, checked against the plain-loop recursion
    F22 = ex.F.copy()
    F22[1, 1] = lam
    peak = max(_gamma_by_hand(F22, r)[0].max() for r in ONSETS)
    assert readings["F22"].gamma_norm_max == pytest.approx(peak, rel=1e-9)
    assert peak == pytest.approx(1.95, abs=0.01)
    assert reproduce("zb2014-fig1").headline["typo_readings_bounded"] == 0


@pytest.mark.parametrize("rid", ["zb2014-fig3", "zb2014-fig4"])
def test_fig3_fig4_visibility_and_estimate_interval(rid):
    res = reproduce(rid, seed=0)
    h, run = res.headline, res.data["run"]
    for (lo, hi), t in zip(h["theta_estimate_ci"], h["theta_estimate"]):
        assert lo < t < hi
    # sigma_k from an independent Riccati loop
    P, sig = ex.Q.copy(), []
    for _ in range(run.innovations.size):
        S = float((ex.H @ P @ ex.H.T + ex.R)[0, 0])
        sig.append(np.sqrt(S))
        K = P @ ex.H.T / S
        A = ex.F @ (np.eye(2) - K @ ex.H)
        P = A @ P @ ex.F.T + ex.Q
    z = np.abs(run.innovations) / np.array(sig)
    assert h["innovation_max_sigma_before_fault"] == pytest.approx(z[:201].max(), rel=1e-9)
    assert h["innovation_max_sigma_after_fault"] == pytest.approx(z[201:].max(), rel=1e-9)
    # the fault is not "hardly visible": the spike dwarfs the pre-fault maximum
    assert h["innovation_max_sigma_after_fault"] > 3 * h["innovation_max_sigma_before_fault"]


def test_youngest_onset_information_matches_direct_sums():
    """C_k(k - s) against a direct sum over j = r .. k of the signature of the onset r."""
    from fdi_lib.filters import kalman_gains
    from fdi_lib.models import impulse_family
    from fdi_lib.reproduce.zb2014 import youngest_onset_information
    from fdi_lib.signatures import fault_signature

    model = ex.unstable_model(60)
    gains = kalman_gains(model)
    fam = impulse_family(model)
    s = 2
    C = youngest_onset_information(model, gains, fam)
    assert C.shape == (60 - s, 2, 2)
    for k in (5, 30, 59):
        r = k - s
        S = fault_signature(model, gains, fam.profile(r)).on_innovation
        direct = sum(S[j].T @ np.linalg.inv(gains.Sigma[j]) @ S[j] for j in range(r, k + 1))
        np.testing.assert_allclose(C[k - s], direct, rtol=1e-10)


def test_pipeline_youngest_onset_information_with_the_default_s():
    """The statement of the GLR chapter: s = ceil(m/p) does not make C_k(k-s) invertible on
    the designed surrogate (rank one at every k); on the physical default it has rank two
    but is badly conditioned."""
    from fdi_lib.filters import kalman_gains
    from fdi_lib.reproduce.zb2014 import youngest_onset_information
    from fdi_lib.systems import gas_pipeline as gp

    ev = {}
    for variant in ("designed", "physical"):
        model = gp.pipeline_model(variant=variant)
        fam = gp.input_fault_family(model, variant=variant)
        ev[variant] = np.linalg.eigvalsh(
            youngest_onset_information(model, kalman_gains(model), fam)
        )
        assert np.all(ev[variant][:, 1] > 0)
    d, p = ev["designed"], ev["physical"]
    assert np.all(np.abs(d[:, 0]) <= 1e-12 * d[:, 1])  # rank one at every k
    assert np.all(p[:, 0] >= 1e-13 * p[:, 1])  # rank two at every k ...
    assert (p[:, 0] / p[:, 1]).min() < 1e-8  # ... barely invertible


def test_window_min_eigenvalue_constant_versus_varying_profile():
    from fdi_lib.filters import kalman_gains
    from fdi_lib.reproduce.zb2014 import window_min_eigenvalue

    model = ex.unstable_model()
    gains = kalman_gains(model)
    const = window_min_eigenvalue(model, gains, np.eye(2), 10)
    k = np.arange(model.n_steps)
    varying = np.stack([np.diag([np.sin(0.2 * j), np.cos(0.05 * j)]) for j in k])
    vary = window_min_eigenvalue(model, gains, varying, 10)
    assert const.shape == vary.shape == (model.n_steps - 9,)
    assert const[-100:].max() < 1e-10 * vary[-100:].min()


def test_chapter_plot_helpers_draw():
    import matplotlib

    matplotlib.use("Agg")
    from fdi_lib.calibration import Calibration
    from fdi_lib.reproduce.views.zb2014 import plot_null_histograms, plot_persistent_excitation

    cal = Calibration(
        statistics=np.random.default_rng(0).chisquare(2, 200),
        dof=2,
        ks_pvalue=0.5,
        alpha=0.05,
        rejection_rate=0.05,
        rejection_ci=(0.02, 0.09),
    )
    fig = plot_null_histograms({"a": cal, "b": cal}, xlabel="$l$")
    assert len(fig.axes) == 2 and all(ax.patches and ax.lines for ax in fig.axes)
    fig = plot_persistent_excitation({"x": np.ones(5), "y": np.zeros(5)}, s=3)
    assert len(fig.axes[0].lines) == 2
    assert fig.axes[0].lines[1].get_ydata().min() == pytest.approx(1e-16)
