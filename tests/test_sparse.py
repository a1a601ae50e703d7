"""Sparse regression (Zhang 2021, eqs. (36)-(39)): Lasso two ways, the flat-range rule, LS re-estimation."""

import numpy as np
import pytest

from fdi_lib.errors import ModelError, NonFiniteError, ShapeError
from fdi_lib.sparse import (
    LassoPath,
    diagnose,
    flat_range,
    lasso_cvxpy,
    lasso_path,
    least_squares_on_support,
    regression_data,
)


def _problem(seed=0, rows=80, m=20, q=3, noise=0.3):
    rng = np.random.default_rng(seed)
    X = rng.standard_normal((rows, m))
    theta = np.zeros(m)
    theta[rng.choice(m, q, replace=False)] = rng.choice([-1.0, 1.0], q) * rng.uniform(1, 2, q)
    return X, X @ theta + noise * rng.standard_normal(rows), theta


@pytest.mark.parametrize("frac", [0.6, 0.2, 0.05, 0.01])
def test_lars_path_and_cvxpy_agree(frac):
    X, y, _ = _problem()
    N = 40  # the paper's normalisation: N time samples of p = 2 outputs
    path = lasso_path(X, y, n_samples=N)
    lam = frac * path.lambdas[0]
    a = path.coef(lam)
    b = lasso_cvxpy(X, y, lam, n_samples=N)
    np.testing.assert_allclose(
        a, b, atol=2e-4 * max(1.0, np.abs(a).max())
    )  # interior-point accuracy

    def objective(t):
        return np.sum((X @ t - y) ** 2) / (2 * N) + lam * np.abs(t).sum()

    # the exact path is at least as good as the solver's optimum, and they agree to solver precision
    assert objective(a) <= objective(b) + 1e-9
    assert objective(b) - objective(a) < 1e-6 * objective(a)


def test_path_satisfies_the_lasso_optimality_conditions():
    """KKT of (39): X^T (y - X theta) / N = lam sign(theta) on the support, |.| <= lam elsewhere."""
    X, y, _ = _problem(seed=1)
    N = 40
    path = lasso_path(X, y, n_samples=N)
    assert np.abs(X.T @ y).max() / N == pytest.approx(path.lambdas[0], rel=1e-10)
    for lam in np.geomspace(path.lambdas[0] * 0.99, path.lambdas[0] * 1e-3, 15):
        th = path.coef(lam)
        g = X.T @ (y - X @ th) / N
        on = th != 0
        np.testing.assert_allclose(g[on], lam * np.sign(th[on]), rtol=1e-7, atol=1e-9)
        assert np.all(np.abs(g[~on]) <= lam * (1 + 1e-7))
    assert np.all(path.coef(path.lambdas[0] * 1.01) == 0)


def _hand_path(lambdas, sizes, m=10):
    """A LassoPath whose interval (lambda_{i+1}, lambda_i) has the first sizes[i] components active."""
    lambdas = np.asarray(lambdas, float)
    K = lambdas.size - 1
    coefs = np.zeros((m, K + 1))
    for i, s in enumerate(
        sizes
    ):  # make components active on interval i: non-zero at both ends' mean
        coefs[:s, i + 1] = 1.0 + i
    return LassoPath(lambdas=lambdas, coefs=coefs, n_samples=10)


def test_flat_range_rule_on_hand_made_paths():
    # sizes on (lam_{i+1}, lam_i): 1 on (6,10), 2 on (5,6), 3 on (0.5,5), 4 on (0.01,0.5), 5 on (0,0.01)
    path = _hand_path([10, 6, 5, 0.5, 0.01, 0.0], [1, 2, 3, 4, 5])
    np.testing.assert_array_equal(path.support_sizes(), [1, 2, 3, 4, 5])
    lin = flat_range(path, scale="linear")
    assert (lin.low, lin.high, lin.size) == (0.5, 5.0, 3) and lin.middle == pytest.approx(2.75)
    assert lin.width == pytest.approx(4.5)
    log = flat_range(path, scale="log")  # log widths: 0.51, 0.18, 2.30, 3.91 -> size 4
    assert (log.low, log.high, log.size) == (0.01, 0.5, 4)
    assert log.middle == pytest.approx(np.sqrt(0.005)) and log.width == pytest.approx(np.log(50))
    np.testing.assert_array_equal(log.support, [0, 1, 2, 3])
    # the window ends where the support first exceeds max_size: with max_size = 2 only sizes 1, 2
    path2 = _hand_path([10, 6, 5, 4.9, 0.01, 0.0], [1, 2, 3, 2, 2])
    assert flat_range(path2, scale="log", max_size=2).size == 1
    # a narrower window (lambda >= 0.02 * 10 = 0.2) clips the size-4 range to (0.2, 0.5): size 3 wins
    assert flat_range(path, scale="log", lambda_ratio=0.02).size == 3
    # the sparsity cap removes sizes above 3
    assert flat_range(path, scale="log", max_size=3).size == 3
    assert flat_range(path, scale="log", max_size=1).size == 1


def test_flat_range_merges_equal_sizes_and_excludes_empty_support():
    path = _hand_path([10, 8, 4, 3, 1], [1, 1, 2, 3])
    fr = flat_range(path, scale="linear")
    assert (fr.low, fr.high, fr.size) == (4.0, 10.0, 1)
    empty = LassoPath(lambdas=np.array([1.0, 0.0]), coefs=np.zeros((3, 2)), n_samples=5)
    with pytest.raises(ModelError, match="no range of lambda"):
        flat_range(empty)
    with pytest.raises(ModelError, match="scale: expected 'log' or 'linear', got 'ln'"):
        flat_range(path, scale="ln")
    with pytest.raises(ModelError, match="lambda_ratio"):
        flat_range(path, lambda_ratio=1.5)


def test_diagnose_recovers_a_clean_sparse_vector_and_least_squares_is_unbiased():
    X, y, theta = _problem(seed=3, rows=120, m=30, q=4, noise=0.05)
    d = diagnose(X, y)
    np.testing.assert_array_equal(d.support, np.flatnonzero(theta))
    np.testing.assert_allclose(d.theta_ls, theta, atol=0.05)
    # the Lasso estimate is shrunk towards zero, the LS re-estimate is not
    assert np.all(np.abs(d.theta_lasso[d.support]) < np.abs(d.theta_ls[d.support]))
    # least squares by its defining property: the residual is orthogonal to the selected columns
    # (normal equations), and the other components are exactly zero
    th = least_squares_on_support(X, y, d.support)
    off = np.setdiff1d(np.arange(30), d.support)
    assert np.all(th[off] == 0.0)
    Xs = X[:, d.support]
    np.testing.assert_allclose(Xs.T @ (y - X @ th), 0.0, atol=1e-10 * np.abs(Xs.T @ y).max())
    np.testing.assert_allclose(th[d.support], np.linalg.solve(Xs.T @ Xs, Xs.T @ y), rtol=1e-10)


def test_regression_data_stacks_rows_in_time_order():
    rng = np.random.default_rng(4)
    r = rng.standard_normal((2, 5, 3))  # batch 2, N = 5, p = 3
    S = rng.standard_normal((5, 3, 4))  # shared signature, m = 4
    reg = regression_data(r, S, start=1)
    assert reg.X.shape == (2, 12, 4) and reg.y.shape == (2, 12) and reg.n_samples == 4
    np.testing.assert_array_equal(reg.y[1, 3:6], r[1, 2])
    np.testing.assert_array_equal(reg.X[0, 3:6], S[2])
    with pytest.raises(ShapeError, match="on_residual: expected shape"):
        regression_data(r, S[:, :2])
    with pytest.raises(ModelError, match=r"start: expected an integer in \[0, 4\]"):
        regression_data(r, S, start=5)


def test_bad_inputs():
    X, y, _ = _problem()
    with pytest.raises(ShapeError, match=r"y: expected shape \(80,\)"):
        lasso_path(X, y[:-1])
    bad = X.copy()
    bad[3, 2] = np.nan
    with pytest.raises(NonFiniteError, match="X: expected finite"):
        lasso_path(bad, y)
    with pytest.raises(ModelError, match="lam: expected a finite lambda > 0"):
        lasso_cvxpy(X, y, -1.0)
    with pytest.raises(ModelError, match="n_samples: expected a positive integer"):
        lasso_path(X, y, n_samples=0)


def test_truncated_path_gives_the_same_flat_range_as_the_full_path():
    """Stopping LARS at the window's lower end (lambda_min) changes nothing inside the window."""
    from fdi_lib.montecarlo import trial_rngs, trial_seeds
    from fdi_lib.reproduce.zhang2021 import example1_regression
    from fdi_lib.systems import zhang2021_example1 as ex

    trials = ex.draw_trials(ex.example1_model(r=50.0), trial_rngs(trial_seeds(5, 12)), q=9)
    reg, _ = example1_regression(trials, r=50.0)
    for b in range(12):
        full = lasso_path(reg.X[b], reg.y[b], n_samples=reg.n_samples)
        cut = lasso_path(reg.X[b], reg.y[b], n_samples=reg.n_samples, lambda_min=1e-4)
        short = lasso_path(
            reg.X[b], reg.y[b], n_samples=reg.n_samples, lambda_min=1e-4, max_size=25
        )
        assert cut.lambdas[-1] >= 1e-4 * full.lambdas[0] * (1 - 1e-9)
        assert short.lambdas.size < full.lambdas.size and short.support_sizes().max() > 25
        np.testing.assert_allclose(
            short.coefs, full.coefs[:, : short.lambdas.size], rtol=1e-9, atol=1e-12
        )
        for scale in ("log", "linear"):
            a = flat_range(full, scale=scale)
            for c in (flat_range(cut, scale=scale), flat_range(short, scale=scale)):
                np.testing.assert_array_equal(a.support, c.support)
                assert a.low == pytest.approx(c.low, rel=1e-9) and a.high == pytest.approx(
                    c.high, rel=1e-9
                )


def _exact_path(lambdas, first_ranges):
    """Hand-made path on breakpoints ``lambdas`` (ending at 0): sizes [a, 3, 2, 4] on its 4 intervals.

    Components 0 and 2 (and 1 when ``first_ranges == 2``) are active where stated; interval 1 is
    where component 2 alone enters and leaves (values cancel at the midpoints of its neighbours).
    """
    coefs = np.zeros((6, 5))
    coefs[0] = [0, 1, 1, 1, 1]  # active on every interval
    coefs[1] = [0, 1, 1, 1, 1] if first_ranges == 2 else [0, 0, 1, 1, 1]
    coefs[2] = [0, 0, 1, -1, 1]  # active on interval 1 only
    coefs[3] = coefs[4] = [0, 0, 0, 0, 1]  # enter on interval 3
    return LassoPath(lambdas=np.asarray(lambdas, dtype=float), coefs=coefs, n_samples=10)


def test_grid_flat_range_on_a_hand_made_path_misses_a_short_range():
    """Sizes 1 on (0.9, 10), 3 on (0.8, 0.9) (short), 2 on (2e-3, 0.8), 4 below; max_size 3."""
    from fdi_lib.sparse import grid_flat_range

    path = _exact_path([10, 0.9, 0.8, 2e-3, 0.0], first_ranges=1)
    np.testing.assert_array_equal(path.support_sizes(), [1, 3, 2, 4])
    exact = flat_range(path, scale="log", max_size=3)
    assert (exact.low, exact.high, exact.size) == (2e-3, 0.8, 2)
    # 9 points, one per half decade from 10 to 1e-3: the size-3 range (0.8, 0.9) holds no point
    g = grid_flat_range(path, 9, lambda_ratio=1e-4, max_size=3)
    np.testing.assert_allclose(g.grid, np.geomspace(10, 1e-3, 9))
    np.testing.assert_array_equal(
        g.sizes, [0, 1, 1, 2, 2, 2, 2, 2, -1]
    )  # 1e-3 is past the window end
    assert (g.start, g.stop, g.size) == (3, 8, 2) and g.middle == pytest.approx(g.grid[5])
    np.testing.assert_array_equal(g.support, [0, 1])
    # a finer grid (one point per 0.01 decade) sees the short range
    fine = grid_flat_range(path, 401, lambda_ratio=1e-4, max_size=3)
    assert 3 in fine.sizes and fine.size == 2
    # when the short range separates two ranges of the same size, the coarse grid merges them
    merged = _exact_path([10, 0.9, 0.8, 2e-3, 0.0], first_ranges=2)
    np.testing.assert_array_equal(merged.support_sizes(), [2, 3, 2, 4])
    assert flat_range(merged, scale="log", max_size=3).high == pytest.approx(0.8)
    gm = grid_flat_range(merged, 9, lambda_ratio=1e-4, max_size=3)
    assert (gm.start, gm.stop, gm.size) == (1, 8, 2) and gm.middle == pytest.approx(gm.grid[4])


def test_grid_flat_range_converges_to_the_exact_rule():
    from fdi_lib.sparse import grid_flat_range

    for seed in range(6):
        X, y, _ = _problem(seed=seed, rows=60, m=30, q=5, noise=0.5)
        path = lasso_path(X, y, lambda_min=1e-4, max_size=15)
        exact = flat_range(path, scale="log")
        prev = np.inf
        for n in (2001, 20001):
            g = grid_flat_range(path, n)
            np.testing.assert_array_equal(g.support, exact.support)
            assert g.size == exact.size
            # the run's ends are within one grid step of the range's ends, its middle near sqrt(lo hi)
            step = np.log(1e4) / (n - 1)
            assert abs(np.log(g.grid[g.start] / exact.high)) <= step * (1 + 1e-9)
            assert abs(np.log(g.grid[g.stop - 1] / exact.low)) <= step * (1 + 1e-9)
            err = abs(np.log(g.middle / exact.middle))
            assert err <= step * (1 + 1e-9) and err <= prev
            prev = err


def test_grid_flat_range_bad_inputs():
    from fdi_lib.sparse import grid_flat_range

    path = _hand_path([10, 1.0, 0.9, 1e-3, 0.0], [1, 3, 2, 4])
    for bad in (2, 0, 10.0, True, "50"):
        with pytest.raises(ModelError, match="n_grid: expected an integer >= 3"):
            grid_flat_range(path, bad)
    with pytest.raises(ModelError, match=r"lambda_ratio: expected a number in \(0, 1\)"):
        grid_flat_range(path, 50, lambda_ratio=0.0)
    with pytest.raises(ModelError, match="max_size: expected a positive integer"):
        grid_flat_range(path, 50, max_size=0)
    short = LassoPath(
        lambdas=np.array([10.0, 1.0]), coefs=np.array([[0.0, 1.0], [0.0, 0.0]]), n_samples=5
    )
    with pytest.raises(ModelError, match="path: stops at lambda = 1 > lambda_ratio"):
        grid_flat_range(short, 50)
    empty = LassoPath(lambdas=np.array([1.0, 0.0]), coefs=np.zeros((3, 2)), n_samples=5)
    with pytest.raises(ModelError, match="no grid point"):
        grid_flat_range(empty, 50)


def _sklearn_path(X, y, N, lambda_min=0.0):
    """scikit-learn's LARS-Lasso (``lars_path``) on the same problem, in the normalisation of (39)."""
    from sklearn.linear_model import lars_path

    alpha_min = lambda_min * np.abs(X.T @ y).max() / X.shape[0]
    alphas, _, coefs = lars_path(X, y, method="lasso", alpha_min=alpha_min, max_iter=1000)
    return alphas * X.shape[0] / N, coefs


@pytest.mark.parametrize("seed, q, noise", [(0, 3, 0.3), (1, 8, 1.0), (2, 15, 3.0), (3, 20, 0.1)])
def test_homotopy_matches_scikit_learn_lars_path(seed, q, noise):
    """Our batched homotopy and scikit-learn's lars_path give the same breakpoints and coefficients,
    including paths with drops (components leaving the support), full and truncated."""
    from fdi_lib.sparse import lasso_paths

    problems = [_problem(seed=10 * seed + i, rows=60, m=30, q=q, noise=noise) for i in range(6)]
    X = np.stack([p[0] for p in problems])
    y = np.stack([p[1] for p in problems])
    drops = 0
    for lambda_min in (0.0, 1e-3):
        paths = lasso_paths(X, y, n_samples=20, lambda_min=lambda_min)
        for b, path in enumerate(paths):
            lam, coefs = _sklearn_path(X[b], y[b], 20, lambda_min)
            assert path.lambdas.shape == lam.shape
            np.testing.assert_allclose(path.lambdas, lam, rtol=1e-9, atol=1e-12 * lam[0])
            np.testing.assert_allclose(
                path.coefs, coefs, rtol=1e-8, atol=1e-10 * np.abs(coefs).max()
            )
            single = lasso_path(X[b], y[b], n_samples=20, lambda_min=lambda_min)  # batch of one
            # bit for bit: a problem's operations do not depend on the other problems of its batch
            np.testing.assert_array_equal(single.lambdas, path.lambdas)
            np.testing.assert_array_equal(single.coefs, path.coefs)
            drops += int(np.sum(np.diff(path.support_sizes()) < 0))
    if q >= 15:
        assert drops > 0  # the Lasso drop rule was exercised


def test_batched_paths_match_scikit_learn_on_example1_and_stop_at_max_size():
    from fdi_lib.montecarlo import trial_rngs, trial_seeds
    from fdi_lib.reproduce.zhang2021 import example1_regression
    from fdi_lib.sparse import lasso_paths
    from fdi_lib.systems import zhang2021_example1 as ex

    trials = ex.draw_trials(ex.example1_model(), trial_rngs(trial_seeds(3, 16)), q=20)
    reg, _ = example1_regression(trials)
    paths = lasso_paths(reg.X, reg.y, n_samples=reg.n_samples, lambda_min=1e-4, max_size=25)
    for b, path in enumerate(paths):
        lam, coefs = _sklearn_path(reg.X[b], reg.y[b], reg.n_samples, 1e-4)
        k = path.lambdas.size
        np.testing.assert_allclose(path.lambdas, lam[:k], rtol=1e-9)
        np.testing.assert_allclose(
            path.coefs, coefs[:, :k], rtol=1e-8, atol=1e-10 * np.abs(coefs).max()
        )
        sizes = path.support_sizes()
        # stopped at the end of the first interval with more than 25 components (or at the window's end)
        assert (sizes[-1] > 25 and sizes[:-1].max() <= 25) or path.lambdas[-1] == pytest.approx(
            lam[-1]
        )


def test_paths_of_a_strided_batch_are_those_of_its_contiguous_copy(monkeypatch):
    """Example 1's regression is a view of residual_signature's stacked realisations (problems
    not contiguous): lasso_path_batch gathers it a few problems at a time (here 3, and a tail of
    1) and gives the paths of the same problems made contiguous, bit for bit."""
    from fdi_lib import sparse
    from fdi_lib.montecarlo import trial_rngs, trial_seeds
    from fdi_lib.reproduce.zhang2021 import example1_regression
    from fdi_lib.systems import zhang2021_example1 as ex

    trials = ex.draw_trials(ex.example1_model(), trial_rngs(trial_seeds(4, 10)), q=8)
    reg, _ = example1_regression(trials)
    assert not reg.X.flags.c_contiguous
    monkeypatch.setattr(sparse, "_BLOCK_VALUES", 3 * reg.X.shape[1] * reg.X.shape[2])
    kw = dict(n_samples=reg.n_samples, lambda_min=1e-4, max_size=25)
    strided = sparse.lasso_path_batch(reg.X, reg.y, **kw)
    dense = sparse.lasso_path_batch(np.ascontiguousarray(reg.X), reg.y, **kw)
    assert strided.lambdas.tobytes() == dense.lambdas.tobytes()
    assert strided.coefs.tobytes() == dense.coefs.tobytes()


def _rule_by_loops(path, scale, lambda_ratio, top):
    """The flat-range rule written as plain loops over the breakpoints (reference)."""
    a, c = path.lambdas, path.coefs
    tol = 1e-12 * max(1.0, float(np.abs(c).max()))
    sizes = [int(np.sum(np.abs(0.5 * (c[:, i] + c[:, i + 1])) > tol)) for i in range(a.size - 1)]
    floor = lambda_ratio * a[0]
    for i, s in enumerate(sizes):
        if s > top:
            floor, sizes = max(floor, a[i]), sizes[:i]
            break
    best, i = None, 0
    while i < len(sizes):
        j = i
        while j + 1 < len(sizes) and sizes[j + 1] == sizes[i]:
            j += 1
        low, high = max(a[j + 1], floor), a[i]
        if 1 <= sizes[i] <= top and high > low:
            width = np.log(high / low) if scale == "log" else high - low
            if best is None or width > best[0]:
                best = (width, low, high, sizes[i])
        i = j + 1
    width, low, high, size = best
    mid = np.sqrt(low * high) if scale == "log" else 0.5 * (low + high)
    return low, high, size, np.flatnonzero(np.abs(path.coef(mid)) > tol)


def _grid_by_loops(path, n_grid, lambda_ratio, top):
    """The grid reading of the rule with plain loops (reference): sizes at each grid point."""
    a, c = path.lambdas, path.coefs
    tol = 1e-12 * max(1.0, float(np.abs(c).max()))
    grid = a[0] * np.geomspace(1.0, lambda_ratio, n_grid)
    grid[0] = a[0]
    act = [np.abs(0.5 * (c[:, i] + c[:, i + 1])) > tol for i in range(a.size - 1)]
    end = grid[-1]
    for i, s in enumerate(act):
        if s.sum() > top:
            end = a[i]
            break
    sizes, ints = [], []
    for g in grid:
        i = max(k for k in range(a.size) if a[k] >= g) if g < a[0] else 0
        i = min(i, len(act) - 1)
        ints.append(i)
        sizes.append(0 if g >= a[0] else (int(act[i].sum()) if g >= end else -1))
    best, start = (0, 0, 0), 0
    for k in range(1, n_grid + 1):
        if k == n_grid or sizes[k] != sizes[start]:
            if 1 <= sizes[start] <= top and k - start > best[0]:
                best = (k - start, start, k)
            start = k
    _, start, stop = best
    mid = (start + stop - 1) // 2
    return start, stop, grid[mid], np.flatnonzero(act[ints[mid]])


def test_batched_rules_match_plain_loops_on_paths_of_different_lengths():
    """flat_ranges / grid_flat_ranges on one padded batch: full paths, truncated ones, hand-made ones."""
    from fdi_lib.sparse import PathBatch, flat_ranges, grid_flat_ranges, lasso_path_batch

    problems = [
        _problem(seed=40 + i, rows=60, m=20, q=1 + i % 6, noise=0.2 + 0.3 * i) for i in range(10)
    ]
    X = np.stack([p[0] for p in problems])
    y = np.stack([p[1] for p in problems])
    full = lasso_path_batch(X, y, n_samples=30).paths()
    short = lasso_path_batch(X, y, n_samples=30, lambda_min=1e-4, max_size=10).paths()
    hand = [
        _hand_path([10, 6, 5, 0.5, 0.01, 0.0], [1, 2, 3, 4, 5], m=20),
        _hand_path([10, 8, 4, 3, 1], [1, 1, 2, 3], m=20),
    ]
    paths = full + short + hand
    assert len({p.lambdas.size for p in paths}) > 5  # really different lengths in one batch
    batch = PathBatch.of(paths)
    for scale in ("log", "linear"):
        fr = flat_ranges(batch, scale=scale, lambda_ratio=1e-3, max_size=10)
        for b, p in enumerate(paths):
            low, high, size, support = _rule_by_loops(p, scale, 1e-3, 10)
            assert (fr.low[b], fr.high[b], fr.size[b]) == (low, high, size)
            np.testing.assert_array_equal(np.flatnonzero(fr.support[b]), support)
    with pytest.raises(ModelError, match=r"paths\[21\]: stops at lambda = 1 > lambda_ratio"):
        grid_flat_ranges(batch, 60, lambda_ratio=1e-3, max_size=10)  # the last path stops at 1
    g = grid_flat_ranges(PathBatch.of(paths[:-1]), 60, lambda_ratio=1e-3, max_size=10)
    for b, p in enumerate(paths[:-1]):
        start, stop, middle, support = _grid_by_loops(p, 60, 1e-3, 10)
        assert (g.start[b], g.stop[b], g.middle[b]) == (start, stop, middle)
        np.testing.assert_array_equal(np.flatnonzero(g.support[b]), support)
    with pytest.raises(ModelError, match=r"paths\[1\]: no range of lambda"):
        flat_ranges(
            PathBatch.of(
                [
                    hand[0],
                    LassoPath(lambdas=np.array([1.0, 0.0]), coefs=np.zeros((20, 2)), n_samples=5),
                ]
            )
        )
