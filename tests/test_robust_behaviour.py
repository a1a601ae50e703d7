"""Behaviours no test checked before issue 15, each against an independent computation."""

from __future__ import annotations

import functools

import numpy as np
import pytest
import scipy.optimize

from fdi_lib.filters import kalman_gains
from fdi_lib.glr import WindowedGLR, first_alarm, glr_window
from fdi_lib.kitanidis import kitanidis_gains
from fdi_lib.models import ltv_model, step_family
from fdi_lib.montecarlo import run_monte_carlo, trial_rngs
from fdi_lib.nonparametric import rejection_projection
from fdi_lib.sets import Polytope
from fdi_lib.sets.svo import SVOModel, run_svo


# ----------------------------------------------------------------- first_alarm: the start boundary
def test_first_alarm_start_is_inclusive_and_bounded():
    stat = np.array([0.0, 9.0, 0.0, 9.0, 0.0])
    assert first_alarm(stat, 1.0, start=1) == 1  # an exceedance at k = start counts
    assert first_alarm(stat, 1.0, start=2) == 3  # one before start does not
    assert first_alarm(stat, 1.0, start=4) == -1
    assert first_alarm(stat, 1.0, start=5) == -1  # start = N: no admissible sample
    assert first_alarm(stat, 9.0) == -1  # strictly above the threshold
    np.testing.assert_array_equal(first_alarm(np.vstack([stat, stat[::-1]]), 1.0, start=2), [3, 3])


# ----------------------------------------------------------------- windowed GLR: default min_samples
@pytest.mark.parametrize("m, p, s", [(3, 2, 2), (1, 2, 1), (4, 2, 2), (5, 3, 2)])
def test_min_samples_default_is_ceil_m_over_p(m, p, s):
    N = 12
    rng = np.random.default_rng(m * 10 + p)
    model = ltv_model(
        F=0.5 * np.eye(2), H=rng.standard_normal((p, 2)), Q=np.eye(2), R=np.eye(p), n_steps=N
    )
    g = kalman_gains(model)
    fam = step_family(model, Phi=rng.standard_normal((p, m)))
    assert WindowedGLR(model, g, fam, window=6).min_samples == s == -(-m // p)
    res = glr_window(rng.standard_normal((N, p)), model, g, fam, window=6)
    # onset r is admissible at k once k - r >= s: the statistic is defined from k = s on.
    assert np.all(np.isnan(res.statistic[:s])) and np.all(np.isfinite(res.statistic[s:]))
    assert np.all(res.onset[s:] <= np.arange(N)[s:] - s)


# ----------------------------------------------------------------- projection with a time-varying E
def test_rejection_projection_uses_E_of_the_previous_step():
    N, n, p = 8, 3, 3
    rng = np.random.default_rng(2)
    model = ltv_model(
        F=0.6 * np.eye(n),
        H=np.eye(p) + 0.1 * rng.standard_normal((p, n)),
        Q=np.eye(n),
        R=np.eye(p),
        n_steps=N,
    )
    E = rng.standard_normal((N, n, 1))  # a different direction at every step
    kg = kitanidis_gains(model, E)
    T = rejection_projection(model, kg)
    for k in range(1, N):
        HE_prev = model.H[k] @ E[k - 1]
        HE_now = model.H[k] @ E[k]
        assert np.abs(T[k] @ HE_prev).max() < 1e-12 * np.abs(HE_prev).max()
        assert np.abs(T[k] @ HE_now).max() > 1e-3  # E_k itself is not rejected (it acts later)
        np.testing.assert_allclose(T[k] @ kg.Sigma[k] @ T[k].T, np.eye(p - 1), atol=1e-12)


# ----------------------------------------------------------------- Monte Carlo: batch-dependent chunks
def _batch_dependent_chunk(seeds):
    """Output depends on the chunk: each row minus the chunk mean, plus the chunk size."""
    x = np.array([rng.standard_normal() for rng in trial_rngs(seeds)])
    return {"centred": x - x.mean(), "size": np.full(len(seeds), float(len(seeds))), "x": x}


def test_monte_carlo_with_batch_dependent_chunks_is_job_independent():
    one = run_monte_carlo(_batch_dependent_chunk, 23, seed=4, jobs=1)
    two = run_monte_carlo(_batch_dependent_chunk, 23, seed=4, jobs=2)
    for key in one:
        np.testing.assert_array_equal(one[key], two[key])
    # The default chunks are ceil(23 / 4) = 6 realisations (the last one 5), whatever the jobs.
    np.testing.assert_array_equal(one["size"], [6.0] * 18 + [5.0] * 5)
    # Each chunk is centred separately: the chunk boundaries are the documented ones.
    for lo, hi in ((0, 6), (6, 12), (12, 18), (18, 23)):
        np.testing.assert_allclose(
            one["centred"][lo:hi], one["x"][lo:hi] - one["x"][lo:hi].mean(), atol=1e-15
        )
    explicit = run_monte_carlo(_batch_dependent_chunk, 23, seed=4, chunk_size=10)
    np.testing.assert_array_equal(explicit["x"], one["x"])  # the draws do not change
    assert not np.allclose(explicit["centred"], one["centred"])  # the batch-dependent part does


# ----------------------------------------------------------------- polytopes: empty and flat sets
def _lp_support(M, m, c):
    res = scipy.optimize.linprog(
        -np.asarray(c, float), A_ub=M, b_ub=m, bounds=[(None, None)] * M.shape[1], method="highs"
    )
    return -res.fun if res.status == 0 else None


def test_flat_set_is_not_empty_and_empty_set_is():
    flat = Polytope.box([0.0, -1.0], [0.0, 1.0])  # a segment in the plane
    assert not flat.is_empty()
    np.testing.assert_allclose(flat.support(np.eye(2)), [0.0, 1.0], atol=1e-12)
    empty = Polytope(
        np.array([[1.0, 0.0], [-1.0, 0.0]]), np.array([-0.5, -0.5])
    )  # x <= -0.5 and x >= 0.5
    assert empty.is_empty()
    barely = Polytope(
        np.array([[1.0, 0.0], [-1.0, 0.0], [0.0, 1.0], [0.0, -1.0]]),
        np.array([1e-6, 1e-6, 1.0, 1.0]),
    )  # a thin but full-dimensional box
    assert not barely.is_empty()


def test_projection_of_empty_and_flat_sets():
    M = np.array(
        [
            [1.0, 0.0, 0.0],
            [-1.0, 0.0, 0.0],
            [0.0, 1.0, 0.0],
            [0.0, -1.0, 0.0],
            [0.0, 0.0, 1.0],
            [0.0, 0.0, -1.0],
            [1.0, 1.0, 0.0],
        ]
    )
    empty = Polytope(
        M, np.array([1.0, 1.0, 1.0, 1.0, 1.0, 1.0, -3.0])
    )  # x + y <= -3 inside the unit cube
    assert empty.is_empty()
    assert empty.project([0, 2]).is_empty()
    # emptiness carried only by the eliminated coordinate: x <= -1 and x >= 1, |y| <= 1
    slab = Polytope(
        np.array([[1.0, 0.0], [-1.0, 0.0], [0.0, 1.0], [0.0, -1.0]]),
        np.array([-1.0, -1.0, 1.0, 1.0]),
    )
    assert slab.is_empty() and slab.project([1]).is_empty()
    flat = Polytope(M[:6], np.array([1.0, 1.0, 1.0, 1.0, 0.0, 0.0]))  # z = 0: a square in R^3
    P = flat.project([0, 1])
    assert not P.is_empty()
    for c in ([1.0, 0.0], [0.0, -1.0], [1.0, 1.0]):
        assert P.support(np.array([c]))[0] == pytest.approx(
            _lp_support(flat.M, flat.m, [*c, 0.0]), abs=1e-9
        )


def test_outer_template_is_tight_in_its_directions():
    """Containment alone is weak: each template face must touch the set (support by an LP)."""
    rng = np.random.default_rng(4)
    P = Polytope.from_vertices(rng.standard_normal((12, 2)))
    D = np.array([[1.0, 0.0], [0.0, 1.0], [-1.0, 0.0], [0.0, -1.0], [1.0, 1.0]])
    T = P.outer_template(D)
    for i, c in enumerate(D):
        assert T.m[i] == pytest.approx(_lp_support(P.M, P.m, c), abs=1e-9)
    assert all(T.contains(v, 1e-12) for v in P.vertices())


# ----------------------------------------------------------------- SVO: tightness at N > 1, margin direction
A, LD, NBAR = 0.9, 0.1, 0.05


def _scalar_record(T=25, seed=0):
    rng = np.random.default_rng(seed)
    x = np.empty(T + 1)
    x[0] = 0.3
    for k in range(T):
        x[k + 1] = A * x[k] + LD * rng.uniform(-1, 1)
    return x, x + NBAR * rng.uniform(-1, 1, size=T + 1)


def _interval_observer(y):
    """The exact set of a scalar system by interval arithmetic: predict, then intersect with the strip."""
    lo, hi = max(-1.0, y[0] - NBAR), min(1.0, y[0] + NBAR)
    out = [(lo, hi)]
    for yk in y[1:]:
        lo, hi = max(A * lo - LD, yk - NBAR), min(A * hi + LD, yk + NBAR)
        out.append((lo, hi))
    return np.array(out)


@pytest.mark.parametrize("N", [1, 2, 3])
@pytest.mark.parametrize("method", ["exact", "template"])
def test_svo_is_tight_for_any_horizon(N, method):
    """In one dimension the exact set is an interval; the SVO must equal it, not merely contain it."""
    x, y = _scalar_record()
    model = SVOModel(A=[[A]], C=[[1.0]], L=[[LD]], noise=NBAR)
    run = run_svo(
        model,
        np.zeros((len(y) - 1, 0)),
        y[:, None],
        Polytope.box([-1.0], [1.0]),
        N=N,
        method=method,
    )
    ref = _interval_observer(y)
    assert run.empty_at is None
    # margin 1e-9 (relative) per step: the sets may be that much larger, never smaller
    np.testing.assert_allclose(run.lower[:, 0], ref[:, 0], atol=1e-8)
    np.testing.assert_allclose(run.upper[:, 0], ref[:, 1], atol=1e-8)
    assert np.all((run.lower[:, 0] <= x + 1e-12) & (x <= run.upper[:, 0] + 1e-12))


def test_svo_round_off_margin_inflates_outwards():
    from fdi_lib.sets.svo import SetValuedObserver

    _, y = _scalar_record(T=10)
    model = SVOModel(A=[[A]], C=[[1.0]], L=[[LD]], noise=NBAR)
    ref = _interval_observer(y)
    svo = SetValuedObserver(Polytope.box([-1.0], [1.0]), method="template", margin=1e-3)
    svo.start(model, y[:1])
    for k in range(1, len(y)):
        X = svo.update(model, np.zeros(0), y[k : k + 1])
        lo, hi = -X.support(np.array([[-1.0]]))[0], X.support(np.array([[1.0]]))[0]
        assert lo <= ref[k, 0] and hi >= ref[k, 1]  # outwards: never excludes a state
        assert max(ref[k, 0] - lo, hi - ref[k, 1]) < 5e-3  # by about the margin only


def test_functools_partial_chunks_are_supported():
    """The engine's documented contract: a functools.partial chunk function, several jobs."""
    fn = functools.partial(_batch_dependent_chunk)
    np.testing.assert_array_equal(
        run_monte_carlo(fn, 7, seed=1, jobs=2)["x"], run_monte_carlo(fn, 7, seed=1, jobs=1)["x"]
    )
