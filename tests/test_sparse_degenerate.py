"""The exact Lasso path on degenerate designs (issue 21, section 2).

Duplicated, scaled, zero and nearly collinear columns, exact ties at lambda_max, lambda exactly at a
breakpoint and the Example 2 regression of Zhang (2021): every path returned must satisfy the
optimality (KKT) conditions of (39), checked here independently of the library (a plain loop over
breakpoints and components), and agree with scikit-learn's ``lars_path`` (the peer implementation
of the same homotopy) where the Lasso solution is unique, or with the Lasso on the reduced design
where it is not (the fitted values and the l1 norm of a Lasso solution are unique even when the
solution is not).
"""

import warnings

import numpy as np
import pytest

from fdi_lib.errors import NumericalError
from fdi_lib.sparse import (
    KKT_TOL,
    LassoPath,
    flat_range,
    kkt_residual,
    lasso_path,
    lasso_path_batch,
    lasso_paths,
)

#: Tolerance of the independent KKT check below, relative to lambda, on the breakpoints above
#: FLOOR * lambda_max (where rounding, not the algorithm, limits any solver on these designs).
TOL = 1e-7
FLOOR = 1e-4


def kkt_violation(X, y, path, floor=FLOOR):
    """Largest KKT violation of ``path`` relative to lambda, on breakpoints >= floor * lambda_max (loops)."""
    lam, th, N = path.lambdas, path.coefs, path.n_samples
    g = X.T @ (y[:, None] - X @ th) / N  # (m, K+1): the gradient at each breakpoint
    zero = 1e-12 * max(1.0, np.abs(th).max())
    worst = 0.0
    for i in range(lam.size):
        if lam[i] < floor * lam[0]:
            continue
        for j in range(th.shape[0]):
            signs = {np.sign(th[j, i])} if abs(th[j, i]) > zero else set()
            for a in (i - 1, i):  # the intervals next to breakpoint i
                if 0 <= a < lam.size - 1 and abs(th[j, a] + th[j, a + 1]) / 2 > zero:
                    signs.add(np.sign(th[j, a] + th[j, a + 1]))
            v = max((abs(g[j, i] - s * lam[i]) for s in signs), default=abs(g[j, i]) - lam[i])
            worst = max(worst, v / lam[i])
    return worst


def sklearn_path(X, y, N, lambda_min=0.0):
    """scikit-learn's lars_path(method="lasso") in the normalisation of (39)."""
    from sklearn.linear_model import lars_path

    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        alphas, _, coefs = lars_path(
            X,
            y,
            method="lasso",
            alpha_min=lambda_min * np.abs(X.T @ y).max() / X.shape[0],
            max_iter=1000,
        )
    return LassoPath(lambdas=alphas * X.shape[0] / N, coefs=coefs, n_samples=N)


def objective(X, y, N, lam, theta):
    return np.sum((X @ theta - y) ** 2) / (2 * N) + lam * np.abs(theta).sum()


def _base(seed, rows=60, m=20, q=3):
    rng = np.random.default_rng(seed)
    X = rng.standard_normal((rows, m))
    theta = np.zeros(m)
    theta[rng.choice(np.arange(2, m), q, replace=False)] = rng.choice([-1.0, 1.0], q) * rng.uniform(
        1, 2, q
    )
    return rng, X, theta


def degenerate(kind, seed):
    """A design with one degenerate feature, the index of the columns to keep for a reference, and y.

    Column 1 is a copy (``dup``), a multiple (``x2``, ``x-0.5``, ``x3``) of a column in the true
    support, or zero (``zero``); ``reduced`` lists the columns of an equivalent non-degenerate design.
    """
    rng, X, theta = _base(seed)
    j = int(np.flatnonzero(theta)[0])
    factor = {"dup": 1.0, "x2": 2.0, "x-0.5": -0.5, "x3": 3.0, "zero": 0.0}[kind]
    X[:, 1] = factor * X[:, j]
    y = X @ theta + 0.3 * rng.standard_normal(X.shape[0])
    # the longest column of the parallel pair carries the group's weight (the other is then 0)
    drop = 1 if abs(factor) <= 1 else j
    return X, y, [c for c in range(X.shape[1]) if c != drop]


DEGENERATE = [(kind, seed) for kind in ("dup", "x2", "x-0.5", "x3", "zero") for seed in range(4)]


@pytest.mark.parametrize("kind, seed", DEGENERATE)
def test_duplicated_scaled_and_zero_columns(kind, seed):
    """A finite path satisfying the KKT conditions, with the objective of the reduced design's Lasso."""
    X, y, keep = degenerate(kind, seed)
    N = 30
    path = lasso_path(X, y, n_samples=N)
    assert np.all(np.isfinite(path.coefs)) and np.all(np.isfinite(path.lambdas))
    assert path.solver in ("homotopy", "sklearn-fallback")
    assert path.kkt_residual <= KKT_TOL
    assert kkt_violation(X, y, path) <= TOL
    ref = sklearn_path(X[:, keep], y, N)  # the same Lasso on a design without the degenerate column
    assert kkt_violation(X[:, keep], y, ref) <= TOL  # the reference itself is a Lasso path
    assert path.lambdas[0] == pytest.approx(ref.lambdas[0], rel=1e-12)
    for lam in ref.lambdas[0] * np.geomspace(0.9, 1e-3, 12):
        full = np.zeros(X.shape[1])
        full[keep] = ref.coef(lam)
        a, b = objective(X, y, N, lam, path.coef(lam)), objective(X, y, N, lam, full)
        assert abs(a - b) <= 1e-10 * b
        np.testing.assert_allclose(X @ path.coef(lam), X @ full, atol=1e-8 * np.abs(X @ full).max())
    flat_range(path)  # the rule reads the path (no "no range of lambda" error after a NaN path)


def collinear(seed):
    """Columns 1, 3, 5 within 1e-8 .. 1e-4 (relative) of columns 0, 2, 4."""
    rng = np.random.default_rng(100 + seed)
    X = rng.standard_normal((50, 15))
    for i, j in ((1, 0), (3, 2), (5, 4)):
        X[:, i] = X[:, j] + 10.0 ** rng.uniform(-8, -4) * rng.standard_normal(50)
    theta = np.zeros(15)
    theta[[0, 2, 6]] = [1.5, -1.0, 2.0]
    return X, X @ theta + 0.3 * rng.standard_normal(50)


@pytest.mark.parametrize("seed", range(6))
def test_nearly_collinear_columns_match_scikit_learn(seed):
    """Three columns each within 1e-8 .. 1e-4 of another: the KKT conditions hold and the path is
    scikit-learn's down to 1e-4 lambda_max: the same breakpoints (to 1e-6: the events of a nearly
    collinear pair are ill-conditioned, the rounding of X moves them by ~1e-8 here) and the same
    objective and fitted values along the path."""
    X, y = collinear(seed)
    path = lasso_path(X, y, lambda_min=FLOOR)
    assert path.kkt_residual <= KKT_TOL and kkt_violation(X, y, path) <= TOL
    ref = sklearn_path(X, y, 50, FLOOR)
    assert kkt_violation(X, y, ref) <= TOL
    np.testing.assert_allclose(path.lambdas, ref.lambdas, rtol=1e-6, atol=1e-12 * ref.lambdas[0])
    for lam in ref.lambdas[0] * np.geomspace(0.9, FLOOR, 15):
        a, b = path.coef(lam), ref.coef(lam)
        assert abs(objective(X, y, 50, lam, a) - objective(X, y, 50, lam, b)) <= 1e-10 * objective(
            X, y, 50, lam, b
        )
        np.testing.assert_allclose(X @ a, X @ b, atol=1e-6 * np.abs(X @ b).max())


def tie_problem(seed):
    """Orthogonal columns and y with |X_0^T y| = |X_1^T y| exactly: two components enter at lambda_max."""
    rng = np.random.default_rng(seed)
    Q, _ = np.linalg.qr(rng.standard_normal((40, 8)))
    X = Q * np.sqrt(40)
    return X, X @ np.array([2.0, -2.0, 0.5, 0.0, 0.0, 0.0, 0.3, 0.0])


@pytest.mark.parametrize("seed", range(4))
def test_exact_tie_at_lambda_max(seed):
    """Against the closed form: ``X^T X = n I``, so the path soft-thresholds ``z = X^T y / n`` and
    its breakpoints are the ``|z_j|``. scikit-learn's ``lars_path`` is no reference here: where the
    rounding of ``X^T y`` leaves the two tied correlations 1e-14 apart (seed 1 on an AVX2 machine,
    not on the one where the test was written), its path ends at 3.5 for a true coefficient of 2."""
    X, y = tie_problem(seed)
    path = lasso_path(X, y)
    assert path.solver == "homotopy"  # the homotopy itself handles the tie (no fallback needed)
    assert kkt_violation(X, y, path, floor=1e-12) <= TOL
    np.testing.assert_array_equal(np.flatnonzero(path.coef(0.99 * path.lambdas[0])), [0, 1])
    z = X.T @ y / X.shape[0]
    knots = np.sort(np.abs(z[np.abs(z) > 1e-12 * np.abs(z).max()]))[::-1]  # 2, 2, 0.5, 0.3
    # the same breakpoints down to the exact fit (y is in the span of X: below, the path only
    # follows correlations of rounding size, ~1e-16 lambda_max)
    k = int(np.sum(path.lambdas > 1e-12 * path.lambdas[0]))
    assert k == knots.size == 4
    np.testing.assert_allclose(path.lambdas[:k], knots, rtol=1e-12)
    for lam in [*path.lambdas[:k], 0.7, 0.1]:
        soft = np.sign(z) * np.maximum(np.abs(z) - lam, 0.0)
        np.testing.assert_allclose(path.coef(lam), soft, atol=1e-12 * np.abs(z).max())


def test_four_way_tie_where_a_joined_component_must_leave_at_once():
    """0/1 design with X^T y = (4, 4, 4, 4): three components tie at lambda_max, and the equiangular
    direction of the three points against the sign of one, which must leave at once. scikit-learn's
    lars_path violates the KKT conditions here (by 2 lambda), so the reference is cvxpy's solution."""
    from fdi_lib.sparse import lasso_cvxpy

    X = np.array(
        [[0, 0, 0, 0], [1, 0, 1, 0], [0, 0, 1, 1], [1, 1, 0, 1], [1, 0, 0, 0], [1, 1, 1, 1]], float
    )
    y = np.array([1.0, 2.0, 0.0, 2.0, -2.0, 2.0])
    np.testing.assert_array_equal(X.T @ y, [4.0, 4.0, 4.0, 4.0])
    path = lasso_path(X, y, n_samples=6, lambda_min=0.3)
    assert path.solver == "homotopy" and path.kkt_residual <= KKT_TOL
    assert kkt_violation(X, y, path) <= TOL
    assert kkt_violation(X, y, sklearn_path(X, y, 6, 0.3)) > 1.0
    for frac in (0.9, 0.6, 0.35):
        lam = frac * path.lambdas[0]
        a, b = path.coef(lam), lasso_cvxpy(X, y, lam, n_samples=6)
        assert (
            objective(X, y, 6, lam, a) <= objective(X, y, 6, lam, b) + 1e-9
        )  # cvxpy: interior-point accuracy


def test_lambda_exactly_at_a_breakpoint():
    """At a breakpoint, coef() returns the stored solution, which is scikit-learn's there and optimal."""
    rng, X, theta = _base(7, rows=50, m=12, q=4)
    y = X @ theta + 0.5 * rng.standard_normal(50)
    path = lasso_path(X, y, n_samples=25)
    ref = sklearn_path(X, y, 25)
    assert path.lambdas.size == ref.lambdas.size
    for i in range(1, path.lambdas.size - 1):
        lam = path.lambdas[i]
        th = path.coef(lam)
        np.testing.assert_array_equal(th, path.coefs[:, i])
        np.testing.assert_allclose(
            th, ref.coefs[:, i], rtol=1e-9, atol=1e-12 * np.abs(ref.coefs).max()
        )
        g = X.T @ (y - X @ th) / 25
        assert np.all(np.abs(g) <= lam * (1 + TOL))
        on = th != 0
        np.testing.assert_allclose(g[on], lam * np.sign(th[on]), rtol=TOL)


def test_batched_and_single_paths_agree_on_a_mixed_batch():
    """Nearly collinear (recomputed by lars_path), duplicated-column and generic problems in one
    batch: each path is bit for bit its single-problem path and satisfies the KKT conditions; the
    homotopy's paths are the same as in a batch without the recomputed ones."""
    probs = [collinear(0), collinear(2)]
    rng, X, theta = _base(30, rows=50, m=15)
    X[:, 1] = X[:, int(np.flatnonzero(theta)[0])]  # a duplicated column of the support
    probs.append((X, X @ theta + 0.3 * rng.standard_normal(50)))
    for seed in range(3):
        rng, X, theta = _base(20 + seed, rows=50, m=15)
        probs.append((X, X @ theta + 0.4 * rng.standard_normal(50)))
    X = np.stack([p[0] for p in probs])
    y = np.stack([p[1] for p in probs])
    batch = lasso_path_batch(X, y, n_samples=25)
    assert batch.solver.shape == batch.kkt_residual.shape == (6,)
    assert np.all(batch.kkt_residual <= KKT_TOL)
    assert list(batch.solver) == ["sklearn-fallback"] * 2 + ["homotopy"] * 4
    for b, path in enumerate(lasso_paths(X, y, n_samples=25)):
        single = lasso_path(X[b], y[b], n_samples=25)
        assert single.solver == path.solver == batch.solver[b]
        np.testing.assert_array_equal(single.lambdas, path.lambdas)
        np.testing.assert_array_equal(single.coefs, path.coefs)
        assert kkt_violation(X[b], y[b], path) <= TOL
    only = lasso_path_batch(X[2:], y[2:], n_samples=25)
    for b in range(4):
        np.testing.assert_array_equal(only.path(b).coefs, batch.path(2 + b).coefs)


@pytest.fixture(scope="module")
def example2():
    """The Example 2 regression of ``zhang2021-fig6`` (surrogate pipeline, seed 0), built as that
    reproduction builds it."""
    from fdi_lib.filters import kalman_filter, kalman_gains
    from fdi_lib.kitanidis import residual_signature
    from fdi_lib.models import fault_profile
    from fdi_lib.montecarlo import trial_seeds
    from fdi_lib.reproduce.zhang2021_example2 import EX2_LEAK_SIZE, EX2_LEAKS, EX2_M, example2_setup
    from fdi_lib.simulate import simulate
    from fdi_lib.sparse import regression_data

    model, u, Psi = example2_setup()
    fault = fault_profile(model, Psi=Psi)
    theta = np.zeros(EX2_M)
    theta[list(EX2_LEAKS)] = EX2_LEAK_SIZE
    sim = simulate(
        model, rng=np.random.default_rng(trial_seeds(0, 1)[0]), u=u, fault=fault, theta=theta
    )
    gains = kalman_gains(model)
    res = kalman_filter(model, sim.y, u, gains=gains)
    reg = regression_data(
        res.updated_residuals, residual_signature(model, gains, fault).on_residual, start=1
    )
    return np.asarray(reg.X), np.asarray(reg.y), reg.n_samples


def test_example2_regression_path_is_optimal_and_matches_scikit_learn(example2):
    """Zhang (2021) Example 2 (condition number ~4e5): the path satisfies the KKT conditions, has
    scikit-learn's breakpoints in the rule's window (to 1e-6: a relative rounding of X, ~1e-16,
    moves them by up to ~1e-8 at this conditioning), and the same support size at every point of
    the 200-point grid of the grid rule."""
    X, y, N = example2
    path = lasso_path(X, y, n_samples=N)
    assert path.kkt_residual <= KKT_TOL and kkt_violation(X, y, path) <= TOL
    ref = sklearn_path(X, y, N)
    assert kkt_violation(X, y, ref) <= TOL
    lam0 = ref.lambdas[0]
    k = int(np.sum(ref.lambdas >= FLOOR * lam0))
    np.testing.assert_allclose(path.lambdas[:k], ref.lambdas[:k], rtol=1e-6)
    grid = np.geomspace(lam0, FLOOR * lam0, 200)
    zero = 1e-12 * max(1.0, np.abs(ref.coefs).max())
    sizes = [
        (
            np.count_nonzero(np.abs(path.coef(g)) > zero),
            np.count_nonzero(np.abs(ref.coef(g)) > zero),
        )
        for g in grid
    ]
    assert all(a == b for a, b in sizes)
    np.testing.assert_array_equal(flat_range(path).support, flat_range(ref).support)


def test_kkt_residual_detects_each_kind_of_violation():
    """The library's check fails on wrong paths (it is not vacuous) and passes on scikit-learn's."""
    rng, X, theta = _base(3, rows=50, m=10, q=3)
    y = X @ theta + 0.3 * rng.standard_normal(50)
    ref = sklearn_path(X, y, 50)
    assert kkt_residual(X, y, ref) <= KKT_TOL
    i = ref.lambdas.size // 2
    j = int(np.flatnonzero(ref.coefs[:, i])[0])

    def altered(change):
        coefs = ref.coefs.copy()
        change(coefs)
        return LassoPath(lambdas=ref.lambdas, coefs=coefs, n_samples=50)

    def scale(c):
        c[j, i] *= 1.001

    def flip(c):  # a sign change across an interval
        c[j, i] *= -1.0

    def wake(c):  # a component that should be zero
        c[int(np.flatnonzero(ref.coefs[:, 1] == 0)[0]), 1] = 1e-3

    def nan(c):
        c[0, -1] = np.nan

    for change, low in ((scale, 1e-5), (flip, 1.0), (wake, 1e-5)):
        assert kkt_residual(X, y, altered(change)) > max(low, KKT_TOL)
    assert kkt_residual(X, y, altered(nan)) == np.inf
    bad_lam = LassoPath(lambdas=ref.lambdas * 1.01, coefs=ref.coefs, n_samples=50)
    assert kkt_residual(X, y, bad_lam) > 1e-3


def test_failure_of_every_solver_is_a_typed_error(monkeypatch):
    """When the homotopy's path and scikit-learn's both fail the check, a NumericalError names the
    problem (never a NaN path read as a result, or a misleading 'no range of lambda')."""
    import sklearn.linear_model

    X, y = collinear(0)  # the homotopy's path violates the KKT conditions (by 2 lambda)

    def broken(X, y, **kw):
        alphas = np.array([np.abs(X.T @ y).max() / X.shape[0], 0.0])
        return alphas, None, np.full((X.shape[1], 2), np.nan)

    monkeypatch.setattr(sklearn.linear_model, "lars_path", broken)
    with pytest.raises(
        NumericalError, match=r"X, y \(problem 1\): the Lasso path violates the optimality"
    ):
        lasso_path_batch(
            np.stack([_base(9, 50, 15)[1], X]),
            np.stack([_base(9, 50, 15)[1] @ _base(9, 50, 15)[2], y]),
        )


@pytest.mark.parametrize("scale", [5.56388252e-306, 1e-200, 1e-160, 1e160])
def test_designs_far_from_unit_scale_are_solved_exactly(scale):
    """Designs whose squares under- or overflow (found by the fuzz test: X = 5.6e-306 had a zero
    Gram matrix and scikit-learn was called with alpha_min = inf): the closed form of one column,
    theta(lambda) = (X^T y - N lambda) / X^T X, at lambda_min = 0.5 and at the path's end."""
    X = scale * np.array([[1.0], [2.0]])
    y = np.array([1.0, 1.0])
    for frac in (0.0, 0.5):
        with warnings.catch_warnings():
            warnings.simplefilter("error")  # no overflow or invalid value on the way
            path = lasso_path(X, y, lambda_min=frac)
        theta_end = (1 - frac) * 3.0 / (5.0 * scale)  # (X^T y - N lambda_min) / X^T X, N = 2
        assert path.lambdas[0] == pytest.approx(
            3.0 * scale / 2, rel=1e-12
        )  # lambda_max = X^T y / N
        assert path.coefs[0, -1] == pytest.approx(theta_end, rel=1e-12)


def test_power_of_two_rescaling_is_exact():
    """Scaling X by 2^-600 (squares underflow) scales theta by 2^600 and lambda by 2^-600, bit for bit."""
    rng = np.random.default_rng(11)
    X, y = rng.normal(size=(12, 4)), rng.normal(size=12)
    s = 2.0**-600
    a, b = lasso_path(X, y), lasso_path(s * X, y)
    np.testing.assert_array_equal(b.lambdas, a.lambdas * s)
    np.testing.assert_array_equal(b.coefs, a.coefs / s)


def test_unrepresentable_path_is_a_typed_error():
    """lambda_max = X^T y / N = 1e400 is not a float64: a NumericalError naming the scales, never inf."""
    with pytest.raises(NumericalError, match="not representable in float64"):
        lasso_path(np.array([[1e200]]), np.array([1e200]))


def test_fallback_refuses_a_problem_it_cannot_scale():
    """The scikit-learn fallback scales y so that lambda_max is about 1e8; where X^T y is too close to
    zero for that scale to be a float64 (1e-310 here), a NumericalError, never lars_path(alpha_min=inf)."""
    from fdi_lib.sparse import _lars_fallback

    with pytest.raises(NumericalError, match="too far from 1 for scikit-learn's lars_path"):
        _lars_fallback(np.array([[1.0]]), np.array([1e-310]), 0.0, None, 0, 1.0)


def test_one_problem_homotopy_is_the_batched_one_bit_for_bit():
    """``lasso_path`` follows one problem with scalar bookkeeping (``_homotopy_one``), the batch with
    arrays (``_homotopy``): on random designs with ties, duplicated, scaled, zero and dependent
    columns, exact fits and both stopping rules, the breakpoints and coefficients are the same bits,
    including the rare branches (a path ended by a NaN, a path longer than the first buffer)."""
    from fdi_lib.sparse import _homotopy, _homotopy_one

    rng = np.random.default_rng(1)
    nan = long = 0
    for t in range(240):
        rows, m = rng.integers(3, 40), rng.integers(2, 20)
        X = rng.standard_normal((rows, m))
        kind = t % 8
        if kind == 1 and m > 2:
            X[:, 1] = X[:, 0]
        if kind == 2 and m > 2:
            X[:, 2] = -3 * X[:, 0]
        if kind == 3:
            X[:, -1] = 0.0
        if kind == 4:
            X = np.round(X)
        if kind == 5 and m > 3:
            X[:, 3] = X[:, 0] + X[:, 1]
        if kind == 6:
            X = np.sign(X)
        theta = rng.standard_normal(m) * (rng.random(m) < 0.4)
        y = X @ theta + (0.0 if kind == 7 else 0.1 * rng.standard_normal(rows))
        if kind == 4:
            y = np.round(y)
        if kind == 6:
            y = np.sign(rng.standard_normal(rows))
        G, Xy = (X.T @ X)[None], (X.T @ y)[None]
        for ratio, max_size in ((0.0, None), (1e-3, None), (0.0, max(1, m // 3))):
            c_min = np.array([ratio * np.abs(Xy).max()])
            with np.errstate(all="ignore"):
                lev, co, k = _homotopy_one(G, Xy, c_min, max_size)
                lev2, co2, k2 = _homotopy(
                    np.concatenate([G, G]), np.concatenate([Xy, Xy]), np.repeat(c_min, 2), max_size
                )
            n = int(k[0])
            assert n == k2[0]
            np.testing.assert_array_equal(lev[0, :n], lev2[0, :n])
            np.testing.assert_array_equal(co[0, :n], co2[0, :n])
            nan += bool(np.isnan(lev[0, :n]).any())
            long += n > 2 * m + 4
    assert nan > 0 and long > 0  # the rare branches were compared


def test_scalar_minimum_of_the_one_problem_homotopy_is_numpys():
    """``_min`` (``_homotopy_one``'s step lengths) is ``numpy.minimum`` bit for bit, the sign of a
    zero and a NaN included, whichever the order of its arguments."""
    from fdi_lib.sparse import _min

    values = [0.0, -0.0, 1e-300, -1.0, 2.5, np.inf, -np.inf, np.nan]
    for a in map(np.float64, values):
        for b in map(np.float64, values):
            got, want = _min(a, b), np.minimum(a, b)
            assert type(got) is np.float64
            assert np.array(got).tobytes() == np.array(want).tobytes(), (a, b)


def test_where_inf_is_numpys_where_bit_for_bit():
    """``_where_inf`` (the homotopy's step lengths without a branch per element) is
    ``numpy.where(mask, x, inf)`` bit for bit, the sign of a zero kept where the mask holds, and
    ``inf`` elsewhere whatever ``x`` is there (NaN, -inf, a negative zero)."""
    from fdi_lib.sparse import _where_inf

    rng = np.random.default_rng(3)
    values = np.array([0.0, -0.0, 5e-324, -1.0, 2.5, 1e300, np.inf, -np.inf, np.nan])
    x = rng.choice(values, (40, 30)) * rng.choice([1.0, 3.0], (40, 30))
    mask = rng.random((40, 30)) < 0.5
    mask &= ~np.isnan(x)  # no NaN where the mask holds (the documented domain)
    assert mask.any() and (~mask & np.isnan(x)).any() and (mask & (x == 0) & np.signbit(x)).any()
    with np.errstate(all="ignore"):
        got = _where_inf(mask, x)
    assert got.tobytes() == np.where(mask, x, np.inf).tobytes()


@pytest.mark.parametrize("exponent", [0, 7, -40, 1021, -1022, -1023, -1024, -1074])
def test_divide_pow2_is_the_division_bit_for_bit(exponent):
    """``_divide_pow2`` (the rescaling of the Lasso problems by powers of 2, multiplied by the
    exact reciprocal) is ``a / s`` bit for bit: normal and subnormal quotients, signed zeros, inf
    and NaN, with powers of 2 whose reciprocal is finite and (below ``2^-1023``) not, when it
    divides; into ``out`` too."""
    from fdi_lib.sparse import _divide_pow2

    rng = np.random.default_rng(5)
    a = rng.standard_normal((6, 500)) * np.ldexp(1.0, rng.integers(-1074, 1023, (6, 500)))
    a[0, :6] = [0.0, -0.0, np.inf, -np.inf, np.nan, 5e-324]
    s = np.ldexp(1.0, exponent + np.array([0, 1, 0, 2, 0, 1]))[:, None]
    with np.errstate(all="ignore"):
        want = a / s
        out = np.empty_like(a)
        got = _divide_pow2(a, s, out=out)
    assert got is out and got.tobytes() == want.tobytes()
    subnormal = (want != 0) & (np.abs(want) < np.finfo(float).tiny)
    assert (subnormal | (np.isinf(want) & np.isfinite(a))).any()  # rounded below or overflowed
