"""Widget callbacks of the Zhang & Basseville (2014) chapters on the unstable example.

:func:`explore_signature`: ``||Gamma_k(r)||`` against the Willsky-Jones ``||alpha_k(r)||`` for
one onset (signature chapter); :func:`explore_glr`: fault size, onset, window and threshold of
the windowed GLR (GLR chapter). ``*_GRID`` are the slider values of the static book's
explorables (:mod:`fdi_lib.explorables`).
"""

from __future__ import annotations

import functools
from typing import Any

import numpy as np

from fdi_lib.errors import ModelError
from fdi_lib.filters import kalman_filter, kalman_gains
from fdi_lib.glr import WindowedGLR, first_alarm, glr_window
from fdi_lib.models import impulse_family
from fdi_lib.plotting import OURS_COLOR, PAPER_COLOR, figure
from fdi_lib.reproduce.zb2014 import UnstableRun
from fdi_lib.reproduce.views.zb2014 import plot_detection
from fdi_lib.simulate import simulate
from fdi_lib.signatures import fault_signature, willsky_jones
from fdi_lib.redraw import keep_artists, reusable_artists, set_limits, stepped_limit
from fdi_lib.widgets import batched_glr
from fdi_lib.systems import zb2014_unstable as ex

__all__ = [
    "explore_glr",
    "explore_signature",
    "glr_run",
    "glr_grid_alarms",
    "DEFAULTS",
    "GLR_GRID",
    "SIGNATURE_GRID",
]

#: Onsets of the signature explorable (paper Figs. 1-2 show r = 1, 101, 201, 301).
SIGNATURE_GRID = {"onset": (1, 51, 101, 151, 201, 251, 301, 351, 401, 451)}


@functools.lru_cache(maxsize=1)
def _unstable_setup():
    # model and Kalman gains do not depend on any slider: computed once per process
    model = ex.unstable_model(ex.N_STEPS)
    return model, kalman_gains(model)


@functools.lru_cache(maxsize=1)
def _impulse_family():
    # one family object: a shared WindowedGLR must be built with the family it is used with
    return impulse_family(_unstable_setup()[0])


#: Windowed GLRs of the records already computed, (onset, seed, window, fault size) -> result
_GLR_CACHE: dict = {}


@functools.lru_cache(maxsize=4)
def _noise_innovations(seed: int) -> np.ndarray:
    # what neither the onset nor the fault size changes: the fault-free innovation of the seed's
    # noise record in closed loop (simulate draws the noise before the fault acts; the fault's
    # part is added by linearity, see glr_run)
    model, gains = _unstable_setup()
    sim = simulate(model, rng=np.random.default_rng(seed), controller=ex.controller())
    return kalman_filter(model, sim.y, sim.u, gains=gains).innovations[:, 0]


@functools.lru_cache(maxsize=16)
def _glr_record(onset: int, seed: int):
    # what a fault size does not change: the fault-free innovation of the seed's noise record
    # and the innovation signature of a unit jump of the first state at the onset
    model, gains = _unstable_setup()
    fam = _impulse_family()
    sig = fault_signature(model, gains, fam.profile(onset)).on_innovation[:, 0, :]
    return fam, _noise_innovations(seed), sig


@functools.lru_cache(maxsize=6)
def _shared_glr(window: int) -> WindowedGLR:
    # the windowed GLR's noise-independent arrays (signatures, informations, the factors of
    # their pseudo-inverses) depend on the window only, not on the onset, the fault size or the
    # seed: a move of those sliders reuses them (glr_window(..., shared=...) gives the same
    # results); 15-40 ms of CPU and 0.4 MB (w = 10) to 9 MB (w = 200) per window, 24 MB for the
    # six windows of the explorable's grid
    model, gains = _unstable_setup()
    return WindowedGLR(model, gains, _impulse_family(), window)


def explore_signature(onset: int = 101, fig: Any = None):
    """Spectral norms of ``Gamma_k(r)``, ``H_k Gamma_k(r)`` and Willsky-Jones ``alpha_k(r)``.

    Parameters
    ----------
    onset : int
        Impulse time ``r`` in ``[1, N - 2]`` (``Psi_k = delta_{r,k+1} I``).
    fig : matplotlib.figure.Figure, optional
        Figure to redraw into.

    Returns
    -------
    matplotlib.figure.Figure
        Top: ``||Gamma_k||_2`` and ``||H_k Gamma_k||_2`` (bounded); bottom: ``||alpha_k(r)||_2``
        on a log scale (diverges with the unstable mode of ``F``).
    """
    model, gains = _unstable_setup()
    if isinstance(onset, bool) or int(onset) != onset or not 1 <= onset <= model.n_steps - 2:
        raise ModelError(f"onset: expected an integer in [1, {model.n_steps - 2}], got {onset!r}")
    r = int(onset)
    sig = fault_signature(model, gains, impulse_family(model).profile(r))
    alpha = np.linalg.norm(willsky_jones(model, gains, r).alpha, ord=2, axis=(-2, -1))
    gamma = np.linalg.norm(sig.Gamma, ord=2, axis=(-2, -1))
    h_gamma = np.linalg.norm(sig.on_innovation, ord=2, axis=(-2, -1))
    ka = np.arange(alpha.size)
    alpha_k, alpha_v = ka[alpha > 0], alpha[alpha > 0]
    top_ylim = (-0.05 * stepped_limit(gamma.max()), stepped_limit(gamma.max()))
    title = f"impulse at r = {r}"
    art = reusable_artists(fig, "explore_signature")
    if art is None:  # first call: build the figure; later calls only move its artists
        fig, axes = figure(2, 1, fig=fig, sharex=True, figsize=(7.0, 5.0))
        top, bottom = axes[:, 0]
        art = {
            "gamma": top.plot(
                np.arange(gamma.size), gamma, color=OURS_COLOR, label=r"$\|\Gamma_k\|_2$"
            )[0],
            "h_gamma": top.plot(
                np.arange(h_gamma.size), h_gamma, color="0.4", lw=1.0, label=r"$\|H_k\Gamma_k\|_2$"
            )[0],
            "r_top": top.axvline(r, color="k", ls=":", lw=0.8),
            "alpha": bottom.semilogy(
                alpha_k, alpha_v, color=PAPER_COLOR, label=r"$\|\alpha_k(r)\|_2$"
            )[0],
            "r_bottom": bottom.axvline(r, color="k", ls=":", lw=0.8),
            "title": top.set_title(title, y=1.0),
            "top": top,
        }
        top.set(ylabel="norm", ylim=top_ylim)
        # fixed legends under the curves: render() keeps them in its saved background
        top.legend(loc="upper right").set_zorder(1.9)
        bottom.set(
            xlabel="k", ylabel=r"$\|\alpha_k(r)\|_2$", xlim=(0, alpha.size - 1), ylim=(0.1, 1e45)
        )
        bottom.legend(loc="upper left").set_zorder(1.9)
        keep_artists(fig, "explore_signature", art)
    else:
        art["gamma"].set_ydata(gamma)
        art["h_gamma"].set_ydata(h_gamma)
        art["alpha"].set_data(alpha_k, alpha_v)
        for line in (art["r_top"], art["r_bottom"]):
            line.set_xdata([r, r])
        art["title"].set_text(title)
        set_limits(art["top"], ylim=top_ylim)
    return fig


#: Default slider values (paper Fig. 3 setting, plus an illustrative threshold).
DEFAULTS = {"fault_size": 1.5, "onset": 201, "window": 100, "threshold": 20.0, "seed": 0}
#: Slider values of the GLR explorable (the other arguments at their defaults).
GLR_GRID = {"fault_size": (0.0, 0.5, 1.0, 1.5, 2.0, 3.0), "window": (10, 25, 50, 100, 150, 200)}


def explore_glr(
    fault_size: float = DEFAULTS["fault_size"],
    onset: int = DEFAULTS["onset"],
    window: int = DEFAULTS["window"],
    threshold: float = DEFAULTS["threshold"],
    seed: int = DEFAULTS["seed"],
    fig: Any = None,
):
    """Redraw the innovation and the windowed GLR ``l_k`` for ``theta = [fault_size, 0]``.

    Parameters
    ----------
    fault_size : float
        First component of the impulsive fault ``theta`` (jump of the first state).
    onset : int
        Jump time ``r`` in ``[10, 490]``.
    window : int
        GLR search window ``w`` in ``[5, 200]``.
    threshold : float
        Alarm threshold on ``l_k`` (> 0).
    seed : int
        Noise seed.
    fig : matplotlib.figure.Figure, optional
        Figure to redraw into (the widget passes its own).

    Returns
    -------
    matplotlib.figure.Figure
    """
    run = glr_run(fault_size, onset, window, threshold, seed)
    delay = run.alarm - run.onset if run.alarm >= run.onset else None
    status = (
        "no alarm"
        if run.alarm < 0
        else f"false alarm at {run.alarm}"
        if delay is None
        else f"alarm after {delay} samples"
    )
    # short enough to fit above the axes in every frame (the title is not re-laid out)
    return plot_detection(
        run, fig=fig, title=f"θ₁ = {fault_size:g}, r = {onset}, w = {window}: {status}", widget=True
    )


def glr_run(
    fault_size: float = DEFAULTS["fault_size"],
    onset: int = DEFAULTS["onset"],
    window: int = DEFAULTS["window"],
    threshold: float = DEFAULTS["threshold"],
    seed: int = DEFAULTS["seed"],
) -> UnstableRun:
    """The run that :func:`explore_glr` draws (same arguments): innovation, windowed GLR, alarm."""
    if not 10 <= onset <= 490:
        raise ModelError(f"onset: expected an integer in [10, 490], got {onset!r}")
    if not 5 <= window <= 200:
        raise ModelError(f"window: expected an integer in [5, 200], got {window!r}")
    if not threshold > 0:
        raise ModelError(f"threshold: expected a positive number, got {threshold!r}")
    model, gains = _unstable_setup()
    fam, eps_noise, eps_fault = _glr_record(int(onset), int(seed))

    def innovations(size: float) -> np.ndarray:
        # linear in theta (Kalman filter of a linear closed loop): the noise's part plus the
        # fault signature H_k Gamma_k(r) theta (tests: equal to unstable_run's)
        return (eps_noise + eps_fault[:, 0] * size)[:, None]

    glr = batched_glr(
        _GLR_CACHE,
        (int(onset), int(seed), int(window)),
        float(fault_size),
        GLR_GRID["fault_size"],
        innovations,
        lambda eps: glr_window(
            eps, model, gains, fam, window=int(window), shared=_shared_glr(int(window))
        ),
    )
    return UnstableRun(
        innovations=innovations(float(fault_size))[:, 0],
        glr=glr,
        theta=(float(fault_size), 0.0),
        onset=int(onset),
        window=int(window),
        threshold=float(threshold),
        seed=int(seed),
        alarm=int(first_alarm(glr.statistic, float(threshold))),
    )


def glr_grid_alarms(grid: dict = GLR_GRID) -> dict[str, Any]:
    """What the window and the fault size do to the alarm over the explorable's grid.

    Returns
    -------
    dict
        ``delay``: (fault size, window) -> samples from the onset to the alarm (negative: a
        false alarm), ``None`` without alarm; ``above``: (fault size, window) -> number of samples with ``l_k`` above the
        threshold; ``peak``: (fault size, window) -> largest ``l_k``; ``threshold``.
    """
    out: dict[str, Any] = {"delay": {}, "above": {}, "peak": {}, "threshold": DEFAULTS["threshold"]}
    for size in grid["fault_size"]:
        for window in grid["window"]:
            run = glr_run(size, window=window)
            key = (size, window)
            out["delay"][key] = run.alarm - run.onset if run.alarm >= 0 else None
            out["above"][key] = int(np.sum(run.glr.statistic > run.threshold))
            out["peak"][key] = float(np.nanmax(run.glr.statistic))
    return out
