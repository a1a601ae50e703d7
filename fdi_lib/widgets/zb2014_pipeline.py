"""Widget callback of the gas pipeline chapter: leak size, fault, threshold, window, seed."""

from __future__ import annotations

import functools
from typing import Any

import numpy as np

from fdi_lib.errors import ModelError
from fdi_lib.filters import kalman_filter
from fdi_lib.glr import first_alarm, glr_window
from fdi_lib.reproduce.registry import ReproductionResult
from fdi_lib.reproduce.zb2014_pipeline import (
    FAULT_ONSET,
    GLR_START,
    SingleRun,
    fault_theta,
    pipeline_setup,
)
from fdi_lib.reproduce.views.zb2014_pipeline import plot_single_run
from fdi_lib.simulate import simulate
from fdi_lib.systems import gas_pipeline as gp
from fdi_lib.widgets import batched_glr

__all__ = ["explore_pipeline", "pipeline_run", "pipeline_grid_delays", "DEFAULTS", "GRID"]

#: Default slider values: Fig. 5 (fault 1, Table 1 size, threshold 50, w = 160).
DEFAULTS = {"fault_size_e5": -2.0, "fault": 1, "threshold": 50.0, "window": 160, "seed": 0}
#: Slider values of the pipeline explorable (the other arguments at their defaults). A window
#: longer than 200 samples changes nothing on a faulty record: from 200 on, the window of every
#: sample after the onset (600 min, sample 300, of 500) already reaches back to it.
GRID = {
    "fault_size_e5": (-10.0, -6.0, -4.0, -2.0, -1.0, 0.0),
    "window": (20, 40, 80, 120, 160, 200),
}


def explore_pipeline(
    fault_size_e5: float = DEFAULTS["fault_size_e5"],
    fault: int = DEFAULTS["fault"],
    threshold: float = DEFAULTS["threshold"],
    window: int = DEFAULTS["window"],
    seed: int = DEFAULTS["seed"],
    fig: Any = None,
):
    """Redraw one run of an input-end leak on the surrogate pipeline (as paper Figs 5-6).

    Parameters
    ----------
    fault_size_e5 : float
        Change of ``G0(1)`` (fault 1) or ``Gp(1)`` (fault 2), in units of ``1e-5``, in ``[-10, 0]``.
    fault : {1, 2}
        Which parameter changes at 600 min.
    threshold : float
        Alarm threshold on ``l_k`` (> 0).
    window : int
        GLR window ``w`` in ``[10, 250]`` samples.
    seed : int
        Noise seed.
    fig : matplotlib.figure.Figure, optional
        Figure to redraw into (the widget passes its own).

    Returns
    -------
    matplotlib.figure.Figure
    """
    run = pipeline_run(fault_size_e5, fault, threshold, window, seed)
    if run.alarm < 0:
        status = "no alarm"
    elif run.alarm < run.true_onset:
        status = f"false alarm at {run.alarm_time_min:g} min"
    else:
        status = f"delay {run.detection_delay_min:g} min"
    title = f"fault {fault}, change {fault_size_e5:g}e-5, w = {window}: {status}"
    # the innovation's panel: the fault's part and 4.5 standard deviations of the noise's, which
    # a record exceeds with probability below 1 % (a new seed keeps the axes)
    st = pipeline_setup()
    theta = fault_theta(int(fault), float(fault_size_e5) * 1e-5)
    bound = float(
        np.max(np.abs(st.known_signature @ theta)[:, 0] + 4.5 * np.sqrt(st.gains.Sigma[:, 0, 0]))
    )
    result = ReproductionResult(
        id="explore",
        headline={},
        settings={"title": title, "innovation_bound": bound},
        data={"run": run},
    )
    return plot_single_run(result, fig=fig, widget=True)


def pipeline_run(
    fault_size_e5: float = DEFAULTS["fault_size_e5"],
    fault: int = DEFAULTS["fault"],
    threshold: float = DEFAULTS["threshold"],
    window: int = DEFAULTS["window"],
    seed: int = DEFAULTS["seed"],
) -> SingleRun:
    """The run that :func:`explore_pipeline` draws (same arguments): innovation, GLR, alarm."""
    if not -10.0 <= fault_size_e5 <= 0.0:
        raise ModelError(f"fault_size_e5: expected a number in [-10, 0], got {fault_size_e5!r}")
    if not 10 <= window <= 250:
        raise ModelError(f"window: expected an integer in [10, 250], got {window!r}")
    if not threshold > 0:
        raise ModelError(f"threshold: expected a positive number, got {threshold!r}")
    st = pipeline_setup()
    eps_noise = _noise_innovations(int(seed))

    def innovations(size: float) -> np.ndarray:
        # linear in the fault: the noise's part plus the signature of the step at 600 min times
        # theta (tests: equal to single_run's)
        return eps_noise + st.known_signature @ fault_theta(int(fault), size * 1e-5)

    glr = batched_glr(
        _GLR_CACHE,
        (int(seed), int(fault), int(window)),
        float(fault_size_e5),
        GRID["fault_size_e5"],
        innovations,
        # at the book's window, the set-up's detector (its signatures and informations computed
        # once; the same statistics)
        lambda eps: glr_window(
            eps,
            st.model,
            st.gains,
            st.input_family,
            int(window),
            shared=st.glr if int(window) == gp.WINDOW else None,
        ),
    )
    return SingleRun(
        t_min=np.arange(st.model.n_steps) * gp.TS_MIN,
        innovations=innovations(float(fault_size_e5))[:, 0],
        statistic=glr.statistic,
        onset=glr.onset,
        true_onset=FAULT_ONSET,
        threshold=float(threshold),
        alarm=int(first_alarm(glr.statistic, float(threshold), start=GLR_START)),
    )


def pipeline_grid_delays(grid: dict = GRID) -> dict[tuple[float, int], float | None]:
    """Detection delay (min) of each frame of the explorable, (change, window) -> delay; ``None``
    without alarm (a false alarm before the onset would be a negative delay)."""
    out = {}
    for size in grid["fault_size_e5"]:
        for window in grid["window"]:
            run = pipeline_run(size, window=window)
            out[(size, window)] = None if run.alarm < 0 else float(run.detection_delay_min)
    return out


#: Windowed GLRs of the records already computed, (seed, fault, window, fault size) -> result
_GLR_CACHE: dict = {}


@functools.lru_cache(maxsize=8)
def _noise_innovations(seed: int) -> np.ndarray:
    # the fault-free innovations of the seed's noise record (simulate draws the noise before the
    # fault acts): what no slider but the seed changes
    st = pipeline_setup()
    profile = st.input_family.profile(FAULT_ONSET)
    sim = simulate(
        st.model,
        rng=np.random.default_rng(seed),
        u=st.u,
        fault=profile,
        theta=np.zeros(st.input_family.m),
    )
    return kalman_filter(st.model, sim.y, st.u, gains=st.gains).innovations
