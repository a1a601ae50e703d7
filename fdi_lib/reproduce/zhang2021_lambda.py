"""Zhang (2021), Example 1: the readings of the rule for ``lambda`` (``zhang2021-lambda-rule``).

The paper defines its rule for ``lambda`` in words (the flat range of the Lasso path); this module
measures how much Tables I-II depend on its reading (exact log or linear width, geometric grids,
standardised or Matlab-style regressors), on the oracle of each path (the true support anywhere on
that Lasso path) and on the initial state, on the first trials of the tables' columns. The
author's Matlab files (MathWorks File Exchange 89847) we do not have.

The trials, the regression and the headline rule are :mod:`fdi_lib.reproduce.zhang2021`'s; the
reader tables are :mod:`fdi_lib.reproduce.views.zhang2021`.
"""

from __future__ import annotations

from functools import lru_cache, partial
from typing import Any, Sequence

import numpy as np

from fdi_lib.errors import ModelError
from fdi_lib.kitanidis import kitanidis_filter, kitanidis_gains, residual_signature
from fdi_lib.montecarlo import binomial_ci, run_monte_carlo_many, trial_rngs, trial_seeds
from fdi_lib.reproduce.ledger_claims import ci_at, ours_at, shown_under
from fdi_lib.reproduce.registry import register, ReproductionResult
from fdi_lib.reproduce.zhang2021 import (
    example1_regression,
    PAPER,
    PAPER_TABLE1,
    PAPER_TABLE2,
    SCALES,
)
from fdi_lib.sparse import (
    LAMBDA_RATIO,
    flat_ranges,
    grid_flat_ranges,
    lasso_path_batch,
    regression_data,
)
from fdi_lib.systems import zhang2021_example1 as ex
from fdi_lib.threads import single_threaded_blas


__all__ = [
    "variant_columns",
    "VARIANT_Q",
    "VARIANT_R",
    "VARIANT_GRIDS",
    "RULE_READINGS",
    "INIT_VARIANTS",
    "lambda_rule_chunk",
    "initial_state_chunk",
    "initial_state_models",
    "unknown_input_effect",
    "ORACLE_PATHS",
    "scaled_regressors",
]

# --------------------------------------------------------------------------- the lambda rule: variants
#: Columns of the variants table: q for Table I (r = 0.5), r for Table II (q = 5); chosen
#: where the paper's rates and ours part (q >= 9) or the noise is high, not tuned.
VARIANT_Q = (9, 15, 25)
VARIANT_R = (100.0, 200.0)
#: Geometric grids of the variants table (a coarse and a fine one), on the window of the rule.
VARIANT_GRIDS = (20, 100)
#: Readings of the rule in the variants table, in display order (keys of :func:`lambda_rule_chunk`).
RULE_READINGS = ("log", "linear", "grid20", "grid100", "standardised", "matlab")
#: The paths whose oracles :func:`lambda_rule_chunk` computes (:func:`scaled_regressors`):
#: ``raw`` (``X`` as built), ``standardised`` (columns scaled to unit root mean square) and
#: ``matlab`` (columns centred and scaled to unit variance, ``y`` centred: the default of
#: Matlab's ``lasso``, which also fits an intercept).
ORACLE_PATHS = ("raw", "standardised", "matlab")
#: Filter initialisations / initial states compared at q = 15 (:func:`initial_state_chunk`):
#: ``paper``: ``X_0 ~ N(0, I)``, the filter starts from ``xhat_{0|0} = 0``, ``P_{0|0} = I`` and
#: does not use ``Y_0`` (the paper's Sec. III-A initialisation); ``spread``: ``X_0 ~ N(0, 100 I)``
#: and ``P_{0|0} = 100 I`` (a large initial state, known to the filter).
INIT_VARIANTS = {"paper": 1.0, "spread": 10.0}
#: ``R_0`` of the filter model that ignores ``Y_0``: the update at k = 0 changes the estimate
#: and the covariance by a relative 1e-12 at most.
_R0_IGNORE = 1e12


def scaled_regressors(X: np.ndarray, y: np.ndarray, path: str) -> tuple[np.ndarray, np.ndarray]:
    """``(X, y)`` of a path of :data:`ORACLE_PATHS`, batched over the leading axis (rows on axis -2).

    ``raw``: unchanged. ``standardised``: each column divided by its root mean square over the
    rows. ``matlab``: each column centred and divided by its standard deviation, ``y`` centred,
    as Matlab's ``lasso`` does by default (``'Standardize', true`` and an intercept); the
    divisor of the standard deviation (``n`` or ``n - 1``) scales every column alike, which
    changes ``lambda`` but no support. Scaling a column changes the path, not which components
    of a given fit are non-zero.
    """
    if path == "raw":
        return X, y
    if path == "standardised":
        return X / np.sqrt(np.mean(X**2, axis=-2, keepdims=True)), y
    if path == "matlab":
        Xc = X - X.mean(axis=-2, keepdims=True)
        return Xc / Xc.std(axis=-2, keepdims=True), y - y.mean(axis=-1, keepdims=True)
    raise ModelError(f"path: expected one of {list(ORACLE_PATHS)}, got {path!r}")


@single_threaded_blas
def lambda_rule_chunk(
    seeds: Sequence[np.random.SeedSequence], *, q: int, r: float
) -> dict[str, np.ndarray]:
    """Monte Carlo chunk of the variants table: readings of the rule and the oracles.

    On the same trials as :func:`~fdi_lib.reproduce.zhang2021.example1_chunk` (same draws for the same seeds), the full
    exact Lasso path (down to ``lambda = 0``) gives: ``log``, ``linear`` (:func:`flat_range`),
    ``grid20``, ``grid100`` (:func:`grid_flat_range` on geometric grids of 20 / 100 points over
    the window ``[1e-4, 1] lambda_max``), and ``oracle``: the true support is the support of
    some interval of the path (then some ``lambda`` finds it on this path; otherwise no
    ``lambda`` does, so no rule that reads this path can succeed). ``standardised``,
    ``matlab``: the log rule on the full path of the regression scaled as in
    :func:`scaled_regressors`, whose own oracles are ``oracle_standardised``,
    ``oracle_matlab``; a rule reading a scaled path is not bounded by the raw ``oracle``.
    Each entry: per-trial booleans (success = selected support equals the true one).
    """
    model = ex.example1_model(r=r)
    trials = ex.draw_trials(model, trial_rngs(seeds), q=q)
    reg, _ = example1_regression(trials, r=r)
    true = trials.theta != 0  # (trials, m)
    paths = lasso_path_batch(
        reg.X, reg.y, n_samples=reg.n_samples
    )  # full paths, all trials at once
    out = {}
    for s in SCALES:
        out[s] = np.all(
            flat_ranges(paths, scale=s, lambda_ratio=LAMBDA_RATIO).support == true, axis=1
        )
    for n in VARIANT_GRIDS:
        g = grid_flat_ranges(paths, n, lambda_ratio=LAMBDA_RATIO)
        out[f"grid{n}"] = np.all(g.support == true, axis=1)
    out["oracle"] = paths.has_interval_support(true)
    for name in ORACLE_PATHS[1:]:
        Xs, ys = scaled_regressors(reg.X, reg.y, name)
        paths_s = lasso_path_batch(Xs, ys, n_samples=reg.n_samples)  # full: the oracle needs it
        out[name] = np.all(flat_ranges(paths_s, lambda_ratio=LAMBDA_RATIO).support == true, axis=1)
        out[f"oracle_{name}"] = paths_s.has_interval_support(true)
    return out


def initial_state_models(r: float, init: str) -> tuple[Any, Any]:
    """``(simulation model, filter model)`` of Example 1 for an initialisation of :data:`INIT_VARIANTS`.

    The filter model has ``P0 = P_{0|0}`` (``s^2 I``, ``s`` the value in :data:`INIT_VARIANTS`)
    and ``R_0 = 1e12 I``, so that its update at ``k = 0`` leaves ``xhat_{0|0} = 0`` and
    ``P_{0|0}`` unchanged to a relative 1e-12: the filter starts as the paper's Kalman and
    Kitanidis filters do and uses the data from ``k = 1``.
    """
    if init not in INIT_VARIANTS:
        raise ModelError(f"init: expected one of {sorted(INIT_VARIANTS)}, got {init!r}")
    from fdi_lib.models import ltv_model

    base = ex.example1_model(r=r)
    s2 = INIT_VARIANTS[init] ** 2
    R = np.repeat(base.R[:1], base.n_steps, axis=0)
    R[0] = _R0_IGNORE * np.eye(base.p)
    filt = ltv_model(
        F=base.F,
        H=base.H,
        Q=base.Q,
        R=R,
        n_steps=base.n_steps,
        x0=np.zeros(base.n),
        P0=s2 * np.eye(base.n),
    )
    return base, filt


@lru_cache(maxsize=16)
def _initial_state_setup(r: float, init: str) -> tuple[Any, Any, Any]:
    """:func:`initial_state_models` and the filter model's Kitanidis gains (noise-independent:
    computed once per process, shared by all the chunks)."""
    sim_model, filt = initial_state_models(r, init)
    return sim_model, filt, kitanidis_gains(filt, ex.E)


@single_threaded_blas
def initial_state_chunk(
    seeds: Sequence[np.random.SeedSequence],
    *,
    q: int,
    r: float,
    inits: Sequence[str] = tuple(INIT_VARIANTS),
) -> dict[str, np.ndarray]:
    """Monte Carlo chunk: the log rule and the oracle under each initialisation ``inits`` of :data:`INIT_VARIANTS` (default all).

    The trials are those of :func:`~fdi_lib.reproduce.zhang2021.example1_chunk` (same seeds, same draws) except the initial
    state, ``X_0`` scaled by the value in :data:`INIT_VARIANTS`. Returns per-trial booleans
    ``log_<init>`` and ``oracle_<init>``; each initialisation's are the same computed alone or
    with the others.
    """
    import dataclasses

    unknown = sorted(set(inits) - set(INIT_VARIANTS))
    if unknown:
        raise ModelError(f"inits: expected names of {sorted(INIT_VARIANTS)}, got {unknown}")
    base = ex.example1_model(r=r)
    trials0 = ex.draw_trials(base, trial_rngs(seeds), q=q)
    out: dict[str, np.ndarray] = {}
    for init in inits:
        s = INIT_VARIANTS[init]
        sim_model, filt, gains = _initial_state_setup(float(r), init)
        noise = dataclasses.replace(trials0.noise, x0=s * trials0.noise.x0)
        trials = dataclasses.replace(trials0, noise=noise)
        y = ex.simulate_trials(sim_model, trials)
        res = kitanidis_filter(filt, y, gains=gains)
        sig = residual_signature(filt, gains, Psi=trials.Psi, upsilon=False)
        reg = regression_data(res.residuals, sig.on_residual, start=1)
        true = trials.theta != 0
        paths = lasso_path_batch(
            reg.X, reg.y, n_samples=reg.n_samples
        )  # full paths, all trials at once
        ok = np.all(flat_ranges(paths, lambda_ratio=LAMBDA_RATIO).support == true, axis=1)
        orc = paths.has_interval_support(true)
        out[f"log_{init}"], out[f"oracle_{init}"] = ok, orc
    return out


def unknown_input_effect(*, q: int = 15, r: float = 0.5, trials: int = 20, seed: int = 0) -> float:
    """Largest change of the regression ``(X, y)`` when ``d_k`` is set to 0, relative to ``max |y|``.

    Proposition 2: the Kitanidis residual does not depend on ``d`` at all, so this is rounding
    error, and the way ``d_k`` is drawn cannot change any rate.
    """
    import dataclasses

    model = ex.example1_model(r=r)
    tr = ex.draw_trials(model, trial_rngs(trial_seeds(seed, trials)), q=q)
    reg, _ = example1_regression(tr, r=r)
    reg0, _ = example1_regression(dataclasses.replace(tr, d=np.zeros_like(tr.d)), r=r)
    return float(
        max(np.abs(reg.y - reg0.y).max(), np.abs(reg.X - reg0.X).max()) / np.abs(reg.y).max()
    )


def variant_columns() -> list[tuple[str, int, float]]:
    return [(f"q{q}", q, 0.5) for q in VARIANT_Q] + [(f"r{r:g}", 5, r) for r in VARIANT_R]


def _chunk_functions(cols: list[tuple[str, int, float]]) -> dict[str, partial]:
    """The chunk functions of :func:`lambda_rule`, keyed by column (:func:`variant_columns`) or
    initialisation (:data:`INIT_VARIANTS`, one function each), in the order handed out.

    The calling process runs the first chunk alone (the memory probe), then takes chunks from the
    front while a worker takes them from the back (:func:`~fdi_lib.montecarlo.run_monte_carlo_many`):
    an initialisation's chunk (about half a column's) first, so that the worker waits less, and the
    other one after two columns, near where the two processes meet at the end of the run (about
    half the work from the front), so that neither waits long for the other's last chunk."""
    init = {i: partial(initial_state_chunk, q=15, r=0.5, inits=(i,)) for i in INIT_VARIANTS}
    col = {key: partial(lambda_rule_chunk, q=q, r=r) for key, q, r in cols}
    first, second = INIT_VARIANTS
    order = [first, *list(col)[:2], second, *list(col)[2:]]
    return {key: {**init, **col}[key] for key in order}


def _column_rates(
    cols: list[tuple[str, int, float]], results: list[dict[str, np.ndarray]], n: int
) -> tuple[dict, dict, dict, dict, dict]:
    """Per column of :func:`variant_columns`: the rates and 95 % intervals of each reading and of
    the raw oracle, of each path's oracle and their union, and each reading's rate beyond the raw
    oracle (``success_rate``, ``ci95``, ``oracle_rate``, ``oracle_ci95``, ``beyond_raw_oracle``
    of :func:`lambda_rule`), from the trials' outcomes ``results`` (one dict per column)."""
    rates: dict[str, dict[str, float]] = {k: {} for k in RULE_READINGS + ("oracle",)}
    cis: dict[str, dict[str, list[float]]] = {k: {} for k in rates}
    orates: dict[str, dict[str, float]] = {k: {} for k in ORACLE_PATHS + ("union",)}
    ocis: dict[str, dict[str, list[float]]] = {k: {} for k in orates}
    beyond: dict[str, dict[str, float]] = {k: {} for k in RULE_READINGS}
    for (key, _, _), col in zip(cols, results):
        for k in rates:
            c = int(col[k].sum())
            rates[k][key] = c / n
            cis[k][key] = list(binomial_ci(c, n))
        on_path = {"raw": col["oracle"], **{p: col[f"oracle_{p}"] for p in ORACLE_PATHS[1:]}}
        on_path["union"] = np.any(np.stack(list(on_path.values())), axis=0)
        for k, v in on_path.items():
            orates[k][key] = int(v.sum()) / n
            ocis[k][key] = list(binomial_ci(int(v.sum()), n))
        for k in RULE_READINGS:
            beyond[k][key] = int(np.sum(col[k] & ~col["oracle"])) / n
    return rates, cis, orates, ocis, beyond


def _paper_rates() -> dict[str, float]:
    """The paper's success rates at the columns of :func:`variant_columns` (Tables I-II)."""
    return {
        **{f"q{q}": PAPER_TABLE1[q] for q in VARIANT_Q},
        **{f"r{r:g}": PAPER_TABLE2["success_rate"][r] for r in VARIANT_R},
    }


@register(
    "zhang2021-lambda-rule",
    paper=PAPER,
    title="Example 1: readings of the lambda rule, the oracle and the initial state (Tables I-II)",
    chapter="zhang2021/sparse",
    claims={
        # the values of Tables I-II that this study checks again on fewer trials: one row,
        # under the table (the paper's trial count)
        f"success_rate/{c}*": shown_under(
            f"zhang2021-table{t}",
            lambda p: (p[0], p[1][1:]),
            ours=ours_at("success_rate", "log"),
            ci=ci_at("ci95", "log"),
        )
        for c, t in (("q", "1"), ("r", "2"))
    },
)
def lambda_rule(*, seed: int, trials: int | None, jobs: int) -> ReproductionResult:
    """Which reading of the paper's rule for ``lambda`` could give the rates of Tables I-II?

    The paper defines the rule in words (Sec. IV, after (39)); the author's Matlab files, which
    the paper says illustrate the approach, we do not have. On the trials of
    ``zhang2021-table1`` / ``zhang2021-table2`` (same seed: the first ``trials`` trials of each
    column), several readings (:data:`RULE_READINGS`, :func:`lambda_rule_chunk`) and an
    **oracle** per path of :data:`ORACLE_PATHS` (the true support is on that Lasso path: an
    upper bound for every rule that reads that path only), for q in :data:`VARIANT_Q`
    (r = 0.5) and r in :data:`VARIANT_R` (q = 5); then, at q = 15, the initial state and the
    filter initialisation (:data:`INIT_VARIANTS`, :func:`initial_state_chunk`). The paper
    gives no trial count for this (``trials=None`` runs 200, our choice).

    Headline keys
    -------------
    success_rate : dict
        ``{reading: {column: rate}}`` for the readings of :data:`RULE_READINGS` and ``oracle``
        (the oracle of the raw path); columns ``"q9"``, ``"q15"``, ``"q25"`` (r = 0.5) and
        ``"r100"``, ``"r200"`` (q = 5).
    ci95 : dict
        Same layout, Clopper-Pearson 95 % intervals ``[low, high]``.
    oracle_rate : dict
        ``{path: {column: rate}}``: the oracle of each path of :data:`ORACLE_PATHS` (``raw``
        equals ``success_rate["oracle"]``) and ``union``: the true support is on at least one
        of them (an upper bound for every rule that reads any of these paths).
    oracle_ci95 : dict
        Same layout, Clopper-Pearson 95 % intervals.
    beyond_raw_oracle : dict
        ``{reading: {column: rate}}``: fraction of the trials in which the reading succeeds
        although the raw path's oracle says that no ``lambda`` can (0 for the readings of the
        raw path).
    init_success_rate, init_oracle_rate : dict
        At q = 15, r = 0.5, per initialisation of :data:`INIT_VARIANTS`: rate of the log rule and
        of the oracle.
    init_ci95 : dict
        ``{"log_<init>" | "oracle_<init>": [low, high]}``.
    unknown_input_change : float
        Largest change of the regression when ``d_k`` is set to 0, relative to ``max |y|``
        (:func:`unknown_input_effect`): rounding error, so ``d_k`` cannot change any rate.
    """
    n = 200 if trials is None else trials
    cols = variant_columns()
    # one pool for the variants' columns and the initial-state runs (same trials)
    fns = _chunk_functions(cols)
    outs = dict(zip(fns, run_monte_carlo_many(list(fns.values()), n, seed=seed, jobs=jobs)))
    results = [outs[key] for key, _, _ in cols]
    res = {k: v for init in INIT_VARIANTS for k, v in outs[init].items()}
    rates, cis, orates, ocis, beyond = _column_rates(cols, results, n)
    init_ci = {k: list(binomial_ci(int(v.sum()), n)) for k, v in res.items()}
    headline = {
        "success_rate": rates,
        "ci95": cis,
        "oracle_rate": orates,
        "oracle_ci95": ocis,
        "beyond_raw_oracle": beyond,
        "init_success_rate": {i: float(res[f"log_{i}"].mean()) for i in INIT_VARIANTS},
        "init_oracle_rate": {i: float(res[f"oracle_{i}"].mean()) for i in INIT_VARIANTS},
        "init_ci95": init_ci,
        "unknown_input_change": unknown_input_effect(seed=seed),
    }
    return ReproductionResult(
        id="zhang2021-lambda-rule",
        headline=headline,
        paper={"success_rate": _paper_rates()},
        settings={
            "seed": seed,
            "trials": n,
            "N": ex.N_DATA,
            "m": ex.N_PARAMS,
            "lambda_ratio": LAMBDA_RATIO,
            "grids": list(VARIANT_GRIDS),
            "init_scales": dict(INIT_VARIANTS),
        },
        data={},
    )
