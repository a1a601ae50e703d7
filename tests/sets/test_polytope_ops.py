"""Polytope operations of fdi_lib.sets.polytope, each checked against a second route."""

from __future__ import annotations

import numpy as np
import pytest

from fdi_lib.errors import EmptySetError, NonFiniteError, ShapeError, UnboundedSetError
from fdi_lib.sets import Polytope, convex_hull
from fdi_lib.sets.polytope import _cdd_hull_exact, _cdd_dd_vertices, _hull_hrep

ANG = np.linspace(0, 2 * np.pi, 48, endpoint=False)
DIRS2 = np.column_stack([np.cos(ANG), np.sin(ANG)])


def random_polytope(rng: np.random.Generator, n: int = 2, p: int = 8) -> Polytope:
    M = rng.standard_normal((p, n))
    return Polytope(
        np.vstack([M, np.eye(n), -np.eye(n)]), np.r_[rng.uniform(0.2, 1.0, p), 3 * np.ones(2 * n)]
    )


def support_lp(P: Polytope, c: np.ndarray) -> float:
    """Support value by LP (HiGHS): independent of vertex enumeration."""
    from scipy.optimize import linprog

    res = linprog(-c, A_ub=P.M, b_ub=P.m, bounds=[(None, None)] * P.dim, method="highs")
    return -res.fun


def test_box_volume_and_vertices():
    P = Polytope.box([-1, 0, 2], [1, 3, 2.5])
    assert P.volume() == pytest.approx(2 * 3 * 0.5, rel=1e-12)
    assert P.vertices().shape == (8, 3)
    lo, hi = P.bounding_box()
    np.testing.assert_allclose(lo, [-1, 0, 2])
    np.testing.assert_allclose(hi, [1, 3, 2.5])


@pytest.mark.parametrize("seed", range(10))
def test_vertices_support_match_lp(seed):
    rng = np.random.default_rng(seed)
    P = random_polytope(rng, n=3, p=10)
    D = rng.standard_normal((20, 3))
    np.testing.assert_allclose(P.support(D), [support_lp(P, d) for d in D], atol=1e-8)
    # qhull-based enumeration against cddlib's double description
    V1 = P.vertices()
    V2 = _cdd_dd_vertices(P.M, P.m)
    np.testing.assert_allclose((V1 @ D.T).max(0), (V2 @ D.T).max(0), atol=1e-8)


@pytest.mark.parametrize("seed", range(15))
def test_emptiness_lp_agrees_with_vertex_enumeration(seed):
    rng = np.random.default_rng(100 + seed)
    P = random_polytope(rng)
    c = rng.standard_normal(2)
    cut = Polytope(c[None], np.array([rng.uniform(-4, 2)]))
    Q = P.intersect(cut)
    assert Q.is_empty() == (Q.vertices().shape[0] == 0)


def test_linear_map_invertible_vs_vertex_route():
    rng = np.random.default_rng(1)
    P = random_polytope(rng)
    A = np.array([[1.2, 0.4], [-0.3, 0.8]])
    Q = P.linear_map(A)  # H-representation route
    R = Polytope.from_vertices(P.vertices() @ A.T)  # vertex route
    np.testing.assert_allclose(Q.support(DIRS2), R.support(DIRS2), atol=1e-9)
    assert Q.volume() == pytest.approx(abs(np.linalg.det(A)) * P.volume(), rel=1e-9)


def test_linear_map_singular_and_rectangular():
    P = Polytope.box([-1, -1], [1, 1])
    Q = P.linear_map(np.array([[1.0, 1.0]]))
    np.testing.assert_allclose(np.sort(Q.vertices().ravel()), [-2, 2])
    S = P.linear_map(np.array([[1.0, 1.0], [1.0, 1.0]]))  # flat image: cddlib handles it
    assert S.volume() == 0.0
    assert S.contains(np.array([1.5, 1.5])) and not S.contains(np.array([1.0, -1.0]))


def test_minkowski_box_support_formula():
    rng = np.random.default_rng(2)
    P = random_polytope(rng)
    L = np.array([[0.3, 0.1], [0.0, 0.2]])
    Q = P.minkowski_box(L, bound=0.5)
    expected = P.support(DIRS2) + 0.5 * np.abs(DIRS2 @ L).sum(axis=1)
    np.testing.assert_allclose(Q.support(DIRS2), expected, atol=1e-9)


def test_hull_qhull_vs_cdd_and_convex_hull():
    rng = np.random.default_rng(3)
    pts = rng.standard_normal((40, 3))
    M1, m1 = _hull_hrep(pts)
    M2, m2 = _cdd_hull_exact(pts)
    D = rng.standard_normal((30, 3))
    np.testing.assert_allclose(Polytope(M1, m1).support(D), Polytope(M2, m2).support(D), atol=1e-9)
    A = Polytope.box([0, 0], [1, 1])
    B = A.translate(np.array([2.0, 0.5]))
    H = convex_hull([A, B])
    assert H.contains(np.array([1.5, 0.75]))
    np.testing.assert_allclose(
        H.support(DIRS2), np.maximum(A.support(DIRS2), B.support(DIRS2)), atol=1e-9
    )


@pytest.mark.parametrize("seed", range(5))
def test_projection_fourier_motzkin_vs_vertices(seed):
    rng = np.random.default_rng(10 + seed)
    P = random_polytope(rng, n=4, p=12)
    F = P.project([2, 0], method="fourier-motzkin")
    V = P.project([2, 0], method="vertex")
    np.testing.assert_allclose(F.support(DIRS2), V.support(DIRS2), atol=1e-8)


def test_redundancy_removal_keeps_the_set():
    P = Polytope.box([-1, -1], [1, 1])
    Q = P.intersect(Polytope(np.array([[1.0, 1.0], [1.0, 0.0]]), np.array([5.0, 3.0])))
    R = Q.remove_redundancy()
    assert R.n_facets == 4
    np.testing.assert_allclose(R.support(DIRS2), Q.support(DIRS2), atol=1e-12)


def test_outer_template_contains():
    rng = np.random.default_rng(4)
    P = random_polytope(rng)
    T = P.outer_template(np.vstack([np.eye(2), -np.eye(2)]))
    assert all(T.contains(v, 1e-9) for v in P.vertices())


def test_strip_intersection():
    P = Polytope.box([-1, -1], [1, 1]).intersect_strip(np.array([[1.0, 0.0]]), [0.5], 0.1)
    lo, hi = P.bounding_box()
    np.testing.assert_allclose([lo[0], hi[0]], [0.4, 0.6])


def test_bad_inputs_have_clear_messages():
    with pytest.raises(NonFiniteError, match=r"M: non-finite value at index \(1, 0\)"):
        Polytope(np.array([[1.0, 0.0], [np.nan, 1.0]]), np.ones(2))
    with pytest.raises(ShapeError, match=r"m: expected shape \(2,\)"):
        Polytope(np.eye(2), np.ones(3))
    with pytest.raises(ShapeError, match="M: expected a 2-D array"):
        Polytope(np.ones(3), np.ones(3))
    with pytest.raises(UnboundedSetError, match="unbounded"):
        Polytope(np.array([[1.0, 0.0]]), np.array([1.0])).vertices()
    with pytest.raises(EmptySetError, match="polytopes"):
        convex_hull([])
    empty = Polytope(np.array([[1.0], [-1.0]]), np.array([-1.0, -1.0]))
    with pytest.raises(EmptySetError, match="bounding_box: the polytope is empty"):
        empty.bounding_box()
    with pytest.raises(ShapeError, match=r"dims: expected distinct indices"):
        Polytope.box([0, 0], [1, 1]).project([0, 0])
    with pytest.raises(ShapeError, match=r"x: expected shape \(2,\)"):
        Polytope.box([0, 0], [1, 1]).contains(np.zeros(3))


def test_chebyshev_falls_back_to_highs_when_cddlib_aborts(monkeypatch):
    """cddlib's float simplex can raise ("LP cycling"); the centre must then come from HiGHS."""
    import cdd

    from fdi_lib.sets import polytope as poly

    def boom(lp):
        raise RuntimeError("*Error: Possibly an LP cycling occurs.")

    monkeypatch.setattr(cdd, "linprog_solve", boom)
    M = np.vstack([np.eye(2), -np.eye(2)])
    # an answer cached before would not reach the patched cddlib, nor HiGHS's stay for the others
    poly._chebyshev_of.cache_clear()
    try:
        status, centre, radius = poly._chebyshev(M, np.array([1.0, 2.0, 1.0, 0.0]))
    finally:
        poly._chebyshev_of.cache_clear()
    assert status == "optimal" and radius == pytest.approx(1.0)
    assert Polytope.box([-1, 0], [1, 2]).vertices().shape == (4, 2)


def test_chebyshev_cache_is_a_fresh_solve_and_cannot_be_changed():
    """_chebyshev's answers, cached on the bytes of (M, m): those of a fresh solve bit for bit
    (a set and an empty one), for arrays of other layouts with the same values too, and a caller
    changing the centre it got changes no later answer."""
    from fdi_lib.sets import polytope as poly

    M = np.vstack([np.eye(2), -np.eye(2), [[0.6, 0.8]]])
    for m in (np.array([1.0, 2.0, 1.0, 0.0, 1.5]), np.array([0.5, 0.5, -0.6, -0.5, 1.0])):
        fresh = poly._chebyshev_of.__wrapped__(M.tobytes(), m.tobytes(), 2, 1e6)
        first = poly._chebyshev(M, m)
        first[1][:] = 7.0
        again = poly._chebyshev(np.asfortranarray(M), m.copy())
        assert again[0] == fresh[0] and again[2] == fresh[2]
        assert again[1].tobytes() == fresh[1].tobytes()
    assert fresh[2] < 0  # the second set is empty: no ball fits


def test_cdd_hull_failure_is_a_numerical_error(monkeypatch):
    import cdd

    from fdi_lib.errors import NumericalError

    def boom(mat):
        raise RuntimeError("*Error: Numerical inconsistency is found.")

    monkeypatch.setattr(cdd, "polyhedron_from_matrix", boom)
    with pytest.raises(NumericalError, match="facet enumeration failed"):
        _cdd_hull_exact(np.array([[0.0, 0.0], [1.0, 0.0], [2.0, 0.0]]))
