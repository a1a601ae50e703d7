"""Interactive exploration of the wind-turbine chapter: fault size and noise level against detection time.

:func:`explore_windturbine` draws, for an offset on one pitch sensor of a blade of the benchmark,
the **mean-signal** detection time of each method against the offset's size: the first sample at
which the statistic computed on the noise-free fault signature crosses the method's threshold
(the expected behaviour, not one noisy run; the scoreboard measures noisy runs). It redesigns the
blade's filters for the chosen noise level, so the threshold and the signatures move with it.
"""

from __future__ import annotations

import functools
from typing import Any

import numpy as np

from fdi_lib import windturbine as W
from fdi_lib.errors import ModelError
from fdi_lib.plotting import figure
from fdi_lib.redraw import keep_artists, reusable_artists

__all__ = ["explore_windturbine", "mean_signal_delays", "GRID", "SIZES"]

#: Slider values: offset size on the pitch sensor (deg) and noise level (times the benchmark's).
GRID = {"size": (0.25, 0.5, 1.0, 2.0, 4.0), "noise": (0.5, 1.0, 2.0)}
#: Offsets (deg) along the curves.
SIZES = np.geomspace(0.05, 20.0, 60)


@functools.lru_cache(maxsize=8)
def _curves(noise: float) -> dict[str, np.ndarray]:
    """Cumulative whitened signature energies of an offset on sensor 1 of blade 1 after its onset,
    for the GLR (Kalman innovation), the Lasso test (updated residual) and the energy test, and
    the thresholds of the chapter's design (:func:`fdi_lib.windturbine.detection_thresholds` of the
    blade)."""
    from fdi_lib.filters import kalman_gains
    from fdi_lib.kitanidis import residual_signature
    from fdi_lib.models import fault_profile, ltv_model
    from fdi_lib.signatures import fault_signature

    c = W.plant_constants()
    st = W.Settings()
    w = st.window
    s = W.subsystems(c)[0]  # blade 1
    thr = W.detection_thresholds(st, c.Ts, len(s.candidates), len(s.outputs))
    sigma = noise * c.sigma[0]
    N, onset = 4 * w, 2 * w
    model = ltv_model(
        F=s.F,
        G=s.G,
        H=s.H,
        Q=1e-12 * np.eye(2),
        R=sigma**2 * np.eye(2),
        n_steps=N,
        P0=1e2 * np.eye(2),
    )
    g = kalman_gains(model)
    after = (np.arange(N) >= onset)[:, None, None]
    prof = fault_profile(model, Psi=s.Psi * after, Phi=s.Phi * after)
    Sw = np.linalg.solve(g.Sigma_chol, fault_signature(model, g, prof).on_innovation)[
        onset : onset + w
    ]
    IHK = np.eye(2) - model.H[-1] @ g.K[-1]
    Wr = W.whitener(IHK @ g.Sigma[-1] @ IHK.T)
    Sr = np.einsum("ij,kjm->kim", Wr, residual_signature(model, g, prof).on_residual)[
        onset : onset + w
    ]
    return {
        "glr": np.cumsum(np.einsum("kp,kp->k", Sw[..., 0], Sw[..., 0])),
        "glr_h": thr.glr,
        "lasso": np.cumsum(np.einsum("kp,kp->k", Sr[..., 0], Sr[..., 0]))
        / np.sqrt(np.sum(Sr[..., 0] ** 2)),
        "lasso_h": thr.lasso,
        "energy_h": thr.energy - w * len(s.outputs),  # over the statistic's mean
        "svo_bound": 2 * st.svo_sigmas * sigma,
        "Ts": c.Ts,
        "w": w,
    }


def mean_signal_delays(size: Any, noise: float = 1.0) -> dict[str, np.ndarray]:
    """Mean-signal detection time (s) of an offset ``size`` (deg) on a pitch sensor, per method
    (``nan``: the mean statistic stays under the threshold for the window's ``w`` samples).

    GLR: the first ``n`` with ``size^2 C_n > h`` (``C_n`` the candidate's information after ``n``
    samples, the GLR's value at the true onset); Lasso test: ``size * <X_j, X_j[:n]> / ||X_j|| > z``;
    energy test: the non-centrality ``size^2 C_n`` over the threshold's excess above the mean ``w p``;
    SVO: an offset beyond the width ``2 k sigma`` of the two sensors' noise strips empties the set at
    its first sample (below it, the mean record stays consistent).
    """
    if not 0.1 <= noise <= 10.0:
        raise ModelError(
            f"noise: expected a multiple of the benchmark's noise in [0.1, 10], got {noise!r}"
        )
    cv = _curves(float(noise))
    a = np.atleast_1d(np.asarray(size, dtype=float))

    def first(stat: np.ndarray, h: float) -> np.ndarray:
        over = stat > h
        return np.where(over.any(axis=-1), (np.argmax(over, axis=-1) + 1) * cv["Ts"], np.nan)

    return {
        "zb2014": first(a[:, None] ** 2 * cv["glr"], cv["glr_h"]),
        "zhang2021": first(a[:, None] * cv["lasso"], cv["lasso_h"]),
        "bz": first(a[:, None] ** 2 * cv["glr"], cv["energy_h"]),
        "rosa2013": np.where(a > cv["svo_bound"], cv["Ts"], np.nan),
    }


def explore_windturbine(size: float = 1.0, noise: float = 1.0, *, fig: Any = None):
    """Mean-signal detection time against the size of a pitch-sensor offset, one curve per method,
    the chosen size marked; ``noise`` scales the benchmark's pitch-sensor noise.

    Parameters
    ----------
    size : float
        Offset on the pitch sensor (deg), marked on the curves.
    noise : float
        Noise level, times the benchmark's (0.447 deg).
    fig : matplotlib.figure.Figure, optional
        Figure to redraw into.

    Returns
    -------
    matplotlib.figure.Figure
    """
    if not size > 0:
        raise ModelError(f"size: expected a positive offset (deg), got {size!r}")
    curves = mean_signal_delays(SIZES, noise)
    marks = mean_signal_delays([size], noise)
    title = f"offset {size:g} deg, noise x{noise:g}"
    art = reusable_artists(fig, "explore_windturbine")
    if art is None:
        fig, axes = figure(1, 1, fig=fig, figsize=(6.4, 3.6))
        ax = axes[0][0]
        art = {}
        for m in curves:
            style = W.METHODS[m].style
            (art[m],) = ax.plot(
                SIZES,
                curves[m],
                label=W.METHODS[m].label,
                color=style.color,
                drawstyle="steps-post",
            )
            (art[m + "_mark"],) = ax.plot([size], marks[m], style.marker, color=style.color)
        art["vline"] = ax.axvline(size, color="0.6", lw=0.8)
        ax.set_xscale("log")
        ax.set_yscale("log")
        ax.set_ylim(0.005, 1.0)
        ax.set_xlabel("offset on a pitch sensor (deg)")
        ax.set_ylabel("mean-signal detection time (s)")
        ax.legend(loc="upper right")
        art["title"] = ax.set_title(title)
        keep_artists(fig, "explore_windturbine", art)
    else:
        for m in curves:
            art[m].set_ydata(curves[m])
            art[m + "_mark"].set_data([size], marks[m])
        art["vline"].set_xdata([size, size])
        art["title"].set_text(title)
    return fig
