"""Vertex enumeration by bases (the fast route for few inequalities) against qhull / cddlib.

The reference is the general route of :func:`fdi_lib.sets.polytope._enumerate_vertices`, reached by
setting ``_MAX_BASES = 0`` (no H-representation qualifies for bases). Both are compared as point
sets, and the template SVO is run on the UAV on fixed seeds with each route: the sets (bounding
boxes, vertex counts) and the first empty sample must agree.
"""

import numpy as np
import pytest

from fdi_lib.errors import UnboundedSetError
from fdi_lib.reproduce import rosa2013
from fdi_lib.sets import polytope
from fdi_lib.sets.polytope import Polytope, _basis_vertices, _enumerate_vertices
from fdi_lib.sets.svo import run_svo
from fdi_lib.systems import eclipse_uav as uav


@pytest.fixture
def general_route(monkeypatch):
    """Switch the basis route off (qhull / cddlib only) for the duration of a test."""
    monkeypatch.setattr(polytope, "_MAX_BASES", 0)
    polytope._bases.cache_clear()
    yield
    polytope._bases.cache_clear()


def _same_points(A, B, tol=1e-9):
    assert A.shape == B.shape
    if A.shape[0] == 0:
        return
    d = np.abs(A[:, None, :] - B[None, :, :]).max(axis=2)
    assert d.min(axis=1).max() <= tol and d.min(axis=0).max() <= tol


def _cases(rng):
    """Random polytopes: boxes cut by random planes, duplicated / scaled rows, zero rows, empty,
    flat (a box of zero width in one coordinate), degenerate (a plane through a corner)."""
    out = []
    for _ in range(40):
        n = int(rng.integers(2, 5))
        lo, hi = -rng.uniform(0.5, 2, n), rng.uniform(0.5, 2, n)
        P = Polytope.box(lo, hi)
        cut = rng.normal(size=(int(rng.integers(0, 4)), n))
        M = np.vstack([P.M, cut, 3.0 * P.M[:1]])
        m = np.concatenate([P.m, rng.uniform(-0.5, 1.0, len(cut)), 3.0 * P.m[:1] + 0.1])
        out.append((M, m))
    box = Polytope.box([-1, -1, -1], [1, 1, 1])
    out.append((np.vstack([box.M, np.zeros((1, 3))]), np.r_[box.m, 1.0]))  # zero row, 0 <= 1
    out.append((np.vstack([box.M, np.zeros((1, 3))]), np.r_[box.m, -1.0]))  # zero row, 0 <= -1
    out.append((np.vstack([box.M, [[1.0, 1.0, 1.0]]]), np.r_[box.m, -4.0]))  # empty
    out.append((np.vstack([box.M, [[1.0, 1.0, 1.0]]]), np.r_[box.m, -3.0]))  # one corner left
    out.append((np.vstack([box.M, [[1.0, 1.0, 0.0]]]), np.r_[box.m, 0.0]))  # plane through an edge
    flat = Polytope.box([-1, 0.5, -1], [1, 0.5, 1])
    out.append((flat.M, flat.m))
    return out


def test_bases_equal_general_route(general_route):
    rng = np.random.default_rng(14)
    cases = _cases(rng)
    polytope._bases.cache_clear()
    reference = [_enumerate_vertices(M, m) for M, m in cases]
    polytope._MAX_BASES = 2000
    polytope._bases.cache_clear()
    for (M, m), ref in zip(cases, reference):
        V = _basis_vertices(M, m)
        assert V is not None
        _same_points(V, ref)


def test_bases_decline_unbounded_and_large():
    strip = (np.array([[1.0, 0.0], [-1.0, 0.0]]), np.array([1.0, 1.0]))  # no vertex, unbounded
    assert _basis_vertices(*strip) is None
    with pytest.raises(UnboundedSetError):
        Polytope(*strip).vertices()
    cone = (np.array([[-1.0, 0.0], [0.0, -1.0], [1.0, -1.0]]), np.zeros(3))  # a vertex, unbounded
    assert _basis_vertices(*cone) is None
    ang = np.linspace(0, 2 * np.pi, 200, endpoint=False)
    disc = np.column_stack([np.cos(ang), np.sin(ang), np.zeros(200), np.zeros(200)])
    M = np.vstack([disc, np.eye(4)[2:], -np.eye(4)[2:]])
    assert _basis_vertices(M, np.ones(len(M))) is None  # too many bases


def _uav_runs():
    out = []
    for fault, scenario, seed in (
        ("none", "step", 3),
        ("alpha", "step", 4),
        ("alpha", "soft", 5),
        ("elevator", "step", 6),
    ):
        run = uav.simulate(fault, scenario, rng=np.random.default_rng(seed), duration=2.0)
        for kind in ("nominal", fault if fault != "none" else "dynamics"):
            res = run_svo(uav.svo_models(run, kind), run.u, run.y, rosa2013.UAV_X0)
            out.append((res.empty_at, res.lower, res.upper, res.n_vertices))
    return out


def test_uav_template_svo_same_with_either_route(monkeypatch):
    fast = _uav_runs()
    monkeypatch.setattr(polytope, "_MAX_BASES", 0)
    polytope._bases.cache_clear()
    try:
        slow = _uav_runs()
    finally:
        polytope._bases.cache_clear()
    assert any(f[0] is not None for f in fast)  # some alarm is compared, not only silence
    for (ea, lo_a, hi_a, nv_a), (eb, lo_b, hi_b, nv_b) in zip(fast, slow):
        assert ea == eb
        np.testing.assert_array_equal(np.isnan(lo_a), np.isnan(lo_b))
        ok = ~np.isnan(lo_a)
        scale = 1.0 + np.abs(hi_b[ok])
        assert np.all(np.abs(lo_a[ok] - lo_b[ok]) <= 1e-9 * scale)
        assert np.all(np.abs(hi_a[ok] - hi_b[ok]) <= 1e-9 * scale)
        np.testing.assert_array_equal(nv_a, nv_b)


def test_boundedness_matches_lp():
    """The cached boundedness flag (Gordan / NNLS) against HiGHS: Set(U, 1) is bounded iff every
    coordinate is bounded above and below on it."""
    from scipy.optimize import linprog

    rng = np.random.default_rng(7)
    seen = set()
    for _ in range(60):
        n = int(rng.integers(2, 4))
        q = int(rng.integers(n, n + 4))
        U = rng.normal(size=(q, n))
        if rng.random() < 0.5:
            U[:, 0] = np.abs(U[:, 0])  # all normals in a half-space: unbounded
        U /= np.linalg.norm(U, axis=1, keepdims=True)
        b = polytope._bases(U.tobytes(), q, n)
        lp = all(
            linprog(
                s * np.eye(n)[i], A_ub=U, b_ub=np.ones(q), bounds=[(None, None)] * n, method="highs"
            ).status
            == 0
            for i in range(n)
            for s in (1, -1)
        )
        assert b.bounded == lp
        seen.add(lp)
    assert seen == {True, False}


def test_unique_rows_is_numpys_unique_along_rows():
    """_unique_rows (the hulls' and the bases' merging of rows) gives the index and inverse of
    np.unique(key, axis=0), and its rows bit for bit (the sign of a zero too), on random keys with
    repeated rows, near-zero and signed-zero entries, and no rows."""
    from fdi_lib.sets.polytope import _unique_rows

    rng = np.random.default_rng(11)
    for _ in range(300):
        p, n = int(rng.integers(0, 30)), int(rng.integers(1, 5))
        key = np.round(rng.normal(size=(p, n)) * rng.choice([1.0, 1e-13, 0.0]), 1)
        if p > 3:
            key[rng.integers(0, p, 3)] = key[rng.integers(0, p, 3)]
        key[key == 0] *= rng.choice([1.0, -1.0], size=int((key == 0).sum()))
        rows, index, inverse = np.unique(key, axis=0, return_index=True, return_inverse=True)
        first, inv = _unique_rows(key)
        assert np.array_equal(first, index) and np.array_equal(inv, inverse.reshape(-1))
        assert key[first].tobytes() == rows.tobytes()
