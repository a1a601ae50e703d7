"""Figures and reader tables of the Basseville & Zhang reproductions (whiteness, Solutions 1-2).

The computing side, with the registrations, is :mod:`fdi_lib.reproduce.bz`.
"""

from __future__ import annotations

from typing import Any, Sequence

import numpy as np

from fdi_lib.plotting import figure, OURS_COLOR, THRESHOLD_COLOR
from fdi_lib.reproduce.registry import ReproductionResult


__all__ = [
    "headline_table",
    "solution2_table",
    "plot_whiteness",
    "plot_solution1",
    "plot_solution2",
    "LABELS",
]


def plot_whiteness(result: ReproductionResult, fig: Any = None):
    """Histograms of the Ljung-Box p-values (uniform under whiteness) and the lag-one covariance."""
    fig, axes = figure(1, 2, fig=fig, figsize=(8.0, 3.4))
    ax = axes[0, 0]
    bins = np.linspace(0, 1, 21)
    for name, label in (
        ("kalman", r"Kalman innovation $\varepsilon_k$"),
        ("kitanidis", r"Kitanidis innovation $\varepsilon_k$ (27)"),
        ("reduced_f", r"projected $T_k\varepsilon_k$, $f\neq 0$"),
    ):
        ax.hist(
            result.data["pvalues"][name].ravel(),
            bins=bins,
            histtype="step",
            density=True,
            label=label,
        )
    ax.axhline(1.0, color="k", lw=0.8, ls=":")
    ax.set(xlabel=r"Ljung-Box $p$-value", ylabel="density", title=r"Portmanteau $p$-values")
    ax.legend(loc="upper right")
    ax = axes[0, 1]
    k = result.data["lag_k"]
    ax.plot(k, result.data["lag1_theory"], color=OURS_COLOR, label="closed form")
    ax.plot(k, result.data["lag1_empirical"], ".", ms=2, color="0.4", label="Monte Carlo")
    ax.axhline(0.0, color=THRESHOLD_COLOR, lw=0.8, ls="--", label="paper (Prop. 2): 0")
    ax.set(
        xlabel=r"$k$",
        ylabel=r"corr$(\varepsilon^{(1)}_{k+1},\varepsilon^{(1)}_k)$",
        title="Kitanidis innovation, lag one",
    )
    ax.legend(loc="lower right")
    return fig


def plot_solution1(result: ReproductionResult, fig: Any = None):
    """Histograms of the GLR alarm times (theta, with and without f) and of the energy alarms (f only),
    in two stacked panels; in each, the first series is drawn wide and pale under the others."""
    fig, axes = figure(1, 2, fig=fig, figsize=(8.0, 3.4))
    d = result.data
    s = result.settings
    ax = axes[0, 0]
    bins = np.arange(0, s["n_steps"] + 1, 5)
    # a pair of histograms that may coincide: the first wide and pale under the second, so that
    # neither hides the other (the legend lists both)
    under, over = dict(lw=5.0, alpha=0.4), dict(lw=1.4)
    for (key, label), style in zip(
        (("theta_glr_alarm", r"$\theta$ jump"), ("both_glr_alarm", r"$\theta$ jump + $f$")),
        (under, over),
    ):
        a = d[key]
        ax.hist(a[a >= 0], bins=bins, histtype="step", label=label, **style)
    ax.hist(
        d["f_kalman_glr_alarm"][d["f_kalman_glr_alarm"] >= 0],
        bins=bins,
        histtype="step",
        ls="--",
        label=r"$f$ only, GLR on Kalman",
    )
    ax.axvline(s["theta_onset"], color=THRESHOLD_COLOR, lw=0.8, ls=":")
    ax.axvline(s["f_onset"], color="0.5", lw=0.8, ls=":")
    ax.set(
        xlabel=r"alarm time $k$", ylabel="number of runs", title=r"GLR alarms on $T_k\varepsilon_k$"
    )
    ax.legend(loc="upper left")
    ax = axes[0, 1]
    for (key, label), style in zip(
        (
            ("f_nonpar_alarm", r"$f$ only"),
            ("both_nonpar_alarm", r"$\theta$ + $f$"),
            ("theta_energy_alarm", r"$\theta$ only (any energy alarm)"),
        ),
        (under, over, over),
    ):
        a = d[key]
        ax.hist(a[a >= 0], bins=bins, histtype="step", label=label, **style)
    ax.axvline(s["f_onset"], color="0.5", lw=0.8, ls=":")
    ax.set(
        xlabel=r"alarm time $k$",
        ylabel="number of runs",
        title="Energy alarms (parallel Kalman filter)",
    )
    ax.legend(loc="upper left")
    return fig


def plot_solution2(result: ReproductionResult, fig: Any = None):
    """Mean tracking error against k for each forgetting factor, with and without ``f``."""
    fig, axes = figure(1, 3, fig=fig, figsize=(9.0, 3.2), sharex=True, sharey=True)
    s = result.settings
    titles = {
        "drift": "drift only",
        "f": r"drift + fast $f$ (period 25)",
        "fslow": r"drift + slow $f$ (period 400)",
    }
    for j, tag in enumerate(("drift", "f", "fslow")):
        ax = axes[0, j]
        for i, lam in enumerate(s["lambdas"]):
            ax.plot(result.data[f"mean_err_{tag}"][i], label=rf"$\lambda$ = {lam}")
        if tag != "drift":
            ax.axvline(s["f_onset"], color=THRESHOLD_COLOR, lw=0.8, ls=":")
        ax.set(xlabel=r"$k$", ylim=(0, None), title=titles[tag])
    axes[0, 0].set_ylabel(r"mean $\|\hat\theta_k-\theta_k\|$")
    axes[0, 0].legend(loc="upper right")
    return fig


_NA_NOTE = "n/a: no run raised the alarm, so there is no delay to average."


def _cell(key: str, value: Any, ci: Any) -> str:
    from fdi_lib.report import NA, fmt_number, fmt_rate

    if value is None:
        return NA
    if "rate" in key:
        return fmt_rate(value, ci)
    if ci is not None and ci[0] is not None:
        return f"{fmt_number(value)} [{fmt_number(ci[0])}, {fmt_number(ci[1])}]"
    return fmt_number(value)


def headline_table(result: ReproductionResult, keys: Sequence[str]):
    """Our values (95 % intervals where known) beside the paper's claim, for the keys of :data:`LABELS`."""
    from fdi_lib.report import NA, table

    h = result.headline
    rows = {
        LABELS[k]: [_cell(k, h[k], h.get(k + "_ci")), str(result.paper.get(k, "not given"))]
        for k in keys
    }
    notes = [
        "Rates in % with their 95 % Clopper-Pearson interval; delays with a 95 % t interval; "
        f"{result.settings['trials']} runs."
    ]
    if any(NA in cells for cells in rows.values()):
        notes.append(_NA_NOTE)
    return table(rows, ["ours", "paper"], notes=notes)


def solution2_table(result: ReproductionResult):
    """Tracking errors, detection rates and delays of ``bz-solution2``, one column per forgetting factor."""
    from fdi_lib.report import NA, fmt_number, fmt_rate, table

    h = result.headline

    def num(xs: Sequence[Any]) -> list[str]:
        return [NA if x is None else fmt_number(x) for x in xs]

    rows = {
        "tracking RMSE, k = 100 to 199": num(h["tracking_rmse"]),
        "RMSE after the onset of f (fast f)": num(h["tracking_rmse_after_f"]),
        "RMSE on the same range, no f": num(h["tracking_rmse_after_f_no_f"]),
        "RMSE after the onset of f (slow f)": num(h["tracking_rmse_after_f_slow"]),
        "detection of f (fast f)": [
            fmt_rate(r, c) for r, c in zip(h["detection_rate"], h["detection_rate_ci"])
        ],
        "mean delay, fast f (samples)": num(h["mean_delay"]),
        "detection of f (slow f)": [fmt_rate(r) for r in h["detection_rate_slow"]],
        "mean delay, slow f (samples)": num(h["mean_delay_slow"]),
        "false alarms (no f)": [
            fmt_rate(r, c) for r, c in zip(h["false_alarm_rate"], h["false_alarm_rate_ci"])
        ],
    }
    notes = [f"{result.settings['trials']} runs; rates in % (95 % Clopper-Pearson interval)."]
    if any(NA in cells for cells in rows.values()):
        notes.append(_NA_NOTE)
    return table(rows, [f"λ = {lam:g}" for lam in h["lambdas"]], notes=notes)


#: Human labels (with units) of the headline keys the book shows.
LABELS: dict[str, str] = {
    "lb_reject_rate_kalman": "Ljung-Box rejections at 5 %, Kalman innovation",
    "lb_reject_rate_kitanidis": "Ljung-Box rejections at 5 %, Kitanidis innovation",
    "lb_reject_rate_reduced_f": "Ljung-Box rejections at 5 %, projected residual, f active",
    "ks_pvalue_kalman": "KS p-value of the Ljung-Box p-values, Kalman",
    "ks_pvalue_kitanidis": "KS p-value of the Ljung-Box p-values, Kitanidis",
    "ks_pvalue_reduced_f": "KS p-value of the Ljung-Box p-values, projected",
    "lag1_corr_theory": "lag-one correlation of ε⁽¹⁾, closed form",
    "lag1_corr_empirical": "lag-one correlation of ε⁽¹⁾, Monte Carlo",
    "cov_rel_error_kitanidis": "relative error of Σₖ = HPHᵀ + R (Kitanidis)",
    "cov_rel_error_reduced": "relative error of the unit covariance (projected)",
    "glr_false_alarm_rate": "GLR false alarms (no fault)",
    "glr_alarm_rate_f_only": "GLR alarms with f only (projected residual)",
    "kalman_glr_alarm_rate_f_only": "GLR alarms with f only (Kalman innovation)",
    "glr_detection_rate_theta": "GLR detection of the θ jump",
    "glr_detection_rate_theta_with_f": "GLR detection of the θ jump, f active",
    "glr_mean_delay_theta": "GLR mean delay, θ jump (samples)",
    "glr_mean_delay_theta_with_f": "GLR mean delay, θ jump, f active (samples)",
    "isolation_correct_rate_theta": "correct isolation, θ = (0.05, 0)",
    "isolation_correct_rate_theta_with_f": "correct isolation, θ = (0.05, 0), f active",
    "isolation_correct_rate_theta2": "correct isolation, θ = (0, 0.05)",
    "energy_false_alarm_rate": "energy-test false alarms (no fault)",
    "nonparametric_detection_rate_f": "f declared non-parametric (f only)",
    "nonparametric_mean_delay_f": "mean delay of that decision (samples)",
    "nonparametric_detection_rate_both": "f declared non-parametric (θ and f)",
    "misattribution_rate_theta": "θ jump first declared non-parametric",
}
