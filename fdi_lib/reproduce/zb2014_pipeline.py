"""Zhang & Basseville (2014), Section 6.2: leak detection on a gas pipeline, its set-up and runs.

All runs use the *physical* surrogate pipeline model of
:mod:`fdi_lib.systems.gas_pipeline` (the identified model of Lopes dos Santos et al.
2011 is not public), the Kalman filter of the fault-free model, and the windowed GLR
test (35)-(37) with ``w = 160`` samples, threshold 50, disabled during the first 320 min.
The surrogate was calibrated on two paper observations only (the Fig 9 level and fault 2
detected in every run, :data:`fdi_lib.systems.gas_pipeline.CALIBRATION`), plus a stated
criterion for its third free constant ``state2_scale``; each reproduction's ``paper`` dict
lists the observations under ``calibrated_to`` and every other compared headline key under
``predictions``, and its ``settings["calibration"]`` the three constants it ran with and what
fixed each (:func:`calibration_settings`).

This module holds the set-up (:func:`pipeline_setup`), the single runs (:func:`single_run`,
:func:`onset_profile`) and the Monte Carlo experiment that Figs 5-8 share
(:func:`detection_chunk`, :func:`fault_runs`, :func:`pipeline_monte_carlo`), cached per seed,
trials, fault, size and surrogate so that the book and the CLI run it once. The reproductions:

* :mod:`fdi_lib.reproduce.zb2014_pipeline_single`: ``zb2014-table1``, ``zb2014-fig5``,
  ``zb2014-fig6`` (one run of fault 1 and its spread over 1000 runs), ``zb2014-fig9``;
* :mod:`fdi_lib.reproduce.zb2014_pipeline_mc`: ``zb2014-fig7`` (detection delays and onset
  errors), ``zb2014-fig8`` (minmax isolation after each alarm) and the sensitivity studies;
* :mod:`fdi_lib.reproduce.views.zb2014_pipeline`: their figures.
"""

from __future__ import annotations

import functools
import sys
from dataclasses import dataclass
from typing import Any

import numpy as np
import scipy.stats

from fdi_lib.errors import ModelError
from fdi_lib.filters import KalmanGains, kalman_filter, kalman_gains
from fdi_lib.glr import WindowedGLR, WindowGLRResult, first_alarm, glr_window
from fdi_lib.isolation import information, minmax_statistic
from fdi_lib.models import FaultFamily, FaultProfile, LTVModel, step_family
from fdi_lib.montecarlo import binomial_ci, draw_noise_batch, run_monte_carlo
from fdi_lib.signatures import fault_signature
from fdi_lib.simulate import simulate
from fdi_lib.systems import gas_pipeline as gp

__all__ = [
    "MINMAX_THRESHOLD",
    "PipelineSetup",
    "pipeline_setup",
    "SingleRun",
    "single_run",
    "detection_chunk",
    "fault_runs",
    "pipeline_monte_carlo",
    "calibration_settings",
    "known_onset_isolation_power",
    "fault_theta",
    "SCHEDULES",
    "DEFAULT_SCHEDULE",
    "fault_schedule",
    "onset_profile",
]

PAPER = "Zhang & Basseville 2014"
#: Threshold of each minmax test (Fig. 8): the 99 % quantile of chi-square with 1 degree of freedom.
MINMAX_THRESHOLD = 6.6349
#: Onset of the input-end faults and of the output leak (sample indices).
FAULT_ONSET = gp.minutes_to_index(gp.FAULT_ONSET_MIN)
LEAK_ONSET = gp.minutes_to_index(gp.LEAK_ONSET_MIN)
#: First sample at which the GLR may alarm (disabled during the first 320 min).
GLR_START = gp.minutes_to_index(gp.DISABLED_MIN)


@dataclass(frozen=True)
class PipelineSetup:
    """Everything noise-independent, shared by all runs (computed once per process).

    Attributes
    ----------
    model : LTVModel
        Fault-free surrogate model.
    u : numpy.ndarray
        Input flow ``(N,)``.
    gains : KalmanGains
    input_family, leak_family : FaultFamily
        Step families of the input-end faults (``m = 2``) and of the output leak (``m = 1``).
    known_signature : numpy.ndarray
        ``H_k Gamma_k(r) + Phi_k`` for the true onset ``r = 300``, ``(N, 1, 2)`` (known-onset minmax).
    glr : WindowedGLR
        The windowed GLR of the input-end faults (``w = 160``) with its noise-independent
        quantities, shared by every run (``glr_window(..., shared=glr)``).
    """

    model: LTVModel
    u: np.ndarray
    gains: KalmanGains
    input_family: FaultFamily
    leak_family: FaultFamily
    known_signature: np.ndarray
    glr: WindowedGLR


#: Schedules of the fault-2 column ``p_k U_k``: the variant's own, or its origin moved.
SCHEDULES = ("centred", "absolute")
#: The schedule each surrogate uses by default.
DEFAULT_SCHEDULE = {"physical": "centred", "designed": "absolute"}


def fault_schedule(
    variant: str = "physical", schedule: str | None = None, state2_scale: float | None = None
) -> np.ndarray:
    """``p_k`` in the fault profile ``Psi_k = [[U_k, p_k U_k], [0, 0]]`` for a surrogate and a schedule origin.

    ``physical``: centred is the deviation ``p_k`` of the model; absolute moves its origin
    to zero absolute mean pressure, ``p_k - 60 bar / beta``. ``designed``: absolute is the
    model's pressure in MPa; centred is ``p_k - 5.5``. The nominal model is the same in
    both cases: only what fault 2 means changes (a question the papers leave open).

    Parameters
    ----------
    variant : {"physical", "designed"}
        Surrogate (:data:`fdi_lib.systems.gas_pipeline.VARIANTS`).
    schedule : {"centred", "absolute"}, optional
        Default: the variant's own (:data:`DEFAULT_SCHEDULE`).
    state2_scale : float, optional
        Physical surrogate calibrated with this scale (:func:`~fdi_lib.systems.gas_pipeline.calibration_for`).
    """
    gp._check_variant(variant)
    _check_scale(variant, state2_scale)
    schedule = DEFAULT_SCHEDULE[variant] if schedule is None else schedule
    if schedule not in SCHEDULES:
        raise ModelError(f"schedule: expected one of {SCHEDULES}, got {schedule!r}")
    if variant == "physical":
        cal = gp.calibration_for(state2_scale)
        p = gp.filtered_surrogate(**cal)[2]
    else:
        p = gp.pipeline_schedule(variant=variant)
    if schedule == DEFAULT_SCHEDULE[variant]:
        return p
    if variant == "physical":
        return p - gp.MEAN_PRESSURE_BAR / gp.physical_section(cal["section_length_km"]).bar_per_unit
    return p - gp.NOMINAL_PRESSURE


def _check_scale(variant: str, state2_scale: float | None) -> None:
    if state2_scale is not None and variant != "physical":
        raise ModelError(
            f"state2_scale: expected None for the {variant!r} surrogate (it has no such "
            f"constant), got {state2_scale!r}"
        )


def calibration_settings(state2_scale: float | None = None) -> dict[str, Any]:
    """The calibrated constants of the physical surrogate a reproduction ran with (its ``settings``).

    Returns
    -------
    dict
        ``constants`` (``section_length_km``, ``state2_scale``, ``pressure_swing_bar``, from
        :func:`~fdi_lib.systems.gas_pipeline.calibration_for`) and ``fixed_by`` (the target
        or criterion that fixed each one, ``CALIBRATION["free"]``).
    """
    return {"constants": gp.calibration_for(state2_scale), "fixed_by": dict(gp.CALIBRATION["free"])}


def pipeline_setup(
    variant: str = "physical", schedule: str | None = None, state2_scale: float | None = None
) -> PipelineSetup:
    """The shared model, input, Kalman gains, fault families and true-onset signature.

    Computed once per surrogate: the arguments are normalised (the default schedule and the
    calibrated scale spelt out or not, positional or keyword) before the cache.

    Parameters
    ----------
    variant : {"physical", "designed"}
        Surrogate.
    schedule : {"centred", "absolute"}, optional
        Origin of ``p_k`` in the fault-2 column (:func:`fault_schedule`).
    state2_scale : float, optional
        Physical surrogate calibrated with this scale of the pressure-drop state
        (:func:`~fdi_lib.systems.gas_pipeline.calibration_for`); default the calibrated one.
    """
    return _pipeline_setup(*_surrogate_key(variant, schedule, state2_scale))


def _surrogate_key(
    variant: str, schedule: str | None, state2_scale: float | None
) -> tuple[str, str, float | None]:
    """``(variant, schedule, state2_scale)`` spelt one way (checked): the variant's default
    schedule spelt out, the calibrated scale as ``None``; one key per surrogate."""
    gp._check_variant(variant)
    _check_scale(variant, state2_scale)
    schedule = DEFAULT_SCHEDULE[variant] if schedule is None else schedule
    if state2_scale is not None and float(state2_scale) == gp.CALIBRATION["fitted"]["state2_scale"]:
        state2_scale = None
    return variant, schedule, None if state2_scale is None else float(state2_scale)


@functools.lru_cache(maxsize=8)
def _pipeline_setup(variant: str, schedule: str, state2_scale: float | None) -> PipelineSetup:
    if variant == "physical":  # shared with the calibration targets of the same surrogate
        model, u, _, gains = gp.filtered_surrogate(**gp.calibration_for(state2_scale))
    else:
        model, u = gp.pipeline_model(variant=variant), gp.pipeline_input(variant=variant)
        gains = kalman_gains(model)
    fam = gp.input_fault_family(
        model, schedule=fault_schedule(variant, schedule, state2_scale), u=u
    )
    sig = fault_signature(model, gains, fam.profile(FAULT_ONSET)).on_innovation
    return PipelineSetup(
        model=model,
        u=u,
        gains=gains,
        input_family=fam,
        leak_family=gp.output_leak_family(model),
        known_signature=sig,
        glr=WindowedGLR(model, gains, fam, gp.WINDOW),
    )


def fault_theta(fault: int, delta: float | None = None) -> np.ndarray:
    """``theta`` of Section 6.2: ``[dG0(1), 0]`` (fault 1) or ``[0, dGp(1)]`` (fault 2), Table 1 sizes by default."""
    if fault not in (1, 2):
        raise ModelError(f"fault: expected 1 or 2, got {fault!r}")
    size = (gp.FAULT1_DELTA if fault == 1 else gp.FAULT2_DELTA) if delta is None else float(delta)
    return np.array([size, 0.0]) if fault == 1 else np.array([0.0, size])


# ----------------------------------------------------------------------------- single runs
@dataclass(frozen=True)
class SingleRun:
    """One simulated record with its detector output (times in minutes).

    Attributes
    ----------
    t_min : numpy.ndarray
        ``k Ts``, ``(N,)``.
    innovations : numpy.ndarray
        ``eps_k``, ``(N,)``.
    statistic : numpy.ndarray
        ``l_k`` of eq. (35), ``(N,)`` (``nan`` while no onset is admissible).
    onset : numpy.ndarray
        ``r_hat_k`` (sample index), ``(N,)``.
    alarm : int
        First ``k >= 160`` with ``l_k > threshold`` (``-1`` if none).
    true_onset : int
        Sample index of the simulated jump.
    threshold : float
    """

    t_min: np.ndarray
    innovations: np.ndarray
    statistic: np.ndarray
    onset: np.ndarray
    alarm: int
    true_onset: int
    threshold: float

    @property
    def alarm_time_min(self) -> float:
        return float(gp.index_to_minutes(self.alarm))

    @property
    def onset_estimate_min(self) -> float:
        return (
            float(gp.index_to_minutes(self.onset[self.alarm])) if self.alarm >= 0 else float("nan")
        )

    @property
    def detection_delay_min(self) -> float:
        return self.alarm_time_min - self.true_onset * gp.TS_MIN


def single_run(
    *,
    seed: int,
    kind: str = "input",
    fault: int = 1,
    delta: float | None = None,
    threshold: float = gp.THRESHOLD,
    window: int = gp.WINDOW,
    variant: str = "physical",
    state2_scale: float | None = None,
) -> SingleRun:
    """Simulate one record and run the windowed GLR (Figs 5, 6 and 9).

    Parameters
    ----------
    seed : int
        Seed of the noise (``numpy.random.default_rng(seed)``).
    kind : {"input", "output"}
        Input-end fault (``Psi_k = [[U_k, p_k U_k], [0, 0]]``, onset 600 min) or output leak
        (``Phi_k = 1``, onset 700 min, size ``delta``, default -43980).
    fault : {1, 2}
        Which input-end parameter changes (``kind == "input"``).
    delta : float, optional
        Fault size; default Table 1 (or the leak size).
    threshold, window : float, int
        GLR threshold and window ``w``.
    variant : {"physical", "designed"}
        Surrogate (its own schedule).
    state2_scale : float, optional
        Physical surrogate calibrated with this scale (:func:`pipeline_setup`).
    """
    st = pipeline_setup(variant, state2_scale=state2_scale)
    if kind == "input":
        fam, onset, theta = st.input_family, FAULT_ONSET, fault_theta(fault, delta)
    elif kind == "output":
        fam, onset = st.leak_family, LEAK_ONSET
        theta = np.array([gp.LEAK_SIZE if delta is None else float(delta)])
    else:
        raise ModelError(f"kind: expected 'input' or 'output', got {kind!r}")
    sim = simulate(
        st.model, rng=np.random.default_rng(seed), u=st.u, fault=fam.profile(onset), theta=theta
    )
    eps = kalman_filter(st.model, sim.y, st.u, gains=st.gains).innovations
    shared = st.glr if (fam is st.input_family and window == gp.WINDOW) else None
    res = glr_window(eps, st.model, st.gains, fam, window, shared=shared)
    alarm = int(first_alarm(res.statistic, threshold, start=GLR_START))
    return SingleRun(
        t_min=np.arange(st.model.n_steps) * gp.TS_MIN,
        innovations=eps[:, 0],
        statistic=res.statistic,
        onset=res.onset,
        alarm=alarm,
        true_onset=onset,
        threshold=float(threshold),
    )


def _onset_signatures(st: PipelineSetup, family: Any, onsets: np.ndarray) -> np.ndarray:
    """Signatures on the innovation of ``family``'s profile at each onset, side by side (columns
    ``j m .. j m + m - 1`` for ``onsets[j]``): one recursion for all of them, each column computed
    as alone (the filter acts column-wise)."""
    profiles = [family.profile(int(r)) for r in onsets]
    return fault_signature(
        st.model,
        st.gains,
        FaultProfile(
            Psi=np.concatenate([pr.Psi for pr in profiles], axis=-1),
            Phi=np.concatenate([pr.Phi for pr in profiles], axis=-1),
        ),
    ).on_innovation


def onset_profile(
    run: SingleRun,
    *,
    fault: int = 1,
    columns: str = "both",
    variant: str = "physical",
    state2_scale: float | None = None,
) -> dict[str, np.ndarray]:
    """GLR statistic and ``theta_hat`` of every candidate onset at the alarm of an input-fault run.

    Recomputed independently of the detector: for each onset ``r`` of the window at the
    alarm ``k*``, the signature of the step ``Psi_k 1{k >= r}`` (:func:`fault_signature`)
    and ``C, d`` over ``r .. k*`` (:func:`fdi_lib.isolation.information`), then
    ``l(r) = d^T C^+ d`` and ``theta_hat(r) = C^+ d``.

    Parameters
    ----------
    run : SingleRun
        A run with an alarm (:func:`single_run`, ``kind="input"``).
    fault : {1, 2}
        Unused by the computation; kept in the result for the record.
    columns : {"both", "U"}
        Both columns of ``Psi_k`` (the paper's test) or the ``U_k`` column alone (``m = 1``).
    variant : {"physical", "designed"}
        Surrogate of the run.
    state2_scale : float, optional
        Calibration of the physical surrogate of the run (:func:`pipeline_setup`).

    Returns
    -------
    dict
        ``onsets`` (sample indices), ``statistic``, ``theta_hat`` ``(n_onsets, m)``, ``fault``.
    """
    if run.alarm < 0:
        raise ModelError("run: expected a run with an alarm, got one without")
    if columns not in ("both", "U"):
        raise ModelError(f"columns: expected 'both' or 'U', got {columns!r}")
    st = pipeline_setup(variant, state2_scale=state2_scale)
    fam = st.input_family
    if columns == "U":
        fam = step_family(st.model, Psi=fam.Psi_tilde[:, :, :1])
    k = run.alarm
    onsets = np.arange(max(0, k - gp.WINDOW + 1), k)
    eps = run.innovations[:, None]
    m = fam.m
    sigs = _onset_signatures(st, fam, onsets)
    stat, theta = [], []
    for j, r in enumerate(onsets):
        sig = sigs[:, :, j * m : (j + 1) * m]
        C, d = information(eps, sig, st.gains, int(r), k + 1)
        th = np.linalg.pinv(C) @ d
        stat.append(float(d @ th))
        theta.append(th)
    return {
        "onsets": onsets,
        "statistic": np.array(stat),
        "theta_hat": np.array(theta),
        "fault": fault,
    }


# ----------------------------------------------------------------------------- Monte Carlo (Figs 5-8)
def _isolation_statistics(
    st: PipelineSetup,
    eps: np.ndarray,
    res: WindowGLRResult,
    alarm: np.ndarray,
    onset_hat: np.ndarray,
) -> dict[str, np.ndarray]:
    """The minmax statistics of :func:`detection_chunk` (``l1``, ..., ``l2_known``) of a chunk
    with innovations ``eps``, windowed GLR ``res`` (its scores at least), first alarms and onset
    estimates. The information at each alarm is the shared detector's ``C_k(r_hat)`` (the
    ``C_hat`` of the GLR there: no sample is missing)."""
    B = alarm.shape[0]
    k = np.where(alarm >= 0, alarm, 0)
    rows = np.arange(B)
    d = res.d_hat[rows, k]
    ok = alarm >= 0
    C = np.full((B, 2, 2), np.nan)
    C[ok] = st.glr.information(alarm[ok], onset_hat[ok])
    nan = np.full(B, np.nan)
    l1, l2, l1_rec, l2_rec, cos2 = nan.copy(), nan.copy(), nan.copy(), nan.copy(), nan.copy()
    info_alarm, info_rec = np.full((B, 2, 2), np.nan), np.full((B, 2, 2), np.nan)
    if ok.any():
        l1[ok] = minmax_statistic(C[ok], d[ok], [0])
        l2[ok] = minmax_statistic(C[ok], d[ok], [1])
        cos2[ok] = C[ok, 0, 1] ** 2 / (C[ok, 0, 0] * C[ok, 1, 1])
        info_alarm[ok] = C[ok]
        # to the end of the record: the signature of each distinct onset estimate, F, zeta per
        # onset, then the minmax statistics of all runs at once (the same bits as per onset: the
        # statistic is computed run by run)
        onsets = np.unique(onset_hat[ok])
        sigs = _onset_signatures(st, st.input_family, onsets)
        zeta_rec = np.zeros((B, 2))
        for j, r in enumerate(onsets):
            sel = ok & (onset_hat == r)
            info_rec[sel], zeta_rec[sel] = information(
                eps[sel], sigs[:, :, 2 * j : 2 * j + 2], st.gains, int(r), st.model.n_steps
            )
        l1_rec[ok] = minmax_statistic(info_rec[ok], zeta_rec[ok], [0])
        l2_rec[ok] = minmax_statistic(info_rec[ok], zeta_rec[ok], [1])
    F, zeta = information(eps, st.known_signature, st.gains, FAULT_ONSET, st.model.n_steps)
    return {
        "l1": l1,
        "l2": l2,
        "cos2": cos2,
        "info_alarm": info_alarm,
        "l1_record": l1_rec,
        "l2_record": l2_rec,
        "info_record": info_rec,
        "l1_known": minmax_statistic(F, zeta, [0]),
        "l2_known": minmax_statistic(F, zeta, [1]),
    }


def detection_chunk(
    seeds,
    *,
    fault: int,
    variant: str = "physical",
    schedule: str | None = None,
    delta: float | None = None,
    state2_scale: float | None = None,
    isolate: bool = True,
) -> dict[str, np.ndarray]:
    """Detection and isolation for a chunk of realisations of input-end fault ``fault``.

    Vectorised over the chunk: noise (one stream per realisation), simulation, Kalman
    innovations, windowed GLR (shared signatures and informations), first alarm,
    onset estimate, and the two minmax statistics (41) from the estimated onset to the
    alarm (``F = C_{k*}(r_hat)``, ``zeta = d_{k*}(r_hat)``, the paper's isolation window) and
    from the estimated onset to the end of the record (``r_hat .. N-1``). Also the minmax
    statistics with the onset *known* (samples 300 .. 499), free of the detector's selection.
    ``variant``, ``schedule`` and ``state2_scale`` select the surrogate (:func:`pipeline_setup`);
    ``delta`` the fault size (default Table 1).

    Returns
    -------
    dict
        ``alarm``, ``onset_hat`` (sample indices, ``-1`` if none), ``max_prefault`` (largest
        ``l_k`` from 320 min to the onset); with ``isolate`` also ``l1``, ``l2`` (minmax
        focusing on fault 1 / fault 2 at the alarm; ``nan`` without alarm), ``cos2`` (squared
        cosine ``F12^2 / (F11 F22)`` between the two fault directions at the alarm),
        ``info_alarm`` ``(B, 2, 2)`` (the Fisher information ``F`` used at the alarm),
        ``l1_record``, ``l2_record``, ``info_record`` (the same from ``r_hat`` to the end of
        the record) and ``l1_known``, ``l2_known``.
    """
    st = pipeline_setup(variant, schedule, state2_scale)
    noise = draw_noise_batch(st.model, seeds)
    sim = simulate(
        st.model,
        noise=noise,
        u=st.u,
        fault=st.input_family.profile(FAULT_ONSET),
        theta=fault_theta(fault, delta),
    )
    eps = kalman_filter(st.model, sim.y, st.u, gains=st.gains).innovations
    res = glr_window(
        eps,
        st.model,
        st.gains,
        st.input_family,
        gp.WINDOW,
        shared=st.glr,
        start=GLR_START,
        estimates="scores" if isolate else False,  # the information at the alarms only
    )
    alarm = first_alarm(res.statistic, gp.THRESHOLD, start=GLR_START)
    B = alarm.shape[0]
    k = np.where(alarm >= 0, alarm, 0)
    rows = np.arange(B)
    onset_hat = np.where(alarm >= 0, res.onset[rows, k], -1)
    pre = np.nan_to_num(res.statistic[:, GLR_START:FAULT_ONSET], nan=0.0).max(axis=1)
    out = {"alarm": alarm, "onset_hat": onset_hat, "max_prefault": pre}
    if not isolate:
        return out
    out.update(_isolation_statistics(st, eps, res, alarm, onset_hat))
    return out


def known_onset_isolation_power(
    *,
    schedule: np.ndarray | None = None,
    start: int = FAULT_ONSET,
    stop: int = gp.N_STEPS,
    alpha_threshold: float = MINMAX_THRESHOLD,
    variant: str = "physical",
    state2_scale: float | None = None,
) -> dict[str, dict[str, float]]:
    """Closed-form power of each minmax test with the onset known (no Monte Carlo).

    With the onset and the samples ``start .. stop-1`` fixed, the minmax statistic (41) for
    the present component ``a`` is non-central chi-square(1) with non-centrality
    ``theta_a^2 F_a*``, ``F_a* = F_aa - F_ab^2 / F_bb`` (Basseville & Nikiforov 2002), so the
    power is ``ncx2.sf(threshold, 1, theta_a^2 F_a*)`` (scipy).

    Parameters
    ----------
    schedule : numpy.ndarray, optional
        Pressure ``p_k`` ``(N,)``; default :func:`fdi_lib.systems.gas_pipeline.pipeline_schedule`.
        The input flow is the surrogate's in all cases.
    start, stop : int
        Samples used (default: from the true onset to the end of the record).
    alpha_threshold : float
        Threshold of each test (default 6.6349).
    variant : {"physical", "designed"}
        Surrogate.
    state2_scale : float, optional
        Physical surrogate calibrated with this scale (:func:`pipeline_setup`); only with the
        surrogate's own schedule (``schedule=None``).

    Returns
    -------
    dict
        Per fault ("1", "2"): ``cos2`` (``F12^2 / (F11 F22)``), ``noncentrality`` and ``power``.
    """
    if schedule is None:  # the surrogate's own: its shared set-up (the same model and gains)
        st = pipeline_setup(variant, state2_scale=state2_scale)
        model, gains, fam = st.model, st.gains, st.input_family
    elif state2_scale is not None:
        raise ModelError(
            f"schedule: expected None with state2_scale={state2_scale!r} (the schedule is "
            f"that surrogate's own), got an array"
        )
    else:
        u = gp.pipeline_input(variant=variant)
        model = gp.pipeline_model(variant=variant, schedule=schedule, u=u)
        gains = kalman_gains(model)
        fam = gp.input_fault_family(model, schedule=schedule, u=u, variant=variant)
    sig = fault_signature(model, gains, fam.profile(start)).on_innovation
    F, _ = information(np.zeros((model.n_steps, model.p)), sig, gains, start, stop)
    out = {}
    for fault in (1, 2):
        a, b = (0, 1) if fault == 1 else (1, 0)
        f_star = F[a, a] - F[a, b] ** 2 / F[b, b]
        lam = float(fault_theta(fault)[a] ** 2 * f_star)
        out[str(fault)] = {
            "cos2": float(F[0, 1] ** 2 / (F[0, 0] * F[1, 1])),
            "noncentrality": lam,
            "power": float(scipy.stats.ncx2.sf(alpha_threshold, 1, lam)),
        }
    return out


def _fault_seed(seed: int, fault: int) -> int:
    """Root seed of fault ``fault``: independent streams for the two faults."""
    return int(np.random.SeedSequence([int(seed), int(fault)]).generate_state(1)[0])


#: Runs of :func:`fault_runs`: ``(settings, trials)`` -> arrays.
_MC_CACHE: dict[tuple[tuple, int], dict[str, np.ndarray]] = {}


def fault_runs(
    *,
    seed: int,
    trials: int,
    fault: int,
    jobs: int = 1,
    delta: float | None = None,
    isolate: bool = True,
    progress: bool | None = None,
    chunk_size: int | None = None,
    variant: str = "physical",
    schedule: str | None = None,
    state2_scale: float | None = None,
) -> dict[str, np.ndarray]:
    """``trials`` runs of input-end fault ``fault`` (:func:`detection_chunk`), one stream per run.

    Fault ``f`` uses the root seed ``SeedSequence([seed, f])`` whatever its size ``delta``, so
    runs of fault 1 at two sizes are *paired* (same noise, run by run), as Figs 5 and 6 are.
    Cached per arguments except ``jobs``, ``progress`` and ``chunk_size``, which do not change
    the numbers (:func:`detection_chunk` is batch-invariant bit for bit,
    ``tests/reproduce/test_zb2014_pipeline.py``), the surrogate spelt one way (its default
    schedule or calibrated scale given or not). So a cached run also serves a request without
    ``isolate`` and one of fewer trials: its first ``trials`` runs, which are those runs (run
    ``i`` draws from stream ``i`` whatever the count; e.g. the 100 runs per fault of the
    chapter's sensitivity studies on the book's surrogate are the first of its 1000).

    Parameters
    ----------
    seed, trials, fault, jobs, progress, chunk_size, variant, schedule
        As in :func:`pipeline_monte_carlo`.
    delta : float, optional
        Fault size (default Table 1).
    isolate : bool
        Also compute the isolation statistics (:func:`detection_chunk`).
    state2_scale : float, optional
        Physical surrogate calibrated with this scale (:func:`pipeline_setup`).
    """
    theta = fault_theta(fault, delta)
    trials = int(trials)
    key = (
        int(seed),
        int(fault),
        tuple(theta.tolist()),
        *_surrogate_key(variant, schedule, state2_scale),
    )
    for iso in (True,) if isolate else (True, False):
        held = [n for k, n in _MC_CACHE if k == key + (iso,) and n >= trials]
        if held:
            out = _MC_CACHE[key + (iso,), min(held)]
            return out if min(held) == trials else {k: v[:trials] for k, v in out.items()}
    if progress is None:
        progress = bool(getattr(sys.stderr, "isatty", lambda: False)())
    chunk = functools.partial(
        detection_chunk,
        fault=fault,
        delta=delta,
        variant=variant,
        schedule=schedule,
        state2_scale=state2_scale,
        isolate=isolate,
    )
    out = run_monte_carlo(
        chunk,
        trials,
        seed=_fault_seed(seed, fault),
        jobs=jobs,
        chunk_size=chunk_size,
        progress=progress,
        description=f"fault {fault}",
    )
    _MC_CACHE[key + (bool(isolate),), trials] = out
    return out


def pipeline_monte_carlo(
    *,
    seed: int,
    trials: int,
    jobs: int = 1,
    progress: bool | None = None,
    chunk_size: int | None = None,
    variant: str = "physical",
    schedule: str | None = None,
    state2_scale: float | None = None,
) -> dict[int, dict[str, np.ndarray]]:
    """The Monte Carlo experiment of Figs 7 and 8: ``trials`` runs of each input-end fault.

    Parameters
    ----------
    seed : int
        Root seed; fault ``f`` uses ``SeedSequence([seed, f])`` and realisation ``i`` its
        ``i``-th spawned stream (:func:`fdi_lib.montecarlo.run_monte_carlo`).
    trials : int
        Runs per fault (paper: 1000).
    jobs : int
        Parallel workers; the results do not depend on it.
    progress : bool, optional
        Progress bar; default when standard error is a terminal (the CLI).
    chunk_size : int, optional
        Passed to :func:`~fdi_lib.montecarlo.run_monte_carlo`.
    variant, schedule : str
        Surrogate and schedule origin (:func:`pipeline_setup`).
    state2_scale : float, optional
        Physical surrogate calibrated with this scale (:func:`pipeline_setup`).

    Returns
    -------
    dict
        ``{1: arrays, 2: arrays}`` with the entries of :func:`detection_chunk` (from
        :func:`fault_runs`, cached).
    """
    return {
        fault: fault_runs(
            seed=seed,
            trials=trials,
            fault=fault,
            jobs=jobs,
            progress=progress,
            chunk_size=chunk_size,
            variant=variant,
            schedule=schedule,
            state2_scale=state2_scale,
        )
        for fault in (1, 2)
    }


def _quartiles(x: np.ndarray) -> dict[str, float | None]:
    if x.size == 0:
        return {"q1": None, "median": None, "q3": None}
    q1, med, q3 = np.percentile(x, [25, 50, 75])
    return {"q1": float(q1), "median": float(med), "q3": float(q3)}


def _rate(k: int, n: int) -> dict[str, float | int | None]:
    if n == 0:
        return {"rate": None, "count": 0, "n": 0, "ci95": [None, None]}
    lo, hi = binomial_ci(int(k), int(n))
    return {"rate": k / n, "count": int(k), "n": int(n), "ci95": [lo, hi]}
