"""Zhang (2021), sparse fault diagnosis: Example 1 (Figs 2-5, Tables I-II) and Example 2 (Figs 6-7).

* ``zhang2021-fig2`` / ``zhang2021-fig3``: one trial of Example 1 (q = 5): number of non-zero
  Lasso components against ``lambda`` with the flat range, then the Lasso "diamonds", the
  least-squares circles and the true asterisks;
* ``zhang2021-table1`` (+ Fig. 4): success rate against the number of faults q = 5 .. 25;
* ``zhang2021-table2`` (+ Fig. 5): success rate and mean SNR of each output against the
  output-noise factor r = 0.5, 10, 20, .., 200 (q = 5);
* ``zhang2021-lambda-rule``: readings of the rule for ``lambda`` (exact log / linear width,
  geometric grids, standardised or Matlab-style X), the oracle of each path (true support
  anywhere on that Lasso path) and the initial state, on the first trials of the tables'
  columns. The rule is defined in words in the paper; the author's Matlab files (MathWorks File
  Exchange 89847), which the paper says illustrate the approach, we do not have;
* ``zhang2021-example2-interventions``: Example 2 (Figs 6-7) on the surrogate pipeline under
  changes of the input and of the noise, to find what prevents the isolation of the leaks.

Each trial: draw the support of ``theta``, ``Psi_k`` and ``d_k`` and the noise
(:mod:`fdi_lib.systems.zhang2021_example1`), simulate, run the Kitanidis filter (gains shared
by all trials), build the regression (36)-(38) from the signature (27), compute the exact
Lasso path and apply the flat-range rule (both width readings, ``log`` being the headline
one). Success = the selected support equals the true one (no miss, no false alarm).
Columns of a table share the same trial seeds (common random numbers).
"""

from __future__ import annotations

from functools import lru_cache, partial
from typing import Any, Sequence

import numpy as np

from fdi_lib.kitanidis import kitanidis_filter, kitanidis_gains, residual_signature
from fdi_lib.errors import ModelError
from fdi_lib.montecarlo import binomial_ci, run_monte_carlo_many, trial_rngs, trial_seeds
from fdi_lib.reproduce.ledger_claims import (
    BY_INTERVAL,
    BY_STANDARD_ERROR,
    BY_TOLERANCE,
    Claim,
    ci_at,
)
from fdi_lib.reproduce.registry import ReproductionResult, register
from fdi_lib.sparse import (
    LAMBDA_RATIO,
    RegressionData,
    flat_range,
    flat_ranges,
    grid_flat_ranges,
    lasso_path,
    lasso_path_batch,
    least_squares_on_support,
    regression_data,
)
from fdi_lib.systems import zhang2021_example1 as ex
from fdi_lib.threads import single_threaded_blas

__all__ = [
    "outputs_with_unknown_input",
    "Q_VALUES",
    "R_VALUES",
    "PAPER_TABLE1",
    "PAPER_TABLE2",
    "example1_regression",
    "snr_db",
    "snr_variants",
    "snr_comparison",
    "closest_snr_reading",
    "example1_chunk",
    "paper_snr_off_curve",
    "example1_rates",
]

PAPER = "Zhang 2021"
Q_VALUES = tuple(range(5, 26))
R_VALUES = (0.5,) + tuple(range(10, 201, 10))
PAPER_TABLE1 = dict(
    zip(
        Q_VALUES,
        (
            0.995,
            0.980,
            0.954,
            0.900,
            0.817,
            0.750,
            0.655,
            0.555,
            0.444,
            0.377,
            0.295,
            0.251,
            0.183,
            0.146,
            0.106,
            0.090,
            0.081,
            0.040,
            0.039,
            0.027,
            0.022,
        ),
    )
)
PAPER_TABLE2 = {
    "success_rate": dict(
        zip(
            R_VALUES,
            (
                0.994,
                0.974,
                0.957,
                0.933,
                0.917,
                0.892,
                0.881,
                0.876,
                0.824,
                0.799,
                0.786,
                0.776,
                0.742,
                0.727,
                0.747,
                0.685,
                0.684,
                0.621,
                0.597,
                0.639,
                0.575,
            ),
        )
    ),
    "snr_db": dict(
        zip(
            R_VALUES,
            zip(
                (
                    34.06,
                    21.65,
                    18.64,
                    16.54,
                    15.37,
                    14.32,
                    13.60,
                    12.86,
                    12.42,
                    11.66,
                    11.63,
                    11.32,
                    11.15,
                    10.56,
                    10.11,
                    10.78,
                    9.808,
                    9.727,
                    9.403,
                    8.892,
                    8.784,
                ),
                (
                    32.63,
                    19.84,
                    17.05,
                    15.02,
                    13.69,
                    12.78,
                    11.81,
                    11.42,
                    10.95,
                    10.23,
                    9.91,
                    9.959,
                    9.320,
                    9.193,
                    8.988,
                    9.065,
                    8.206,
                    8.037,
                    7.965,
                    7.374,
                    7.489,
                ),
            ),
        )
    ),
}
SCALES = ("log", "linear")
#: Sizes of the geometric lambda grids of the grid reading of the rule (:func:`fdi_lib.sparse.grid_flat_range`),
#: on the same window; chosen before any run (a coarse and a fine grid), not tuned.
GRID_SIZES = (50, 200)


def snr_db(y: np.ndarray, v: np.ndarray, *, start: int = 1) -> np.ndarray:
    """Per-output SNR in dB, ``10 log10(var_k(Y_k) / var_k(V_k))`` over ``k = start .. N-1``.

    Sample variances over time of the measured output and of its sensor noise, shape
    ``(*batch, p)``. The paper only says an SNR is computed per sensor and averaged over
    trials; of the simple readings of :func:`snr_variants`, the two variance ratios are within a
    few tenths of a dB of its Table II, this one or ``var(Y - V) / var(V)`` being the closer
    depending on the noise level (:func:`closest_snr_reading`; the book chapter shows it).
    """
    return 10.0 * np.log10(y[..., start:, :].var(axis=-2) / v[..., start:, :].var(axis=-2))


def snr_variants(y: np.ndarray, v: np.ndarray, *, start: int = 1) -> dict[str, np.ndarray]:
    """Four readings of the SNR, each ``(*batch, p)`` in dB: power or variance, with or without V in the signal."""
    yy, vv = y[..., start:, :], v[..., start:, :]
    s = yy - vv
    return {
        "var(Y) / var(V)": 10 * np.log10(yy.var(-2) / vv.var(-2)),
        "var(Y - V) / var(V)": 10 * np.log10(s.var(-2) / vv.var(-2)),
        "sum (Y - V)^2 / sum V^2": 10 * np.log10((s**2).sum(-2) / (vv**2).sum(-2)),
        "sum Y^2 / sum V^2": 10 * np.log10((yy**2).sum(-2) / (vv**2).sum(-2)),
    }


@lru_cache(maxsize=64)
def _example1_setup(r: float) -> tuple[Any, Any]:
    """Model and Kitanidis gains of Example 1 for noise factor ``r`` (noise-independent: computed
    once per process and ``r``, shared by all the chunks of a column)."""
    model = ex.example1_model(r=r)
    return model, kitanidis_gains(model, ex.E)


def outputs_with_unknown_input(
    model: Any,
    E: np.ndarray,
    Psi: np.ndarray,
    Phi: np.ndarray,
    *,
    noise: Any,
    u: np.ndarray,
    d: np.ndarray,
    theta: np.ndarray,
) -> np.ndarray:
    """Outputs of ``X+ = F X + G U + E_k d_k + W + Psi_k theta``, ``Y = H X + V + Phi_k theta``.

    The unknown input and the state fault enter :func:`fdi_lib.simulate.simulate` as extra
    inputs ``[d_k, Psi_k theta]`` with input matrix ``[G_k, E_k, I]`` (the filters never see
    them). ``E``: ``(N, n, s)``; ``Psi``: ``(N, n, m)``; ``Phi``: ``(N, p, m)``; ``u``: ``(N, 1)``;
    ``d``: ``(N, s)``; returns ``(N, p)``.
    """
    from fdi_lib.models import ltv_model
    from fdi_lib.simulate import simulate

    N, n = model.n_steps, model.n
    G_aug = np.concatenate(
        [
            model.G,
            np.broadcast_to(E, (N, *np.shape(E)[-2:])),
            np.broadcast_to(np.eye(n), (N, n, n)),
        ],
        axis=2,
    )
    sim_model = ltv_model(F=model.F, G=G_aug, H=model.H, Q=model.Q, R=model.R, n_steps=N)
    sim = simulate(sim_model, noise=noise, u=np.concatenate([u, d, Psi @ theta], axis=1))
    return sim.y + Phi @ theta


def snr_comparison(
    r_values: Sequence[float] = (0.5, 100.0, 200.0), *, trials: int = 200, seed: int = 1
) -> dict[str, np.ndarray]:
    """Mean SNR of each reading of :func:`snr_variants`, ``{reading: (len(r_values), p)}`` in dB.

    ``trials`` simulated trials of Example 1 (q = 5) per noise factor, the same seeds for all.
    """
    out: dict[str, list[np.ndarray]] = {}
    for r in r_values:
        model = ex.example1_model(r=float(r))
        tr = ex.draw_trials(model, trial_rngs(trial_seeds(seed, trials)), q=5)
        for name, val in snr_variants(ex.simulate_trials(model, tr), tr.noise.v).items():
            out.setdefault(name, []).append(val.mean(axis=0))
    return {k: np.asarray(v) for k, v in out.items()}


def closest_snr_reading(
    readings: dict[str, np.ndarray], r_values: Sequence[float] = (0.5, 100.0, 200.0)
) -> list[str]:
    """Per noise factor, the reading whose mean SNR is closest to Table II's (mean |dB gap| over outputs)."""
    paper = np.array(
        [PAPER_TABLE2["snr_db"][float(r) if r != int(r) else int(r)] for r in r_values]
    )
    names = list(readings)
    gaps = np.array([np.abs(readings[k] - paper).mean(axis=1) for k in names])  # (readings, r)
    return [names[i] for i in gaps.argmin(axis=0)]


def example1_regression(
    trials: ex.Example1Trial, *, r: float = 0.5
) -> tuple[RegressionData, np.ndarray]:
    """Simulate trials of Example 1 and build their regressions (36) with the Kitanidis filter.

    Returns the :class:`~fdi_lib.sparse.RegressionData` (batched over trials) and the outputs ``y``.
    """
    model, gains = _example1_setup(float(r))  # gains shared by all trials
    y = ex.simulate_trials(model, trials)
    res = kitanidis_filter(model, y, gains=gains)
    sig = residual_signature(model, gains, Psi=trials.Psi, upsilon=False)  # Psi_k differs per trial
    return regression_data(res.residuals, sig.on_residual, start=1), y


@single_threaded_blas
def example1_chunk(
    seeds: Sequence[np.random.SeedSequence], *, q: int, r: float
) -> dict[str, np.ndarray]:
    """Monte Carlo chunk: success (both width readings, and the grid rule), selected sizes and SNR.

    Returns per-trial arrays: ``success_log``, ``success_linear`` (exact path, log / linear width),
    ``size_log``, ``size_linear`` (selected support size), ``success_grid50``, ``success_grid200``
    (the rule on a geometric grid of 50 / 200 ``lambda`` values over the same window, read off the
    same exact path, :func:`fdi_lib.sparse.grid_flat_range`) and ``snr_db`` (``(trials, p)``).
    """
    model, _ = _example1_setup(float(r))
    trials = ex.draw_trials(model, trial_rngs(seeds), q=q)
    reg, y = example1_regression(trials, r=r)
    true = trials.theta != 0  # (trials, m)
    snr = snr_db(y, trials.noise.v)
    del trials  # its Psi_k (tens of MB) are not needed by the paths: freed before they are followed
    paths = lasso_path_batch(
        reg.X,
        reg.y,
        n_samples=reg.n_samples,
        lambda_min=LAMBDA_RATIO,
        max_size=reg.X.shape[-1] // 2,
    )  # all the chunk's paths at once
    out = {}
    for s in SCALES:
        fr = flat_ranges(paths, scale=s)
        out[f"success_{s}"] = np.all(fr.support == true, axis=1)
        out[f"size_{s}"] = fr.size
    for n in GRID_SIZES:
        g = grid_flat_ranges(paths, n, lambda_ratio=LAMBDA_RATIO)
        out[f"success_grid{n}"] = np.all(g.support == true, axis=1)
    out["snr_db"] = snr
    return out


def example1_rates(
    *, q_values: Sequence[int], r_values: Sequence[float], trials: int, seed: int, jobs: int
) -> dict[str, Any]:
    """Success rates (and SNRs) over a grid of ``(q, r)`` columns, ``trials`` trials each.

    Returns a dict of per-column arrays: ``success_log``, ``success_linear``, ``success_grid50``,
    ``success_grid200`` (counts), ``ci_log`` (95 % Clopper-Pearson), ``snr_db`` (mean over trials,
    per output) and ``snr_db_se`` (its standard error, NaN for one trial), ``mean_size_log`` (mean
    selected size).
    """
    cols: dict[str, list[Any]] = {
        "success_log": [],
        "success_linear": [],
        "ci_log": [],
        "snr_db": [],
        "snr_db_se": [],
        "mean_size_log": [],
    }
    cols.update({f"success_grid{n}": [] for n in GRID_SIZES})
    columns = run_monte_carlo_many(
        [partial(example1_chunk, q=int(q), r=float(r)) for q, r in zip(q_values, r_values)],
        trials,
        seed=seed,
        jobs=jobs,
    )
    for res in columns:
        k_log = int(res["success_log"].sum())
        cols["success_log"].append(k_log)
        cols["success_linear"].append(int(res["success_linear"].sum()))
        cols["ci_log"].append(binomial_ci(k_log, trials))
        cols["snr_db"].append(res["snr_db"].mean(axis=0))
        n_snr = res["snr_db"].shape[0]
        cols["snr_db_se"].append(
            res["snr_db"].std(axis=0, ddof=1) / np.sqrt(n_snr)
            if n_snr > 1
            else np.full(res["snr_db"].shape[1], np.nan)
        )
        cols["mean_size_log"].append(float(res["size_log"].mean()))
        for n in GRID_SIZES:
            cols[f"success_grid{n}"].append(int(res[f"success_grid{n}"].sum()))
    return {k: np.asarray(v) for k, v in cols.items()}


# --------------------------------------------------------------------------- Figures 2-3
def _single_trial(seed: int, q: int = 5) -> dict[str, Any]:
    model = ex.example1_model()
    trials = ex.draw_trials(model, trial_rngs(trial_seeds(seed, 1)), q=q)
    reg, _ = example1_regression(trials)
    X, y = reg.X[0], reg.y[0]
    path = lasso_path(X, y, n_samples=reg.n_samples)
    flats = {s: flat_range(path, scale=s) for s in SCALES}
    fr = flats["log"]
    grid = np.geomspace(fr.low, fr.high, 10)[1:-1]  # lambdas strictly inside the flat range
    return {
        "path": path,
        "flats": flats,
        "grid": grid,
        "lasso": np.stack([path.coef(lam) for lam in grid]),
        "theta_ls": least_squares_on_support(X, y, fr.support),
        "theta": trials.theta[0],
        "true_support": np.flatnonzero(trials.theta[0]),
    }


@register(
    "zhang2021-fig2",
    paper=PAPER,
    title="Example 1: support size of the Lasso estimate against lambda",
    plot="fdi_lib.reproduce.views.zhang2021.plot_fig2",
    chapter="zhang2021/sparse",
    claims={
        "flat_size": Claim(
            location="Fig. 2",
            label="support size on the flat range of λ",
            units="",
            test=BY_TOLERANCE,
        )
    },
)
def fig2(*, seed: int, trials: int | None, jobs: int) -> ReproductionResult:
    """Paper Fig. 2: one trial of Example 1 (q = 5), support size along the exact Lasso path.

    Headline keys
    -------------
    flat_range : list of float
        ``[low, high]`` of the widest constant-size range, log width (our default rule).
    flat_size : int
        Number of non-zero components in that range (paper: 5).
    flat_range_linear : list of float
        The same with linear width.
    flat_size_linear : int
    lambda_mid : float
        Geometric middle of ``flat_range``: the ``lambda`` used.
    n_breakpoints : int
        Number of breakpoints of the exact path.
    """
    d = _single_trial(seed)
    fl, fli = d["flats"]["log"], d["flats"]["linear"]
    headline = {
        "flat_range": [fl.low, fl.high],
        "flat_size": fl.size,
        "flat_range_linear": [fli.low, fli.high],
        "flat_size_linear": fli.size,
        "lambda_mid": fl.middle,
        "n_breakpoints": int(d["path"].lambdas.size),
    }
    return ReproductionResult(
        id="zhang2021-fig2",
        headline=headline,
        paper={"flat_size": 5},
        settings={
            "seed": seed,
            "q": 5,
            "r": 0.5,
            "N": ex.N_DATA,
            "m": ex.N_PARAMS,
            "lambda_ratio": LAMBDA_RATIO,
        },
        data={"lambdas": d["path"].lambdas, "sizes": d["path"].support_sizes(), "grid": d["grid"]},
    )


@register(
    "zhang2021-fig3",
    paper=PAPER,
    title="Example 1: Lasso diamonds, least-squares circles, true asterisks",
    plot="fdi_lib.reproduce.views.zhang2021.plot_fig3",
    chapter="zhang2021/sparse",
    claims={
        "same_support_in_range": Claim(
            location="Fig. 3 (§IV text), every λ of the flat range",
            label="the same support",
            units="",
            test=BY_TOLERANCE,
        ),
        "support_equals_true": Claim(
            location="Fig. 3, diamonds against asterisks",
            label="the selected support is the true one",
            units="",
            test=BY_TOLERANCE,
            ours=lambda h, p: sorted(h["support"]) == sorted(h["true_support"]),
        ),
    },
)
def fig3(*, seed: int, trials: int | None, jobs: int) -> ReproductionResult:
    """Paper Fig. 3: the same trial as ``zhang2021-fig2``.

    Headline keys
    -------------
    flat_range : list of float
        ``[low, high]`` of the flat range (log width).
    support : list of int
        Components selected at the middle of the flat range (0-based).
    true_support : list of int
        Components of ``theta`` set to 1 (0-based).
    same_support_in_range : bool
        Whether every ``lambda`` of the displayed grid inside the flat range gives that support.
    theta_ls : list of float
        Least-squares re-estimates of the selected components (true value 1).
    lasso_mid : list of float
        Lasso estimates of the selected components at the middle (shrunk towards 0).
    """
    d = _single_trial(seed)
    fl = d["flats"]["log"]
    same = all(np.array_equal(np.flatnonzero(row), fl.support) for row in d["lasso"])
    mid = d["path"].coef(fl.middle)
    headline = {
        "flat_range": [fl.low, fl.high],
        "support": fl.support.tolist(),
        "true_support": d["true_support"].tolist(),
        "same_support_in_range": bool(same),
        "theta_ls": d["theta_ls"][fl.support].tolist(),
        "lasso_mid": mid[fl.support].tolist(),
    }
    return ReproductionResult(
        id="zhang2021-fig3",
        headline=headline,
        paper={"same_support_in_range": True, "support_equals_true": True},
        settings={"seed": seed, "q": 5, "r": 0.5, "N": ex.N_DATA, "m": ex.N_PARAMS},
        data={
            "lasso": d["lasso"],
            "grid": d["grid"],
            "theta_ls": d["theta_ls"],
            "theta": d["theta"],
        },
    )


def _rate_dict(keys: Sequence[Any], counts: np.ndarray, trials: int) -> dict[str, float]:
    return {str(k): float(c) / trials for k, c in zip(keys, counts)}


def _between_readings(paper: Any, ours: Any, h: dict[str, Any], path: tuple[str, ...]) -> bool:
    """The paper's rate lies between our log-width and linear-width readings of the λ rule,
    on the same trials (a bracket, not a cause)."""
    lin = h.get("success_rate_linear", {}).get(path[-1])
    return lin is not None and min(ours, lin) <= paper <= max(ours, lin)


def _rate_claim(table: str, column: str) -> Claim:
    """A success rate of Table I or II: the paper's rate in our 95 % interval at its 1000 trials."""
    return Claim(
        location=f"Table {table}, success rate at {column} = {{0}}",
        units="%",
        test=BY_INTERVAL,
        ci=ci_at("ci95"),
        explain="zhang2021-lambda-rule",
        bracket=_between_readings,
        bracket_text="the paper's rate lies between our log-width and linear-width "
        "readings of the rule for λ on the same trials, inside the interval "
        "of neither",
        ruled_out="our readings of the rule for λ (the paper's rate lies outside them), "
        "the unknown input d_k, and at q = 15 the initial state",
    )


@register(
    "zhang2021-table1",
    paper=PAPER,
    title="Example 1: success rate against the number of faults q",
    default_trials=1000,
    plot="fdi_lib.reproduce.views.zhang2021.plot_table1",
    chapter="zhang2021/sparse",
    claims={"success_rate/*": _rate_claim("I", "q")},
)
def table1(*, seed: int, trials: int | None, jobs: int) -> ReproductionResult:
    """Paper Table I / Fig. 4: isolation success rate for q = 5 .. 25 (r = 0.5, N = 100).

    Headline keys
    -------------
    success_rate : dict
        Per q (string key): fraction of trials whose selected support (log-width rule) equals
        the true one.
    success_rate_linear : dict
        Same with the linear-width rule.
    ci95 : dict
        Per q, ``[low, high]`` Clopper-Pearson 95 % interval of ``success_rate``.
    mean_size : dict
        Per q, mean number of selected components (log rule).
    success_rate_grid50, success_rate_grid200 : dict
        Per q, success fraction of the rule read on a geometric grid of 50 / 200 ``lambda`` values
        over the same window (:func:`fdi_lib.sparse.grid_flat_range`), on the same trials.
    """
    n = 1000 if trials is None else trials
    rates = example1_rates(
        q_values=Q_VALUES, r_values=[0.5] * len(Q_VALUES), trials=n, seed=seed, jobs=jobs
    )
    headline = {
        "success_rate": _rate_dict(Q_VALUES, rates["success_log"], n),
        "success_rate_linear": _rate_dict(Q_VALUES, rates["success_linear"], n),
        "ci95": {str(q): list(c) for q, c in zip(Q_VALUES, rates["ci_log"])},
        "mean_size": {str(q): float(s) for q, s in zip(Q_VALUES, rates["mean_size_log"])},
    }
    headline.update(
        {
            f"success_rate_grid{g}": _rate_dict(Q_VALUES, rates[f"success_grid{g}"], n)
            for g in GRID_SIZES
        }
    )
    return ReproductionResult(
        id="zhang2021-table1",
        headline=headline,
        paper={"success_rate": {str(q): v for q, v in PAPER_TABLE1.items()}},
        settings={
            "seed": seed,
            "trials": n,
            "r": 0.5,
            "N": ex.N_DATA,
            "m": ex.N_PARAMS,
            "lambda_rule": "log width, window [1e-4, 1] lambda_max, size <= m/2",
            "grid_sizes": list(GRID_SIZES),
        },
        data=rates,
    )


@register(
    "zhang2021-table2",
    paper=PAPER,
    title="Example 1: success rate and SNR against the noise factor r",
    default_trials=1000,
    plot="fdi_lib.reproduce.views.zhang2021.plot_table2",
    chapter="zhang2021/sparse",
    claims={
        "success_rate/*": _rate_claim("II", "r"),
        "snr_db/150": Claim(
            location="Table II, SNR of outputs 1 and 2 at r = 150",
            units="dB",
            test=BY_STANDARD_ERROR,
            explain="fig-zhang2021-5",
            cause="sec-zhang2021-snr-150",
            cause_glue=("zhang2021_snr150_rise_*", "zhang2021_snr150_off_*"),
            cause_text="a paper-side inconsistency: the paper's SNR rises from r = 140 to r "
            "= 150, while 10 log10(1 + S/r) decreases in r, and lies many of our "
            "standard errors off the curve through its neighbours",
        ),
        "snr_db/*": Claim(
            location="Table II, SNR of outputs 1 and 2 at r = {0}",
            units="dB",
            test=BY_STANDARD_ERROR,
            explain="fig-zhang2021-5",
        ),
    },
)
def table2(*, seed: int, trials: int | None, jobs: int) -> ReproductionResult:
    """Paper Table II / Fig. 5: isolation rate and mean output SNR for R = r I_2 (q = 5, N = 100).

    Headline keys
    -------------
    success_rate : dict
        Per r (string key, e.g. ``"0.5"``, ``"10"``): success fraction, log-width rule.
    success_rate_linear : dict
        Same with the linear-width rule.
    ci95 : dict
        Per r, Clopper-Pearson 95 % interval of ``success_rate``.
    snr_db : dict
        Per r, ``[output 1, output 2]``: mean over trials of the SNR of :func:`snr_db`.
    snr_db_se : dict
        Per r, ``[output 1, output 2]``: standard error of that mean (the SNR rows of the claims
        ledger are compared by it; ``null`` for one trial).
    success_rate_grid50, success_rate_grid200 : dict
        Per r, success fraction of the rule on a geometric grid of 50 / 200 ``lambda`` values
        (:func:`fdi_lib.sparse.grid_flat_range`), on the same trials.
    """
    n = 1000 if trials is None else trials
    rates = example1_rates(
        q_values=[5] * len(R_VALUES), r_values=R_VALUES, trials=n, seed=seed, jobs=jobs
    )
    keys = [f"{r:g}" for r in R_VALUES]
    headline = {
        "success_rate": _rate_dict(keys, rates["success_log"], n),
        "success_rate_linear": _rate_dict(keys, rates["success_linear"], n),
        "ci95": {k: list(c) for k, c in zip(keys, rates["ci_log"])},
        "snr_db": {k: [float(s[0]), float(s[1])] for k, s in zip(keys, rates["snr_db"])},
        "snr_db_se": {k: [float(s[0]), float(s[1])] for k, s in zip(keys, rates["snr_db_se"])},
    }
    headline.update(
        {
            f"success_rate_grid{g}": _rate_dict(keys, rates[f"success_grid{g}"], n)
            for g in GRID_SIZES
        }
    )
    paper = {
        "success_rate": {f"{r:g}": v for r, v in PAPER_TABLE2["success_rate"].items()},
        "snr_db": {f"{r:g}": list(v) for r, v in PAPER_TABLE2["snr_db"].items()},
    }
    return ReproductionResult(
        id="zhang2021-table2",
        headline=headline,
        paper=paper,
        settings={
            "seed": seed,
            "trials": n,
            "q": 5,
            "N": ex.N_DATA,
            "m": ex.N_PARAMS,
            "snr": "10 log10(var_k y / var_k v), k = 1..N, mean over trials",
            "grid_sizes": list(GRID_SIZES),
        },
        data=rates,
    )


def paper_snr_off_curve(result: ReproductionResult, r: str = "150") -> dict[str, list[float]]:
    """How Table II's SNR at ``r`` sits among the paper's own neighbours (a paper-side check).

    ``SNR = 10 log10(1 + S / r)`` decreases in ``r`` for a fixed signal power ``S``, so each
    column of Table II must fall from one ``r`` to the next. Returns, per output, ``rise_db``:
    the paper's value at ``r`` minus its value at the previous ``r`` (positive: an increase the
    formula forbids), and ``off_curve_se``: the paper's value at ``r`` minus the mean of its two
    neighbours, in standard errors of our estimate at ``r`` (``result``: a ``zhang2021-table2``
    result with ``snr_db_se``).
    """
    keys = list(result.paper["snr_db"])
    i = keys.index(r)
    if not 0 < i < len(keys) - 1:
        raise ModelError(f"r: expected a value of Table II with two neighbours, got {r!r}")
    paper = {k: np.asarray(result.paper["snr_db"][k], dtype=float) for k in keys[i - 1 : i + 2]}
    lo, mid, hi = (paper[k] for k in keys[i - 1 : i + 2])
    se = np.asarray(result.headline["snr_db_se"][r], dtype=float)
    return {"rise_db": (mid - lo).tolist(), "off_curve_se": ((mid - (lo + hi) / 2) / se).tolist()}
