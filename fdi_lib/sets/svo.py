r"""Set-valued observers (SVOs) for uncertain LPV systems, and FDI by model invalidation.

Rosa & Silvestre (2013), §2-§4. The model (eq. (1)) is

.. math::

    x(k+1) &= \Big(A(k) + \sum_i \Delta_i(k) A_i(k)\Big) x(k) + L(k) d(k) \\
           &\quad + \Big(B(k) + \sum_b \Delta_b(k) B_b(k)\Big) u(k), \\
    y(k) &= \Big(C(k) + \sum_c \Delta_c(k) C_c(k)\Big) x(k) + n(k),

with :math:`|\Delta| \le 1`, :math:`\|d(k)\|_\infty \le 1` and :math:`|n_i(k)| \le \bar n_i`.
An SVO returns a convex polytope :math:`\hat X(k)` that contains every state compatible with the
model and the data (Proposition 2); an empty :math:`\hat X(k)` proves that the data cannot come
from the model, i.e. a fault (Proposition 3). No threshold is involved.

Two update rules are offered (``method``):

``"exact"``
    The paper's construction: for every vertex v of the uncertainty cube (eq. (4)) the
    set :math:`\hat X_v(k+1)` of states compatible with (3) is computed exactly (images of
    vertices, Minkowski sum with the disturbance zonotope, facet and vertex enumeration by
    cddlib, intersection with the measurement strip), and
    :math:`\hat X(k+1) = \mathrm{co}\{\hat X_v(k+1)\}`. Complexity
    grows with time: on the 4-state UAV model (run with ``scale``) the sets reach hundreds of
    vertices after two steps; used for the 2-D figures and the comparisons of the book. With
    :math:`N > 1` the hull over the :math:`2^{N n_A}` vertex sequences is built recursively, one one-step hull
    per horizon level and update (hulls commute with linear maps and Minkowski sums).
``"template"``
    A fixed-complexity outer approximation of the same set: the support function of each
    :math:`\hat X_v` in a fixed set of directions :math:`D` (template) is computed in closed form
    from the vertices of the previous sets, so :math:`\hat X(k+1) = \mathrm{Set}([D; C; -C],
    [\max_v h_v; y + \bar n; \bar n - y])` always has :math:`|D| + 2 n_y` inequalities. It contains the exact set, so Propositions 2 and 3
    still hold; only conservatism is added. Used for the UAV (fast, bounded complexity).
    With N > 1 each row of the horizon is projected on its own and the results intersected
    (disturbances not shared between rows); ``joint=True`` solves the stacked form of eq. (3)
    with shared disturbances by linear programming (tighter, slower).

Soundness. With the default options both rules contain every state compatible with the model
and the data (Proposition 2), so an empty set proves a fault (Proposition 3); emptiness is decided
by a linear program with a stated tolerance (:data:`fdi_lib.sets.polytope._EMPTY_TOL`), never by
an empty vertex enumeration, and an enumeration that contradicts it raises
:class:`~fdi_lib.errors.NumericalError` rather than an alarm. Two options trade this guarantee for
tightness and **can lose the true state when A is uncertain** (``A_unc`` given): ``joint=True``
with N > 1 (template rule) and ``strip_before_hull=True`` (exact rule, the paper's literal order
of Fig. 2). With either, a healthy record can empty the set (a false alarm); both issue an
:class:`~fdi_lib.errors.UnsoundOptionWarning` at the first update with an uncertain A, and the
book measures how often they fail (:func:`fdi_lib.reproduce.rosa2013_studies.horizon_comparison`).

Many records at once: :class:`TemplateBatch` steps many template observers (N = 1) together on
stacked arrays (:class:`ModelSequence`), with :func:`run_svo_many` and
:func:`run_architecture_i_many` on top; each observer's result is the one it gets alone.

B uncertainty is folded into the disturbance as in the paper (:math:`L_d(k) = B_b(k) u(k)`).
C uncertainty is handled by the relaxation idea of eq. (11) applied directly to the output:
the bilinear term :math:`\Delta_c C_c x` is replaced by an extra bounded noise whose bound is the
largest :math:`|C_c x|` over the predicted set (see :func:`SVOModel` and the book chapter, which
explains why this differs from the augmented system (9)-(10)).
"""

from __future__ import annotations

import functools
import itertools
import time
from dataclasses import dataclass, field
from typing import Any, Callable, Mapping, Sequence

import numba
import numpy as np

import warnings

from fdi_lib.errors import (
    EmptySetError,
    ModelError,
    NonFiniteError,
    NumericalError,
    ShapeError,
    UnboundedSetError,
    UnsoundOptionWarning,
)
from fdi_lib.validation import integer, real
from fdi_lib.sets.polytope import (
    Polytope,
    _bases,
    _enumerate_vertices,
    _hull,
    _hull_hrep,
    box_corners,
)
from fdi_lib.threads import single_threaded_blas

__all__ = [
    "SVOModel",
    "SetValuedObserver",
    "SVORun",
    "run_svo",
    "FDIResult",
    "run_architecture_i",
    "run_architecture_ii",
    "default_template",
    "actuator_effectiveness_model",
    "sensor_bias_model",
    "dynamics_entry_model",
    "ModelSequence",
    "TemplateBatch",
    "SVOBatchRun",
    "run_svo_many",
    "run_architecture_i_many",
    "ROUNDOFF_MARGIN",
]


#: Default relative outward inflation of every computed support (the ``margin`` of
#: :class:`SetValuedObserver` and :class:`TemplateBatch`): the round-off guard that keeps
#: Proposition 2 valid in floating point.
ROUNDOFF_MARGIN = 1e-9


def _arr(name: str, a: Any, ndim: int) -> np.ndarray:
    x = np.asarray(a, dtype=float)
    if x.ndim != ndim:
        raise ShapeError(f"{name}: expected a {ndim}-D array, got shape {x.shape}")
    if not np.isfinite(x).all():
        bad = np.argwhere(~np.isfinite(x))
        raise NonFiniteError(f"{name}: non-finite value at index {tuple(int(i) for i in bad[0])}")
    return x


@functools.lru_cache(maxsize=16)
def _cube_vertices(n_A: int) -> np.ndarray:
    """The 2**n_A vertices of the cube {|Delta| <= 1} (eq. (4)), shape (2**n_A, n_A)."""
    v = np.array(list(itertools.product((-1.0, 1.0), repeat=n_A)), dtype=float).reshape(2**n_A, n_A)
    v.flags.writeable = False
    return v


def _vertex_matrices(A: np.ndarray, A_unc: np.ndarray) -> np.ndarray:
    """A + sum_i v_i A_i for every vertex v of the cube (eq. (4)): shape (..., 2**n_A, n, n) for A of
    shape (..., n, n) and A_unc of shape (..., n_A, n, n). The signs are +-1, so each entry is one
    sum of exact terms, the same whatever the leading (batch) dimensions."""
    signs = _cube_vertices(A_unc.shape[-3])
    acc = np.zeros(A.shape[:-2] + (signs.shape[0],) + A.shape[-2:])
    for i in range(signs.shape[1]):  # the uncertain part first, then A (as the paper's sum)
        acc = acc + signs[:, i, None, None] * A_unc[..., i : i + 1, :, :]
    return A[..., None, :, :] + acc


@dataclass(frozen=True, eq=False)
class SVOModel:
    r"""One step of the uncertain model (1) of Rosa & Silvestre (2013).

    Parameters
    ----------
    A : ndarray, shape (n, n)
        Known part :math:`A(k)`.
    B : ndarray, shape (n, n_u), optional
        Known input matrix (default: no input).
    C : ndarray, shape (n_y, n)
        Known output matrix.
    L : ndarray, shape (n, n_d), optional
        Disturbance directions; :math:`\|d(k)\|_\infty \le 1` (scale ``L`` to set the bounds).
    noise : float or ndarray, shape (n_y,)
        Sensor noise bounds :math:`\bar n_i`, :math:`|n_i(k)| \le \bar n_i` (a vector generalises
        the paper's scalar).
    A_unc : ndarray, shape (n_A, n, n), optional
        Directions :math:`A_i` of the parametric uncertainty :math:`\sum_i \Delta_i A_i`,
        :math:`|\Delta_i| \le 1`.
    B_unc : ndarray, shape (n_B, n, n_u), optional
        Directions :math:`B_b` of the input uncertainty; handled as disturbance
        :math:`L = B_b u(k)` (§2).
    C_unc : ndarray, shape (n_C, n_y, n), optional
        Directions :math:`C_c` of the output uncertainty (eq. (8)).
    """

    A: Any
    C: Any
    B: Any = None
    L: Any = None
    noise: Any = 0.0
    A_unc: Any = None
    B_unc: Any = None
    C_unc: Any = None
    _vertex_A: np.ndarray = field(init=False, repr=False)

    def __post_init__(self) -> None:
        A = _arr("A", self.A, 2)
        n = A.shape[0]
        if A.shape != (n, n):
            raise ShapeError(f"A: expected a square matrix, got shape {A.shape}")
        C = _arr("C", self.C, 2)
        if C.shape[1] != n:
            raise ShapeError(f"C: expected {n} columns (n = A.shape[0]), got shape {C.shape}")
        ny = C.shape[0]
        B = np.zeros((n, 0)) if self.B is None else _arr("B", self.B, 2)
        if B.shape[0] != n:
            raise ShapeError(f"B: expected {n} rows, got shape {B.shape}")
        L = np.zeros((n, 0)) if self.L is None else _arr("L", self.L, 2)
        if L.shape[0] != n:
            raise ShapeError(f"L: expected {n} rows, got shape {L.shape}")
        noise = (
            np.broadcast_to(_arr("noise", np.atleast_1d(self.noise), 1), (ny,)).copy()
            if np.size(self.noise) in (1, ny)
            else None
        )
        if noise is None:
            raise ShapeError(
                f"noise: expected a scalar or shape ({ny},), got shape {np.shape(self.noise)}"
            )
        if np.any(noise < 0):
            raise ModelError(f"noise: expected non-negative bounds, got {noise}")
        Au = np.zeros((0, n, n)) if self.A_unc is None else _arr("A_unc", self.A_unc, 3)
        if Au.shape[1:] != (n, n):
            raise ShapeError(f"A_unc: expected shape (n_A, {n}, {n}), got {Au.shape}")
        Bu = np.zeros((0, n, B.shape[1])) if self.B_unc is None else _arr("B_unc", self.B_unc, 3)
        if Bu.shape[1:] != B.shape:
            raise ShapeError(f"B_unc: expected shape (n_B, {n}, {B.shape[1]}), got {Bu.shape}")
        Cu = np.zeros((0, ny, n)) if self.C_unc is None else _arr("C_unc", self.C_unc, 3)
        if Cu.shape[1:] != (ny, n):
            raise ShapeError(f"C_unc: expected shape (n_C, {ny}, {n}), got {Cu.shape}")
        for name, val in [
            ("A", A),
            ("C", C),
            ("B", B),
            ("L", L),
            ("noise", noise),
            ("A_unc", Au),
            ("B_unc", Bu),
            ("C_unc", Cu),
        ]:
            object.__setattr__(self, name, val)
        object.__setattr__(self, "_vertex_A", _vertex_matrices(A, Au))

    @classmethod
    def _checked_parts(
        cls,
        A: np.ndarray,
        C: np.ndarray,
        B: np.ndarray,
        L: np.ndarray,
        noise: np.ndarray,
        A_unc: np.ndarray,
        B_unc: np.ndarray,
        vertex_A: np.ndarray,
    ) -> "SVOModel":
        """A model from parts that :class:`ModelSequence` has already checked (no second check)."""
        model = object.__new__(cls)
        for name, val in (
            ("A", A),
            ("C", C),
            ("B", B),
            ("L", L),
            ("noise", noise),
            ("A_unc", A_unc),
            ("B_unc", B_unc),
            ("C_unc", np.zeros((0,) + C.shape)),
            ("_vertex_A", vertex_A),
        ):
            object.__setattr__(model, name, val)
        return model

    @property
    def n(self) -> int:
        return int(self.A.shape[0])

    @property
    def n_y(self) -> int:
        return int(self.C.shape[0])

    @property
    def n_u(self) -> int:
        return int(self.B.shape[1])

    def vertex_matrices(self) -> np.ndarray:
        r""":math:`A(k) + \sum_i v_i A_i(k)` for every vertex :math:`v` of the cube
        :math:`\{|\Delta| \le 1\}`, shape ``(2**n_A, n, n)`` (eq. (4))."""
        return self._vertex_A

    def generators(self, u: np.ndarray) -> np.ndarray:
        r"""Columns :math:`G` with :math:`L d + \sum_b \Delta_b B_b u = G s`,
        :math:`\|s\|_\infty \le 1` (B uncertainty as disturbance, §2)."""
        if self.B_unc.shape[0] == 0:
            return self.L
        return np.column_stack([self.L, np.einsum("bij,j->ib", self.B_unc, u)])


def default_template(n: int, C: np.ndarray | None = None) -> np.ndarray:
    r"""Template directions in dimension ``n``: :math:`\pm e_i`, plus :math:`\pm` the normalised
    rows of ``C`` not parallel to those, shape (p, n)."""
    C = None if C is None else np.asarray(C, dtype=float)
    return _default_template(
        int(n), None if C is None else C.tobytes(), None if C is None else C.shape
    ).copy()


@functools.lru_cache(maxsize=64)
def _default_template(n: int, key: bytes | None, shape: tuple | None) -> np.ndarray:
    rows = list(np.eye(n))
    if key is not None:
        for c in np.frombuffer(key, dtype=float).reshape(shape):
            c = c / np.linalg.norm(c)
            if all(abs(abs(c @ r) - 1.0) > 1e-6 for r in rows):
                rows.append(c)
    D = np.array(rows)
    return np.vstack([D, -D])


@dataclass
class _Entry:
    X: Polytope
    V: np.ndarray
    model: SVOModel | None = None
    u: np.ndarray | None = None
    P: np.ndarray | None = None  # "exact" rule: points spanning X's propagation to the latest step


def _lp_maxima(
    D: np.ndarray,
    A_ub: np.ndarray,
    b_ub: np.ndarray,
    A_eq: np.ndarray,
    b_eq: np.ndarray,
    bounds: list,
) -> np.ndarray:
    """max d . x[:n] over {A_ub x <= b_ub, A_eq x = b_eq, bounds} for every row d of ``D`` (HiGHS).

    One HiGHS model for all the directions: only the objective changes between them, so each
    solve starts from the previous optimal basis (``scipy.optimize.linprog`` would set the
    problem up again every time, at several times the cost of the solve). ``-inf`` everywhere when
    the set is empty.
    """
    import highspy

    nv, inf = A_ub.shape[1], highspy.kHighsInf
    A = np.vstack([A_ub, A_eq])
    lp = highspy.HighsLp()
    lp.num_col_, lp.num_row_ = nv, A.shape[0]
    lp.col_cost_ = np.zeros(nv)
    lp.col_lower_ = np.array([-inf if lo is None else lo for lo, _ in bounds], dtype=float)
    lp.col_upper_ = np.array([inf if hi is None else hi for _, hi in bounds], dtype=float)
    lp.row_lower_ = np.concatenate([np.full(len(b_ub), -inf), b_eq])
    lp.row_upper_ = np.concatenate([b_ub, b_eq])
    rows, cols = np.nonzero(A)
    lp.a_matrix_.format_ = highspy.MatrixFormat.kRowwise
    lp.a_matrix_.start_ = np.searchsorted(rows, np.arange(A.shape[0] + 1)).astype(np.int32)
    lp.a_matrix_.index_ = cols.astype(np.int32)
    lp.a_matrix_.value_ = A[rows, cols]
    solver = highspy.Highs()
    solver.setOptionValue("output_flag", False)
    solver.passModel(lp)
    out = np.full(D.shape[0], -np.inf)
    idx = np.arange(D.shape[1], dtype=np.int32)
    for i, d in enumerate(D):
        solver.changeColsCost(len(idx), idx, -d)
        solver.run()
        status = solver.getModelStatus()
        if status == highspy.HighsModelStatus.kInfeasible:
            return out  # this vertex sequence explains nothing: no contribution to the hull
        if status != highspy.HighsModelStatus.kOptimal:
            raise NumericalError(
                f"joint horizon: the support LP failed ({solver.modelStatusToString(status)})"
            )
        out[i] = -solver.getInfo().objective_function_value
    return out


class SetValuedObserver:
    r"""Recursive SVO of Rosa & Silvestre (2013), §2, with horizon N (eq. (3)).

    Parameters
    ----------
    X0 : Polytope
        Prior set of :math:`x(0)`, :math:`\mathrm{Set}(M_0, m_0)`; must be non-empty and bounded.
    N : int
        Horizon: :math:`\hat X(k+1)` uses :math:`\hat X(k), \dots, \hat X(k-N+1)` (Remark 1).
    method : {"template", "exact"}
        Update rule (see module docstring).
    template : ndarray, shape (p, n), optional
        Template directions of the ``"template"`` method (default :func:`default_template`).
    margin : float
        Relative outward inflation of the computed supports (round-off guard, keeps Prop. 2
        valid under floating point).
    scale : ndarray, shape (n,), optional
        Positive state scaling s: the observer works internally in z = x / s (every matrix
        transformed, sets mapped back on output). Sets in which some coordinates are known 10^3
        times better than others (the UAV: pitch to 1e-4 rad, speeds to 0.1 m/s) are nearly flat
        for a floating-point hull; scaling each coordinate by its typical width makes them round.
        The sets are the same up to rounding; default: no scaling.
    joint : bool
        ``"template"`` method with N > 1 only. False (default, fast): each row j of eq. (3) is
        projected on its own and the results are intersected, so the disturbances d(k), d(k-1), ...
        may take different values in different rows. True: the rows are stacked with shared
        disturbances as in eq. (3) and the support of the joint set is found by one linear program
        per direction and Delta-vertex sequence (HiGHS); tighter, and much slower. Sound (contains
        every compatible state) when A is known (no ``A_unc``); with an uncertain A the hull over
        vertex sequences can miss the true state, as the paper's strip-before-hull order can
        (:func:`fdi_lib.reproduce.rosa2013_studies.horizon_comparison` measures it): an
        :class:`~fdi_lib.errors.UnsoundOptionWarning` is issued at the first update with an uncertain A.
    strip_before_hull : bool
        ``"exact"`` method only. False (default):
        :math:`\hat X(k+1) = \bigcap_j \mathrm{co}_v\{\mathrm{Prop}_j(v)\} \cap S`, which always
        contains the true state. True: the paper's literal construction
        :math:`\mathrm{co}_v\{\mathrm{Prop}_0(v) \cap S\}` (Fig. 2),
        which is tighter but can exclude the true state when the uncertain parameter is strictly
        inside the cube (a counter-example is in the tests and the book): an
        :class:`~fdi_lib.errors.UnsoundOptionWarning` is issued at the first update with an uncertain A.

    Examples
    --------
    >>> import numpy as np
    >>> from fdi_lib.sets import Polytope
    >>> from fdi_lib.sets.svo import SVOModel, SetValuedObserver
    >>> model = SVOModel(A=np.array([[0.9]]), C=np.array([[1.0]]), L=np.array([[0.1]]), noise=0.05)
    >>> svo = SetValuedObserver(Polytope.box([-1], [1]), method="exact")
    >>> X = svo.start(model, y0=np.array([0.2]))
    >>> X = svo.update(model, u=np.zeros(0), y_next=np.array([0.15]))
    >>> svo.empty
    False
    """

    def __init__(
        self,
        X0: Polytope,
        *,
        N: int = 1,
        method: str = "template",
        template: np.ndarray | None = None,
        margin: float = ROUNDOFF_MARGIN,
        strip_before_hull: bool = False,
        scale: Any = None,
        joint: bool = False,
    ) -> None:
        if not isinstance(X0, Polytope):
            raise ModelError(f"X0: expected a Polytope, got {type(X0).__name__}")
        N = integer(N, "N", low=1)
        if method not in ("template", "exact"):
            raise ModelError(f"method: expected 'template' or 'exact', got {method!r}")
        try:  # no vertex only when the Chebyshev LP finds the set empty (_enumerate_vertices)
            V0 = X0.vertices()
        except UnboundedSetError:
            raise UnboundedSetError(
                "X0: the initial set Set(M_0, m_0) is unbounded; give finite bounds on every state"
            ) from None
        if V0.shape[0] == 0:
            raise EmptySetError("X0: the initial set Set(M_0, m_0) is empty")
        self.N = int(N)
        self.method = method
        self.template = None if template is None else np.asarray(template, dtype=float)
        if self.template is not None and (
            self.template.ndim != 2 or self.template.shape[1] != X0.dim
        ):
            raise ShapeError(f"template: expected shape (p, {X0.dim}), got {self.template.shape}")
        if scale is None:
            self._s = None
        else:
            sc = _arr("scale", np.atleast_1d(scale), 1)
            if sc.shape != (X0.dim,) or np.any(sc <= 0):
                raise ModelError(f"scale: expected {X0.dim} positive numbers, got {sc}")
            self._s = sc
            X0, V0 = Polytope(X0.M * sc[None, :], X0.m), V0 / sc[None, :]
            if self.template is not None:  # D x = (D S) z
                self.template = self.template * sc[None, :]
        self.margin = real(margin, "margin", low=0.0, what="a non-negative relative inflation")
        self.strip_before_hull = bool(strip_before_hull)
        self.joint = bool(joint)
        self._warned = False
        self.n = X0.dim
        self._prior = _Entry(X0, V0)
        self.history: list[_Entry] = []  # most recent first
        self.empty = False

    # -------------------------------------------------------------- public API
    @property
    def current(self) -> Polytope | None:
        """The latest set X̂(k) (state coordinates x), or None once empty."""
        if self.empty or not self.history:
            return None
        X = self.history[0].X
        return X if self._s is None else Polytope(X.M / self._s[None, :], X.m)

    @property
    def current_vertices(self) -> np.ndarray | None:
        """Vertices of :attr:`current`, shape (v, n), or None once empty."""
        if self.empty or not self.history:
            return None
        V = self.history[0].V
        return V if self._s is None else V * self._s[None, :]

    def start(self, model: SVOModel, y0: np.ndarray) -> Polytope | None:
        """X̂(0) = X(0) ∩ {x : |y(0) - C x| <= nbar}."""
        model = self._check_model(model)
        X = self._strip(self._prior.X, model, y0, self._prior.V)
        return self._wrap(self._push(X))

    def start_from(self, other: "SetValuedObserver") -> None:
        """Initialise with another observer's current history (Architecture II, §4.2)."""
        if other.empty or not other.history:
            raise EmptySetError("other: the observer to copy from has no non-empty set")
        if (self._s is None) != (other._s is None) or (
            self._s is not None and np.any(self._s != other._s)
        ):
            raise ModelError("other: expected an observer with the same state scaling")
        self.history = [_Entry(e.X, e.V, e.model, e.u, e.P) for e in other.history]
        self.empty = False

    def update(self, model: SVOModel, u: np.ndarray, y_next: np.ndarray) -> Polytope | None:
        """X̂(k+1) from X̂(k..k-N+1), the model and input of step k, and y(k+1). None if empty."""
        if self.empty:
            return None
        if not self.history:
            raise ModelError("update: call start(model, y0) first")
        model = self._check_model(model)
        u = np.asarray(u, dtype=float).reshape(-1)
        if u.shape != (model.n_u,):
            raise ShapeError(f"u: expected shape ({model.n_u},), got {u.shape}")
        y_next = np.asarray(y_next, dtype=float).reshape(-1)
        if y_next.shape != (model.n_y,):
            raise ShapeError(f"y_next: expected shape ({model.n_y},), got {y_next.shape}")
        self.history[0].model = model
        self.history[0].u = u
        entries = self.history[: self.N]
        self._warn_unsound(model)
        if self.method == "template":
            X = self._update_template(entries, model, y_next)
        else:
            X = self._update_exact(entries, model, y_next)
        return self._wrap(self._push(X))

    # -------------------------------------------------------------- internals
    def _warn_unsound(self, model: SVOModel) -> None:
        """Warn once if an option that can lose the true state meets an uncertain A (module docstring)."""
        if self._warned or model.A_unc.shape[0] == 0:
            return
        option = (
            "strip_before_hull=True"
            if self.method == "exact" and self.strip_before_hull
            else "joint=True"
            if self.method == "template" and self.joint and self.N > 1
            else None
        )
        if option is not None:
            self._warned = True
            warnings.warn(
                f"{option}: with an uncertain A (A_unc has {model.A_unc.shape[0]} directions) the set can "
                f"lose the true state, so an empty set is no proof of a fault; use the default "
                f"{option.split('=')[0]}=False for detection",
                UnsoundOptionWarning,
                stacklevel=3,
            )

    def _wrap(self, X: Polytope | None) -> Polytope | None:
        return None if X is None else self.current

    def _check_model(self, model: SVOModel) -> SVOModel:
        """Validate ``model`` and express it in the internal coordinates z = x / s."""
        if not isinstance(model, SVOModel):
            raise TypeError(f"model: expected an SVOModel, got {type(model).__name__}")
        if model.n != self.n:
            raise ShapeError(f"model: expected state dimension {self.n} (from X0), got {model.n}")
        s = self._s
        if s is None:
            return model
        T = s[None, :] / s[:, None]  # S^-1 A S
        return SVOModel(
            A=model.A * T,
            C=model.C * s[None, :],
            B=model.B / s[:, None],
            L=model.L / s[:, None],
            noise=model.noise,
            A_unc=model.A_unc * T[None],
            B_unc=model.B_unc / s[None, :, None],
            C_unc=model.C_unc * s[None, None, :],
        )

    def _push(self, X: Polytope | None) -> Polytope | None:
        if X is None:
            self.empty = True
            return None
        V = X.vertices()
        if V.shape[0] == 0:
            self.empty = True
            return None
        self.history.insert(0, _Entry(X, V))
        del self.history[self.N + 1 :]
        return X

    def _strip(self, X: Polytope, model: SVOModel, y: np.ndarray, V: np.ndarray) -> Polytope:
        y = np.asarray(y, dtype=float).reshape(-1)
        if y.shape != (model.n_y,):
            raise ShapeError(f"y0: expected shape ({model.n_y},), got {y.shape}")
        nb = model.noise + self._c_unc_bound(model, V)
        return X.intersect_strip(model.C, y, nb)

    @staticmethod
    def _c_unc_bound(model: SVOModel, V: np.ndarray) -> np.ndarray:
        """Relaxation (11) applied to the output: |Delta_c C_c x| <= max over the predicted set of |C_c x|."""
        if model.C_unc.shape[0] == 0 or V.shape[0] == 0:
            return np.zeros(model.n_y)
        vals = np.abs(np.einsum("cyn,vn->cyv", model.C_unc, V)).max(axis=2)  # (n_C, n_y)
        return vals.sum(axis=0)

    def _propagations(
        self, entries: list[_Entry]
    ) -> list[list[tuple[np.ndarray, np.ndarray, np.ndarray]]]:
        """For each horizon j = 0..N'-1 and each Delta-vertex sequence of length j+1 (most recent step
        first): (Phi, c, G) such that x(k+1) in Phi X(k-j) + c + G [-1, 1]^g (eqs. (3)-(4))."""
        out = []
        # sequences built recursively: prefix over steps k, k-1, ..., k-j
        for j, e in enumerate(entries):
            model, u = e.model, e.u
            G_step = model.generators(u)
            Bu = model.B @ u
            if j == 0:  # x(k+1) = A_v x(k) + B u(k) + G s
                level = [(Av, Bu, G_step) for Av in model.vertex_matrices()]
            else:  # Phi maps x(k-j+1) to x(k+1); add step k-j
                level = [
                    (Phi @ Av, c + Phi @ Bu, np.column_stack([G, Phi @ G_step]))
                    for Phi, c, G in level
                    for Av in model.vertex_matrices()
                ]
            out.append(level)
        return out

    def _joint_support(self, entries: list[_Entry], props: list, Dall: np.ndarray) -> np.ndarray:
        """Support of co_v{joint set of eq. (3)} in the directions Dall (one LP per direction and v).

        For a full Delta-vertex sequence v, the rows j = 0..N'-1 share x(k+1) and the disturbance
        coefficients: row j uses the first g_j columns of v's generator matrix (its own prefix).
        Variables (x(k+1), x(k), ..., x(k-N'+1), s); x(k-j) in X̂(k-j), |s| <= 1.
        """
        n, Np = self.n, len(props)
        full = props[-1]
        g_full = full[0][2].shape[1]
        widths = [lvl[0][2].shape[1] for lvl in props]
        nv = n * (Np + 1) + g_full
        A_ub = [np.zeros((0, nv))]
        b_ub = [np.zeros(0)]
        for j, e in enumerate(entries[:Np]):
            blk = np.zeros((e.X.n_facets, nv))
            blk[:, n * (j + 1) : n * (j + 2)] = e.X.M
            A_ub.append(blk)
            b_ub.append(e.X.m)
        A_ub, b_ub = np.vstack(A_ub), np.concatenate(b_ub)
        bounds = [(None, None)] * (n * (Np + 1)) + [(-1.0, 1.0)] * g_full
        h = np.full(Dall.shape[0], -np.inf)
        reps = [len(props[j]) for j in range(Np)]
        for iv, (_, _, G) in enumerate(full):
            A_eq, b_eq = [], []
            for j in range(Np):
                # the prefix of v of length j+1 is entry iv // (reps[-1] // reps[j]) of level j
                Phi_j, c_j, G_j = props[j][iv // (reps[-1] // reps[j])]
                row = np.zeros((n, nv))
                row[:, :n] = np.eye(n)
                row[:, n * (j + 1) : n * (j + 2)] = -Phi_j
                row[:, n * (Np + 1) : n * (Np + 1) + widths[j]] = -G[:, : widths[j]]
                A_eq.append(row)
                b_eq.append(c_j)
            A_eq, b_eq = np.vstack(A_eq), np.concatenate(b_eq)
            h = np.maximum(h, _lp_maxima(Dall, A_ub, b_ub, A_eq, b_eq, bounds))
        return h

    def _update_template(
        self, entries: list[_Entry], model_next: SVOModel, y: np.ndarray
    ) -> Polytope | None:
        D = self.template if self.template is not None else default_template(self.n, model_next.C)
        Cu = model_next.C_unc.reshape(-1, self.n)
        Dall = np.vstack([D, Cu, -Cu]) if Cu.size else D
        props = self._propagations(entries)
        if self.joint and len(props) > 1:
            h = self._joint_support(entries, props, Dall)
            if np.all(np.isinf(h)):
                return None
        else:
            h = np.full(Dall.shape[0], np.inf)
            for j, level in enumerate(props):
                V = entries[j].V
                # support of co_v{Prop_j(v)} = max over the Delta-vertex sequences v (eq. (4))
                hj = np.max(
                    [
                        (V @ (Dall @ Phi).T).max(axis=0) + Dall @ c + np.abs(Dall @ G).sum(axis=1)
                        for Phi, c, G in level
                    ],
                    axis=0,
                )
                h = np.minimum(h, hj)  # intersection over the horizon: take the tightest bound
        h = h + self.margin * (1.0 + np.abs(h))
        p = D.shape[0]
        nb = model_next.noise.copy()
        if Cu.size:
            q = Cu.shape[0]
            rho = np.maximum(h[p : p + q], h[p + q : p + 2 * q])  # max |C_c x| over the prediction
            nb = nb + rho.reshape(model_next.C_unc.shape[:2]).sum(axis=0)
        nb = nb * (1.0 + self.margin) + self.margin
        C = model_next.C
        return Polytope(np.vstack([D, C, -C]), np.concatenate([h[:p], nb + y, nb - y]))

    def _update_exact(
        self, entries: list[_Entry], model_next: SVOModel, y: np.ndarray
    ) -> Polytope | None:
        # Level j is co over the 2^(n_A (j+1)) vertex sequences of {Phi_v X̂(k-j) + c_v + G_v [-1, 1]^g}.
        # Linear maps and Minkowski sums commute with convex hulls, so it is one step (k) of level
        # j-1 of the previous update: each entry keeps the points spanning its propagation so far
        # (``P``), and an update costs N one-step hulls instead of hulls over 2^(N n_A) sequences.
        model, u = entries[0].model, entries[0].u
        corners = box_corners(model.generators(u))
        Bu = model.B @ u
        H = []
        imgs0 = None
        per_vertex = []
        for j, e in enumerate(entries):
            P = e.V if e.P is None else e.P
            imgs = [
                ((P @ Av.T + Bu)[:, None, :] + corners[None, :, :]).reshape(-1, self.n)
                for Av in model.vertex_matrices()
            ]
            if j == 0:
                imgs0 = imgs
            # co_v{Prop_j(v)}: hull of the union of the vertex images (qhull / cddlib)
            pts = np.vstack(imgs)
            M, m, keep = _hull(pts)
            e.P = pts[keep]
            H.append(np.column_stack([M, m + self.margin * (1.0 + np.abs(m))]))
        nb = model_next.noise + self._c_unc_bound(model_next, np.vstack(imgs0))
        nb = nb * (1.0 + self.margin) + self.margin
        if self.strip_before_hull:
            # the paper's literal reading: co_v{Prop_0(v) ∩ S}; can exclude the true state (see docs)
            for pts in imgs0:
                M, m = _hull_hrep(pts)
                Xv = Polytope(M, m + self.margin * (1.0 + np.abs(m))).intersect_strip(
                    model_next.C, y, nb
                )
                Vv = _enumerate_vertices(Xv.M, Xv.m)
                if Vv.shape[0]:
                    per_vertex.append(Vv)
            if not per_vertex:
                return None
            X = Polytope.from_vertices(np.vstack(per_vertex))
            return X.intersect(
                Polytope(
                    np.vstack([h[:, :-1] for h in H[1:]]) if len(H) > 1 else X.M[:0],
                    np.concatenate([h[:, -1] for h in H[1:]]) if len(H) > 1 else X.m[:0],
                )
            )
        Hs = np.vstack(H)
        X = Polytope(Hs[:, :-1], Hs[:, -1]).intersect_strip(model_next.C, y, nb)
        # only the vertices feed the next step: no second hull for an irredundant H-representation
        return None if X.vertices().shape[0] == 0 else X


ModelSpec = SVOModel | Sequence[SVOModel] | Callable[[int], SVOModel]


def _model_at(models: ModelSpec, k: int) -> SVOModel:
    if isinstance(models, SVOModel):
        return models
    if callable(models):
        return models(k)
    return models[k]


@dataclass(frozen=True)
class SVORun:
    """Result of :func:`run_svo`.

    Attributes
    ----------
    empty_at : int or None
        First sample k with X̂(k) = ∅ (Proposition 3: a fault occurred at some k0 <= k); None if never.
    lower, upper : ndarray, shape (T+1, n)
        Bounding boxes of X̂(k) (NaN once empty).
    n_facets, n_vertices : ndarray, shape (T+1,)
        Complexity of X̂(k) (0 once empty).
    step_time : ndarray, shape (T,)
        Wall time of each update, in seconds (NaN after the set became empty).
    sets : tuple of Polytope or None
        The sets themselves when ``keep_sets=True``.
    """

    empty_at: int | None
    lower: np.ndarray
    upper: np.ndarray
    n_facets: np.ndarray
    n_vertices: np.ndarray
    step_time: np.ndarray
    sets: tuple | None = field(default=None, repr=False)


@single_threaded_blas
def run_svo(
    models: ModelSpec,
    u: Any,
    y: Any,
    X0: Polytope,
    *,
    N: int = 1,
    method: str = "template",
    template: np.ndarray | None = None,
    keep_sets: bool = False,
    scale: Any = None,
    joint: bool = False,
) -> SVORun:
    """Run an SVO over a record: X̂(0), ..., X̂(T), stopping at the first empty set.

    Parameters
    ----------
    models : SVOModel, sequence of SVOModel (length >= T+1) or callable k -> SVOModel
        The (possibly time-varying) model; step k uses ``models(k)``, and y(k) uses its C.
    u : ndarray, shape (T, n_u)
        Inputs u(0), ..., u(T-1).
    y : ndarray, shape (T+1, n_y)
        Measurements y(0), ..., y(T).
    X0 : Polytope
        Prior set of x(0).
    N, method, template, scale, joint
        See :class:`SetValuedObserver`.
    keep_sets : bool
        Keep every X̂(k) in the result.

    Returns
    -------
    SVORun
    """
    y = _arr("y", y, 2)
    if y.shape[0] == 0:
        raise ShapeError(
            f"y: expected at least one measurement y(0) (shape (T+1, n_y), T >= 0), got shape {y.shape}"
        )
    T = y.shape[0] - 1
    u = _arr("u", np.asarray(u, dtype=float).reshape(T, -1) if np.size(u) == 0 else u, 2)
    if u.shape[0] != T:
        raise ShapeError(f"u: expected {T} rows (one less than y's {T + 1}), got shape {u.shape}")
    svo = SetValuedObserver(X0, N=N, method=method, template=template, scale=scale, joint=joint)
    n = X0.dim
    lower = np.full((T + 1, n), np.nan)
    upper = np.full((T + 1, n), np.nan)
    nf = np.zeros(T + 1, dtype=int)
    nv = np.zeros(T + 1, dtype=int)
    st = np.full(T, np.nan)
    sets = []
    X = svo.start(_model_at(models, 0), y[0])
    empty_at = None
    for k in range(T + 1):
        if k > 0:
            t0 = time.perf_counter()
            X = svo.update(_model_at(models, k - 1), u[k - 1], y[k])
            st[k - 1] = time.perf_counter() - t0
        if X is None:
            empty_at = k
            break
        V = svo.current_vertices
        lower[k], upper[k] = V.min(axis=0), V.max(axis=0)
        nf[k], nv[k] = X.n_facets, V.shape[0]
        if keep_sets:
            sets.append(X)
    return SVORun(empty_at, lower, upper, nf, nv, st, tuple(sets) if keep_sets else None)


@dataclass(frozen=True)
class FDIResult:
    """Outcome of a bank of SVOs (Architectures I and II, §4, Fig. 6).

    Attributes
    ----------
    architecture : str
        ``"I"`` or ``"II"``.
    detection_step : int or None
        First sample at which the nominal SVO's set is empty (fault detected).
    isolation_step : int or None
        First sample at which exactly one fault SVO remains non-empty.
    isolated : str or None
        Name of that fault SVO.
    empty_at : dict
        First empty sample of every SVO (None if never).
    """

    architecture: str
    detection_step: int | None
    isolation_step: int | None
    isolated: str | None
    empty_at: dict


def _bank(named_models: Mapping[str, ModelSpec], u, y, X0, N, method, template):
    y = _arr("y", y, 2)
    if y.shape[0] == 0:
        raise ShapeError(
            f"y: expected at least one measurement y(0) (shape (T+1, n_y), T >= 0), got shape {y.shape}"
        )
    T = y.shape[0] - 1
    u = _arr("u", u, 2)
    if u.shape[0] != T:
        raise ShapeError(f"u: expected {T} rows (one less than y's {T + 1}), got shape {u.shape}")
    return y, u, T


@single_threaded_blas
def run_architecture_i(
    nominal: ModelSpec,
    faults: Mapping[str, ModelSpec],
    u: Any,
    y: Any,
    X0: Polytope,
    *,
    N: int = 1,
    method: str = "template",
    template: np.ndarray | None = None,
    stop_when_isolated: bool = True,
    scale: Any = None,
) -> FDIResult:
    """Architecture I (§4.1, Fig. 6(a)): a nominal SVO for detection, and one SVO per fault whose
    model also contains the nominal plant; a fault is isolated when only one fault SVO is non-empty.

    Parameters
    ----------
    nominal : model specification (see :func:`run_svo`)
    faults : dict name -> model specification
    u, y, X0, N, method, template, scale : see :func:`run_svo`
    stop_when_isolated : bool
        Stop the record once the fault is isolated (saves time; ``empty_at`` of the survivor is then None).
    """
    y, u, T = _bank({"nominal": nominal, **faults}, u, y, X0, N, method, template)
    specs = {"nominal": nominal, **faults}
    svos = {
        k: SetValuedObserver(X0, N=N, method=method, template=template, scale=scale) for k in specs
    }
    empty_at: dict[str, int | None] = {k: None for k in specs}
    for name, svo in svos.items():
        if svo.start(_model_at(specs[name], 0), y[0]) is None:
            empty_at[name] = 0
    det = iso = None
    isolated = None
    for k in range(T + 1):
        if k > 0:
            for name, svo in svos.items():
                if (
                    empty_at[name] is None
                    and svo.update(_model_at(specs[name], k - 1), u[k - 1], y[k]) is None
                ):
                    empty_at[name] = k
        if det is None and empty_at["nominal"] is not None:
            det = k
        alive = [f for f in faults if empty_at[f] is None]
        if det is not None and iso is None and len(alive) == 1:
            iso, isolated = k, alive[0]
            if stop_when_isolated:
                break
        if det is not None and not alive:
            break
    return FDIResult("I", det, iso, isolated, empty_at)


@single_threaded_blas
def run_architecture_ii(
    nominal: ModelSpec,
    global_model: ModelSpec,
    faults: Mapping[str, ModelSpec],
    u: Any,
    y: Any,
    X0: Polytope,
    *,
    N: int = 1,
    method: str = "template",
    template: np.ndarray | None = None,
    stop_when_isolated: bool = True,
    scale: Any = None,
) -> FDIResult:
    """Architecture II (§4.2, Fig. 6(b)): nominal SVO for detection, a Global SVO valid for the
    healthy and every faulty plant, and fault SVOs started from the Global SVO's set at detection.

    The fault models need not contain the nominal plant.

    Parameters
    ----------
    nominal, faults, u, y, X0, N, method, template, stop_when_isolated, scale
        As in :func:`run_architecture_i`.
    global_model : SVOModel, sequence or callable
        A model valid for the healthy plant and for every fault model.
    """
    y, u, T = _bank(
        {"nominal": nominal, "global": global_model, **faults}, u, y, X0, N, method, template
    )
    nom = SetValuedObserver(X0, N=N, method=method, template=template, scale=scale)
    glob = SetValuedObserver(X0, N=N, method=method, template=template, scale=scale)
    empty_at: dict[str, int | None] = {"nominal": None, "global": None, **{f: None for f in faults}}
    if nom.start(_model_at(nominal, 0), y[0]) is None:
        empty_at["nominal"] = 0
    if glob.start(_model_at(global_model, 0), y[0]) is None:
        empty_at["global"] = 0
    fsvos: dict[str, SetValuedObserver] = {}
    det = iso = None
    isolated = None
    for k in range(T + 1):
        if k > 0:
            if (
                empty_at["nominal"] is None
                and nom.update(_model_at(nominal, k - 1), u[k - 1], y[k]) is None
            ):
                empty_at["nominal"] = k
            if (
                empty_at["global"] is None
                and glob.update(_model_at(global_model, k - 1), u[k - 1], y[k]) is None
            ):
                empty_at["global"] = k
            for name, svo in fsvos.items():
                if (
                    empty_at[name] is None
                    and svo.update(_model_at(faults[name], k - 1), u[k - 1], y[k]) is None
                ):
                    empty_at[name] = k
        if det is None and empty_at["nominal"] is not None:
            det = k
            if empty_at["global"] is not None:
                break
            for name in faults:
                svo = SetValuedObserver(X0, N=N, method=method, template=template, scale=scale)
                svo.start_from(glob)
                fsvos[name] = svo
        if det is not None:
            alive = [f for f in faults if empty_at[f] is None]
            if iso is None and len(alive) == 1:
                iso, isolated = k, alive[0]
                if stop_when_isolated:
                    break
            if not alive:
                break
    return FDIResult("II", det, iso, isolated, empty_at)


# ----------------------------------------------------------------------------- many observers at once


@dataclass(frozen=True, eq=False)
class ModelSequence:
    """A time-varying model (1) stored as arrays: step k is the :class:`SVOModel` with ``A[k]``,
    ``B[k]``, ``A_unc[k]``, ``B_unc[k]`` and the constant ``C``, ``L``, ``noise`` (no output
    uncertainty).

    It is a model specification like a callable ``k -> SVOModel`` (:func:`run_svo`), checked once
    here rather than at every step, and the input of :class:`TemplateBatch`, which steps many
    observers together on the stacked arrays.

    Parameters
    ----------
    A : ndarray, shape (T, n, n)
    B : ndarray, shape (T, n, n_u)
    C : ndarray, shape (n_y, n)
    L : ndarray, shape (n, n_d)
    noise : ndarray, shape (n_y,)
    A_unc : ndarray, shape (T, n_A, n, n), optional
    B_unc : ndarray, shape (T, n_B, n, n_u), optional
        As in :class:`SVOModel`, one slice per step.
    """

    A: Any
    B: Any
    C: Any
    L: Any
    noise: Any
    A_unc: Any = None
    B_unc: Any = None
    _vertex_A: np.ndarray = field(init=False, repr=False)

    def __post_init__(self) -> None:
        A = _arr("A", self.A, 3)
        T, n = A.shape[0], A.shape[1]
        if A.shape != (T, n, n):
            raise ShapeError(f"A: expected shape (T, n, n), got {A.shape}")
        C = _arr("C", self.C, 2)
        if C.shape[1] != n:
            raise ShapeError(f"C: expected {n} columns, got shape {C.shape}")
        B = _arr("B", self.B, 3)
        if B.shape[:2] != (T, n):
            raise ShapeError(f"B: expected shape ({T}, {n}, n_u), got {B.shape}")
        L = _arr("L", self.L, 2)
        if L.shape[0] != n:
            raise ShapeError(f"L: expected {n} rows, got shape {L.shape}")
        noise = _arr("noise", self.noise, 1)
        if noise.shape != (C.shape[0],) or np.any(noise < 0):
            raise ModelError(f"noise: expected {C.shape[0]} non-negative bounds, got {noise}")
        Au = np.zeros((T, 0, n, n)) if self.A_unc is None else _arr("A_unc", self.A_unc, 4)
        if Au.shape[:1] + Au.shape[2:] != (T, n, n):
            raise ShapeError(f"A_unc: expected shape ({T}, n_A, {n}, {n}), got {Au.shape}")
        Bu = np.zeros((T, 0) + B.shape[1:]) if self.B_unc is None else _arr("B_unc", self.B_unc, 4)
        if Bu.shape[:1] + Bu.shape[2:] != B.shape:
            raise ShapeError(f"B_unc: expected shape ({T}, n_B, {n}, {B.shape[2]}), got {Bu.shape}")
        for name, val in (
            ("A", A),
            ("B", B),
            ("C", C),
            ("L", L),
            ("noise", noise),
            ("A_unc", Au),
            ("B_unc", Bu),
            ("_vertex_A", _vertex_matrices(A, Au)),
        ):
            val.flags.writeable = False
            object.__setattr__(self, name, val)

    def __len__(self) -> int:
        return int(self.A.shape[0])

    def __call__(self, k: int) -> SVOModel:
        """The model of step ``k``."""
        if not 0 <= k < len(self):
            raise ModelError(f"k: expected a step in [0, {len(self)}), got {k}")
        return SVOModel._checked_parts(
            self.A[k],
            self.C,
            self.B[k],
            self.L,
            self.noise,
            self.A_unc[k],
            self.B_unc[k],
            self._vertex_A[k],
        )


def _dot(M: np.ndarray, x: np.ndarray) -> np.ndarray:
    """M x over the last axes (M (..., r, c), x (..., c), broadcast), as elementwise products added
    in column order: each result depends on its own operands only, whatever the batch (a BLAS
    product may round differently with the batch size)."""
    out = M[..., 0] * x[..., None, 0]
    for j in range(1, M.shape[-1]):
        out = out + M[..., j] * x[..., None, j]
    return out


@numba.njit(cache=True)
def _support_max(
    DPhi: np.ndarray, mi: np.ndarray, V: np.ndarray, F: np.ndarray, rows: np.ndarray
) -> np.ndarray:  # pragma: no cover
    """``max`` over the vertex matrices ``v`` and the live vertices ``j`` (``F[rows[a], j]``) of
    ``DPhi[mi[a], v] @ V[rows[a], :, j]``, shape ``(a, p)`` (``V`` ``(observers, n, J)``, a vertex
    per column): the support of the propagated set of
    observer ``rows[a]`` (its model's ``D A_v``, ``DPhi`` ``(models, v, p, n)``, shared by the
    observers of one model) in each template direction (:meth:`TemplateBatch._step`). Each product
    is summed in column order from its first term, as :func:`_dot` does, so the result is the same
    bits as ``_dot`` followed by ``max`` (a NaN propagates), in one pass without the
    ``(a, 2^n_A, v, p)`` intermediate nor copies of the observers' vertices."""
    n, J = V.shape[1], V.shape[2]
    out = np.empty((rows.shape[0], DPhi.shape[2]))
    scratch = (np.empty((n, J)), np.empty(J), np.empty(J, dtype=np.int64))
    _support_into(out, scratch, DPhi, mi, V, F, rows, np.empty((0, 2), np.int64), F[:, 0])
    return out


@numba.njit(cache=True)
def _support_into(
    out: np.ndarray,
    scratch: tuple,
    DPhi: np.ndarray,
    mi: np.ndarray,
    V: np.ndarray,
    F: np.ndarray,
    rows: np.ndarray,
    corner: np.ndarray,
    boxed: np.ndarray,
) -> None:  # pragma: no cover
    """:func:`_support_max` into ``out[:len(rows)]`` with the caller's scratch arrays (``(n, J)``,
    ``(J,)`` and ``(J,)`` integers, or larger): the live vertices side by side (a vector loop),
    each product summed in column order, and the largest kept as ``max`` keeps it (the first of
    equal values, without a branch); an observer with a NaN product is redone as ``max``
    propagates it (:func:`_support_nan`). An observer whose set is a box with its corners in
    ``V`` (``boxed[rows[a]]``, ``corner`` from :func:`_box_route`) goes by :func:`_support_box`,
    the same bits."""
    _, nv, p, n = DPhi.shape
    Vt, acc, live = scratch
    for a in range(rows.shape[0]):
        r, q = rows[a], mi[a]
        if corner.shape[0] and boxed[r] and _support_box(out[a], acc, DPhi[q], V[r], corner):
            continue
        nan = _support_vertices(out[a], Vt, acc, live, DPhi[q], V[r], F[r])
        if nan:
            _support_nan(out[a], DPhi[q], V[r], F[r])


@numba.njit(cache=True)
def _support_vertices(
    out: np.ndarray,
    Vt: np.ndarray,
    acc: np.ndarray,
    live: np.ndarray,
    DPhi: np.ndarray,
    V: np.ndarray,
    F: np.ndarray,
) -> bool:  # pragma: no cover
    """The support of one observer (its model's ``DPhi`` ``(v, p, n)``, vertices ``V`` ``(n, J)``,
    live ``F``) in each direction into ``out`` (:func:`_support_into`'s vertex route, scratch
    ``Vt``, ``acc``, ``live``); returns whether a product is NaN."""
    nv, p, n = DPhi.shape
    L = 0
    for j in range(V.shape[1]):
        if F[j]:
            live[L] = j
            L += 1
    for c in range(n):
        for j in range(L):
            Vt[c, j] = V[c, live[j]]
    nan = False
    for i in range(p):
        best = -np.inf
        for v in range(nv):
            x = DPhi[v, i, 0]
            for j in range(L):
                acc[j] = x * Vt[0, j]
            for c in range(1, n):
                x = DPhi[v, i, c]
                for j in range(L):
                    acc[j] = acc[j] + x * Vt[c, j]
            for j in range(L):
                t = acc[j]
                nan = nan | (t != t)
                best = t if t > best else best
        out[i] = best
    return nan


@numba.njit(cache=True, inline="always")
def _support_box(
    out: np.ndarray, bounds: np.ndarray, DPhi: np.ndarray, V: np.ndarray, corner: np.ndarray
) -> bool:  # pragma: no cover
    """The support of one observer whose live vertices are all the corners of a box (``V``
    ``(n, J)``; coordinate ``c`` of corner ``corner[c, 0]`` is its one bound, of ``corner[c, 1]``
    the other, copied into ``bounds[c]`` and ``bounds[n + c]``) in each direction of ``DPhi``
    ``(v, p, n)`` into ``out``. Returns False when a product or a sum is not finite: then
    :func:`_support_vertices` redoes it (the order in which a NaN wins).

    Over a box, ``d . x`` is largest at the corner that takes, in each coordinate, the larger of
    the two products; rounded addition is monotone, so that corner's sum in column order is also
    the largest of the rounded sums :func:`_support_vertices` compares: the same bits in ``2 n``
    products per direction instead of ``n 2^n``."""
    nv, p, n = DPhi.shape
    for c in range(n):
        bounds[c] = V[c, corner[c, 0]]
        bounds[n + c] = V[c, corner[c, 1]]
    check = 0.0  # a sum of every product and total: finite unless one is not
    for i in range(p):
        best = -np.inf
        for v in range(nv):
            x = DPhi[v, i, 0]
            lo, hi = x * bounds[0], x * bounds[n]
            t = lo if lo >= hi else hi
            check = check + lo + hi
            for c in range(1, n):
                x = DPhi[v, i, c]
                lo, hi = x * bounds[c], x * bounds[n + c]
                t = t + (lo if lo >= hi else hi)
                check = check + lo + hi
            check = check + t
            best = t if t > best else best
        out[i] = best
    return check - check == 0.0


@numba.njit(cache=True)
def _support_nan(
    out: np.ndarray, DPhi: np.ndarray, V: np.ndarray, F: np.ndarray
) -> None:  # pragma: no cover
    """:func:`_support_into` of one observer (its model's ``DPhi`` ``(v, p, n)``, vertices ``V``
    ``(n, J)``, live ``F``) with a NaN product: in each direction, the first NaN in the order of
    the vertex matrices and the live vertices, as ``max`` propagates it."""
    nv, p, n = DPhi.shape
    for i in range(p):
        best = -np.inf
        for v in range(nv):
            for j in range(V.shape[1]):
                if not F[j]:
                    continue
                t = DPhi[v, i, 0] * V[0, j]
                for c in range(1, n):
                    t = t + DPhi[v, i, c] * V[c, j]
                if t > best or t != t:
                    best = t
                    if best != best:
                        break
            if best != best:
                break
        out[i] = best


@numba.njit(cache=True)
def _basic_one(
    m: np.ndarray,
    norms: np.ndarray,
    pad: np.ndarray,
    idx: np.ndarray,
    invT: np.ndarray,
    U: np.ndarray,
    zero: np.ndarray,
    X: np.ndarray,
    F: np.ndarray,
    work: tuple,
) -> bool:  # pragma: no cover
    """The basic solutions of one set ``Set(M, m)`` into ``X[:, :K]`` (``X`` ``(n, K)`` or wider, a
    solution per column) and whether each is feasible into ``F[:K]`` (:func:`_basic_solutions`; ``invT[i, j, k]`` is ``inv[k, i, j]``,
    ``work`` the scratch arrays of :func:`_basic_work`); returns whether any is."""
    q = pad.shape[0]
    K, n = idx.shape
    mu, Mu, acc, ok = work
    bad, tol = _tightest(m, norms, pad, zero, mu)
    for j in range(n):
        for k in range(K):
            Mu[j, k] = mu[idx[k, j]]
    # the bases side by side (k innermost, a vector loop): each sum still in its own order
    for i in range(n):
        for k in range(K):
            X[i, k] = 0.0
        for j in range(n):
            for k in range(K):
                X[i, k] += invT[i, j, k] * Mu[j, k]
    for k in range(K):
        ok[k] = not bad
    for g in range(q):
        lim = mu[g] + tol
        for k in range(K):
            acc[k] = 0.0
        for c in range(n):
            w = U[g, c]
            for k in range(K):
                acc[k] += X[c, k] * w
        for k in range(K):  # without a branch: a vector loop
            ok[k] = ok[k] & (acc[k] <= lim)
    found = False
    for k in range(K):
        F[k] = ok[k]
        found = found | ok[k]
    return found


@numba.njit(cache=True)
def _tightest(
    m: np.ndarray, norms: np.ndarray, pad: np.ndarray, zero: np.ndarray, mu: np.ndarray
) -> tuple[bool, float]:  # pragma: no cover
    """The tightest offset ``mu[g]`` of each distinct unit normal of ``Set(M, m)`` (into ``mu``),
    whether a zero row has a negative offset (no solution), and the feasibility tolerance
    ``1e-12 (1 + max |mu|)`` (:func:`_basic_one`)."""
    p = m.shape[0]
    q, r = pad.shape
    bad = False
    for i in range(p):
        if zero[i] and m[i] < 0:
            bad = True
    big = 0.0
    for g in range(q):
        best = np.inf
        for j in range(r):
            i = pad[g, j]
            if i < p:
                v = m[i] / norms[i]
                if v < best:
                    best = v
        mu[g] = best
        big = max(big, abs(best))
    return bad, 1e-12 * (1.0 + big)


@numba.njit(cache=True, inline="always")
def _basic_box(
    m: np.ndarray,
    norms: np.ndarray,
    pad: np.ndarray,
    zero: np.ndarray,
    route: tuple,
    X: np.ndarray,
    F: np.ndarray,
    work: tuple,
) -> int:  # pragma: no cover
    """:func:`_basic_one` when the distinct unit normals are ``+-e_i`` (``route`` the box's
    tables, :func:`_box_route`): each basic solution is a corner, whose coordinate ``c`` is one
    of two values ``sign mu[normal]`` (``side[c, k]`` says which), and its product with a unit
    normal has one nonzero term. :func:`_basic_one` adds the other terms, all zeros, so ``+ 0.0``
    gives the same bits (a ``-0.0`` made ``0.0``), and each feasibility test depends on one
    coordinate's side only: two tests per normal instead of one per corner. Returns -1 when an
    offset is not finite (``0 * inf``: :func:`_basic_one` must do it), else 0, 1 or 2: no
    solution, some or all feasible (then ``X[:, :K]`` holds the box's corners)."""
    side, normal, sign, axis, unit = route[:5]
    mu, val, _, good = work  # good[2 c + e]: value e of coordinate c passes every test
    bad, tol = _tightest(m, norms, pad, zero, mu)
    for v in mu:
        if not np.isfinite(v):
            return -1
    n, K = side.shape
    for c in range(n):
        for e in range(2):
            val[c, e] = sign[c, e] * mu[normal[c, e]] + 0.0
            good[2 * c + e] = not bad
    for h in range(axis.shape[0]):
        c, w, lim = axis[h], unit[h], mu[h] + tol
        for e in range(2):
            good[2 * c + e] = good[2 * c + e] & (val[c, e] * w + 0.0 <= lim)
    for c in range(n):  # k innermost: a vector loop
        for k in range(K):
            X[c, k] = val[c, side[c, k]]
    every = True
    for i in range(2 * n):
        every = every & good[i]
    for k in range(K):
        F[k] = True
    if every:  # every value passes: every corner is feasible
        return 2
    for c in range(n):
        for k in range(K):
            F[k] = F[k] & good[2 * c + side[c, k]]
    found = False
    for k in range(K):
        found = found | F[k]
    return 1 if found else 0


@numba.njit(cache=True)
def _basic_rows(
    m_out: np.ndarray,
    rows: np.ndarray,
    bases: tuple,
    route: tuple,
    boxed: np.ndarray,
    V: np.ndarray,
    F: np.ndarray,
    found: np.ndarray,
    work: tuple,
) -> bool:  # pragma: no cover
    """The basic solutions of the sets ``m_out[a]`` of the observers ``rows[a]`` of one group
    (``bases``: :func:`_basic_one`'s arrays; ``route``: :func:`_box_route`'s) into
    ``V[rows[a], :, :K]`` and ``F[rows[a]]`` (``False`` beyond ``K``), by :func:`_basic_box` when
    the group's sets are boxes (``boxed[rows[a]]``: all ``K`` corners feasible), else
    :func:`_basic_one`; ``found[a]``: whether any is
    feasible. Returns whether all observers have one."""
    norms, pad, idx, invT, U, zero = bases
    K = idx.shape[0]
    every = True
    for a in range(rows.shape[0]):
        r = rows[a]
        status = (
            _basic_box(m_out[a], norms, pad, zero, route, V[r], F[r], work)
            if route[5].shape[0]
            else -1
        )
        if status < 0:
            found[a] = _basic_one(m_out[a], norms, pad, idx, invT, U, zero, V[r], F[r], work)
        else:
            found[a] = status > 0
        boxed[r] = status == 2
        every = every and found[a]
        for j in range(K, F.shape[1]):
            F[r, j] = False
    return every


@numba.njit(cache=True)
def _basic_work(q: int, K: int, n: int) -> tuple:  # pragma: no cover
    """Scratch arrays of :func:`_basic_one` (``q`` distinct normals, ``K`` bases, dimension ``n``),
    allocated once per batch of sets."""
    return (np.empty(q), np.empty((n, K)), np.empty(K), np.empty(K, dtype=np.bool_))


@numba.njit(cache=True)
def _inv_t(inv: np.ndarray) -> np.ndarray:  # pragma: no cover
    """``inv[k, i, j]`` at ``[i, j, k]`` (:func:`_basic_one`'s layout)."""
    K, n, _ = inv.shape
    invT = np.empty((n, n, K))
    for k in range(K):
        for i in range(n):
            for j in range(n):
                invT[i, j, k] = inv[k, i, j]
    return invT


@numba.njit(cache=True)
def _basic_solutions(
    m: np.ndarray,
    norms: np.ndarray,
    pad: np.ndarray,
    idx: np.ndarray,
    inv: np.ndarray,
    U: np.ndarray,
    zero: np.ndarray,
) -> tuple[np.ndarray, np.ndarray]:  # pragma: no cover
    """The basic solutions ``x = U_S^-1 mu_S`` of every set ``Set(M, m[b])`` ``(B, K, n)`` and
    whether each is feasible ``(B, K)`` (:func:`fdi_lib.sets.polytope._basis_vertices`'s route and
    tolerance, the arrays of its :class:`~fdi_lib.sets.polytope._Bases`): ``mu`` the tightest
    offset per distinct unit normal, feasible to ``1e-12 (1 + max |mu|)``, none where a zero row
    has a negative offset. Each set is computed on its own (:func:`_basic_one`), with sums in a
    fixed order, so its result does not depend on the batch."""
    B = m.shape[0]
    K, n = idx.shape
    X = np.empty((B, K, n))
    F = np.empty((B, K), dtype=np.bool_)
    invT = _inv_t(inv)
    work = _basic_work(pad.shape[0], K, n)
    Xt = np.empty((n, K))
    for b in range(B):
        _basic_one(m[b], norms, pad, idx, invT, U, zero, Xt, F[b], work)
        for k in range(K):
            for i in range(n):
                X[b, k, i] = Xt[i, k]
    return X, F


@numba.njit(cache=True)
def _group_step(
    g: tuple,
    k: int,
    u: np.ndarray,
    y: np.ndarray,
    margin: float,
    W: np.ndarray,
    scratch: tuple,
    Bu: np.ndarray,
    Gu: np.ndarray,
    work: tuple,
) -> bool:  # pragma: no cover
    """Step ``k`` of the observers ``rows`` of one group (:meth:`TemplateBatch._step`, basis
    route; ``g`` as :meth:`TemplateBatch._kernel_group` builds it) in place: the supports ``h``
    (:func:`_support_into`, plus ``D B u`` and the uncertainty's ``sum |D B_b u|``, each product in
    :func:`_dot`'s order, then the margin), the offsets ``m_out[a] = (h, nb + y, nb - y)`` and the
    basic solutions (:func:`_basic_rows`); returns whether every observer has one. The same
    operations in the same order as the array route, hence the same bits; the scratch arrays
    (``W``, ``scratch``, ``Bu``, ``Gu``, ``work``) are the caller's, at least the group's
    sizes."""
    DPhi, first, rows, obs, mi, V, F, D, B, B_unc, sL, noise = g[:12]
    m_out, found, route, boxed = g[18:]
    Phi = DPhi[0] if DPhi.shape[0] == 1 else DPhi[k - first]
    _support_into(W, scratch, Phi, mi, V, F, rows, route[5], boxed)
    p, n = D.shape
    n_u, n_y, n_b = u.shape[2], y.shape[2], B_unc.shape[2]
    for a in range(rows.shape[0]):
        q, o = mi[a], obs[a]
        for i in range(n):
            t = B[q, k - 1, i, 0] * u[o, k - 1, 0]
            for c in range(1, n_u):
                t = t + B[q, k - 1, i, c] * u[o, k - 1, c]
            Bu[i] = t
            for b in range(n_b):
                t = B_unc[q, k - 1, b, i, 0] * u[o, k - 1, 0]
                for c in range(1, n_u):
                    t = t + B_unc[q, k - 1, b, i, c] * u[o, k - 1, c]
                Gu[b, i] = t
        for i in range(p):
            c = D[i, 0] * Bu[0]
            for j in range(1, n):
                c = c + D[i, j] * Bu[j]
            s = sL[q, i]
            for b in range(n_b):
                t = D[i, 0] * Gu[b, 0]
                for j in range(1, n):
                    t = t + D[i, j] * Gu[b, j]
                s = s + abs(t)
            h = W[a, i] + c + s
            m_out[a, i] = h + margin * (1.0 + abs(h))
        for j in range(n_y):
            nb = noise[q, j] * (1.0 + margin) + margin
            m_out[a, p + j] = nb + y[o, k, j]
            m_out[a, p + n_y + j] = nb - y[o, k, j]
    return _basic_rows(m_out, rows, g[12:18], route, boxed, V, F, found, work)


@numba.njit(cache=True)
def _template_run(
    groups: Any, u: np.ndarray, y: np.ndarray, k: int, last: int, margin: float
) -> int:  # pragma: no cover
    """Steps ``k``, ``k + 1``, ... ``last`` of every group (:func:`_group_step`, the groups in
    order at each step; ``groups`` a ``numba.typed.List`` of their tuples) in one compiled loop,
    the scratch arrays allocated once; stops after the first step at which a set has no feasible
    basis (its ``m_out`` and ``found`` are that step's) and returns the last step made."""
    n = groups[0][5].shape[1]
    na = p = J = n_b = q = K = 0
    for g in groups:
        na, p, J = max(na, g[2].shape[0]), max(p, g[7].shape[0]), max(J, g[5].shape[2])
        n_b, q, K = max(n_b, g[9].shape[2]), max(q, g[13].shape[0]), max(K, g[14].shape[0])
    W = np.empty((na, p))
    scratch = (np.empty((n, J)), np.empty(J), np.empty(J, dtype=np.int64))
    Bu, Gu, work = np.empty(n), np.empty((n_b, n)), _basic_work(q, K, n)
    while True:
        every = True
        for g in groups:
            ok = _group_step(g, k, u, y, margin, W, scratch, Bu, Gu, work)
            every = every and ok
        if not every or k == last:
            return k
        k += 1


@numba.njit(cache=True)
def _group_list(g: tuple) -> Any:  # pragma: no cover
    """A ``numba.typed.List`` holding the group ``g``, for :func:`_template_run`; :func:`_push`
    appends the others. Built in compiled code, cached on disk with it: ``numba.typed.List(...)``
    in Python compiles the list's methods, which numba does not cache, 0.7 s in every process."""
    groups = numba.typed.List()
    groups.append(g)
    return groups


@numba.njit(cache=True)
def _push(groups: Any, g: tuple) -> None:  # pragma: no cover
    """Appends the group ``g`` to ``groups`` (:func:`_group_list`)."""
    groups.append(g)


#: The tables of :func:`_box_route` for normals that are not a box's.
_NO_BOX = (
    np.empty((0, 0), dtype=np.int64),
    np.empty((0, 2), dtype=np.int64),
    np.empty((0, 2)),
    np.empty(0, dtype=np.int64),
    np.empty(0),
    np.empty((0, 2), dtype=np.int64),
)


def _box_route(b: Any) -> tuple:
    """The tables of :func:`_basic_box` and :func:`_support_box` when the distinct unit normals of
    ``b`` (:func:`~fdi_lib.sets.polytope._bases`) are exactly ``+-e_i`` for every coordinate and
    each basis inverse is a signed permutation (then every set is a box and the basic solutions
    are its corners): ``side[c, k]``, which of its two values coordinate ``c`` of solution ``k``
    takes; value ``e`` of coordinate ``c`` is ``sign[c, e] mu[normal[c, e]]``; normal ``g`` is
    ``unit[g] e_axis[g]``; ``corner[c, e]``, a solution whose coordinate ``c`` takes value ``e``.
    Else :data:`_NO_BOX`."""
    U, inv = b.U, b.inv
    n = U.shape[1]
    nonzero = U != 0
    if U.shape[0] != 2 * n or not (nonzero.sum(axis=1) == 1).all():
        return _NO_BOX
    axis = nonzero.argmax(axis=1)
    unit = U[np.arange(len(U)), axis]
    if {(int(a), float(w)) for a, w in zip(axis, unit)} != {
        (c, w) for c in range(n) for w in (-1.0, 1.0)
    }:
        return _NO_BOX
    if not (np.isin(inv, (-1.0, 0.0, 1.0)).all() and ((inv != 0).sum(axis=2) == 1).all()):
        return _NO_BOX
    j = (inv != 0).argmax(axis=2)  # (K, n): the one term of each coordinate
    K = inv.shape[0]
    normal_k = b.idx[np.arange(K)[:, None], j].T  # (n, K)
    sign_k = np.take_along_axis(inv, j[:, :, None], axis=2)[:, :, 0].T
    side = np.ascontiguousarray(normal_k != normal_k[:, :1], dtype=np.int64)
    corner = np.column_stack([np.zeros(n, dtype=np.int64), side.argmax(axis=1)])
    rows = np.arange(n)[:, None]
    normal = np.ascontiguousarray(normal_k[rows, corner])
    sign = np.ascontiguousarray(sign_k[rows, corner])
    return side, normal.astype(np.int64), sign, axis.astype(np.int64), unit, corner


#: Steps of a time-varying model whose products ``D A_v`` :meth:`TemplateBatch.advance` makes at
#: once (the memory of one call).
_DPHI_CHUNK = 64


def _invariant_product(D: np.ndarray, vA: np.ndarray) -> np.ndarray | None:
    """``D A_v`` of every model ``(1, models, v, p, n)`` when the vertex matrices ``vA``
    ``(models, T, v, n, n)`` are the same bits at every step (computed once, by the product each
    step makes), else None."""
    bits = vA.reshape(vA.shape[0], vA.shape[1], -1).view(np.uint64)
    if vA.shape[1] == 0 or not (bits == bits[:, :1]).all():
        return None
    return np.ascontiguousarray(np.matmul(D, vA[:, 0])[None])


def _vertices_many(M: np.ndarray, m: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Vertices of Set(M, m[b]) for every row b of m, shape (B, K, n), with a mask (B, K) of the
    rows that are vertices; a set is empty when its mask is all False, which the Chebyshev LP
    confirms (a set with no feasible basis but a point goes to :func:`_enumerate_vertices`).

    The basic solutions of :func:`fdi_lib.sets.polytope._basis_vertices`, for all sets at once (the
    same normals M, hence the same bases); a vertex on more than n facets may appear several times.
    When that route does not apply, each set's vertices are enumerated on their own and padded.
    """
    b = _bases(M.tobytes(), M.shape[0], M.shape[1])
    if b is None or not b.bounded:
        Vs = [_enumerate_vertices(M, row) for row in m]
        K = max(1, max(len(V) for V in Vs))
        X = np.zeros((len(Vs), K, M.shape[1]))
        F = np.zeros((len(Vs), K), dtype=bool)
        for i, V in enumerate(Vs):
            X[i, : len(V)], F[i, : len(V)] = V, True
        return X, F
    X, F = _basic_solutions(
        np.ascontiguousarray(m, dtype=float), b.norms, b.pad, b.idx, b.inv, b.U, b.zero
    )
    # no feasible basis is not a proof of emptiness: the Chebyshev LP decides (_enumerate_vertices)
    for i in np.flatnonzero(~F.any(axis=1)):
        V = _enumerate_vertices(M, m[i])
        if len(V) > X.shape[1]:
            X = np.concatenate([X, np.zeros((X.shape[0], len(V) - X.shape[1], X.shape[2]))], axis=1)
            F = np.concatenate([F, np.zeros((F.shape[0], len(V) - F.shape[1]), dtype=bool)], axis=1)
        X[i, : len(V)], F[i, : len(V)] = V, True
    return X, F


class TemplateBatch:
    """Many independent template SVOs (horizon N = 1) stepped together.

    Observer b runs on ``models[b]``, ``u[b]``, ``y[b]`` and computes the sets of
    ``SetValuedObserver(X0, method="template", template=template, margin=margin)`` (Proposition 2
    and 3 hold as for one observer): the support of X̂(k+1) in each template direction is the
    largest one over the vertices of X̂(k) and the vertex matrices, then the vertices of X̂(k+1)
    are the basic solutions of its fixed normals (:func:`_vertices_many`), for all observers with
    the same model structure at once. Each observer's sets do not depend on the batch (tested bit
    for bit): the products are elementwise, or one matrix product of fixed shapes per observer.
    Against :class:`SetValuedObserver` (other products, duplicate vertices merged) they agree to
    rounding (tested), far inside the relative ``margin`` added at every step.

    Parameters
    ----------
    models : sequence of ModelSequence
        One per observer, each of length at least T (step k uses ``models[b](k)``).
    u : ndarray, shape (B, T, n_u)
        Inputs of each observer.
    y : ndarray, shape (B, T + 1, n_y)
        Measurements of each observer.
    X0 : Polytope
        Prior set of x(0), shared.
    template : ndarray, shape (p, n), optional
        Template directions (default :func:`default_template` of each model's C).
    margin : float
        As in :class:`SetValuedObserver`.

    Attributes
    ----------
    alive : ndarray of bool, shape (B,)
        Observers whose set is not empty.
    """

    def __init__(
        self,
        models: Sequence[ModelSequence],
        u: Any,
        y: Any,
        X0: Polytope,
        *,
        template: np.ndarray | None = None,
        margin: float = ROUNDOFF_MARGIN,
    ) -> None:
        if not isinstance(X0, Polytope):
            raise ModelError(f"X0: expected a Polytope, got {type(X0).__name__}")
        models = list(models)
        for b, mdl in enumerate(models):
            if not isinstance(mdl, ModelSequence):
                raise ModelError(f"models[{b}]: expected a ModelSequence, got {type(mdl).__name__}")
        y = _arr("y", y, 3)
        Bn, T = y.shape[0], y.shape[1] - 1
        u = _arr("u", u, 3)
        if u.shape[:2] != (Bn, T) or len(models) != Bn:
            raise ShapeError(
                f"u, models: expected u of shape ({Bn}, {T}, n_u) and {Bn} models (from y "
                f"{y.shape}), got u {u.shape} and {len(models)} models"
            )
        for b, mdl in enumerate(models):
            if (
                len(mdl) < T
                or mdl.A.shape[1] != X0.dim
                or mdl.C.shape[0] != y.shape[2]
                or mdl.B.shape[2] != u.shape[2]
            ):
                raise ShapeError(
                    f"models[{b}]: expected at least {T} steps, n = {X0.dim}, n_y = {y.shape[2]}, "
                    f"n_u = {u.shape[2]}, got A {mdl.A.shape}, C {mdl.C.shape}, B {mdl.B.shape}"
                )
        self.margin = real(margin, "margin", low=0.0, what="a non-negative relative inflation")
        self.T, self.n, self.X0 = T, X0.dim, X0
        self.u, self.y = np.ascontiguousarray(u), np.ascontiguousarray(y)
        self.template = None if template is None else _arr("template", template, 2)
        self.alive = np.ones(Bn, dtype=bool)
        # observers with the same array shapes and C are stepped together
        groups: dict = {}
        for b, mdl in enumerate(models):
            key = (mdl.A_unc.shape[1], mdl.B_unc.shape[1], mdl.L.shape[1], mdl.C.tobytes())
            groups.setdefault(key, []).append(b)
        self._groups = []
        for idx in groups.values():
            first = models[idx[0]]
            D = self.template if self.template is not None else default_template(self.n, first.C)
            # a model object shared by many observers (one bank on many records) is stored once;
            # "mi" gives each observer's row in the model arrays
            rows: dict[int, int] = {}
            uniq: list[ModelSequence] = []
            for b in idx:
                if id(models[b]) not in rows:
                    rows[id(models[b])] = len(uniq)
                    uniq.append(models[b])
            mi = np.array([rows[id(models[b])] for b in idx])
            L = np.stack([mdl.L for mdl in uniq])
            M = np.vstack([D, first.C, -first.C])
            # the basis route in compiled loops (advance, _template_run) when its normals allow it
            b = _bases(M.tobytes(), *M.shape) if u.shape[2] else None
            usable = b is not None and b.bounded
            vA = np.stack([mdl._vertex_A[:T] for mdl in uniq])
            self._groups.append(
                {
                    "idx": np.array(idx),
                    "mi": mi,
                    "D": D,
                    "C": first.C,
                    "M": M,
                    "bases": b if usable else None,
                    "invT": _inv_t(b.inv) if usable else None,
                    "route": _box_route(b) if usable else _NO_BOX,
                    "boxed": np.zeros(len(idx), dtype=bool),  # V holds the box's K corners
                    "vA": vA,
                    "DPhi": _invariant_product(D, vA),
                    "chunk": None,  # (first step, D A_v of the steps from it) when time-varying
                    "B": np.stack([mdl.B[:T] for mdl in uniq]),
                    "B_unc": np.stack([mdl.B_unc[:T] for mdl in uniq]),
                    "noise": np.stack([mdl.noise for mdl in uniq]),
                    # sum_c |D L|_{:, c}: the fixed columns of the generators (disturbance)
                    "sL": np.abs((D[None, :, :, None] * L[:, None, :, :]).sum(axis=2)).sum(axis=2),
                    "V": None,
                    "F": None,
                }
            )

    def start(self) -> np.ndarray:
        """X̂(0) = X(0) ∩ strip of y(0) for every observer; returns the mask of empty ones."""
        for g in self._groups:
            y0 = self.y[g["idx"], 0]
            m = np.column_stack(
                [
                    np.broadcast_to(self.X0.m, (len(y0), self.X0.m.size)),
                    g["noise"][g["mi"]] + y0,
                    g["noise"][g["mi"]] - y0,
                ]
            )
            X, g["F"] = _vertices_many(np.vstack([self.X0.M, g["C"], -g["C"]]), m)
            g["V"] = np.ascontiguousarray(np.swapaxes(X, 1, 2))  # a vertex per column
            g["boxed"][:] = False
            self.alive[g["idx"]] = g["F"].any(axis=1)
        return ~self.alive

    def update(self, k: int, which: np.ndarray | None = None) -> np.ndarray:
        """X̂(k) from X̂(k-1) for the live observers in the mask ``which`` (default all);
        returns the mask of the observers that became empty at k."""
        return self.advance(k, which, last=k)[1]

    def advance(
        self, k: int, which: np.ndarray | None = None, last: int | None = None
    ) -> tuple[int, np.ndarray]:
        """:meth:`update` at k, k + 1, ... ``last`` (default T) for the live observers in the mask
        ``which`` (default all), in one compiled loop (the same bits), until the first step at
        which a set has no feasible basis (it may be empty: the LP decides) or ``last``; returns
        the last step made and the mask of the observers that became empty at it. The array route
        (a group whose normals have no usable bases) makes one step per call."""
        if not 1 <= k <= self.T:
            raise ModelError(f"k: expected a sample in [1, {self.T}], got {k}")
        last = self.T if last is None else last
        if not k <= last <= self.T:
            raise ModelError(f"last: expected a sample in [{k}, {self.T}], got {last}")
        which = self.alive if which is None else self.alive & np.asarray(which, dtype=bool)
        before = self.alive.copy()
        live = [(g, np.flatnonzero(which[g["idx"]])) for g in self._groups]
        live = [(g, a) for g, a in live if a.size]
        if any(g["bases"] is None for g, _ in live):
            last = k
        fused = [(g, a) for g, a in live if g["bases"] is not None]
        for g, _ in fused:
            if g["DPhi"] is None:  # D A_v of each step: a chunk at a time
                last = min(last, self._chunk(g, k))
        if fused:
            last = self._run_bases(fused, k, last)
        for g, a in live:
            if g["bases"] is None:
                self._step(g, a, k)
        return last, before & ~self.alive

    def _step(self, g: dict, a: np.ndarray, k: int) -> None:
        """One step by the array route (:func:`_dot` products, :func:`_vertices_many`)."""
        D, obs = g["D"], g["idx"][a]
        mi = g["mi"][a]  # the observers' rows in the model arrays
        DPhi = np.matmul(D, g["vA"][:, k - 1])  # (models, 2^n_A, p, n): D A_v of each model
        W = _support_max(DPhi, mi, g["V"], g["F"], a)  # (a, p): over A_v and the live vertices
        uk = self.u[obs, k - 1]
        c = _dot(D, _dot(g["B"][mi, k - 1], uk))  # D B u
        s = g["sL"][mi]
        Gu = _dot(g["B_unc"][mi, k - 1], uk[:, None, :])  # (a, n_B, n): B_b u
        for j in range(Gu.shape[1]):
            s = s + np.abs(_dot(D, Gu[:, j]))
        h = W + c + s
        h = h + self.margin * (1.0 + np.abs(h))
        nb = g["noise"][mi] * (1.0 + self.margin) + self.margin
        yk = self.y[obs, k]
        X, Fn = _vertices_many(g["M"], np.column_stack([h, nb + yk, nb - yk]))
        if g["V"].shape[2] < X.shape[1]:
            self._widen(g, X.shape[1])
        g["V"][a, :, : X.shape[1]], g["F"][a, : X.shape[1]] = np.swapaxes(X, 1, 2), Fn
        g["F"][a, X.shape[1] :] = False
        self.alive[obs] = Fn.any(axis=1)

    def _chunk(self, g: dict, k: int) -> int:
        """``D A_v`` of a time-varying group at step ``k`` and up to ``_DPHI_CHUNK - 1`` steps after
        it (by the product the array route makes), kept until a step beyond them; returns the last
        step it holds."""
        if g["chunk"] is None or not g["chunk"][0] <= k < g["chunk"][0] + len(g["chunk"][1]):
            steps = range(k, min(self.T, k + _DPHI_CHUNK - 1) + 1)
            g["chunk"] = (k, np.stack([np.matmul(g["D"], g["vA"][:, j - 1]) for j in steps]))
        return g["chunk"][0] + len(g["chunk"][1]) - 1

    def _kernel_group(self, g: dict, a: np.ndarray, k: int) -> tuple:
        """The arrays of one group for :func:`_group_step` from step ``k`` on (within the group's
        chunk, :meth:`_chunk`, when it is time-varying)."""
        b = g["bases"]
        if g["V"].shape[2] < b.idx.shape[0]:
            self._widen(g, b.idx.shape[0])
        first, DPhi = (k, g["DPhi"]) if g["DPhi"] is not None else g["chunk"]
        return (
            DPhi,
            first,
            a,
            g["idx"][a],
            g["mi"][a],
            g["V"],
            g["F"],
            np.ascontiguousarray(g["D"]),  # one array type for every group
            g["B"],
            g["B_unc"],
            g["sL"],
            g["noise"],
            b.norms,
            b.pad,
            b.idx,
            g["invT"],
            b.U,
            b.zero,
            np.empty((len(a), g["M"].shape[0])),
            np.empty(len(a), dtype=bool),
            g["route"],
            g["boxed"],
        )

    def _run_bases(self, fused: list, k: int, last: int) -> int:
        """Steps ``k`` to ``last`` of the groups ``fused`` (pairs group, observers) by the basis
        route in one compiled loop (:func:`_template_run`), the vertices written in place; a set
        with no feasible basis goes to :func:`~fdi_lib.sets.polytope._enumerate_vertices`
        (emptiness by LP), as in :func:`_vertices_many`. Returns the last step made."""
        args = [self._kernel_group(g, a, k) for g, a in fused]
        # a typed list: one compiled signature whatever the number of groups (a tuple of them
        # compiled one per length, in minutes for a dozen groups: LLVM on one huge aggregate),
        # built by cached functions (_group_list)
        groups = _group_list(args[0])
        for arg in args[1:]:
            _push(groups, arg)
        last = _template_run(groups, self.u, self.y, k, last, self.margin)
        for (g, a), arg in zip(fused, args):
            m, found = arg[18:20]
            for i in np.flatnonzero(~found):
                V = _enumerate_vertices(g["M"], m[i])
                if len(V) > g["V"].shape[2]:
                    self._widen(g, len(V))
                g["V"][a[i], :, : len(V)], g["F"][a[i], : len(V)] = V.T, True
                g["boxed"][a[i]] = False
                found[i] = len(V) > 0
            self.alive[g["idx"][a]] = found
        return last

    def _widen(self, g: dict, K: int) -> None:
        """Room for ``K`` vertices per observer in the group's arrays (zeros, not live)."""
        pad = K - g["V"].shape[2]
        g["V"] = np.concatenate([g["V"], np.zeros((len(g["idx"]), self.n, pad))], axis=2)
        g["F"] = np.concatenate([g["F"], np.zeros((len(g["idx"]), pad), dtype=bool)], axis=1)

    def bounding_boxes(self) -> tuple[np.ndarray, np.ndarray]:
        """Lower and upper corners of the bounding box of every current set, shape (B, n) each
        (NaN for the empty ones)."""
        lower = np.full((len(self.alive), self.n), np.nan)
        upper = lower.copy()
        for g in self._groups:
            live = self.alive[g["idx"]]
            V = np.ascontiguousarray(np.swapaxes(g["V"][live], 1, 2))  # a vertex per row
            F = g["F"][live][:, :, None]
            lower[g["idx"][live]] = np.where(F, V, np.inf).min(axis=1)
            upper[g["idx"][live]] = np.where(F, V, -np.inf).max(axis=1)
        return lower, upper


@dataclass(frozen=True)
class SVOBatchRun:
    """Result of :func:`run_svo_many`.

    Attributes
    ----------
    empty_at : tuple of (int or None)
        First sample at which each observer's set is empty (None: never).
    lower, upper : ndarray, shape (B, T+1, n), or None
        Bounding boxes of the sets (NaN once empty), when asked for.
    """

    empty_at: tuple
    lower: np.ndarray | None = field(default=None, repr=False)
    upper: np.ndarray | None = field(default=None, repr=False)


@single_threaded_blas
def run_svo_many(
    models: Sequence[ModelSequence],
    u: Any,
    y: Any,
    X0: Polytope,
    *,
    template: np.ndarray | None = None,
    bounds: bool = False,
) -> SVOBatchRun:
    """:func:`run_svo` (template rule, N = 1) for many records at once (:class:`TemplateBatch`).

    Parameters
    ----------
    models : sequence of ModelSequence
        One per record.
    u : ndarray, shape (B, T, n_u)
    y : ndarray, shape (B, T+1, n_y)
        Inputs and measurements of each record.
    X0 : Polytope
        Prior set of x(0).
    template : ndarray, shape (p, n), optional
        See :class:`SetValuedObserver`.
    bounds : bool
        Also return the bounding boxes of every set.

    Returns
    -------
    SVOBatchRun
    """
    bank = TemplateBatch(models, u, y, X0, template=template)
    T = bank.T
    empty_at = np.where(bank.start(), 0, -1)
    lower = upper = None
    if bounds:
        lower = np.full((len(empty_at), T + 1, bank.n), np.nan)
        upper = lower.copy()
        lower[:, 0], upper[:, 0] = bank.bounding_boxes()
    k = 1
    while k <= T and bank.alive.any():
        # to the next set with no feasible basis in one call, one step at a time for the boxes
        k, emptied = bank.advance(k, last=k if bounds else T)
        empty_at[emptied] = k
        if bounds:
            lower[:, k], upper[:, k] = bank.bounding_boxes()
        k += 1
    return SVOBatchRun(tuple(None if e < 0 else int(e) for e in empty_at), lower, upper)


@single_threaded_blas
def run_architecture_i_many(
    nominal: Sequence[ModelSequence],
    faults: Sequence[Mapping[str, ModelSequence]],
    u: Any,
    y: Any,
    X0: Polytope,
    *,
    template: np.ndarray | None = None,
) -> list[FDIResult]:
    """:func:`run_architecture_i` (template rule, N = 1, ``stop_when_isolated=True``) for many
    records at once: every SVO of every bank in one :class:`TemplateBatch`, each bank stopped
    where :func:`run_architecture_i` stops it.

    Parameters
    ----------
    nominal : sequence of ModelSequence
        The nominal model of each record.
    faults : sequence of dict name -> ModelSequence
        The fault models of each record (the same names, in the same order, for every record).
    u : ndarray, shape (R, T, n_u)
    y : ndarray, shape (R, T+1, n_y)
        Inputs and measurements of each record.
    X0 : Polytope
        Prior set of x(0).
    template : ndarray, shape (p, n), optional
        See :class:`SetValuedObserver`.

    Returns
    -------
    list of FDIResult
        One per record, equal to what :func:`run_architecture_i` returns on it.
    """
    R = len(nominal)
    if len(faults) != R:
        raise ShapeError(f"faults: expected one dict per record ({R}), got {len(faults)}")
    names = list(faults[0]) if R else []
    if any(list(f) != names for f in faults):
        raise ModelError(f"faults: expected the same fault names {names} for every record")
    y = _arr("y", y, 3)
    u = _arr("u", u, 3)
    per = 1 + len(names)  # observers per record: nominal, then the faults
    models = [m for r in range(R) for m in [nominal[r], *(faults[r][f] for f in names)]]
    bank = TemplateBatch(
        models, np.repeat(u, per, axis=0), np.repeat(y, per, axis=0), X0, template=template
    )
    empty_at = np.where(bank.start(), 0, -1).reshape(R, per)
    det = np.full(R, -1)
    iso = np.full(R, -1)
    done = np.zeros(R, dtype=bool)
    k = 0
    while True:
        # the decisions change only where a set empties: from one such step to the next in one
        # call (TemplateBatch.advance), the same as every step
        det = np.where((det < 0) & (empty_at[:, 0] >= 0), k, det)
        live = (empty_at[:, 1:] < 0).sum(axis=1)
        found = ~done & (det >= 0) & (live == 1)
        iso[found] = k
        done |= found | ((det >= 0) & (live == 0))
        if done.all() or k == bank.T:
            break
        k, emptied = bank.advance(k + 1, np.repeat(~done, per))
        empty_at.reshape(-1)[emptied] = k
    out = []
    for r in range(R):
        e = {name: None if v < 0 else int(v) for name, v in zip(["nominal", *names], empty_at[r])}
        alive = [f for f in names if e[f] is None]
        isolated = alive[0] if iso[r] >= 0 else None
        out.append(
            FDIResult(
                "I",
                None if det[r] < 0 else int(det[r]),
                None if iso[r] < 0 else int(iso[r]),
                isolated,
                e,
            )
        )
    return out


# ----------------------------------------------------------------------------- fault models (Tables 1-2)


def _replace(model: SVOModel, **changes: Any) -> SVOModel:
    fields = {
        k: getattr(model, k) for k in ("A", "C", "B", "L", "noise", "A_unc", "B_unc", "C_unc")
    }
    fields.update(changes)
    return SVOModel(**fields)


def actuator_effectiveness_model(model: SVOModel, input_index: int, lowest: float) -> SVOModel:
    """Fault hypothesis "loss of effectiveness" of actuator ``input_index`` of ``model`` (Table 1):
    gain in [``lowest``, 1].

    The column b of B becomes b (1 + lowest)/2 + Delta b (1 - lowest)/2, |Delta| <= 1, i.e. an
    uncertain input matrix handled as a disturbance (§2). It contains the healthy plant
    (gain 1), as Architecture I requires. ``lowest = 0`` is a floating actuator.
    """
    if not 0 <= input_index < model.n_u:
        raise ModelError(f"input_index: expected 0 <= index < {model.n_u}, got {input_index}")
    if not 0.0 <= lowest <= 1.0:
        raise ModelError(f"lowest: expected a gain in [0, 1], got {lowest}")
    B = model.B.copy()
    extra = np.zeros((1,) + B.shape)
    extra[0, :, input_index] = B[:, input_index] * (1.0 - lowest) / 2.0
    B[:, input_index] *= (1.0 + lowest) / 2.0
    return _replace(model, B=B, B_unc=np.concatenate([model.B_unc * 1.0, extra]))


def sensor_bias_model(model: SVOModel, output_index: int, bound: float) -> SVOModel:
    """Fault hypothesis "biased sensor" (Table 2) of ``model``: an additive fault |q| <= ``bound`` on
    output ``output_index``,
    folded into that sensor's noise bound (how SVO #2 of §6 is built). Contains the healthy plant."""
    if not 0 <= output_index < model.n_y:
        raise ModelError(f"output_index: expected 0 <= index < {model.n_y}, got {output_index}")
    if not bound >= 0:
        raise ModelError(f"bound: expected a non-negative bias bound, got {bound}")
    noise = model.noise.copy()
    noise[output_index] += bound
    return _replace(model, noise=noise)


def dynamics_entry_model(model: SVOModel, row: int, col: int, low: float, high: float) -> SVOModel:
    """Fault hypothesis "system dynamics" (§4.3.1) of ``model``: entry A[``row``, ``col``] anywhere in
    [``low``, ``high``].

    Adds the direction ``(high - low) / 2`` times :math:`E_{rc}` (1 at ``row``, ``col``, 0
    elsewhere) to the parametric uncertainty and moves the entry to the middle of the interval. Include the healthy value in [low, high] for Architecture I.
    """
    n = model.n
    if not (0 <= row < n and 0 <= col < n):
        raise ModelError(f"row, col: expected indices in [0, {n}), got ({row}, {col})")
    if not low <= high:
        raise ModelError(f"low, high: expected low <= high, got [{low}, {high}]")
    A = model.A.copy()
    A[row, col] = (low + high) / 2.0
    E = np.zeros((1, n, n))
    E[0, row, col] = (high - low) / 2.0
    return _replace(model, A=A, A_unc=np.concatenate([model.A_unc, E]))
