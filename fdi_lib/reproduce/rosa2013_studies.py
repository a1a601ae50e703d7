"""Rosa & Silvestre (2013): why some UAV faults stay hidden, and the diagnostics of the SVO bank.

:func:`explanation_scale` and :func:`hidden_fault_study` measure why the elevator and ``M_u``
faults are not detected in the 6 s record; :func:`isolation_lags`, :func:`containment_check`,
:func:`envelope_study`, :func:`exact_vs_template` and :func:`horizon_comparison` check the
observers themselves. None is a registered reproduction: the chapter calls them.
"""

from __future__ import annotations

import warnings
from functools import lru_cache
from typing import Any, Sequence

import numpy as np

from fdi_lib.errors import EnvelopeWarning, UnsoundOptionWarning
from fdi_lib.reproduce.rosa2013 import UAV_X0
from fdi_lib.sets.svo import run_svo, run_svo_many, SVOModel
from fdi_lib.systems import eclipse_uav as uav
from fdi_lib.threads import single_threaded_blas

__all__ = [
    "explanation_scale",
    "hidden_fault_study",
    "isolation_lags",
    "containment_check",
    "envelope_study",
    "exact_vs_template",
    "horizon_comparison",
    "random_system",
    "healthy_record",
]


# ----------------------------------------------------------------------------- why the elevator and M_u faults stay hidden


def _block_diagonal(blocks: np.ndarray):
    """Sparse block-diagonal matrix of ``blocks`` (shape (T, r, c)), its non-zero entries only."""
    import scipy.sparse as sp

    T, r, c = blocks.shape
    t, i, j = np.nonzero(blocks)
    return sp.coo_matrix((blocks[t, i, j], (t * r + i, t * c + j)), shape=(T * r, T * c))


def _dynamics_constraints(models: Any, run: "uav.UAVRun", start: int, stop: int) -> tuple[Any, Any]:
    """The equality constraints of :func:`explanation_scale`'s linear program: the dynamics
    ``x(j+1) - A(j) x(j) - L(j) d(j) = B(j) u(j)`` over the window, as sparse blocks over the
    variables ``x(start..stop), d(start..stop-1), s``."""
    import scipy.sparse as sp

    T, n = stop - start, 4
    shift = sp.hstack([sp.csr_matrix((T * n, n)), sp.identity(T * n)])  # picks x(j+1)
    dyn = sp.hstack([_block_diagonal(models.A[start:stop]), sp.csr_matrix((T * n, n))])  # A(j) x(j)
    Aeq = sp.hstack(
        [
            shift - dyn,
            -_block_diagonal(np.broadcast_to(models.L, (T,) + models.L.shape)),
            sp.csr_matrix((T * n, 1)),
        ]
    )
    beq = np.concatenate([models.B[start + j] @ run.u[start + j] for j in range(T)])
    return Aeq, beq


def _bound_constraints(
    models: Any, run: "uav.UAVRun", start: int, stop: int, scale: str, dist_scale: float
) -> tuple[Any, np.ndarray]:
    """The inequality constraints of :func:`explanation_scale`'s linear program: the disturbances
    within ``s`` (``scale="disturbance"``) or ``dist_scale``, the measurement errors within the
    noise bound (times ``s`` when ``scale="noise"``)."""
    import scipy.sparse as sp

    T, n, nd = stop - start, 4, models.L.shape[1]
    nx, si = (T + 1) * n, (T + 1) * n + T * nd
    # Disturbances: +-d <= s (scaled) or +-d <= dist_scale.
    pm = np.array([[1.0], [-1.0]])
    d_rows = sp.hstack(
        [
            sp.csr_matrix((2 * T * nd, nx)),
            sp.kron(sp.identity(T * nd), pm),
            sp.csr_matrix((2 * T * nd, 1)),
        ]
    )
    # Measurements: +-(C x - y) <= nbar (or s nbar when the noise bound is scaled).
    C = _block_diagonal(
        np.broadcast_to(np.vstack([models.C, -models.C]), (T + 1, 2 * models.C.shape[0], n))
    )
    y_pm = np.concatenate(
        [np.concatenate([run.y[start + j], -run.y[start + j]]) for j in range(T + 1)]
    )
    nbar = np.tile(np.concatenate([models.noise, models.noise]), T + 1)
    y_rows = sp.hstack([C, sp.csr_matrix((C.shape[0], T * nd + 1))])
    if scale == "disturbance":
        d_rows = d_rows - sp.csr_matrix(
            (np.ones(2 * T * nd), (np.arange(2 * T * nd), np.full(2 * T * nd, si))),
            shape=d_rows.shape,
        )
        d_bound, y_bound = np.zeros(2 * T * nd), y_pm + nbar
    else:
        y_rows = y_rows - sp.csr_matrix(
            (nbar, (np.arange(nbar.size), np.full(nbar.size, si))), shape=y_rows.shape
        )
        d_bound, y_bound = np.full(2 * T * nd, float(dist_scale)), y_pm
    return sp.vstack([d_rows, y_rows]).tocsr(), np.concatenate([d_bound, y_bound])


def explanation_scale(
    run: "uav.UAVRun",
    *,
    kind: str = "nominal",
    scale: str = "disturbance",
    start: int = 0,
    stop: int | None = None,
    dist_scale: float = 1.0,
) -> float:
    r"""Smallest multiplier s of one bound for which the SVO model still explains the record (one LP).

    The model is the one of :func:`fdi_lib.systems.eclipse_uav.svo_models` with every uncertain
    parameter frozen at the centre of its interval (Delta = 0, no input uncertainty). The linear
    program finds states x(start..stop), disturbances d and noises n with

    .. math::

        x(k+1) = A(k) x(k) + B(k) u(k) + L(k) d(k), \qquad y(k) = C x(k) + n(k),

    with :math:`x(0)` in ``UAV_X0`` (if ``start`` = 0), and minimises :math:`s` subject to
    :math:`|d_i(k)| \le s`, :math:`|n_j(k)| \le \bar n_j` (``scale="disturbance"``) or
    :math:`|d_i(k)| \le` ``dist_scale``, :math:`|n_j(k)| \le s \bar n_j` (``scale="noise"``).

    How to read it: Delta = 0 is one admissible value, so when s <= 1 the data of the window are
    reproduced by the healthy model within the bounds, and **no** SVO built on that model (exact
    polytopes, any horizon N, any template) can become empty on that window. Conversely an SVO
    whose disturbance bound is ``s_bound`` times the design one cannot detect anything on the
    window unless ``s_bound`` < s.

    Parameters
    ----------
    run : UAVRun
        The record (its measured airspeed also schedules the model).
    kind : str
        SVO model, as in ``svo_models``.
    scale : {"disturbance", "noise"}
        Which bound is scaled.
    start, stop : int
        Window of samples [start, stop] (stop defaults to the last sample).
    dist_scale : float
        Disturbance multiplier kept fixed when ``scale="noise"``.

    Returns
    -------
    float
        The minimal s (``inf`` if no s works, which cannot happen for these models).
    """
    from scipy.optimize import linprog

    from fdi_lib.errors import ModelError, NumericalError

    if scale not in ("disturbance", "noise"):
        raise ModelError(f"scale: expected 'disturbance' or 'noise', got {scale!r}")
    K = len(run.y) - 1
    stop = K if stop is None else int(stop)
    if not (0 <= int(start) < stop <= K):
        raise ModelError(f"start, stop: expected 0 <= start < stop <= {K}, got ({start}, {stop})")
    start = int(start)
    models = uav.svo_models(run, kind, dist_scale=1.0)
    T, n, nd = stop - start, 4, models.L.shape[1]
    nv = (T + 1) * n + T * nd + 1  # variables: x(start..stop), d(start..stop-1), s
    si = nv - 1
    Aeq, beq = _dynamics_constraints(models, run, start, stop)
    Aub, bub = _bound_constraints(models, run, start, stop, scale, dist_scale)
    bounds = [(None, None)] * (nv - 1) + [(0.0, None)]
    if start == 0:
        lo, hi = UAV_X0.bounding_box()
        bounds[:n] = list(zip(lo, hi))
    c = np.zeros(nv)
    c[si] = 1.0
    # fall back when one HiGHS solver stalls numerically
    for method in ("highs-ds", "highs-ipm", "highs"):
        res = linprog(c, A_ub=Aub, b_ub=bub, A_eq=Aeq, b_eq=beq, bounds=bounds, method=method)
        if res.status in (0, 2):
            break
    if res.status == 2:
        return float("inf")
    if res.status != 0:
        raise NumericalError(f"explanation_scale: the linear program failed ({res.message})")
    return float(res.x[si])


#: detection times (ms after onset) at which :func:`hidden_fault_study` evaluates the explanation scale
HIDDEN_TIMES_MS = (20, 50, 100, 500, 2500)
#: disturbance multipliers of the template-SVO sensitivity study
HIDDEN_SCALES = (1.0, 0.1, 0.01)


def _hidden_widths(
    runs: dict[str, Any], svo: Any, keys: list, onset: int, eta_unit: str
) -> tuple[dict, dict]:
    """For the elevator and dynamics faults of :func:`hidden_fault_study`: the median width of the
    nominal SVO's state bounds after the onset (scale 1), and the offset of ``w`` that would make
    the fault's largest one-step pitch-rate effect (true states and inputs)."""
    width, needed = {}, {}
    A37, _ = uav.lpv_matrices(uav.V_TRIM, eta_unit=eta_unit)
    for f in ("elevator", "dynamics"):
        i = keys.index((1.0, f))
        w = np.nanmedian(svo.upper[i, onset:] - svo.lower[i, onset:], axis=0)
        width[f] = dict(zip(("u", "w", "theta", "q"), w.tolist()))
        # one-step pitch-rate effect of the fault, from the true states and inputs, and the w offset doing the same
        dq = np.abs(
            runs[f].x[onset + 1 :, 3]
            - runs[f].x[onset:-1, 3]
            - (runs["none"].x[onset + 1 :, 3] - runs["none"].x[onset:-1, 3])
        ).max()
        needed[f] = float(dq / (abs(A37[3, 1]) * uav.TS))
    return width, needed


def _explanation_scales(runs: dict[str, Any], onset: int) -> tuple[dict, dict, dict]:
    """:func:`explanation_scale` of each run of :func:`hidden_fault_study`: at the detection times
    of :data:`HIDDEN_TIMES_MS`, of the noise over the first faulty sample, of the noise over the
    whole record."""
    K = len(runs["none"].y) - 1
    explanation = {
        f: {t: explanation_scale(r, stop=min(K, onset - 1 + t // 10)) for t in HIDDEN_TIMES_MS}
        for f, r in runs.items()
    }
    first = {
        f: explanation_scale(r, scale="noise", dist_scale=0.0, stop=onset + 1)
        for f, r in runs.items()
    }
    full = {f: explanation_scale(r, scale="noise") for f, r in runs.items()}
    return explanation, first, full


@lru_cache(maxsize=4)
def hidden_fault_study(seed: int, duration: float = 3.0, eta_unit: str = uav.ETA_UNIT) -> dict:
    r"""Why the elevator and :math:`M_u` step faults are not detected: effect sizes, LP bounds,
    sensitivity.

    Healthy and faulty runs share ``seed``, hence the same disturbance and noise sequences;
    ``eta_unit`` is the reading of the elevator coefficients (per radian, the elevator fault is
    hidden as well; per degree only the :math:`M_u` fault is).

    Returns
    -------
    dict with keys
        ``effect``: fault -> output -> :math:`\max_k |y_\mathrm{faulty}(k) - y_\mathrm{healthy}(k)|`
        divided by the SVO noise
        bound of that output (sensor bound plus margin);
        ``width``: fault -> state -> median width of the nominal template SVO's bounding box on the
        faulty run, together with ``width_needed``: the w-offset (m/s) whose pitch-rate effect
        (through :math:`M_w`) equals the fault's largest one-step pitch-rate effect;
        ``explanation``: run ("none", "elevator", "dynamics") -> detection time (ms, as in Fig. 11)
        -> :func:`explanation_scale` of the disturbance on the window from 0 to the sample at
        which that detection time would be reached (an SVO whose disturbance bound is s times ours
        cannot have detected by then unless s is below this number);
        ``first_sample_noise``: run -> smallest multiplier of the noise bounds that explains the
        record up to the first sample on which an actuator fault is visible (20 ms after onset)
        with no disturbance at all;
        ``full_record_noise``: run -> the same over the whole record, disturbances at our bound;
        ``template``: disturbance multiplier -> run -> detection time (ms) of the nominal template
        SVO with that multiplier (None: never empty within ``duration``);
        ``onset``: the onset sample.
    """
    faults = (
        "none",
        "elevator",
        "dynamics",
    )  # simulated together, each from its own default_rng(seed)
    runs = dict(
        zip(
            faults,
            uav.simulate_many(
                [(f, "step") for f in faults],
                [np.random.default_rng(seed) for _ in faults],
                duration=duration,
                eta_unit=eta_unit,
            ),
        )
    )
    onset = runs["elevator"].onset_step
    nb = uav.NOISE_BOUND + uav.SVO_NOISE_MARGIN
    outputs = ("airspeed", "alpha", "theta", "q")
    effect = {
        f: dict(zip(outputs, (np.abs(runs[f].y - runs["none"].y).max(axis=0) / nb).tolist()))
        for f in ("elevator", "dynamics")
    }
    # the nominal template SVOs of every scale and run, stepped together
    keys = [(s, f) for s in HIDDEN_SCALES for f in runs]
    svo = run_svo_many(
        [uav.svo_models(runs[f], "nominal", dist_scale=s) for s, f in keys],
        np.stack([runs[f].u for _, f in keys]),
        np.stack([runs[f].y for _, f in keys]),
        UAV_X0,
        bounds=True,
    )
    template = {s: {} for s in HIDDEN_SCALES}
    for (s, f), e in zip(keys, svo.empty_at):
        template[s][f] = None if e is None else (e - onset + 1) * uav.TS * 1e3
    width, needed = _hidden_widths(runs, svo, keys, onset, eta_unit)
    explanation, first, full = _explanation_scales(runs, onset)
    return {
        "effect": effect,
        "width": width,
        "width_needed": needed,
        "explanation": explanation,
        "first_sample_noise": first,
        "full_record_noise": full,
        "template": template,
        "onset": onset,
    }


# ----------------------------------------------------------------------------- diagnostics of issue 14


def isolation_lags(runs: tuple, fault: str = "alpha", scenario: str = "soft") -> dict:
    """Samples between the nominal SVO's emptiness and each fault SVO's, over the runs of one case.

    Returns SVO name -> list of lags in ms (None when that SVO never emptied: the survivor).
    Isolation in Architecture I waits for the last wrong hypothesis, so the largest lag of the
    other SVOs is the isolation delay after detection.
    """
    out: dict = {f: [] for f in uav.FAULTS}
    for r in runs:
        if r["fault"] != fault or r["scenario"] != scenario or r["detection"] is None:
            continue
        for f in uav.FAULTS:
            e = r["empty_at"].get(f)
            out[f].append(None if e is None else (e - r["detection"]) * uav.TS * 1e3)
    return out


@single_threaded_blas
def containment_check(
    eta_unit: str, seed: int, amplitude: float = 3.6, duration: float = 3.0
) -> dict:
    """Nominal template SVO on a healthy run with +-``amplitude`` m/s airspeed commands.

    Returns ``{"samples": ..., ...}``: ``samples``, the checked samples; ``outside``, the samples
    whose true state is outside the set; ``empty_at``, the first empty sample or None;
    ``airspeed_swing``, the peak-to-peak measured airspeed (m/s); ``max_airspeed``, the largest
    measured airspeed deviation :math:`|y_V(k)|` over the checked samples (m/s);
    ``loss_airspeed``, the largest :math:`|y_V(k)|` up to the first sample whose true state is
    outside the set, the deviation the record had reached when the state was lost (None if
    never).
    The record may leave the manoeuvre envelope on purpose: its :class:`EnvelopeWarning` is not shown.
    """
    return _containment_checks(eta_unit, [(seed, amplitude)], duration)[0]


@single_threaded_blas
def _containment_checks(
    eta_unit: str, cases: Sequence[tuple[int, float]], duration: float
) -> list[dict]:
    """:func:`containment_check` of each (seed, amplitude), the records simulated together
    (:func:`uav.simulate_many`: each the same as alone)."""
    runs = uav.simulate_many(
        [("none", "step")] * len(cases),
        [np.random.default_rng(seed) for seed, _ in cases],
        duration=duration,
        eta_unit=eta_unit,
        amplitude=[a for _, a in cases],
    )
    out = []
    for run in runs:
        with warnings.catch_warnings():  # leaving the envelope is what is measured here
            warnings.simplefilter("ignore", EnvelopeWarning)
            models = uav.svo_models(run, "nominal")
        res = run_svo(models, run.u, run.y, UAV_X0, keep_sets=True)
        lost = np.array(
            [not S.contains(run.x[k], 1e-7) for k, S in enumerate(res.sets)], dtype=bool
        )
        dev = np.abs(run.y[: len(res.sets), 0])
        out.append(
            {
                "samples": len(res.sets),
                "outside": int(lost.sum()),
                "empty_at": res.empty_at,
                "airspeed_swing": float(np.ptp(run.y[:, 0])),
                "max_airspeed": float(dev.max()),
                "loss_airspeed": float(dev[: int(np.argmax(lost)) + 1].max())
                if lost.any()
                else None,
            }
        )
    return out


def envelope_study(
    seeds: tuple = (0, 1),
    amplitudes: tuple = (2.0, 3.6, 5.0, 7.0),
    eta_units: tuple = uav.ETA_UNITS,
    duration: float = 3.0,
) -> dict:
    """The manoeuvre envelope of the UAV's SVO margins (:data:`uav.ENVELOPE_AIRSPEED`), measured.

    :func:`containment_check` on every (reading, amplitude, seed). Returns, per reading of the
    elevator coefficients: ``runs``; ``outside`` {amplitude: [samples outside, per seed]};
    ``min_loss_airspeed``, over the runs that lost the true state, the smallest measured airspeed
    deviation (m/s) reached up to the loss (``loss_airspeed`` of :func:`containment_check`; None:
    no loss), so no record that stayed below it lost the state; ``max_clean_airspeed``, the largest
    deviation reached by a run whose true state never left; ``envelope``,
    :data:`uav.ENVELOPE_AIRSPEED` of the reading.
    """
    out = {}
    n = len(seeds)
    for unit in eta_units:  # the records of every amplitude and seed simulated together
        flat = _containment_checks(unit, [(s, a) for a in amplitudes for s in seeds], duration)
        checks = {a: flat[i * n : (i + 1) * n] for i, a in enumerate(amplitudes)}
        losses = [c["loss_airspeed"] for c in flat if c["loss_airspeed"] is not None]
        clean = [c["max_airspeed"] for c in flat if c["loss_airspeed"] is None]
        out[unit] = {
            "runs": len(flat),
            "outside": {a: [c["outside"] for c in cs] for a, cs in checks.items()},
            "min_loss_airspeed": min(losses) if losses else None,
            "max_clean_airspeed": max(clean) if clean else None,
            "envelope": uav.ENVELOPE_AIRSPEED[unit],
        }
    return out


@single_threaded_blas
def exact_vs_template(seed: int, steps: int = 2, N: int = 1) -> dict:
    """The paper's exact update (vertex images and hulls, eq. (3)-(4)) against the template one.

    Nominal UAV SVO on a healthy run, ``steps`` updates, state scaling :func:`uav.svo_scale`.
    Returns, per method, per-update lists: ``vertices``, ``facets`` (inequalities kept),
    ``ms`` (wall time of the update including the model's construction) and ``widths`` (bounding
    box widths, shape (steps + 1, 4)).
    """
    import time

    run = uav.simulate("none", "step", rng=np.random.default_rng(seed), duration=steps * uav.TS)
    out = {}
    for method in ("exact", "template"):
        t0 = time.perf_counter()
        models = uav.svo_models(run, "nominal")
        build = (time.perf_counter() - t0) / steps
        res = run_svo(models, run.u, run.y, UAV_X0, N=N, method=method, scale=uav.svo_scale())
        out[method] = {
            "vertices": res.n_vertices.tolist(),
            "facets": res.n_facets.tolist(),
            "ms": ((res.step_time + build) * 1e3).tolist(),
            "widths": res.upper - res.lower,
        }
    return out


def horizon_comparison(
    seed: int, runs: int = 20, steps: int = 12, horizons: tuple = (2, 3)
) -> dict:
    """Separate projection of the horizon rows against the joint form of eq. (3) (template rule).

    Random stable 2-D systems with one A and one B uncertainty (:func:`random_system`), healthy
    records of ``steps`` samples, 16 template directions, N in ``horizons``. Returns N -> a dict:
    ``cases``, the runs; ``tighter``, the runs in which the joint set is smaller in some direction by
    more than 1e-9; ``max_gap``, the largest support difference over the runs without alarm;
    ``outside``, the samples with the true state outside the joint set; ``alarms``, the runs in
    which the joint set became empty.

    With an uncertain A the joint form can lose the true state: for a vertex sequence, the image of
    x(k-1) under the older vertex matrix stands in for x(k) and need not lie in X̂(k), which the
    strip has already cut (the same effect as the paper's strip-before-hull order).
    """
    from fdi_lib.sets import Polytope

    rng = np.random.default_rng(seed)
    X0 = Polytope.box([-1, -1], [1, 1])
    D = np.array([[np.cos(a), np.sin(a)] for a in np.linspace(0, 2 * np.pi, 16, endpoint=False)])
    T = np.vstack([np.eye(2), -np.eye(2), D])
    out = {
        N: {"cases": runs, "tighter": 0, "max_gap": 0.0, "outside": 0, "alarms": 0}
        for N in horizons
    }
    for _ in range(runs):
        m = random_system(rng)
        x, u, y = healthy_record(m, rng, steps)
        for N in horizons:
            a = run_svo(m, u, y, X0, N=N, template=T, keep_sets=True)
            with (
                warnings.catch_warnings()
            ):  # the joint form's loss of the true state is what is measured
                warnings.simplefilter("ignore", UnsoundOptionWarning)
                b = run_svo(m, u, y, X0, N=N, template=T, keep_sets=True, joint=True)
            o = out[N]
            o["alarms"] += b.empty_at is not None
            o["outside"] += sum(not S.contains(x[k], 1e-7) for k, S in enumerate(b.sets))
            gap = max(
                float((Sa.support(D) - Sb.support(D)).max()) for Sa, Sb in zip(a.sets, b.sets)
            )
            o["tighter"] += gap > 1e-9
            if b.empty_at is None:
                o["max_gap"] = max(o["max_gap"], gap)
    return out


def random_system(rng: np.random.Generator) -> SVOModel:
    """A random stable 2-D system with one uncertain direction in A and one in B (Props 2-3 checks)."""
    A = rng.standard_normal((2, 2))
    A *= rng.uniform(0.6, 0.95) / max(abs(np.linalg.eigvals(A)))
    return SVOModel(
        A=A,
        B=rng.standard_normal((2, 1)),
        C=np.array([[1.0, rng.uniform(-0.5, 0.5)]]),
        L=np.diag(rng.uniform(0.01, 0.1, 2)),
        noise=rng.uniform(0.05, 0.2),
        A_unc=0.1 * rng.standard_normal((1, 2, 2)),
        B_unc=0.1 * rng.standard_normal((1, 2, 1)),
    )


def healthy_record(model: SVOModel, rng: np.random.Generator, T: int = 25):
    """Simulate ``model`` with every uncertainty uniform in its bound: x (T+1, 2), u (T, 1), y (T+1, 1)."""
    x = np.zeros((T + 1, 2))
    x[0] = rng.uniform(-0.5, 0.5, 2)
    u = rng.uniform(-1, 1, (T, 1))
    for k in range(T):
        x[k + 1] = (
            (model.A + rng.uniform(-1, 1) * model.A_unc[0]) @ x[k]
            + (model.B + rng.uniform(-1, 1) * model.B_unc[0]) @ u[k]
            + model.L @ rng.uniform(-1, 1, 2)
        )
    y = x @ model.C.T + model.noise * rng.uniform(-1, 1, (T + 1, 1))
    return x, u, y
