"""Convex polytopes in H-representation, Set(M, m) = {x : M x <= m}.

Rosa & Silvestre (2013), eq. (2). The hard, combinatorial parts are delegated to
well-kept libraries rather than written here:

* vertex enumeration (H -> V) and facet enumeration (V -> H), redundancy removal and
  Fourier-Motzkin / block elimination: ``pycddlib`` (Fukuda's cddlib, double
  description method), which handles degenerate and lower-dimensional inputs that
  qhull rejects;
* emptiness and support values on H-representations: linear programming with
  :func:`scipy.optimize.linprog` (HiGHS);
* area / volume: :class:`scipy.spatial.ConvexHull` (qhull) on the vertices.

Every operation returns a new :class:`Polytope`; nothing is modified in place.

Examples
--------
>>> import numpy as np
>>> from fdi_lib.sets import Polytope
>>> P = Polytope.box([-1, -1], [1, 1])
>>> float(P.volume())
4.0
>>> Q = P.linear_map(np.array([[2.0, 0.0], [0.0, 1.0]]))
>>> float(Q.volume())
8.0
"""

from __future__ import annotations

import functools
import itertools
import math
from dataclasses import dataclass, field
from typing import Any, Iterable, Sequence

import numpy as np

from fdi_lib.errors import (
    EmptySetError,
    ModelError,
    NonFiniteError,
    NumericalError,
    ShapeError,
    UnboundedSetError,
)
from fdi_lib.validation import array

__all__ = ["Polytope", "convex_hull", "plot_polytope", "polygon_outline", "box_corners"]

_TOL = 1e-9


def _as_2d(name: str, a: Any, ncols: int | None = None) -> np.ndarray:
    arr = array(a, name, finite=False)
    if arr.ndim != 2:
        raise ShapeError(f"{name}: expected a 2-D array, got shape {arr.shape}")
    if ncols is not None and arr.shape[1] != ncols:
        raise ShapeError(f"{name}: expected {ncols} columns, got shape {arr.shape}")
    _check_finite(name, arr)
    return arr


def _check_finite(name: str, arr: np.ndarray) -> None:
    if np.isfinite(arr).all():
        return
    bad = np.argwhere(~np.isfinite(arr))
    if bad.size:
        raise NonFiniteError(f"{name}: non-finite value at index {tuple(int(i) for i in bad[0])}")


def box_corners(generators: np.ndarray) -> np.ndarray:
    """All points ``G s`` with ``s`` in {-1, 1}^g: the corners of the zonotope ``G [-1, 1]^g``.

    Parameters
    ----------
    generators : ndarray, shape (n, g)

    Returns
    -------
    ndarray, shape (2**g, n)
    """
    G = np.asarray(generators, dtype=float)
    g = G.shape[1]
    if g == 0:
        return np.zeros((1, G.shape[0]))
    signs = np.array(list(itertools.product((-1.0, 1.0), repeat=g)))
    return signs @ G.T


def _unique_rows(key: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """The distinct rows of ``key`` (p, n) in lexicographic order, as the index of the first row
    equal to each, and for every row the position of its own among them: the ``index`` and
    ``inverse`` of ``np.unique(key, axis=0)``, without the structured copy that makes numpy's slow
    on the small arrays here (a stable sort, so the first of equal rows is the earliest)."""
    order = np.lexsort(key.T[::-1])
    first = np.ones(len(order), dtype=bool)
    first[1:] = np.any(key[order[1:]] != key[order[:-1]], axis=1)
    inverse = np.empty(len(order), dtype=np.intp)
    inverse[order] = np.cumsum(first) - 1
    return order[first], inverse


def _normalise(M: np.ndarray, m: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Unit-norm rows, exact duplicates merged (keeping the tightest offset), zero rows checked."""
    norms = np.linalg.norm(M, axis=1)
    zero = norms < 1e-14
    if np.any(m[zero] < 0):  # 0 <= m_i < 0: infeasible
        return np.array([[1.0] + [0.0] * (M.shape[1] - 1)] * 2) * np.array(
            [[1.0], [-1.0]]
        ), np.array([-1.0, -1.0])
    M, m, norms = M[~zero], m[~zero], norms[~zero]
    M, m = M / norms[:, None], m / norms
    key = np.round(M, 12)
    order = np.lexsort(np.column_stack([m, key]).T[::-1])
    key, M, m = key[order], M[order], m[order]
    first = np.ones(len(m), dtype=bool)
    first[1:] = np.any(key[1:] != key[:-1], axis=1)
    return M[first], m[first]


def _chebyshev(M: np.ndarray, m: np.ndarray, cap: float = 1e6) -> tuple[str, np.ndarray, float]:
    """Chebyshev centre of Set(M, m) (unit rows) with cddlib's small dense simplex LP.

    Returns (status, centre, radius); status is "optimal", "infeasible" or "unbounded".
    cddlib's LP is used rather than HiGHS because it has microsecond overhead on these
    tiny problems (HiGHS is the independent route used by :meth:`Polytope.is_empty`).
    Cached on the bytes of M and m (:func:`_chebyshev_of`): the SVOs of a study meet the same
    sets again (a record's nominal SVO in the detection pass, then in each bank of observers),
    and an emptied set's LP goes to HiGHS, at about a millisecond.
    """
    status, centre, radius = _chebyshev_of(M.tobytes(), m.tobytes(), M.shape[1], float(cap))
    return status, centre.copy(), radius


@functools.lru_cache(maxsize=512)
def _chebyshev_of(
    M_bytes: bytes, m_bytes: bytes, n: int, cap: float
) -> tuple[str, np.ndarray, float]:
    """:func:`_chebyshev` of M = frombuffer(M_bytes).reshape(-1, n), m = frombuffer(m_bytes) (fresh
    C-ordered arrays, as :func:`_normalise` gives them)."""
    import cdd

    M = np.frombuffer(M_bytes, dtype=float).reshape(-1, n).copy()
    m = np.frombuffer(m_bytes, dtype=float).copy()
    # variables (x, r): maximise r s.t. m - M x - r >= 0, r <= cap
    rows = np.column_stack([m, -M, -np.ones(len(m))])
    rows = np.vstack([rows, np.r_[cap, np.zeros(n), -1.0], np.r_[0.0, np.zeros(n), 1.0]])
    obj = np.r_[0.0, np.zeros(n), 1.0]
    lp = cdd.linprog_from_array(np.vstack([rows, obj]), obj_type=cdd.LPObjType.MAX)
    try:
        cdd.linprog_solve(lp)
        solved = lp.status == cdd.LPStatusType.OPTIMAL
    except (
        RuntimeError
    ):  # cddlib's float simplex can abort ("LP cycling", "numerical inconsistency")
        solved = False
    if solved:
        sol = np.array(lp.primal_solution, dtype=float)
        x, r = sol[:n], float(sol[n])
        # accept cddlib's answer only if it verifies (its float simplex can fail silently)
        if np.all(M @ x + r <= m + 1e-9 * (1.0 + np.abs(m))):
            return "optimal", x, r
    # any other outcome (claimed infeasible/unbounded, or an unverified optimum) is
    # decided by HiGHS: an empty set means an alarm, so it must not rest on a fragile solver
    from scipy.optimize import linprog

    res = linprog(
        np.r_[np.zeros(n), -1.0],
        A_ub=np.column_stack([M, np.ones(len(m))]),
        b_ub=m,
        bounds=[(None, None)] * n + [(None, cap)],
        method="highs",
    )
    if res.status == 2:
        return "infeasible", np.zeros(n), -np.inf
    if res.status == 3:
        return "unbounded", np.zeros(n), np.inf
    if res.status != 0:  # pragma: no cover
        raise RuntimeError(f"Chebyshev centre LP failed: {res.message}")
    return "optimal", res.x[:n], float(res.x[n])


def _opposite_rows_bound(M: np.ndarray, m: np.ndarray) -> float:
    """An upper bound of the Chebyshev radius of Set(M, m) (unit rows) from its exactly opposite
    rows, +inf when there are none: ``M_i = -M_j`` gives, for every x, ``min_k (m_k - M_k x) <=
    ((m_i - M_i x) + (m_j - M_j x)) / 2 = (m_i + m_j) / 2`` (the LP's dual certificate with weights
    1/2 on the pair; exact, since the rows cancel exactly in floating point).

    Rows are matched by their bytes, in one pass over the rows (a comparison of every pair took
    most of an exact SVO update on sets of thousands of rows): ``+ 0.0`` first, since ``==`` takes
    -0.0 for 0.0, and a row with a NaN matches none. The smallest offset among the rows equal to
    ``M_i`` is enough for each ``j``: ``(a + b) / 2`` rounds monotonically in ``a`` and ``b``, so the
    bound is the smallest over every pair, bit for bit.
    """
    keep = ~np.isnan(M).any(axis=1)
    rows = np.ascontiguousarray(M[keep] + 0.0)
    width = rows.shape[1] * rows.itemsize
    same, opposite = rows.tobytes(), np.ascontiguousarray(-rows + 0.0).tobytes()
    offsets = m[keep].tolist()
    least: dict[bytes, float] = {}  # row -> the smallest offset of the rows equal to it
    for i, mi in enumerate(offsets):
        key = same[i * width : (i + 1) * width]
        if key not in least or mi < least[key]:
            least[key] = mi
    best = np.inf
    for j, mj in enumerate(offsets):
        mi = least.get(opposite[j * width : (j + 1) * width])
        if mi is not None:
            best = min(best, (mi + mj) / 2.0)
    return float(best)


def _all_inside(V: np.ndarray, M: np.ndarray, m: np.ndarray, tol: float) -> bool:
    """Whether every row of V satisfies M v <= m + tol (in blocks: V and M can both be large)."""
    step = max(1, 2_000_000 // max(1, M.shape[0]))
    return all(np.all(V[i : i + step] @ M.T <= m + tol) for i in range(0, V.shape[0], step))


#: qhull options tried in turn: default, then allowing wide merges ("Q12", the remedy qhull itself
#: proposes for a "dupridge" topology error between nearly coincident vertices), then also merging
#: pinched vertices ("Q14"). Each result is verified against the inequalities.
_QHULL_RETRIES = (None, "Q12", "Q12 Q14")


#: Outward expansion of a vertex set that qhull found with wide merges ("Q12", "Q14"): such merges
#: can drop vertices, so the hull of the vertices found can miss part of the set. On the healthy UAV
#: records of issue 21 (exact rule, scaled coordinates, 11 records, 12 such sets) the largest support
#: shortfall against HiGHS in 150 random directions per set was 7.3e-8 for sets of size 1.2 to 1.9;
#: the vertices are moved away from the Chebyshev centre so that the support grows by at least
#: ``_MERGE_EXPANSION (1 + size)``, some 40 times that shortfall (size: largest |v - centre|).
_MERGE_EXPANSION = 1e-6


def _qhull_vertices(M: np.ndarray, m: np.ndarray, centre: np.ndarray, radius: float) -> np.ndarray:
    """Vertices by qhull's halfspace intersection around an interior point (the Chebyshev centre,
    ball of radius ``radius``).

    Many nearly parallel inequalities (the hull of thousands of vertex images) make qhull's
    default merging fail with a topology error. Each option of :data:`_QHULL_RETRIES` is then tried
    in the given coordinates and in coordinates centred on ``centre`` (vertex enumeration commutes
    with translations, qhull's rounding does not: on the UAV records of issue 21 the default
    failed in both and "Q12" worked in the second). A result is accepted only if every vertex
    satisfies every inequality to 1e-9 (relative). A result found with wide merges is expanded
    about ``centre`` (:data:`_MERGE_EXPANSION`) so that its hull still contains the set: a slightly
    larger set is sound for an observer, a smaller one is not. Raises the last qhull error if no
    option works.
    """
    from scipy.spatial import HalfspaceIntersection, QhullError

    err: Exception | None = None
    for opts in _QHULL_RETRIES:
        for shift in (np.zeros_like(centre), centre):
            ms = m - M @ shift  # Set(M, m) - shift
            try:
                hs = HalfspaceIntersection(
                    np.column_stack([M, -ms]), centre - shift, qhull_options=opts
                )
            except QhullError as exc:
                err = exc
                continue
            V = hs.intersections + shift
            if not _all_inside(V, M, m, 1e-9 * (1.0 + np.abs(m))):
                err = NumericalError(f"qhull ({opts}): vertices violate the inequalities")
                continue
            # merge vertices reported once per incident facet
            key = np.round(V / (1e-9 * (1.0 + np.abs(V).max())), 0)
            V = V[_unique_rows(key)[0]]
            if opts is not None:
                # conv(V) holds B(centre, radius), so (1 + s)(conv(V) - centre) holds conv(V) + s radius B
                size = np.abs(V - centre).max()
                V = centre + (V - centre) * (1.0 + _MERGE_EXPANSION * (1.0 + size) / radius)
            return V
    raise err  # type: ignore[misc]


#: Largest number of row subsets (bases) for which vertices are found by enumerating bases
#: (:func:`_basis_vertices`) rather than by qhull / cddlib.
_MAX_BASES = 2000


@dataclass(frozen=True, eq=False)
class _Bases:
    """What the vertex enumeration by bases needs for a fixed normal matrix M (cached per M)."""

    norms: np.ndarray  # (p,) row norms of M (1 for zero rows)
    zero: np.ndarray  # (p,) rows of M that are zero
    pad: np.ndarray  # (q, r) indices into [m / norms, +inf]: the rows of each distinct unit normal
    U: np.ndarray  # (q, n) distinct unit normals
    idx: np.ndarray  # (K, n) the non-singular n-subsets of U's rows
    inv: np.ndarray  # (K, n, n) inverses of U[idx[k]]
    bounded: bool  # whether Set(U, 1) is bounded (then every non-empty Set(M, m) is a polytope)


@functools.lru_cache(maxsize=64)
def _combinations(q: int, n: int) -> np.ndarray:
    """The n-subsets of range(q) in lexicographic order, shape (comb(q, n), n) (read-only)."""
    idx = np.array(list(itertools.combinations(range(q), n)), dtype=int).reshape(-1, n)
    idx.flags.writeable = False
    return idx


@functools.lru_cache(maxsize=64)
def _bases(key: bytes, p: int, n: int) -> _Bases | None:
    """Structure of Set(M, m) for M = frombuffer(key).reshape(p, n); None when there are too many bases."""
    M = np.frombuffer(key, dtype=float).reshape(p, n)
    norms = np.linalg.norm(M, axis=1)
    zero = norms < 1e-14
    norms = np.where(zero, 1.0, norms)
    unit = np.round(M / norms[:, None], 12)[~zero]
    first, group = _unique_rows(unit)
    U = unit[first]
    rows = np.flatnonzero(~zero)
    q = U.shape[0]
    if q < n or math.comb(q, n) > _MAX_BASES:
        return None
    # pad[g] = the rows with normal g, in increasing order, then p (an index for +inf)
    order = np.argsort(group, kind="stable")
    counts = np.bincount(group, minlength=q)
    pad = np.full((q, counts.max()), p)
    pad[group[order], np.arange(len(order)) - np.repeat(np.cumsum(counts) - counts, counts)] = rows[
        order
    ]
    idx = _combinations(q, n)
    sub = U[idx]
    ok = np.abs(np.linalg.det(sub)) > 1e-10
    idx, inv = idx[ok], np.linalg.inv(sub[ok])
    # bounded iff {d : U d <= 0} = {0} iff rank U = n and U^T lam = 0 for some lam > 0 (Gordan);
    # lam = 1 + mu, mu >= 0, found by non-negative least squares
    from scipy.optimize import nnls

    rhs = -U.sum(axis=0)
    _, resid = nnls(U.T, rhs)
    bounded = len(idx) > 0 and resid <= 1e-9 * (1.0 + np.linalg.norm(rhs))
    return _Bases(norms, zero, pad, U, idx, inv, bool(bounded))


def _basis_vertices(M: np.ndarray, m: np.ndarray) -> np.ndarray | None:
    """Vertices of Set(M, m) as the feasible basic solutions: x = U_S^-1 m_S for every non-singular
    n-subset S of the distinct unit rows U (rows with the same normal keep the tightest offset),
    feasible to 1e-12 (1 + max |m|), the emptiness threshold of the Chebyshev test of
    :func:`_enumerate_vertices`. Exact in exact arithmetic, vectorised, and cheap when M has few rows;
    the structure (subsets, inverses, boundedness) is cached per M, so a sequence of sets with the
    same normals (an SVO template) pays for it once. None when the route does not apply (too many
    subsets, or normals that do not bound the set).
    """
    b = _bases(M.tobytes(), M.shape[0], M.shape[1])
    if b is None or not b.bounded:
        return None
    n = M.shape[1]
    if np.any(m[b.zero] < 0):
        return np.zeros((0, n))
    mp = np.empty(len(m) + 1)
    np.divide(m, b.norms, out=mp[:-1])
    mp[-1] = np.inf
    mu = mp[b.pad].min(axis=1)
    X = (b.inv * mu[b.idx][:, None, :]).sum(axis=2)
    tol = 1e-12 * (1.0 + np.abs(mu).max())
    X = X[(X @ b.U.T <= mu + tol).all(axis=1)]
    if X.shape[0] == 0:
        return np.zeros((0, n))
    # a vertex on more than n facets is found once per basis: merge (as for qhull's output)
    key = np.round(X / (1e-9 * (1.0 + np.abs(X).max())), 0)
    order = np.lexsort(key.T)
    key, X = key[order], X[order]
    first = np.ones(len(X), dtype=bool)
    first[1:] = np.any(key[1:] != key[:-1], axis=1)
    return X[first]


#: Emptiness tolerance: Set(M, m) (rows of unit norm) is empty when the largest ball it holds has
#: a radius below ``-_EMPTY_TOL (1 + max |m|)`` (the Chebyshev LP, :func:`_chebyshev`), that is
#: when no point violates every inequality by less than that. The same tolerance as the
#: feasibility test of the basis route (:func:`_basis_vertices`).
_EMPTY_TOL = 1e-12


def _enumerate_vertices(M: np.ndarray, m: np.ndarray) -> np.ndarray:
    """Vertices of Set(M, m), shape (v, n); (0, n) if empty; raises if unbounded.

    Emptiness is decided by linear programming, never by an empty enumeration: (0, n) is returned
    only when the Chebyshev LP (:func:`_chebyshev`, cddlib verified, HiGHS when unsure) finds no
    ball of radius above ``-_EMPTY_TOL (1 + max |m|)`` (:data:`_EMPTY_TOL`), or when a dual
    certificate of that LP already proves it: two exactly opposite rows whose offsets leave twice
    that margin (:func:`_opposite_rows_bound`; an emptied SVO set usually is so, its measurement
    strip beyond the propagated set in one direction).

    Few rows (at most :data:`_MAX_BASES` n-subsets of distinct normals) and normals that bound
    the set: :func:`_basis_vertices`; when it finds no vertex, the LP decides. Otherwise rows are
    normalised and de-duplicated and the Chebyshev centre is found. A full-dimensional set goes to
    qhull's halfspace intersection (:func:`_qhull_vertices`, several options and frames), which is
    robust in floating point; cddlib's double description in floating point can silently drop
    vertices when nearly parallel inequalities are present, so it is the last resort and its
    answer is verified too. Flat sets (radius ~ 0), which qhull cannot handle, go to cddlib. When
    every enumeration fails, or finds no vertex of a set the LP found non-empty, a
    :class:`NumericalError` is raised (an exact-arithmetic retry would need cddlib's GMP build,
    which ``pycddlib-standalone`` does not ship): a failure is never reported as an empty set.
    """
    V = _basis_vertices(M, m)
    if V is not None and V.shape[0]:
        return V
    M, m = _normalise(M, m)
    n = M.shape[1]
    limit = _EMPTY_TOL * (1.0 + np.abs(m).max(initial=0.0))
    # two opposite rows with no room between them prove the radius below -limit without the LP
    # (twice -limit: the rounding of their mean, about 1e-16 max |m|, cannot cross the threshold)
    if _opposite_rows_bound(M, m) < -2.0 * limit:
        return np.zeros((0, n))
    status, centre, radius = _chebyshev(M, m)
    if status == "infeasible" or radius < -limit:
        return np.zeros((0, n))
    if status == "unbounded" or radius >= 1e6 * (1 - 1e-12):
        raise UnboundedSetError(
            "Set(M, m): the polytope is unbounded (it contains arbitrarily large balls)"
        )
    scale = 1e-9 * (1.0 + np.abs(m).max())
    if radius > scale:
        try:
            V = _qhull_vertices(M, m, centre, radius)
        except Exception:  # qhull precision failure: fall back to cddlib
            V = None
        if V is not None and _spans_ball(V, centre, radius, scale):
            return V
    try:
        V = _cdd_dd_vertices(M, m)
    except RuntimeError as exc:  # cddlib: "Numerical inconsistency is found"
        raise NumericalError(
            f"Set(M, m): vertex enumeration failed in floating point for {len(m)} "
            f"inequalities in dimension {n} (Chebyshev radius {radius:.3g}): {exc}"
        ) from None
    if not (
        V.shape[0]
        and _all_inside(V, M, m, 1e-9 * (1.0 + np.abs(m)))
        and _spans_ball(V, centre, max(radius, 0.0), scale)
    ):
        raise NumericalError(
            f"Set(M, m): the linear program finds a ball of radius {radius:.3g} in the set "
            f"({len(m)} inequalities, dimension {n}), but vertex enumeration in floating point "
            f"(qhull, cddlib) found {V.shape[0]} vertices that do not span it; the set is not "
            f"empty (no alarm), its vertices are unknown"
        )
    return V


def _spans_ball(V: np.ndarray, centre: np.ndarray, radius: float, tol: float) -> bool:
    """Whether the bounding box of V holds the ball B(centre, radius) (to ``tol``): a necessary
    condition for conv(V) to be the set in which the Chebyshev LP found that ball."""
    return bool(V.shape[0]) and bool(
        np.all(V.min(axis=0) <= centre - radius + tol)
        and np.all(V.max(axis=0) >= centre + radius - tol)
    )


def _cdd_dd_vertices(M: np.ndarray, m: np.ndarray) -> np.ndarray:
    """Vertices with cddlib's double description method (handles flat sets); raises if unbounded."""
    import cdd

    mat = cdd.matrix_from_array(np.column_stack([m, -M]), rep_type=cdd.RepType.INEQUALITY)
    poly = cdd.polyhedron_from_matrix(mat)
    gen = cdd.copy_generators(poly)
    arr = np.array(gen.array, dtype=float).reshape(-1, M.shape[1] + 1)
    if arr.shape[0] == 0:
        return np.zeros((0, M.shape[1]))
    if gen.lin_set or np.any(arr[:, 0] < 0.5):
        raise UnboundedSetError("Set(M, m): the polytope is unbounded (cddlib found rays or lines)")
    return arr[:, 1:]


def _hull_hrep(V: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """H-representation (M, m) of conv(V) (see :func:`_hull`)."""
    return _hull(V)[:2]


def _hull(V: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """H-representation (M, m) of conv(V), and the indices of the points of V that span it.

    In dimension 1 the hull is the interval between the two extreme points, computed exactly.
    Full-dimensional point sets go to qhull (:class:`scipy.spatial.ConvexHull`), retried with the
    options of :data:`_QHULL_RETRIES` on a topology error, on the points as given and then centred
    on their mean, and the spanning points are qhull's vertices; flat (lower-dimensional) sets,
    which qhull rejects, go to cddlib, whose equalities become pairs of inequalities, and keep
    every point. Every result is verified (all points inside, to 1e-9 relative); a failed
    verification raises :class:`NumericalError` rather than returning a wrong set.
    """
    from scipy.spatial import ConvexHull, QhullError

    scale = 1.0 + np.abs(V).max()
    if (
        V.shape[1] == 1
    ):  # an interval: its end points, exactly (cddlib's float answer can miss them)
        keep = np.unique([V[:, 0].argmin(), V[:, 0].argmax()])
        return np.array([[1.0], [-1.0]]), np.array([V[:, 0].max(), -V[:, 0].min()]), keep
    if V.shape[0] > V.shape[1]:
        # the points as given, then centred on their mean (a hull commutes with translations,
        # qhull's rounding does not: see _qhull_vertices)
        for shift in (np.zeros(V.shape[1]), V.mean(axis=0)):
            for opts in _QHULL_RETRIES:
                try:
                    hull = ConvexHull(V - shift, qhull_options=opts)
                except QhullError:
                    continue
                eq = hull.equations  # rows [a, b] with a (x - shift) + b <= 0 (unit normals)
                eq = eq[_unique_rows(np.round(eq, 12))[0]]
                M, m = eq[:, :-1].copy(), -eq[:, -1] + eq[:, :-1] @ shift
                if _all_inside(V, M, m, 1e-9 * scale):
                    return M, m, hull.vertices
    M, m = _cdd_hull_exact(V)
    if not _all_inside(V, M, m, 1e-9 * scale):
        raise NumericalError(
            f"conv(V): the facets found in floating point exclude some of the {len(V)} points"
        )
    return M, m, np.arange(len(V))


def _cdd_hull_exact(V: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """H-representation of conv(V) with cddlib (double description); handles flat sets."""
    import cdd

    mat = cdd.matrix_from_array(
        np.column_stack([np.ones(len(V)), V]), rep_type=cdd.RepType.GENERATOR
    )
    try:
        poly = cdd.polyhedron_from_matrix(mat)
    except RuntimeError as exc:  # cddlib: "Numerical inconsistency is found"
        raise NumericalError(
            f"conv(V): facet enumeration failed in floating point for {len(V)} points in "
            f"dimension {V.shape[1]} (flat or nearly flat set): {exc}"
        ) from None
    ineq = cdd.copy_inequalities(poly)
    arr = np.array(ineq.array, dtype=float).reshape(-1, V.shape[1] + 1)
    lin = sorted(ineq.lin_set)
    if lin:
        arr = np.vstack([arr, -arr[lin]])
    # cdd row [b, a] means b + a x >= 0, i.e. (-a) x <= b
    M, m = -arr[:, 1:], arr[:, 0]
    keep = np.linalg.norm(M, axis=1) > 1e-12
    return M[keep], m[keep]


@dataclass(frozen=True, eq=False)
class Polytope:
    r"""The convex polytope :math:`\mathrm{Set}(M, m) = \{x \in \mathbb{R}^n : M x \le m\}`
    (Rosa & Silvestre 2013, eq. (2)).

    Parameters
    ----------
    M : ndarray, shape (p, n)
        Facet normals (rows). Rows need not be normalised nor irredundant.
    m : ndarray, shape (p,)
        Offsets.

    Notes
    -----
    The object is immutable; vertices are computed lazily and cached.
    """

    M: np.ndarray
    m: np.ndarray
    _cache: dict = field(default_factory=dict, init=False, repr=False, compare=False)

    def __post_init__(self) -> None:
        M = _as_2d("M", self.M)
        m = array(self.m, "m", finite=False)
        if m.ndim != 1 or m.shape[0] != M.shape[0]:
            raise ShapeError(
                f"m: expected shape ({M.shape[0]},) to match M {M.shape}, got {m.shape}"
            )
        _check_finite("m", m)
        if M.shape[1] < 1:
            raise ShapeError(f"M: expected at least one column, got shape {M.shape}")
        object.__setattr__(self, "M", M)
        object.__setattr__(self, "m", m)

    # ------------------------------------------------------------------ constructors
    @classmethod
    def box(cls, lower: Sequence[float], upper: Sequence[float]) -> "Polytope":
        """The axis-aligned box {lower <= x <= upper}."""
        lo = np.atleast_1d(array(lower, "lower"))
        hi = np.atleast_1d(array(upper, "upper"))
        if lo.shape != hi.shape or lo.ndim != 1:
            raise ShapeError(
                f"lower, upper: expected equal 1-D shapes, got {lo.shape} and {hi.shape}"
            )
        n = lo.size
        return cls(np.vstack([np.eye(n), -np.eye(n)]), np.concatenate([hi, -lo]))

    @classmethod
    def from_vertices(cls, points: Any) -> "Polytope":
        """Convex hull of a point cloud, in H-representation (facet enumeration by cddlib).

        Parameters
        ----------
        points : ndarray, shape (q, n), q >= 1
        """
        V = _as_2d("points", points)
        if V.shape[0] == 0:
            raise EmptySetError(f"points: expected at least one point, got shape {V.shape}")
        M, m = _hull_hrep(V)
        P = cls(M, m)
        return P

    # ------------------------------------------------------------------ basic queries
    @property
    def dim(self) -> int:
        """Ambient dimension n."""
        return int(self.M.shape[1])

    @property
    def n_facets(self) -> int:
        """Number of inequalities p (after :meth:`remove_redundancy`: the facets)."""
        return int(self.M.shape[0])

    def vertices(self) -> np.ndarray:
        """Vertices, shape (v, n); (0, n) if empty. Raises :class:`UnboundedSetError` if unbounded.

        Vertex enumeration by bases for few inequalities, otherwise by qhull (cddlib for flat sets);
        see :func:`_enumerate_vertices`. Emptiness is decided by a linear program
        (:data:`_EMPTY_TOL`); an enumeration that finds no vertex of a non-empty set raises
        :class:`NumericalError`. Vertices that qhull found with wide merges are moved away from the
        Chebyshev centre (:data:`_MERGE_EXPANSION`) so that their hull contains the set.
        """
        if "V" not in self._cache:
            self._cache["V"] = _enumerate_vertices(self.M, self.m)
        return self._cache["V"]

    def is_empty(self, tol: float = _TOL) -> bool:
        r"""Emptiness by linear programming (HiGHS): maximise the slack :math:`t` with
        :math:`M_i x + t \|M_i\| \le m_i` for every row :math:`i`.

        The set is declared empty when the optimal slack is below ``-tol`` (a point violating
        no inequality by more than ``tol`` does not exist). Independent of vertex enumeration.
        """
        from scipy.optimize import linprog

        if self.n_facets == 0:
            return False
        norms = np.linalg.norm(self.M, axis=1)
        A = np.column_stack([self.M, norms])
        c = np.zeros(self.dim + 1)
        c[-1] = -1.0
        bounds = [(None, None)] * self.dim + [(None, 1.0)]
        res = linprog(c, A_ub=A, b_ub=self.m, bounds=bounds, method="highs")
        if res.status == 2:
            return True
        if res.status != 0:  # pragma: no cover - HiGHS failures are unexpected
            raise NumericalError(f"linprog failed: {res.message}")
        return bool(-res.fun < -tol)

    def contains(self, x: Any, tol: float = 1e-9) -> bool:
        """Whether ``x`` (shape (n,)) satisfies every inequality up to ``tol``."""
        x = np.asarray(x, dtype=float)
        if x.shape != (self.dim,):
            raise ShapeError(f"x: expected shape ({self.dim},), got {x.shape}")
        return bool(np.all(self.M @ x <= self.m + tol * (1.0 + np.abs(self.m))))

    def support(self, directions: Any) -> np.ndarray:
        r"""Support function :math:`h(c) = \max_{x \in P} c^\top x` for each row :math:`c` of
        ``directions`` (via vertices).

        Returns ``-inf`` for every direction when the set is empty.
        """
        D = np.atleast_2d(np.asarray(directions, dtype=float))
        if D.shape[1] != self.dim:
            raise ShapeError(f"directions: expected {self.dim} columns, got shape {D.shape}")
        V = self.vertices()
        if V.shape[0] == 0:
            return np.full(D.shape[0], -np.inf)
        return (V @ D.T).max(axis=0)

    def bounding_box(self) -> tuple[np.ndarray, np.ndarray]:
        """Smallest axis-aligned box (lower, upper), each shape (n,). Raises if empty."""
        V = self._nonempty_vertices("bounding_box")
        return V.min(axis=0), V.max(axis=0)

    def volume(self) -> float:
        """n-dimensional volume (area in 2-D, length in 1-D); 0 for empty or flat sets (qhull)."""
        V = self.vertices()
        if V.shape[0] <= self.dim:
            return 0.0
        if self.dim == 1:
            return float(V.max() - V.min())
        from scipy.spatial import ConvexHull, QhullError

        try:
            return float(ConvexHull(V).volume)
        except QhullError:  # flat (lower-dimensional) set
            return 0.0

    def _nonempty_vertices(self, what: str) -> np.ndarray:
        V = self.vertices()
        if V.shape[0] == 0:
            raise EmptySetError(f"{what}: the polytope is empty")
        return V

    # ------------------------------------------------------------------ operations
    def remove_redundancy(self) -> "Polytope":
        """Drop redundant inequalities (cddlib ``matrix_canonicalize``); empty sets are returned unchanged."""
        import cdd

        if (
            _chebyshev(*_normalise(self.M, self.m))[0] == "infeasible"
        ):  # empty (cddlib's LP, HiGHS if unsure)
            return self
        mat = cdd.matrix_from_array(
            np.column_stack([self.m, -self.M]), rep_type=cdd.RepType.INEQUALITY
        )
        cdd.matrix_canonicalize(mat)
        arr = np.array(mat.array, dtype=float).reshape(-1, self.dim + 1)
        lin = sorted(mat.lin_set)
        if lin:
            arr = np.vstack([arr, -arr[lin]])
        M, m = -arr[:, 1:], arr[:, 0]
        keep = np.linalg.norm(M, axis=1) > 1e-12
        return Polytope(M[keep], m[keep])

    def intersect(self, other: "Polytope") -> "Polytope":
        """Intersection: stack the inequalities."""
        if other.dim != self.dim:
            raise ShapeError(f"other: expected dimension {self.dim}, got {other.dim}")
        return Polytope(np.vstack([self.M, other.M]), np.concatenate([self.m, other.m]))

    def intersect_strip(self, C: Any, y: Any, bound: Any) -> "Polytope":
        """Intersection with the measurement strip {x : |y - C x| <= bound} (componentwise).

        Rosa & Silvestre (2013), eq. (3): the rows ``[C; -C] x <= [bound + y; bound - y]``.
        """
        C = _as_2d("C", C, self.dim)
        y = np.atleast_1d(np.asarray(y, dtype=float))
        b = np.broadcast_to(np.asarray(bound, dtype=float), y.shape)
        if y.shape != (C.shape[0],):
            raise ShapeError(f"y: expected shape ({C.shape[0]},), got {y.shape}")
        _check_finite("y", y)
        return Polytope(np.vstack([self.M, C, -C]), np.concatenate([self.m, b + y, b - y]))

    def translate(self, b: Any) -> "Polytope":
        """The set P + b."""
        b = np.asarray(b, dtype=float)
        if b.shape != (self.dim,):
            raise ShapeError(f"b: expected shape ({self.dim},), got {b.shape}")
        return Polytope(self.M, self.m + self.M @ b)

    def linear_map(self, A: Any) -> "Polytope":
        r"""Image :math:`\{A x : x \in P\}`.

        Invertible square ``A``: exact in H-representation, :math:`\mathrm{Set}(M A^{-1}, m)`.
        Otherwise
        (singular or rectangular ``A``, shape (r, n)): map the vertices and take their hull.
        """
        A = _as_2d("A", A, self.dim)
        if A.shape[0] == A.shape[1] and np.linalg.cond(A) < 1e10:
            return Polytope(np.linalg.solve(A.T, self.M.T).T, self.m)
        V = self._nonempty_vertices("linear_map")
        return Polytope.from_vertices(V @ A.T)

    def minkowski_box(self, L: Any, bound: Any = 1.0) -> "Polytope":
        """Minkowski sum P + L [-bound, bound]^g (L shape (n, g)): sums of vertices and box corners, then hull."""
        L = _as_2d("L", L)
        if L.shape[0] != self.dim:
            raise ShapeError(f"L: expected {self.dim} rows, got shape {L.shape}")
        G = L * np.broadcast_to(np.asarray(bound, dtype=float), (L.shape[1],))
        V = self._nonempty_vertices("minkowski_box")
        pts = (V[:, None, :] + box_corners(G)[None, :, :]).reshape(-1, self.dim)
        return Polytope.from_vertices(pts)

    def project(self, dims: Sequence[int], method: str = "fourier-motzkin") -> "Polytope":
        r"""Orthogonal projection onto the coordinates ``dims`` (eq. (3) :math:`\to \mathbb{R}^n`,
        Fig. 1).

        Parameters
        ----------
        dims : sequence of int
            Coordinates kept, in this order.
        method : {"fourier-motzkin", "vertex"}
            ``"fourier-motzkin"``: eliminate the other coordinates with cddlib's
            block elimination (dual double description, a Fourier-Motzkin variant),
            then remove redundancy. ``"vertex"``: project the vertices and take the hull.
        """
        dims = [int(d) for d in dims]
        if not dims or min(dims) < 0 or max(dims) >= self.dim or len(set(dims)) != len(dims):
            raise ShapeError(f"dims: expected distinct indices in [0, {self.dim}), got {dims}")
        if method == "vertex":
            V = self._nonempty_vertices("project")
            return Polytope.from_vertices(V[:, dims])
        if method != "fourier-motzkin":
            raise ModelError(f"method: expected 'fourier-motzkin' or 'vertex', got {method!r}")
        import cdd

        elim = [d for d in range(self.dim) if d not in dims]
        mat = cdd.matrix_from_array(
            np.column_stack([self.m, -self.M]), rep_type=cdd.RepType.INEQUALITY
        )
        if elim:
            mat = cdd.block_elimination(mat, {d + 1 for d in elim})
        kept = sorted(dims)  # cdd drops the eliminated columns and keeps the others in order
        arr = np.array(mat.array, dtype=float).reshape(-1, len(kept) + 1)
        M, m = -arr[:, [kept.index(d) + 1 for d in dims]], arr[:, 0]
        keep = np.linalg.norm(M, axis=1) > 1e-12
        if np.any(m[~keep] < -1e-9):  # 0 <= m_i violated: the set was empty
            return Polytope(
                np.vstack([np.eye(len(dims))[:1], -np.eye(len(dims))[:1]]), np.array([-1.0, -1.0])
            )
        return Polytope(M[keep], m[keep]).remove_redundancy()

    def outer_template(self, directions: Any) -> "Polytope":
        r"""Outer approximation :math:`\mathrm{Set}(D, h_P(D))` by a fixed set of directions
        (support via vertices).

        Always contains P, with at most ``len(D)`` inequalities: the complexity reduction used by
        the fast SVO update.
        """
        D = _as_2d("directions", directions, self.dim)
        return Polytope(D, self.support(D))


def convex_hull(polytopes: Iterable[Polytope]) -> Polytope:
    r""":math:`\mathrm{co}\{P_1, \dots, P_r\}` of ``polytopes``: hull of the union of their
    vertices (eq. (4) of Rosa & Silvestre 2013).

    Empty members are ignored; raises :class:`EmptySetError` if all are empty.
    """
    polys = list(polytopes)
    if not polys:
        raise EmptySetError("polytopes: expected at least one polytope, got none")
    n = polys[0].dim
    for i, P in enumerate(polys):
        if P.dim != n:
            raise ShapeError(f"polytopes[{i}]: expected dimension {n}, got {P.dim}")
    V = [P.vertices() for P in polys]
    V = [v for v in V if v.shape[0]]
    if not V:
        raise EmptySetError("polytopes: all members are empty")
    return Polytope.from_vertices(np.vstack(V))


def polygon_outline(P: Polytope) -> np.ndarray:
    """Vertices of a 2-D polytope ``P`` in counter-clockwise order, shape (v, 2) ((0, 2) if empty)."""
    if P.dim != 2:
        raise ShapeError(f"P: expected a 2-D polytope, got dimension {P.dim}")
    V = P.vertices()
    if V.shape[0] == 0:
        return V
    c = V.mean(axis=0)
    return V[np.argsort(np.arctan2(V[:, 1] - c[1], V[:, 0] - c[0]))]


def plot_polytope(P: Polytope, ax: Any, **kwargs: Any) -> Any:
    """Draw a 2-D polytope ``P`` as a filled polygon on ``ax``; returns ``ax``. Empty sets draw nothing.

    ``**kwargs`` go to matplotlib's ``fill``.
    """
    V = polygon_outline(P)
    if V.shape[0] == 0:
        return ax
    kwargs.setdefault("alpha", 0.35)
    ax.fill(V[:, 0], V[:, 1], **kwargs)
    edge = kwargs.get("color", kwargs.get("facecolor", "k"))
    ax.plot(np.r_[V[:, 0], V[0, 0]], np.r_[V[:, 1], V[0, 1]], color=edge, lw=1.0)
    return ax
