r"""Sparse fault isolation: from filter residuals to a linear regression, then Lasso.

Zhang (2021), Section IV. Propositions 1 and 2 say that the updated residual
:math:`\tilde Y_k` of a Kalman (resp. Kitanidis) filter designed for :math:`\theta = 0` is
affine in :math:`\theta`:

.. math::

    \tilde Y_k = (H_k \Upsilon_k + \Phi_k) \theta + \tilde Y^0_k \qquad (6) / (26)

Stacking ``k = start .. N-1`` gives the regression :math:`\mathbf y = \mathbf X \theta + \mathbf e`
of (36)-(38) (:func:`regression_data`), solved under a sparsity assumption by the Lasso (39):

.. math::

    \hat\theta(\lambda) = \arg\min_\theta\ \frac{1}{2N} \|\mathbf X \theta - \mathbf y\|_2^2
    + \lambda \|\theta\|_1

with :math:`N` the number of *time samples* used (the paper's normalisation; scikit-learn
normalises by the number of *rows*, :math:`Np`, and we convert).

Two solvers, which must agree:

* :func:`lasso_cvxpy` - the convex programme written as is in cvxpy (readable, for teaching,
  one ``lambda`` at a time);
* :func:`lasso_path` - the exact, piecewise-linear Lasso path by the LARS-Lasso homotopy of
  Efron et al. (2004), the algorithm of scikit-learn's ``lars_path(method="lasso")``, here in
  Gram form and batched over problems (:func:`lasso_path_batch`, for Monte Carlo chunks): every
  breakpoint (every change of support) comes out, with no ``lambda`` grid. Every path returned
  satisfies the optimality (KKT) conditions to :data:`KKT_TOL` relative to ``lambda``, checked as
  exact arithmetic would (:func:`kkt_residual`), down to its stated float floor
  (:attr:`LassoPath.kkt_floor`); on a degenerate design (duplicated, scaled, zero or nearly
  collinear columns) where the homotopy's path does not, it is refined or recomputed by
  scikit-learn's ``lars_path``, :attr:`LassoPath.solver` says so, and a path nothing certifies is
  refused.

The rules for ``lambda`` below have batched forms too (:func:`flat_ranges`,
:func:`grid_flat_ranges` on a :class:`PathBatch`): a Monte Carlo chunk applies them to all its
paths at once, with the same results as one path at a time.

The paper's rule for ``lambda`` (:func:`flat_range`): take the widest range of ``lambda``
over which the *number* of non-zero components stays constant and pick its middle; then
re-estimate the selected components by least squares (:func:`diagnose`). The paper does
not say how width is measured; we offer both readings and state the choice:

* ``scale="log"`` (default): width ``log(lambda_hi / lambda_lo)``, middle the geometric mean
  ``sqrt(lambda_lo lambda_hi)`` - the reading of a ``lambda`` grid that is geometric, as the
  default grids of Matlab's ``lasso`` and scikit-learn's ``lasso_path`` are;
* ``scale="linear"``: width ``lambda_hi - lambda_lo``, middle the arithmetic mean.

Like any exploration of ``lambda``, the rule needs a bounded window: we use
``[lambda_ratio * lambda_max, lambda_max]`` with
:math:`\lambda_{\max} = \max |\mathbf X^\T \mathbf y| / N` (the first breakpoint, above which
:math:`\hat\theta = 0`) and ``lambda_ratio =`` :data:`LAMBDA_RATIO` (``1e-4``), the default window of
Matlab's ``lasso`` for more rows than unknowns. Ranges are clipped to the window; only ranges
with between 1 and ``max_size`` non-zero components (default ``m // 2``: the sparsity
assumption) are candidates, and the window ends where the support first exceeds ``max_size``. Without these bounds the log reading would favour the last
ranges near ``lambda = 0`` (nearly all components non-zero, i.e. no selection at all), whose
log-width is unbounded.

:func:`grid_flat_range` is the same rule read on a finite geometric grid of ``lambda`` values
(what "numerically exploring different values of lambda" gives, Zhang 2021, Sec. IV after (39)):
the support at each grid point is read off the exact path, the widest *run* of grid points with
constant support size wins. It tends to :func:`flat_range` (``scale="log"``) as the grid gets finer,
and misses ranges shorter than the grid step.
"""

from __future__ import annotations

import functools
import math
from dataclasses import dataclass
from typing import Any, Callable, Iterator, Literal

import numpy as np

from fdi_lib.errors import ModelError, NumericalError, ShapeError
from fdi_lib.validation import array, integer, real

__all__ = [
    "RegressionData",
    "regression_data",
    "KKT_TOL",
    "KKT_FLOOR",
    "LassoPath",
    "lasso_path",
    "kkt_residual",
    "lasso_paths",
    "lasso_path_batch",
    "PathBatch",
    "lasso_cvxpy",
    "FlatRange",
    "flat_range",
    "GridFlatRange",
    "grid_flat_range",
    "FlatRanges",
    "flat_ranges",
    "GridFlatRanges",
    "grid_flat_ranges",
    "Diagnosis",
    "diagnose",
    "least_squares_on_support",
]

Scale = Literal["log", "linear"]

#: Lower end of the ``lambda`` window that the flat-range rule explores, as a fraction of
#: ``lambda_max`` (:func:`flat_ranges`): the default window of Matlab's ``lasso`` for more rows than
#: unknowns. Paths followed for the rule alone may stop there (``lambda_min`` of :func:`lasso_path_batch`).
LAMBDA_RATIO = 1e-4
#: Largest violation of the optimality (KKT) conditions accepted on a returned path, relative to
#: ``lambda`` (:func:`kkt_residual`); a homotopy path above it is recomputed (:func:`lasso_path_batch`).
KKT_TOL = 1e-6
#: Below ``KKT_FLOOR * lambda_max`` the KKT tolerance is absolute, ``KKT_TOL * KKT_FLOOR * lambda_max``
#: (:func:`kkt_residual`; at ``lambda = 0``, the end of a full path, a relative one has no meaning).
KKT_FLOOR = 1e-6
# values of X per block of problems that lasso_path_batch scales and multiplies together (a few
# hundred kB: they stay in cache between the passes)
_BLOCK_VALUES = 2**17
# values of X per block of problems of the gradient in double-double (_residual_blocks)
_DD_BLOCK_VALUES = 1_000_000
_EPS, _TINY = np.finfo(float).eps, np.finfo(float).tiny  # (np.finfo costs a call per use)


@dataclass(frozen=True)
class RegressionData:
    """The sparse regression ``y = X theta + e`` of Zhang (2021), eqs. (36)-(38).

    Attributes
    ----------
    X : numpy.ndarray
        Stacked ``H_k Upsilon_k + Phi_k`` for ``k = start .. N-1``, shape ``(*batch, (N - start) p, m)``.
    y : numpy.ndarray
        Stacked residuals, shape ``(*batch, (N - start) p)``.

    ``X`` and ``y`` are read-only views of the residuals and signature when their layout allows
    (e.g. :func:`fdi_lib.kitanidis.residual_signature`'s), copies otherwise.
    n_samples : int
        Number of time samples ``N - start`` (the ``N`` of the Lasso normalisation (39)).
    """

    X: np.ndarray
    y: np.ndarray
    n_samples: int


def regression_data(residuals: Any, on_residual: Any, *, start: int = 1) -> RegressionData:
    """Stack residuals and their fault signature into the regression (36)-(38).

    Explained in the book: :doc:`/book/zhang2021/sparse`.

    Parameters
    ----------
    residuals : array_like
        Updated residuals ``(*batch, N, p)``: ``kalman_filter(...).updated_residuals`` (Prop. 1) or
        ``kitanidis_filter(...).residuals`` (Prop. 2). A feed-through ``J_k U_k`` (the paper's
        ``D_k u_k``, Example 2) is already removed by the filters.
    on_residual : array_like
        ``H_k Upsilon_k + Phi_k``, shape ``(*batch, N, p, m)`` (batch axes broadcast), from
        :func:`fdi_lib.kitanidis.residual_signature`.
    start : int
        First time index used. Default 1: the paper uses ``k = 1 .. N`` since ``Upsilon_0 = 0``
        (row ``k = 0`` carries no information on a state fault).

    Returns
    -------
    RegressionData

    Examples
    --------
    >>> import numpy as np
    >>> d = regression_data(np.ones((5, 2)), np.ones((5, 2, 3)))   # N = 5, p = 2, m = 3
    >>> d.X.shape, d.y.shape, d.n_samples          # rows of k = 1 .. 4 stacked
    ((8, 3), (8,), 4)
    """
    r = array(residuals, "residuals")
    S = array(on_residual, "on_residual")
    if r.ndim < 2:
        raise ShapeError(f"residuals: expected shape (..., N, p), got {r.shape}")
    if S.ndim < 3 or S.shape[-3:-1] != r.shape[-2:]:
        raise ShapeError(
            f"on_residual: expected shape (..., {r.shape[-2]}, {r.shape[-1]}, m), got {S.shape}"
        )
    N, p = r.shape[-2:]
    start = integer(start, "start", low=0, high=N - 1)
    try:
        batch = np.broadcast_shapes(r.shape[:-2], S.shape[:-3])
    except ValueError:
        raise ShapeError(
            f"residuals, on_residual: batch axes {r.shape[:-2]} and {S.shape[:-3]} do not broadcast"
        ) from None
    m = S.shape[-1]
    X = np.broadcast_to(S[..., start:, :, :], (*batch, N - start, p, m)).reshape(
        *batch, (N - start) * p, m
    )
    y = np.broadcast_to(r[..., start:, :], (*batch, N - start, p)).reshape(*batch, (N - start) * p)
    return RegressionData(
        X=X, y=y, n_samples=int(N - start)
    )  # views of the inputs when their layout allows


def _check_xy(X: Any, y: Any) -> tuple[np.ndarray, np.ndarray]:
    X = array(X, "X")
    y = array(y, "y")
    if X.ndim != 2 or X.shape[0] < 1 or X.shape[1] < 1:
        raise ShapeError(f"X: expected a non-empty matrix (rows, m), got shape {X.shape}")
    if y.shape != (X.shape[0],):
        raise ShapeError(f"y: expected shape ({X.shape[0]},), got {y.shape}")
    return X, y


def _norm(n_samples: int | None, rows: int) -> int:
    if n_samples is None:
        return rows
    return integer(n_samples, "n_samples", low=1)


@dataclass(frozen=True)
class LassoPath:
    """The exact Lasso path: ``theta_hat(lambda)`` is linear between consecutive breakpoints.

    Attributes
    ----------
    lambdas : numpy.ndarray
        Breakpoints ``lambda_0 > lambda_1 > ... >= 0`` in the normalisation of (39), shape ``(K+1,)``;
        ``lambda_0 = max |X^T y| / N``: above it ``theta_hat = 0``.
    coefs : numpy.ndarray
        ``theta_hat`` at each breakpoint, shape ``(m, K+1)``.
    n_samples : int
        The ``N`` of (39).
    solver : str
        What computed the path: ``"homotopy"`` (this module's batched homotopy),
        ``"homotopy-refined"`` (its coefficients refined on its own supports after the KKT check
        failed), ``"sklearn-fallback"`` (scikit-learn's ``lars_path``, after the homotopy's path
        failed the KKT check; see :func:`lasso_path_batch`), or ``"given"`` (a path built by hand).
    kkt_residual : float
        Largest violation of the optimality conditions along the path, relative to ``lambda``
        (:func:`kkt_residual`, or an upper bound of it: the batched screen's rounding bound
        included); at most :data:`KKT_TOL` for a computed path; NaN when not checked.
    kkt_floor : float
        The float floor of the check (the largest ``floor_i`` of :func:`kkt_residual`): below this
        ``lambda`` float64 coefficients cannot satisfy the conditions to ``KKT_TOL lambda``
        (rounding the exact solution moves the gradient by more), and the path is checked to that
        representation limit instead. NaN when not checked.
    """

    lambdas: np.ndarray
    coefs: np.ndarray
    n_samples: int
    solver: str = "given"
    kkt_residual: float = float("nan")
    kkt_floor: float = float("nan")

    def coef(self, lam: float) -> np.ndarray:
        """``theta_hat(lambda)``, shape ``(m,)``, by linear interpolation between breakpoints (exact)."""
        lam = float(lam)
        if not np.isfinite(lam) or lam < 0:
            raise ModelError(f"lam: expected a finite lambda >= 0, got {lam!r}")
        a = self.lambdas
        if lam >= a[0]:
            return np.zeros(self.coefs.shape[0])
        if lam <= a[-1]:
            return self.coefs[:, -1].copy()
        i = int(np.searchsorted(-a, -lam, side="right")) - 1  # a[i] >= lam > a[i+1]
        t = (a[i] - lam) / (a[i] - a[i + 1])
        return (1 - t) * self.coefs[:, i] + t * self.coefs[:, i + 1]

    @functools.cached_property
    def _support_matrix(self) -> np.ndarray:
        return _activity(self.coefs.T[None])[1][0].T  # (m, K), computed once per path

    def _active(self) -> np.ndarray:
        return self._support_matrix

    def interval_supports(self) -> list[np.ndarray]:
        """Support (indices of non-zero components) on each open interval ``(lambda_{i+1}, lambda_i)``."""
        act = self._active()
        return [np.flatnonzero(act[:, i]) for i in range(act.shape[1])]

    def support_sizes(self) -> np.ndarray:
        """Number of non-zero components on each interval ``(lambda_{i+1}, lambda_i)``, shape ``(K,)``."""
        return self._active().sum(axis=0)


def _activity(coefs: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Zero tolerance ``(B,)`` and support on each interval ``(B, S-1, m)`` of paths ``coefs`` ``(B, S, m)``.

    A coefficient counts as zero below ``1e-12 max(1, max |theta_hat|)`` (per path); the support of
    an interval is read at the mean of its two end breakpoints.
    """
    tol = 1e-12 * np.maximum(1.0, np.abs(coefs).max(axis=(1, 2), initial=0.0))
    mid = 0.5 * (coefs[:, :-1] + coefs[:, 1:])
    return tol, np.abs(mid) > tol[:, None, None]


@dataclass(frozen=True)
class PathBatch:
    """Exact Lasso paths of a batch of problems, padded to a common number of breakpoints.

    The batched form of :class:`LassoPath`, for Monte Carlo chunks: :func:`flat_ranges` and
    :func:`grid_flat_ranges` apply the rules for ``lambda`` to all the paths at once.

    Attributes
    ----------
    lambdas : numpy.ndarray
        ``(B, S)``: the breakpoints of path ``b`` in ``lambdas[b, :n_points[b]]``, then ``-inf``.
    coefs : numpy.ndarray
        ``(B, S, m)``: ``theta_hat`` at the breakpoints, then zeros.
    n_points : numpy.ndarray
        ``(B,)`` numbers of breakpoints (``K + 1`` of each :class:`LassoPath`).
    n_samples : int
        The ``N`` of (39).
    solver : numpy.ndarray
        ``(B,)`` strings: :attr:`LassoPath.solver` of each path.
    kkt_residual : numpy.ndarray
        ``(B,)``: :attr:`LassoPath.kkt_residual` of each path.
    kkt_floor : numpy.ndarray
        ``(B,)``: :attr:`LassoPath.kkt_floor` of each path.
    """

    lambdas: np.ndarray
    coefs: np.ndarray
    n_points: np.ndarray
    n_samples: int
    solver: np.ndarray
    kkt_residual: np.ndarray
    kkt_floor: np.ndarray

    def __len__(self) -> int:
        return int(self.n_points.size)

    @functools.cached_property
    def _activity(self) -> tuple[np.ndarray, np.ndarray]:
        return _activity(self.coefs)  # computed once per batch, shared by the rules

    @functools.cached_property
    def _sizes(self) -> np.ndarray:
        """Support size on each interval ``(B, S-1)`` (of :attr:`_activity`), -1 in the padding;
        computed once per batch, shared by the rules."""
        S = self.lambdas.shape[1]
        valid = np.arange(S - 1) < (self.n_points - 1)[:, None]
        return np.where(valid, self._activity[1].sum(axis=2), -1)

    def path(self, b: int) -> LassoPath:
        """Path ``b`` as a :class:`LassoPath`."""
        k = int(self.n_points[b])
        return LassoPath(
            lambdas=self.lambdas[b, :k].copy(),
            coefs=self.coefs[b, :k].T.copy(),
            n_samples=self.n_samples,
            solver=str(self.solver[b]),
            kkt_residual=float(self.kkt_residual[b]),
            kkt_floor=float(self.kkt_floor[b]),
        )

    def paths(self) -> list[LassoPath]:
        """All the paths, as :class:`LassoPath` objects."""
        return [self.path(b) for b in range(len(self))]

    def has_interval_support(self, support: Any) -> np.ndarray:
        """Whether ``support[b]`` (``(B, m)`` booleans) is the support of some interval of path ``b``, ``(B,)``.

        The supports are those of :meth:`LassoPath.interval_supports`.
        """
        mask = np.asarray(support, dtype=bool)
        if mask.shape != (len(self), self.coefs.shape[2]):
            raise ShapeError(
                f"support: expected shape {(len(self), self.coefs.shape[2])}, got {mask.shape}"
            )
        _, act = self._activity
        valid = np.arange(act.shape[1]) < (self.n_points - 1)[:, None]
        return np.any(valid & np.all(act == mask[:, None, :], axis=2), axis=1)

    @classmethod
    def of(cls, paths: Any) -> "PathBatch":
        """The batch of a sequence of :class:`LassoPath` (same number ``m`` of components)."""
        paths = list(paths)
        if not paths or not all(isinstance(p, LassoPath) for p in paths):
            raise ModelError(
                f"paths: expected a non-empty sequence of LassoPath, got {paths!r:.80}"
            )
        m = paths[0].coefs.shape[0]
        if any(p.coefs.shape[0] != m for p in paths):
            raise ShapeError(
                f"paths: expected paths of {m} components each, got "
                f"{sorted({p.coefs.shape[0] for p in paths})}"
            )
        n_points = np.array([p.lambdas.size for p in paths])
        S = int(n_points.max())
        lambdas = np.full((len(paths), S), -np.inf)
        coefs = np.zeros((len(paths), S, m))
        for b, p in enumerate(paths):
            lambdas[b, : p.lambdas.size] = p.lambdas
            coefs[b, : p.lambdas.size] = p.coefs.T
        return cls(
            lambdas=lambdas,
            coefs=coefs,
            n_points=n_points,
            n_samples=paths[0].n_samples,
            solver=np.array([p.solver for p in paths], dtype=object),
            kkt_residual=np.array([p.kkt_residual for p in paths]),
            kkt_floor=np.array([p.kkt_floor for p in paths]),
        )


def lasso_path(
    X: Any,
    y: Any,
    *,
    n_samples: int | None = None,
    lambda_min: float = 0.0,
    max_size: int | None = None,
) -> LassoPath:
    """Exact Lasso path of (39) by the LARS-Lasso homotopy (Efron et al. 2004).

    The homotopy follows ``theta_hat(lambda)`` from ``lambda_max`` down, from one breakpoint (a
    change of support) to the next, with the drop rule that turns LARS into the Lasso: it is
    exact at every breakpoint, which a hand-written ``lambda`` grid would not be. It is the
    algorithm of scikit-learn's ``lars_path(method="lasso")`` (the tests check that both give
    the same breakpoints), written here batched over problems (:func:`lasso_path_batch`) so that a
    Monte Carlo chunk follows all its paths at once. Every path returned has passed the check of
    the optimality conditions (:func:`kkt_residual`, at most :data:`KKT_TOL` relative to
    ``lambda``); a homotopy path that fails it (a degenerate design: duplicated, scaled, zero or
    nearly collinear columns) is recomputed by scikit-learn's ``lars_path``, and
    :attr:`LassoPath.solver` says which.

    Explained in the book: :doc:`/book/zhang2021/sparse`.

    Parameters
    ----------
    X : array_like
        ``(rows, m)``.
    y : array_like
        ``(rows,)``.
    n_samples : int, optional
        The ``N`` of the ``1/(2N)`` in (39); default ``rows`` (scikit-learn's convention).
    lambda_min : float
        Stop the path at this ``lambda`` (as a fraction of ``lambda_max``), e.g. the lower end of the
        window explored by :func:`flat_range`; the path is exact down to it. Default 0: the full path
        (which ends earlier at an exact fit, ``y`` in the span of the columns: once ``lambda`` falls
        to ``1e-12 lambda_max``, only rounding is left to follow).
    max_size : int, optional
        Also stop at the end of the first interval where the support has more than ``max_size``
        components (the other end of the window of :func:`flat_range`); the path is exact up to
        there. Default: no such stop.

    Returns
    -------
    LassoPath

    Raises
    ------
    NumericalError
        When no path passes the KKT check (neither the homotopy's nor scikit-learn's).

    Examples
    --------
    >>> import numpy as np
    >>> rng = np.random.default_rng(0)
    >>> X = rng.standard_normal((40, 6))
    >>> y = X @ [0.0, 2.0, 0.0, 0.0, -1.5, 0.0] + 0.1 * rng.standard_normal(40)
    >>> path = lasso_path(X, y)
    >>> [sorted(map(int, np.flatnonzero(c))) for c in path.coefs[:, 1:3].T]  # breakpoints 1, 2
    [[1], [1, 4]]
    >>> path.kkt_residual <= KKT_TOL
    True
    """
    X, y = _check_xy(X, y)  # checked once: lasso_path_batch's own checks are the same
    rule = _path_rule(X.shape[0], n_samples, lambda_min, max_size)
    return _path_batch(X[None], y[None], *rule).path(0)


def lasso_paths(
    X: Any,
    y: Any,
    *,
    n_samples: int | None = None,
    lambda_min: float = 0.0,
    max_size: int | None = None,
) -> list[LassoPath]:
    """Exact Lasso paths of a batch of problems, as :func:`lasso_path` for each.

    Explained in the book: :doc:`/book/zhang2021/sparse`.

    Parameters
    ----------
    X, y, n_samples, lambda_min, max_size
        As in :func:`lasso_path_batch`, which computes the paths.

    Returns
    -------
    list of LassoPath
        One per problem, each identical to :func:`lasso_path` of that problem alone.

    Examples
    --------
    >>> import numpy as np
    >>> rng = np.random.default_rng(0)
    >>> X = rng.standard_normal((40, 6))
    >>> y = X @ [0.0, 2.0, 0.0, 0.0, -1.5, 0.0] + 0.1 * rng.standard_normal(40)
    >>> paths = lasso_paths(np.stack([X, X]), np.stack([y, -y]))
    >>> bool(np.array_equal(paths[0].lambdas, lasso_path(X, y).lambdas))
    True
    >>> bool(np.allclose(paths[1].coefs, -paths[0].coefs))     # the path of -y is minus that of y
    True
    """
    return lasso_path_batch(
        X, y, n_samples=n_samples, lambda_min=lambda_min, max_size=max_size
    ).paths()


def lasso_path_batch(
    X: Any,
    y: Any,
    *,
    n_samples: int | None = None,
    lambda_min: float = 0.0,
    max_size: int | None = None,
) -> PathBatch:
    """Exact Lasso paths of a batch of problems, followed together, as a :class:`PathBatch`.

    Explained in the book: :doc:`/book/zhang2021/sparse`.

    Parameters
    ----------
    X : array_like
        ``(B, rows, m)``, e.g. :attr:`RegressionData.X` of a batch of trials.
    y : array_like
        ``(B, rows)``.
    n_samples : int, optional
        The ``N`` of (39); default ``rows``.
    lambda_min : float
        Lower end of the path as a fraction of each problem's ``lambda_max`` (see :func:`lasso_path`).
    max_size : int, optional
        Stop each path at the end of its first interval with more than ``max_size`` components.

    Returns
    -------
    PathBatch
        Path ``b`` (``.path(b)``) is identical to :func:`lasso_path` of problem ``b`` alone.

    Raises
    ------
    NumericalError
        Naming the first problem whose path passes the KKT check neither from the homotopy nor
        from scikit-learn's ``lars_path`` (see :func:`lasso_path`).

    Notes
    -----
    Every path is checked against the optimality conditions (:func:`kkt_residual`): the whole
    batch at once in the Gram form of the homotopy (one batched product and a few passes over
    the breakpoints), with a bound of that form's rounding *added* to each violation (the screen
    can fail a good path, never pass a bad one), then, at the breakpoints the screen does not
    pass, from ``X`` and ``y``: the residual in double-double and the bound of the rest of the
    gradient's rounding added (it passes where nearly collinear columns defeat the screen), and,
    where that does not pass either, the gradient in double-double, nothing subtracted. A path
    that fails is recomputed alone: its coefficients refined on its own supports
    (``solver="homotopy-refined"``) and by scikit-learn's ``lars_path(method="lasso")``
    (``solver="sklearn-fallback"``: on the whole design, then, if that path fails too, with its
    duplicated or scaled columns merged and its zero columns removed); the one with the smaller
    residual is kept, and a path that no route brings to :data:`KKT_TOL` is a NumericalError.

    Examples
    --------
    >>> import numpy as np
    >>> rng = np.random.default_rng(0)
    >>> X = rng.standard_normal((40, 6))
    >>> y = X @ [0.0, 2.0, 0.0, 0.0, -1.5, 0.0] + 0.1 * rng.standard_normal(40)
    >>> batch = lasso_path_batch(np.stack([X, X]), np.stack([y, 2 * y]))
    >>> bool(np.array_equal(batch.path(0).coefs, lasso_path(X, y).coefs))
    True
    >>> bool(np.allclose(batch.path(1).lambdas, 2 * batch.path(0).lambdas))
    True
    """
    X = array(X, "X", ndim=3)
    y = array(y, "y")
    if y.shape != X.shape[:2]:
        raise ShapeError(f"y: expected shape {X.shape[:2]}, got {y.shape}")
    return _path_batch(X, y, *_path_rule(X.shape[1], n_samples, lambda_min, max_size))


def _path_rule(
    rows: int, n_samples: int | None, lambda_min: float, max_size: int | None
) -> tuple[int, float, int | None]:
    """The checked ``n_samples`` (``N``), ``lambda_min`` and ``max_size`` of :func:`lasso_path_batch`
    for problems of ``rows`` rows."""
    N = _norm(n_samples, rows)
    lambda_min = real(
        lambda_min, "lambda_min", low=0.0, high=1.0, high_open=True, what="a fraction of lambda_max"
    )
    if max_size is not None:
        max_size = integer(max_size, "max_size", low=1)
    return N, lambda_min, max_size


def _path_batch(
    X: np.ndarray, y: np.ndarray, N: int, lambda_min: float, max_size: int | None
) -> PathBatch:
    """:func:`lasso_path_batch` of checked arguments (``X`` ``(B, rows, m)`` and ``y`` ``(B, rows)``
    finite float arrays, ``N``, ``lambda_min`` and ``max_size`` from :func:`_path_rule`)."""
    rows = X.shape[1]
    # Exact rescaling X = sx X', y = sy y' per problem: theta = (sy / sx) theta', lambda = sx sy lambda'
    # (keeps the homotopy's tolerances meaningful whatever the units, e.g. gas flows ~1e5). sx and sy
    # are the powers of 2 nearest to the RMS of X and y: exact, so an exact tie stays one.
    # Computed from the scaled X and y: the raw squares would overflow beyond 1e154 and underflow
    # below 1e-154 (a design of 1e-160 had a zero Gram matrix).
    sx, sy, ys, Gram, Xy = _scaled_problems(X, y)
    B = X.shape[0]
    c_min = lambda_min * np.abs(Xy).max(axis=1)
    with np.errstate(
        all="ignore"
    ):  # a singular step (a degenerate design) gives NaN: the KKT check rejects it
        levels, coefs, n_points = _homotopy(Gram, Xy, c_min, max_size)
    S = int(n_points.max())
    levels, coefs = levels[:, :S], coefs[:, :S]
    # KKT check of every path: a batched screen with the Gram matrix (one product; the bound of its
    # rounding is added to the violation, so it can fail a good path but never pass a bad
    # one), then,
    # for the paths it does not pass, the check in double-double from X and y (nothing subtracted),
    # then the coefficients refined on the path's own supports, then scikit-learn's lars_path.
    ynorm = np.sqrt(np.einsum("br,br->b", ys, ys))
    g, slack, terms, point_res, point_floor = _kkt_screen(
        Gram, Xy, ynorm, levels, coefs, n_points, rows
    )
    # the exact check where the screen does not pass (its bound holds elsewhere): all such
    # breakpoints of the batch at once, from the scaled X of their problems (X / sx, formed only
    # for them, where used, divided in the gathered copy: a new array for the quotient costs
    # several times the division)
    broken = (point_res == np.inf).any(axis=1)  # a NaN (a singular step or a cycle): recomputed
    checked = np.flatnonzero((point_res > KKT_TOL).any(axis=1))
    if checked.size:  # (a batch that the screen passes skips the call's set-up)
        point_res[checked] = _kkt_where_screen_fails(
            lambda p: np.divide(Xp := X[checked[p]], sx[checked[p], None, None], out=Xp),
            ys[checked],
            g[checked],
            slack[checked],
            levels[checked],
            coefs[checked],
            tuple(t[checked] for t in terms),
            point_res[checked],
        )
    kkt, floor = np.maximum(point_res.max(axis=1), 0.0), point_floor.max(axis=1)
    solver = np.full(B, "homotopy", dtype=object)
    levels, coefs = _recompute_failed(
        X, sx, ys, broken, c_min, max_size, levels, coefs, n_points, kkt, floor, solver
    )
    S = levels.shape[1]
    # the correlation level c is rows * alpha (scikit-learn's 1/(2 rows)); (39) has 1/(2N): lambda = c / N
    with np.errstate(over="ignore", invalid="ignore"):  # checked just below
        lam = levels * (sx * sy / N)[:, None]
        th = coefs * (sy / sx)[:, None, None]  # zeros in the padding
    on_path = np.arange(S) < n_points[:, None]
    bad = ~(np.isfinite(lam) | ~on_path).all(axis=1) | ~np.isfinite(th).all(axis=(1, 2))
    if bad.any():
        b = int(np.flatnonzero(bad)[0])
        raise NumericalError(
            f"X, y (problem {b}): the Lasso path is not representable in float64 (lambda_max "
            f"or a coefficient overflows: RMS of X {sx[b]:.3g}, of y {sy[b]:.3g}); expected a "
            f"design and data scaled towards 1"
        )
    lam[~on_path] = -np.inf  # padding
    return PathBatch(
        lambdas=lam,
        coefs=th,
        n_points=n_points,
        n_samples=N,
        solver=solver,
        kkt_residual=kkt,
        kkt_floor=floor * (sx * sy / N),
    )


def _recompute_failed(
    X: np.ndarray,
    sx: np.ndarray,
    ys: np.ndarray,
    broken: np.ndarray,
    c_min: np.ndarray,
    max_size: int | None,
    levels: np.ndarray,
    coefs: np.ndarray,
    n_points: np.ndarray,
    kkt: np.ndarray,
    floor: np.ndarray,
    solver: np.ndarray,
) -> tuple[np.ndarray, np.ndarray]:
    """The paths of :func:`_path_batch` that fail the KKT check (``kkt > KKT_TOL``), recomputed
    alone (see :func:`lasso_path_batch`): ``X / sx`` and ``ys`` are the scaled problems,
    ``broken`` the paths with a NaN. ``n_points``, ``kkt``, ``floor``, ``solver`` and
    ``coefs`` are updated in place; returns ``levels`` and ``coefs``, padded to the longest path."""
    S = levels.shape[1]
    fixed = []
    for b in np.flatnonzero(kkt > KKT_TOL):  # degenerate or ill-conditioned designs
        Xb, yb, k = X[b] / sx[b], ys[b], n_points[b]
        if broken[b]:
            fixed.append((b, *_lars_fallback(Xb, yb, float(c_min[b]), max_size, b, float(kkt[b]))))
            continue
        # recomputed: by lars_path (stable Cholesky updates), and the homotopy's path with
        # its coefficients
        # refined on its own supports; the one with the smaller residual, refused when both fail
        refined = _refine(Xb, yb, levels[b, :k], coefs[b, :k])
        res, fl = _kkt_path(Xb, yb, levels[b, :k], refined)
        try:
            lars = _lars_fallback(Xb, yb, float(c_min[b]), max_size, b, float(kkt[b]))
        except NumericalError as error:
            if res > KKT_TOL:
                raise NumericalError(
                    f"{error} (and by {res:.3g} lambda with the homotopy's path refined)"
                ) from None
            lars = None
        if lars is None or res < lars[2]:
            coefs[b, :k], kkt[b], floor[b], solver[b] = refined, res, fl, "homotopy-refined"
        else:
            fixed.append((b, *lars))
    if fixed:
        S = max(S, *(lev.size for _, lev, _, _, _ in fixed))
        levels = np.pad(levels, ((0, 0), (0, S - levels.shape[1])))
        coefs = np.pad(coefs, ((0, 0), (0, S - coefs.shape[1]), (0, 0)))
        for b, lev, co, res, fl in fixed:
            levels[b], coefs[b] = 0.0, 0.0
            levels[b, : lev.size], coefs[b, : lev.size] = lev, co
            n_points[b], kkt[b], floor[b], solver[b] = lev.size, res, fl, "sklearn-fallback"
    return levels, coefs


def _scaled_problems(X: np.ndarray, y: np.ndarray) -> tuple[np.ndarray, ...]:
    """The exact rescaling of :func:`lasso_path_batch`'s problems ``X`` ``(B, rows, m)``, ``y``
    ``(B, rows)`` and their Gram form: ``sx``, ``sy`` ``(B,)`` (:func:`_pow2_rms` of each problem's
    ``X`` and ``y``), ``ys = y / sy``, and, for ``Xs = X / sx``, ``Gram = Xs^T Xs`` ``(B, m, m)``
    and ``Xs^T ys`` ``(B, m)``. Computed a few problems at a time, while their ``X`` and ``Xs`` are
    in cache (``Xs`` is not kept; an ``X`` whose problems are not contiguous, e.g. the regression
    of :func:`fdi_lib.kitanidis.residual_signature`'s stacked realisations, is gathered into the
    buffer first); each problem's values are those of the whole batch at once (the same
    operations on its rows)."""
    B, rows, m = X.shape
    sy = _pow2_rms(y)
    ys = y / sy[:, None]
    sx, Gram, Xy = np.empty(B), np.empty((B, m, m)), np.empty((B, m))
    block = max(1, _BLOCK_VALUES // (rows * m))
    buf = np.empty((min(block, B), rows, m))
    for b0 in range(0, B, block):
        sl = slice(b0, b0 + block)
        Xb = X[sl]
        if not Xb.flags.c_contiguous:  # gathered into the buffer, then scaled there
            Xb = buf[: Xb.shape[0]]
            Xb[...] = X[sl]
        sx[sl] = _pow2_rms(Xb.reshape(-1, rows * m))
        Xs = _divide_pow2(Xb, sx[sl, None, None], out=buf[: sx[sl].size])
        np.matmul(Xs.transpose(0, 2, 1), Xs, out=Gram[sl])
        Xy[sl] = np.einsum("bri,br->bi", Xs, ys[sl])
    return sx, sy, ys, Gram, Xy


def kkt_residual(X: Any, y: Any, path: "LassoPath") -> float:
    """Largest violation of the Lasso optimality (KKT) conditions of (39) along ``path``, relative to ``lambda``.

    ``theta`` is the Lasso solution at ``lambda`` if and only if the gradient
    ``g = X^T (y - X theta) / N`` has ``|g_j| <= lambda`` for every ``j`` and ``g_j = lambda sign(theta_j)``
    where ``theta_j != 0``. The path is linear between breakpoints, so checking both ends of each
    interval checks all of it. At each breakpoint ``lambda_i`` and for each ``j``, the violation is
    ``|g_j| - lambda_i``, or ``|g_j - sigma lambda_i|`` when ``theta_j`` has the sign ``sigma`` at
    ``lambda_i`` or on one of the two intervals next to it (supports and signs as
    :meth:`LassoPath.interval_supports` reads them; a sign change across an interval thus counts
    as ``|g_j| + lambda_i``).

    The gradient is computed as an independent check in exact rational arithmetic would: in
    double-double arithmetic (error-free products and sums), with an error below ``1e-25`` of ``max
    |X^T y|`` on the tests' designs, and no rounding allowance is subtracted. The violation is
    divided by ``max(lambda_i, KKT_FLOOR lambda_0, floor_i)``, where ``floor_i = eps/2 max_j sum_k
    |(X^T X)_jk theta_k| / (N KKT_TOL)`` is the *float floor* at breakpoint ``i``: rounding the
    exact solution to float64 moves the gradient by up to ``KKT_TOL floor_i``, so below ``floor_i``
    no float64 path can satisfy the conditions to ``KKT_TOL lambda``, and the check there is to that
    representation limit (:attr:`LassoPath.kkt_floor` states the largest ``floor_i`` of a path). It
    is 0 for a path exact to rounding, ``inf`` for a path with a NaN.

    :func:`lasso_path_batch` checks every path it returns and stores the residual in
    :attr:`LassoPath.kkt_residual`; it is at most :data:`KKT_TOL`.

    Explained in the book: :doc:`/book/zhang2021/sparse`.

    Parameters
    ----------
    X, y : array_like
        The problem of ``path``: ``(rows, m)``, ``(rows,)``.
    path : LassoPath
        Its ``n_samples`` is the ``N`` of (39).

    Returns
    -------
    float

    Examples
    --------
    >>> import numpy as np
    >>> rng = np.random.default_rng(0)
    >>> X = rng.standard_normal((40, 6))
    >>> y = X @ [0.0, 2.0, 0.0, 0.0, -1.5, 0.0] + 0.1 * rng.standard_normal(40)
    >>> path = lasso_path(X, y)
    >>> kkt_residual(X, y, path) <= KKT_TOL
    True
    >>> wrong = LassoPath(path.lambdas, 1.1 * path.coefs, path.n_samples)
    >>> kkt_residual(X, y, wrong) > KKT_TOL                # scaled coefficients are not optimal
    True
    """
    X, y = _check_xy(X, y)
    if not isinstance(path, LassoPath) or path.coefs.shape[0] != X.shape[1]:
        raise ModelError(f"path: expected a LassoPath of {X.shape[1]} components, got {path!r:.80}")
    # exact power-of-2 rescaling (the error-free products need |entries| well below 1e300)
    sx, sy = _pow2_rms(X.reshape(1, -1))[0], _pow2_rms(y[None])[0]
    with np.errstate(over="ignore", invalid="ignore"):
        levels = path.lambdas * (path.n_samples / (sx * sy))
        coefs = path.coefs.T * (sx / sy)
    return _kkt_direct(X / sx, y / sy, levels, coefs)[0]


def _split(
    a: np.ndarray, out: tuple[np.ndarray, np.ndarray] | None = None
) -> tuple[np.ndarray, np.ndarray]:
    """Dekker's split ``a = hi + lo`` into halves of 26 bits (so that ``hi * hi`` is exact), into
    the buffers ``out`` if given."""
    hi, lo = (np.empty_like(a), np.empty_like(a)) if out is None else out
    np.multiply(a, 134217729.0, out=hi)  # c = (2^27 + 1) a
    np.subtract(hi, a, out=lo)
    np.subtract(hi, lo, out=hi)  # hi = c - (c - a)
    return hi, np.subtract(a, hi, out=lo)


def _product_error(a: tuple[np.ndarray, np.ndarray], b: np.ndarray, p: np.ndarray) -> np.ndarray:
    """``a b - p`` exactly, for ``p = fl(a b)``, ``a`` given by its split (Dekker's TwoProduct)."""
    ah, al = a
    bh, bl = _split(b)
    return ((ah * bh - p) + ah * bl + al * bh) + al * bl


def _two_sum(a: np.ndarray, b: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """``s = fl(a + b)`` and ``a + b - s`` exactly (Knuth's TwoSum)."""
    s = a + b
    z = s - a
    return s, (a - (s - z)) + (b - z)


def _gradient_dd(X: np.ndarray, y: np.ndarray, coefs: np.ndarray) -> np.ndarray:
    """``X_b^T (y_b - X_b theta_b)`` for each row ``theta_b`` of ``coefs`` (double-double).

    ``X`` is ``(P, rows, m)`` and ``y`` ``(P, rows)`` (one problem per row of ``coefs``), or
    ``(rows, m)`` and ``(rows,)`` (one problem for all). The residual ``y - X theta`` is accumulated
    with error-free products and sums (Ogita, Rump and Oishi's Dot2) and kept as an unevaluated sum
    ``s + e``, then ``X^T (s + e)`` is summed over the rows with error-free products and a pairwise
    tree of error-free sums. The result is as accurate as if computed in about twice the float64
    precision, then rounded: its error is of the order of ``eps^2`` times the sums of absolute
    values, not ``eps`` (no cancellation between large coefficients of nearly collinear columns
    survives). Processed in blocks of ``coefs`` rows.
    """
    out = np.empty(coefs.shape)
    for sl, Xb, s, e in _residual_blocks(X, y, coefs):
        XT = Xb.transpose(0, 2, 1)
        P = XT * s[:, None, :]  # (P, m, rows)
        E = _product_error(_split(XT), s[:, None, :], P) + XT * e[:, None, :]
        while P.shape[2] > 1:
            if P.shape[2] % 2:
                P = np.concatenate([P, np.zeros(P.shape[:2] + (1,))], axis=2)
                E = np.concatenate([E, np.zeros(E.shape[:2] + (1,))], axis=2)
            P, err = _two_sum(P[:, :, 0::2], P[:, :, 1::2])
            E = E[:, :, 0::2] + E[:, :, 1::2] + err
        out[sl] = P[:, :, 0] + E[:, :, 0]
    return out


def _residual_blocks(X: np.ndarray, y: np.ndarray, coefs: np.ndarray) -> Iterator[tuple[Any, ...]]:
    """The residuals ``y_b - X_b theta_b`` of :func:`_gradient_dd` (its first stage), in blocks of
    ``coefs`` rows: for each block, its slice of the rows of ``coefs``, its ``X`` ``(1 or P, rows,
    m)`` and the residuals as unevaluated sums ``s + e`` ``(P, rows)`` (Ogita, Rump and Oishi's
    Dot2: ``|fl(s + e) - r| <= eps/2 |r| + gamma_(m+1)^2 (|y| + |X| |theta|)``, ``gamma_n = n
    (eps/2) / (1 - n eps/2)``). A loop over the columns of ``X``, each copied and split
    (:func:`_split`) where it is used, in cache (rather than a transposed copy and split of the
    whole block before the loop: the same values, several times the memory traffic)."""
    X = X[None] if X.ndim == 2 else X
    y = y[None] if y.ndim == 1 else y
    rows, m = X.shape[1:]
    block = max(1, _DD_BLOCK_VALUES // (rows * m))
    for b0 in range(0, coefs.shape[0], block):
        c = coefs[b0 : b0 + block]
        Xb = X if X.shape[0] == 1 else X[b0 : b0 + block]
        XT = Xb.transpose(0, 2, 1)  # (1 or P, m, rows), a view
        yb = y if y.shape[0] == 1 else y[b0 : b0 + block]
        s = np.array(np.broadcast_to(yb, (c.shape[0], rows)))
        e = np.zeros_like(s)
        # s, err = _two_sum(s, -p) and e += err - _product_error(...) for p = X_k theta_k, the same
        # operations in the same order, into buffers kept across the columns (a new array of
        # this size per operation costs more than the operation)
        p, b, s2, z, err, u, v = (np.empty_like(s) for _ in range(7))
        # column k of X (copied contiguous: elementwise, the same values) and its split
        xk, ah, al = (np.empty(XT.shape[::2]) for _ in range(3))
        th, tl = _split(c)
        for k in range(m):
            t = c[:, k, None]
            np.copyto(xk, XT[:, k])
            _split(xk, out=(ah, al))
            np.multiply(xk, t, out=p)
            np.negative(p, out=b)
            np.add(s, b, out=s2)  # _two_sum(s, b): s2 = fl(s + b), err = s + b - s2
            np.subtract(s2, s, out=z)
            np.subtract(s2, z, out=u)
            np.subtract(s, u, out=u)
            np.subtract(b, z, out=z)
            np.add(u, z, out=err)
            s, s2 = s2, s
            bh, bl = th[:, k, None], tl[:, k, None]  # _product_error((ah, al), t, p)
            np.multiply(ah, bh, out=u)
            np.subtract(u, p, out=u)
            np.multiply(ah, bl, out=v)
            np.add(u, v, out=u)
            np.multiply(al, bh, out=v)
            np.add(u, v, out=u)
            np.multiply(al, bl, out=v)
            np.add(u, v, out=u)
            np.subtract(err, u, out=err)
            np.add(e, err, out=e)
        yield slice(b0, b0 + c.shape[0]), Xb, s, e


def _gradient_bounded(
    X: np.ndarray, y: np.ndarray, coefs: np.ndarray
) -> tuple[np.ndarray, np.ndarray]:
    """``X_b^T (y_b - X_b theta_b)`` for each row of ``coefs`` (shapes of :func:`_gradient_dd`) and a
    bound of its error ``(P,)``: the residual in double-double (:func:`_residual_blocks`), rounded,
    then its product with ``X^T`` in float64.

    Between the Gram-form screen and the gradient in double-double: where the columns are nearly
    collinear (large coefficients that cancel), the screen's bound, which grows with ``|X|^T |X|
    |theta|``, cannot pass a breakpoint; this one grows with ``|X|^T |r|`` only (the residual,
    which the first stage computes without cancellation): ``|fl(X_j^T fl(r)) - X_j^T r| <=
    (gamma_rows + eps/2 (1 + gamma_rows)) (|X|^T |fl(r)|)_j + (1 + gamma_rows) gamma_(m+1)^2
    (|X|^T (|y| + |X| |theta|))_j``, bounded here by ``2 eps (rows + 2)`` and ``2 (eps (m +
    2))^2`` times those sums (twice the bound or more). It costs the first stage of
    :func:`_gradient_dd` (about a third of it) and two products with ``|X|^T``."""
    Xd = X[None] if X.ndim == 2 else X
    rows, m = Xd.shape[1:]
    eps = _EPS
    g, slack = np.empty(coefs.shape), np.empty(coefs.shape[0])
    for sl, Xb, s, e in _residual_blocks(X, y, coefs):
        r = s + e
        absX = np.abs(Xb)
        yb = np.abs(y[None] if y.ndim == 1 else y)
        yb = yb if yb.shape[0] == 1 else yb[sl]
        if Xb.shape[0] == 1:  # one X for every row of coefs: matrix products
            g[sl] = r @ Xb[0]
            big = (yb + np.abs(coefs[sl]) @ absX[0].T) @ absX[0]
            small = np.abs(r) @ absX[0]
        else:
            g[sl] = np.einsum("pri,pr->pi", Xb, r)
            big = np.einsum(
                "pri,pr->pi", absX, yb + np.einsum("prk,pk->pr", absX, np.abs(coefs[sl]))
            )
            small = np.einsum("pri,pr->pi", absX, np.abs(r))
        slack[sl] = (2 * eps * (rows + 2) * small + 2 * (eps * (m + 2)) ** 2 * big).max(axis=1)
    return g, slack


def _gradient_exact(
    X: np.ndarray, y: np.ndarray, coefs: np.ndarray
) -> tuple[np.ndarray, np.ndarray]:
    """:func:`_gradient_dd` with a zero error bound (the form of :func:`_gradient_bounded`)."""
    return _gradient_dd(X, y, coefs), np.zeros(coefs.shape[0])


def _kkt_where_screen_fails(
    design: Callable[[np.ndarray], np.ndarray],
    y: np.ndarray,
    g: np.ndarray,
    slack: np.ndarray,
    levels: np.ndarray,
    coefs: np.ndarray,
    terms: tuple[np.ndarray, ...],
    point_res: np.ndarray,
) -> np.ndarray:
    """The per-breakpoint residuals of :func:`_kkt` after the screen (:func:`_kkt_screen`'s ``g``,
    ``slack`` and ``point_res``, updated in place, and ``terms``), its failures checked again: with
    the gradient from the residual in double-double and its bound (:func:`_gradient_bounded`),
    then, where that does not pass either, with the gradient in double-double, nothing subtracted
    (:func:`_gradient_dd`).
    ``design(p)`` is the ``X`` ``(P, rows, m)`` of the problems ``p`` (indices into the ``B``
    problems), ``y`` ``(B, rows)`` (``B = 1``: one problem). A problem with a non-finite residual
    (a NaN path) is left as it is: no check can pass it."""
    broken = (point_res == np.inf).any(axis=1)
    for gradient in (_gradient_bounded, _gradient_exact):
        pb, pi = np.nonzero((point_res > KKT_TOL) & ~broken[:, None])
        if not pb.size:
            break
        with np.errstate(all="ignore"):
            Xp, yp = (design(pb[:1])[0], y[0]) if y.shape[0] == 1 else (design(pb), y[pb])
            g[pb, pi], slack[pb, pi] = gradient(Xp, yp, coefs[pb, pi])
            # the residuals of these breakpoints only, as breakpoints (P, 1) of their own: a
            # breakpoint's residual reads its own gradient, slack and terms only (the same
            # values as over the whole batch; the others are unchanged)
            at = tuple(t[pb, pi][:, None] for t in (g, slack, levels, *terms))
            point_res[pb, pi] = _kkt(*at[:3], at[3:], points=True)[0][:, 0]
    return point_res


def _kkt_direct(
    X: np.ndarray, y: np.ndarray, levels: np.ndarray, coefs: np.ndarray
) -> tuple[float, float]:
    """:func:`kkt_residual` of one path, levels ``(S,)`` (``N lambda``) and coefficients ``(S, m)``,
    and its float floor (levels); the gradient in double-double (:func:`_gradient_dd`), nothing
    subtracted."""
    with np.errstate(all="ignore"):
        g = _gradient_dd(X, y, coefs)
        terms = _kkt_terms(
            levels[None], coefs[None], np.array([levels.size]), np.abs(X.T @ X)[None]
        )
        res, floor = _kkt(g[None], np.zeros((1, levels.size)), levels[None], terms)
    return float(res[0]), float(floor[0])


def _kkt_path(
    X: np.ndarray, y: np.ndarray, levels: np.ndarray, coefs: np.ndarray
) -> tuple[float, float]:
    """:func:`_kkt_direct`'s residual (or an upper bound of it) and float floor, computed as
    :func:`lasso_path_batch` does: the batched screen, then double-double where it does not pass
    (:func:`_kkt_where_screen_fails`)."""
    k = np.array([levels.size])
    gram = X.T @ X
    with np.errstate(all="ignore"):
        g, slack, terms, res, _ = _kkt_screen(
            gram[None],
            (X.T @ y)[None],
            np.sqrt(y @ y)[None],
            levels[None],
            coefs[None],
            k,
            X.shape[0],
        )
        _kkt_where_screen_fails(
            lambda p: X[None], y[None], g, slack, levels[None], coefs[None], terms, res
        )
        res, floor = _kkt(g, slack, levels[None], terms)
    return float(res[0]), float(floor[0])


def _kkt_screen(
    Gram: np.ndarray,
    Xy: np.ndarray,
    ynorm: np.ndarray,
    levels: np.ndarray,
    coefs: np.ndarray,
    n_points: np.ndarray,
    rows: int,
) -> tuple[np.ndarray, ...]:
    """The batched screen of :func:`lasso_path_batch`'s KKT check, from ``Gram`` ``(B, m, m)``,
    ``Xy`` ``(B, m)`` and ``||y||`` ``(B,)``: the gradients ``g`` ``(B, S, m)`` (Gram form), the
    bound of their rounding ``slack`` ``(B, S)``, the paths' :func:`_kkt_terms`, and the
    per-breakpoint residuals and floors of :func:`_kkt` (the slack added)."""
    m = Gram.shape[1]
    with np.errstate(all="ignore"):
        norms = np.sqrt(np.einsum("bii->bi", Gram))
        # |fl(g_j) - g_j| <= gamma_(rows + m) ||X_j|| (||y|| + sum_k ||X_k|| |theta_k|)
        # (Cauchy-Schwarz on
        # X^T y, X^T X and G theta), doubled
        slack = (
            (2 * _EPS * (rows + m + 2))
            * norms.max(axis=1, keepdims=True)
            * (ynorm[:, None] + np.einsum("bsi,bi->bs", np.abs(coefs), norms))
        )
        g = np.matmul(coefs, Gram)
        np.subtract(Xy[:, None, :], g, out=g)  # in place: one (B, S, m) array, not two
        terms = _kkt_terms(levels, coefs, n_points, np.abs(Gram))
        point_res, point_floor = _kkt(g, slack, levels, terms, points=True)
    return g, slack, terms, point_res, point_floor


def _kkt_terms(
    levels: np.ndarray, coefs: np.ndarray, n_points: np.ndarray, abs_gram: np.ndarray
) -> tuple[np.ndarray, ...]:
    """What :func:`_kkt` needs of paths ``coefs`` ``(B, S, m)`` padded after ``n_points``, at the
    levels ``levels`` ``(B, S)`` (``N lambda``), besides their gradients (computed once for a
    check whose gradients are computed again at some breakpoints, :func:`_kkt_where_screen_fails`):
    the breakpoints on the paths ``(B, S)``, the signs ``pos``, ``neg`` ``(B, S, m)`` each
    ``theta_j`` has at a breakpoint or on an interval next to it (as :func:`_activity` reads them),
    the float floors ``(B, S)`` (0 in the padding) and the scales of the violations ``(B, S)``.
    ``abs_gram`` ``(B, m, m)`` is ``|X^T X|`` (for the float floor)."""
    B, S, m = coefs.shape
    valid = np.arange(S) < n_points[:, None]  # (B, S)
    with np.errstate(all="ignore"):
        top = np.maximum(coefs.max(axis=(1, 2), initial=0.0), -coefs.min(axis=(1, 2), initial=0.0))
        zero = 1e-12 * np.maximum(1.0, top)[:, None, None]
        pos, neg = coefs > zero, coefs < -zero
        mid = coefs[:, :-1] + coefs[:, 1:]
        mid[~valid[:, 1:]] = 0.0
        for mask, on in ((pos, mid > 2 * zero), (neg, mid < -2 * zero)):
            mask[:, :-1] |= on
            mask[:, 1:] |= on
        # float floor: rounding theta to float64 (|delta_k| <= eps/2 |theta_k|) moves g_j by up to
        # eps/2 sum_k |G_jk theta_k|; below floor_i = that / KKT_TOL, KKT_TOL lambda cannot be met
        floor = np.matmul(np.abs(coefs), abs_gram).max(axis=2) * (0.5 * _EPS / KKT_TOL)
        scale = np.maximum(np.maximum(levels, KKT_FLOOR * levels[:, :1]), floor)
        scale = np.maximum(scale, _TINY)
    return valid, pos, neg, np.where(valid, floor, 0.0), scale


def _kkt(
    g: np.ndarray,
    slack: np.ndarray,
    levels: np.ndarray,
    terms: tuple[np.ndarray, ...],
    *,
    points: bool = False,
) -> tuple[np.ndarray, np.ndarray]:
    """The residuals of :func:`kkt_residual` ``(B,)`` and the float floors ``(B,)`` (the largest
    ``floor_i``, in levels) of paths padded to ``S`` breakpoints (with ``points=True``, per
    breakpoint ``(B, S)``: residual, ``-inf`` in the padding, and floor), from the gradients ``g``
    ``(B, S, m)`` (without the ``1/N``) at the levels ``levels`` ``(B, S)`` (``N lambda``) and the
    paths' :func:`_kkt_terms`. ``slack`` ``(B, S)`` bounds the error of ``g`` at each breakpoint
    and is *added* to the violation (a screen with a rounded ``g`` can then fail a good path, never
    pass a bad one). Vectorised over the batch: a few passes over ``(B, S, m)``."""
    valid, pos, neg, floor, scale = terms
    with np.errstate(all="ignore"):
        # |g_j| <= c for every j; c - g_j <= 0 where theta_j > 0 and c + g_j <= 0 where theta_j < 0 (with
        # the first, g_j = c sign(theta_j); a sign change on an interval gives c + |g_j|): four
        # reductions over j
        worst = np.maximum(g.max(axis=2), -g.min(axis=2)) - levels
        np.maximum(worst, levels - np.where(pos, g, np.inf).min(axis=2), out=worst)
        np.maximum(worst, levels + np.where(neg, g, -np.inf).max(axis=2), out=worst)
        res = np.where(valid, (worst + slack) / scale, -np.inf)
        if points:  # per breakpoint, (B, S)
            return np.where(np.isnan(res), np.inf, res), floor
        res, floor = res.max(axis=1), floor.max(axis=1)
    # NaN, anywhere in a path, fails
    return np.where(np.isnan(res), np.inf, np.maximum(res, 0.0)), floor


def _refine(
    X: np.ndarray, y: np.ndarray, levels: np.ndarray, coefs: np.ndarray, steps: int = 3
) -> np.ndarray:
    """The coefficients ``(S, m)`` of a path refined at each breakpoint on the path's own supports.

    At breakpoint ``i`` the Lasso solution solves ``(X^T X)_AA theta_A = X_A^T y - c_i sign_A`` on
    the components ``A`` non-zero at ``c_i`` (with their signs), ``theta = 0`` elsewhere. An
    up/down-dated solver (the homotopy's inverse, ``lars_path``'s Cholesky factor) loses accuracy on
    nearly collinear active columns; iterative refinement with residuals in double-double
    (:func:`_gradient_dd`) restores it while ``eps cond(X_A^T X_A) < 1``. The levels and supports
    are unchanged.
    """
    zero = 1e-12 * max(1.0, float(np.abs(coefs).max(initial=0.0)))
    sign = np.where(np.abs(coefs) > zero, np.sign(coefs), 0.0)
    gram = X.T @ X
    theta = np.where(sign != 0, coefs, 0.0)
    for _ in range(steps):
        r = _gradient_dd(X, y, theta) - levels[:, None] * sign  # zero on A at the solution
        for i in range(theta.shape[0]):
            a = np.flatnonzero(sign[i])
            if a.size:
                theta[i, a] += np.linalg.lstsq(gram[np.ix_(a, a)], r[i, a], rcond=None)[0]
    return theta


def _pow2_rms(a: np.ndarray) -> np.ndarray:
    """Per row of ``a`` ``(B, k)``, the power of 2 nearest its RMS (1 for a zero row), computed
    without squaring the raw entries (scaling by a power of 2 is exact)."""
    top = np.maximum(a.max(axis=1), -a.min(axis=1))  # max |a|, without an |a| temporary
    _, e = np.frexp(top)  # top = f 2^e, f in [0.5, 1)
    u = np.ldexp(
        1.0, np.maximum(e - 1, -1074)
    )  # 2^(e-1) <= top: representable even near the limits
    ok = top > 0
    u[~ok] = 1.0
    t = _divide_pow2(a, u[:, None])
    ms = np.einsum("bk,bk->b", t, t) / a.shape[1]
    with np.errstate(divide="ignore"):
        s = np.exp2(np.round(np.log2(ms) / 2 + (e - 1)))
    s[~ok] = 1.0
    return s


def _divide_pow2(a: np.ndarray, s: np.ndarray, out: np.ndarray | None = None) -> np.ndarray:
    """``a / s`` for powers of 2 ``s`` (broadcast against ``a``; into ``out`` if given), bit for bit,
    as ``a * (1 / s)``, which costs less: the reciprocal of a power of 2 is exact while finite, and
    both are then one rounding of the same value. Divides when a reciprocal is not finite
    (``s < 2^-1023``, or a zero ``s``)."""
    with np.errstate(over="ignore", divide="ignore"):
        r = 1.0 / s
    if np.isfinite(r).all():
        return np.multiply(a, r, out=out)
    return np.divide(a, s, out=out)


def _lars_fallback(
    X: np.ndarray, y: np.ndarray, c_min: float, max_size: int | None, b: int, kkt: float
) -> tuple[np.ndarray, np.ndarray, float, float]:
    """The path of one problem whose homotopy path failed the KKT check, by scikit-learn's ``lars_path``.

    Why not only the homotopy: its inverse of ``Gram_AA`` is up/down-dated (fast, batched) and loses
    accuracy when active columns are nearly collinear (``Gram_AA`` nearly singular); scikit-learn's
    ``lars_path(method="lasso")`` keeps a Cholesky factor (stable) and handles ties. It is tried on
    the whole design, then, if that path fails the check (scikit-learn drops a degenerate regressor
    for good, which can violate the conditions later), on the design with its parallel columns
    (``|cos| >= 1 - 1e-12``: duplicated or scaled) merged into the longest of each group and its
    zero columns removed (an exact reduction for exactly parallel columns: the Lasso puts a group's
    whole weight on its longest column, and the others' correlations are multiples of its own by at
    most 1 in absolute value). ``X``, ``y`` are the
    scaled ones of :func:`lasso_path_batch`, ``c_min`` the lower end of the path in levels, ``b`` and
    ``kkt`` the problem's index and homotopy residual (for the error message).

    Returns the levels ``(S,)``, the coefficients ``(S, m)`` (the path stopped as the homotopy's
    would be, at ``c_min`` or after the first interval with more than ``max_size`` components;
    refined on its supports, :func:`_refine`, when that lowers its residual), the KKT residual and
    float floor. A path that stops above ``c_min`` is accepted only below ``1e-9`` times its first
    level (where only rounding is left on the degenerate designs that come here).

    Raises
    ------
    NumericalError
        When no path passes the KKT check (naming the problem and the residuals).
    """
    import warnings

    from sklearn.exceptions import ConvergenceWarning
    from sklearn.linear_model import lars_path

    rows, m = X.shape
    norms = np.sqrt(np.einsum("ri,ri->i", X, X))
    keep = np.flatnonzero(norms > 0)
    cos = np.abs(X[:, keep].T @ X[:, keep]) / np.outer(norms[keep], norms[keep])
    longest = np.ones(
        keep.size, bool
    )  # the longest column of each parallel group (the first on ties)
    for i in range(keep.size):
        par = cos[i] >= 1 - 1e-12
        longest[i] = not np.any(
            par
            & (
                (norms[keep] > norms[keep[i]])
                | ((norms[keep] == norms[keep[i]]) & (np.arange(keep.size) < i))
            )
        )
    designs = [np.arange(m)] + ([keep[longest]] if longest.sum() < m else [])
    # lars_path stops once alpha <= alpha_min + float32 eps (an absolute tolerance): y is scaled by a
    # power of 2 (exact) so that alpha_max is about 1e8, which puts that stop 15 decades down.
    with np.errstate(over="ignore"):
        top = float(np.abs(X.T @ y).max())
    e = np.log2(1e8 * rows) - np.log2(top) if 0 < top < np.inf else np.inf  # in logs: no overflow
    if not abs(e) <= 1000:  # t (or t * y) would leave float64: the design's scale is the problem
        raise NumericalError(
            f"X, y (problem {b}): the Lasso path violates the optimality (KKT) conditions "
            f"by {kkt:.3g} lambda with the homotopy, and max |X^T y| = {top:.3g} (X and y at "
            f"unit RMS) is too far from 1 for scikit-learn's lars_path to be scaled in float64; "
            f"expected X^T y not (nearly) zero or infinite"
        )
    t = 2.0 ** np.round(e)
    tried = []
    for cols in designs:
        with (
            warnings.catch_warnings()
        ):  # degenerate-regressor warnings: the KKT check below decides
            warnings.simplefilter("ignore", ConvergenceWarning)
            alphas, _, co = lars_path(
                X[:, cols], t * y, method="lasso", alpha_min=t * c_min / rows, max_iter=50 * m + 100
            )
        levels = alphas * (rows / t)
        coefs = np.zeros((levels.size, m))
        coefs[:, cols] = co.T / t
        over = np.flatnonzero(
            _activity(coefs[None])[1][0].sum(axis=1) > (m if max_size is None else max_size)
        )
        if over.size:  # stop after the first interval with more than max_size components
            levels, coefs = levels[: over[0] + 2], coefs[: over[0] + 2]
        res, fl = _kkt_path(X, y, levels, coefs)
        if res > KKT_TOL:  # its Cholesky updates lose accuracy too: refined on its own supports
            refined = _refine(X, y, levels, coefs)
            r2, f2 = _kkt_path(X, y, levels, refined)
            if r2 < res:
                res, fl, coefs = r2, f2, refined
        done = over.size or levels[-1] <= max(c_min, 1e-9 * levels[0])  # lars_path's own tail ends
        if res <= KKT_TOL and done:
            return levels, coefs, res, fl
        tried.append(
            f"{res:.3g} lambda"
            + ("" if done else f" (stopped at {levels[-1] / levels[0]:.3g} lambda_max)")
        )
    raise NumericalError(
        f"X, y (problem {b}): the Lasso path violates the optimality (KKT) conditions by "
        f"{kkt:.3g} lambda with the homotopy and by {', '.join(tried)} with scikit-learn's "
        f"lars_path; expected at most KKT_TOL = {KKT_TOL:g} down to lambda_min"
    )


def _homotopy(
    Gram: np.ndarray, Xy: np.ndarray, c_min: np.ndarray, max_size: int | None
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """LARS-Lasso homotopy of Efron et al. (2004) in Gram form, batched over a leading axis.

    ``Gram`` ``(B, m, m)``, ``Xy`` ``(B, m)``; the path is followed in the correlation level
    ``c = max_j |Xy_j - (Gram beta)_j|`` (``c = rows * alpha``) from its maximum down to ``c_min``
    ``(B,)``, or until an interval with more than ``max_size`` active components is complete.
    Each step moves every unfinished problem to its next breakpoint at once: the direction on
    the active set solves ``Gram_AA d = sign_A``, kept through the inverse of ``Gram_AA``
    (rank-one up/down-date when a component joins or drops); the next event is the first join
    (an inactive correlation reaching ``c``), drop (an active coefficient reaching 0, the Lasso
    modification; the dropped component cannot rejoin at once with its old sign), or the end of
    the window. The active set is stored compactly, in join order (a dropped component's slot
    takes the last one): the inverse ``(B, K, K)`` and the active rows of the Gram matrix
    ``(B, K, m)`` span ``K = min(m, max_size + 1)`` slots, not ``m``. ``K`` does not depend on
    the batch, so that every floating-point operation on a problem is the same whatever the
    other problems of its batch: a path is bit for bit the same computed alone or in any chunk.
    Problems that have finished are dropped from the working arrays whenever they are half of
    them. The tests check it against scikit-learn's ``lars_path`` to 1e-9.

    Degenerate designs: components tied with the level (to ``1e-12 c_0``) join in zero-length
    steps, one per step; a component that joined so with a direction against its sign leaves at
    once; a column in the span of the active ones is kept out; a path ends at an exact fit (``c``
    down to ``1e-12 c_0``). A path that meets a singular step (NaN), runs more than
    ``50 m + 100`` steps or more than ``4 m + 10`` zero-length steps in a row (a cycle) ends with
    a NaN, which :func:`lasso_path_batch`'s KKT check rejects.

    Returns the correlation levels ``(B, S)`` and coefficients ``(B, S, m)`` at the
    breakpoints, and the number ``(B,)`` of breakpoints of each problem (the tails are padding).
    """
    B, m = Xy.shape
    if B == 1:  # one problem (lasso_path): the same operations, with scalar bookkeeping
        return _homotopy_one(Gram, Xy, c_min, max_size)
    K = m if max_size is None else min(m, max_size + 1)  # most components active at once
    rows = np.arange(B)
    beta = np.zeros((B, m))
    cov = Xy.copy()
    sign = np.zeros((B, m + 1))  # column m: the (zero) sign of an unused slot
    active = np.zeros((B, m), bool)
    order = np.full(
        (B, K), m
    )  # active components in their slots (the first n_act[b]); m when unused
    slot = np.zeros((B, m), int)  # slot of each active component
    n_act = np.zeros(B, int)
    inv = np.zeros((B, K, K))  # inverse of Gram_AA in slot order, zero outside the used slots
    GA = np.zeros((B, K, m))  # Gram[:, order, :]: the active rows, zero in unused slots
    j = np.abs(cov).argmax(axis=1)
    c = np.abs(cov[rows, j])
    near = (
        1e-12 * c
    )  # a correlation this close to the level ties with it (rounding of cov, ~eps c_0)
    cap = 2 * m + 4  # breakpoints stored per problem (grown if needed)
    levels = np.zeros((B, cap))
    levels[:, 0] = c
    # the coefficients of each step's breakpoint, (problems, m), stored at the end: writing them at
    # once into a (B, S, m) array costs less than one strided row per problem at every step
    steps: list[tuple[np.ndarray, np.ndarray]] = []
    n_points = np.ones(B, int)
    step = 1  # breakpoints so far of every problem still running (each step adds one to each)
    # problems still followed: the arrays below are compacted to them, Gram (the largest, read a
    # row per step) is not, and is indexed through ids
    ids = np.arange(B)
    running = c > c_min
    joining = running.copy()  # problems whose event is the join of component j
    dropping = np.zeros(B, bool)  # ... the drop of component j
    barred = np.full(B, -1)  # a component that just dropped cannot rejoin with its old sign at once
    barred_sign = np.zeros(B)
    stalled = np.zeros(B, int)  # zero-length steps in a row
    outer_buf = np.empty(B * K * K)  # the rank-one change of inv (below)
    while running.any():
        if rows.size >= 16 and running.sum() <= 3 * rows.size // 4:  # drop finished problems
            keep = running
            c_min, beta, cov, sign, active, inv, GA = (
                x[keep] for x in (c_min, beta, cov, sign, active, inv, GA)
            )
            order, slot, n_act, c, j, near = (x[keep] for x in (order, slot, n_act, c, j, near))
            joining, dropping, barred, barred_sign, stalled, running, ids = (
                x[keep] for x in (joining, dropping, barred, barred_sign, stalled, running, ids)
            )
            rows = np.arange(ids.size)
        # slot of the event: a joining component takes the next free slot
        s_ev = np.where(joining, n_act, slot[rows, j])
        # Slots 0 .. k-1 are all that the batch uses in this step: the rows and columns of inv
        # beyond are zero and stay so, so only the sums (over all K slots) need them.
        k = min(K, int(n_act.max()) + int(joining.any()))
        # rank-one change of inv: + w w^T / schur (j joins), - col col^T / col_s (j drops)
        g = GA[rows, :, j]  # Gram[A, j] (zero in unused slots)
        u = np.zeros((rows.size, K))
        np.einsum("bij,bj->bi", inv[:, :k], g, out=u[:, :k])
        schur = Gram[ids, j, j] - np.einsum("bi,bi->b", g, u)  # G_jj - g_A^T inv g_A
        u[rows[joining], s_ev[joining]] = -1.0  # w: the new column of inv is -w / schur
        # over all K slots once most are used: inv[:, :K, :K] is contiguous, faster to add to than
        # its strided corner (the unused slots' zeros in z add zeros, to zeros: inv is unchanged)
        kk = K if 4 * k > 3 * K else k
        col = inv[rows, :kk, s_ev]
        z = np.where(joining[:, None], u[:, :kk], col)
        f = np.where(joining, 1.0 / schur, np.where(dropping, -1.0 / inv[rows, s_ev, s_ev], 0.0))
        # the outer product in a buffer kept across steps: a new (B, k, k) array at each step
        # (megabytes) is mapped and faulted in anew by the allocator (same products, same sums;
        # einsum forms them faster than a broadcast multiply)
        outer = outer_buf[: rows.size * kk * kk].reshape(rows.size, kk, kk)
        np.einsum("bi,bj->bij", z * f[:, None], z, out=outer)
        inv[:, :kk, :kk] += outer
        if joining.any():
            b = rows[joining]
            GA[b, s_ev[b]] = Gram[ids[b], j[b]]  # row j (the Gram matrix is symmetric)
            order[b, s_ev[b]] = j[b]
            slot[b, j[b]] = s_ev[b]
            n_act[b] += 1
        if dropping.any():  # the last used slot moves into the freed one
            b = rows[dropping]
            sd, last = s_ev[b], n_act[b] - 1
            inv[b, sd, :] = inv[b, last, :]
            inv[b, :, sd] = inv[b, :, last]
            inv[b, last, :] = 0.0
            inv[b, :, last] = 0.0
            GA[b, sd] = GA[b, last]
            GA[b, last] = 0.0
            order[b, sd] = order[b, last]
            slot[b, order[b, sd]] = sd
            order[b, last] = m
            n_act[b] -= 1
        active[rows, j] = (active[rows, j] | joining) & ~dropping
        sign[rows, j] = np.where(
            joining, np.sign(cov[rows, j]), np.where(dropping, 0.0, sign[rows, j])
        )
        dA = np.zeros((rows.size, K))
        np.einsum("bij,bj->bi", inv[:, :k], sign[rows[:, None], order], out=dA[:, :k])
        a = np.einsum("bji,bj->bi", GA[:, :k], dA[:, :k])  # a sum in slot order: unused slots add 0
        d = np.zeros((rows.size, m + 1))
        d[rows[:, None], order[:, :k]] = dA[:, :k]  # unused slots write into column m, dropped
        d = d[:, :m]
        below, above = c[:, None] - cov, c[:, None] + cov  # the level's gaps to +-cov
        up = below / (1.0 - a)
        down = above / (1.0 + a)
        zero = -beta / d
        inactive = ~active  # the components that can join
        join = np.fmin(_where_inf((up > 0) & inactive, up), _where_inf((down > 0) & inactive, down))
        # A correlation at the level (a tie, e.g. at lambda_max; to rounding, `near`, while the level
        # is well above it) that would overtake it joins at once (gamma = 0); one that moves away
        # from it does not, nor one that moves with it to 1e-9 (a column in the span of the active
        # ones, e.g. a duplicate: joining would make Gram_AA singular, and staying out keeps the KKT
        # conditions to 1e-9 lambda).
        tol = np.where(c > 1e3 * near, near, 0.0)[:, None]
        tie = ((below <= tol) & (a < 1 - 1e-9)) | ((above <= tol) & (a > -1 + 1e-9))
        np.putmask(join, tie & inactive, 0.0)  # join[tie & inactive] = 0.0, faster
        hit = barred >= 0
        if hit.any():
            b = rows[hit]
            back = np.where(barred_sign[b] > 0, down[b, barred[b]], up[b, barred[b]])
            join[b, barred[b]] = np.where(back > 0, back, np.inf)
        # a component that joined in a tie (beta_j = 0) but whose direction opposes its sign leaves
        # at once (gamma = 0): it cannot stay active (its coefficient would take the wrong sign)
        zero = _where_inf(active & ((zero > 0) | ((beta == 0) & (d * sign[:, :m] < 0))), zero)
        j_join, j_drop = join.argmin(axis=1), zero.argmin(axis=1)
        g_join, g_drop = join[rows, j_join], zero[rows, j_drop]
        g_end = c - c_min
        g_next = np.minimum(g_join, g_drop)
        gamma = np.where(running, np.minimum(g_next, g_end), 0.0)
        stalled = np.where(gamma == 0, stalled + 1, 0)
        beta += gamma[:, None] * d
        cov -= gamma[:, None] * a
        c = c - gamma
        ended = running & (g_end <= g_next)
        c[ended] = c_min[ended]
        ended |= running & (c <= near)  # an exact fit: below, only rounding is left to follow
        dropping = running & ~ended & (g_drop < g_join)
        joining = running & ~ended & ~dropping
        j = np.where(dropping, j_drop, j_join)
        beta[rows[dropping], j[dropping]] = 0.0
        barred = np.where(dropping, j, -1)
        barred_sign = sign[rows, j]
        at = ids[running]
        point = step  # the index of the next breakpoint, the same for every running problem
        step += 1
        if point >= cap:
            levels = np.concatenate([levels, np.zeros_like(levels)], axis=1)
            cap *= 2
        levels[at, point] = c[running]
        steps.append((at, beta[running]))
        n_points[at] += 1
        if step > 50 * m + 100:  # far more steps than a path has (a cycle of zero-length steps on a
            levels[at, point] = (
                np.nan
            )  # degenerate design): NaN makes the KKT check reject the path
            running[:] = False
        # More zero-length steps in a row than ties can make (each component joins once and, if
        # its direction opposes its sign, leaves at once: 2 m), with a margin: a cycle on a
        # degenerate design (Example 2's regression ran the 50 m + 100 steps of the cap in zero-
        # length steps), rejected at once in the same way
        cycling = running & (stalled > 4 * m + 10)
        if cycling.any():
            levels[ids[cycling], point] = np.nan
            running &= ~cycling
        if max_size is not None:  # the interval just followed had more than max_size components
            running &= n_act <= max_size  # n_act: the active components, active.sum(axis=1)
        running &= (
            ~ended & np.isfinite(c) & np.isfinite(beta).all(axis=1)
        )  # the KKT check rejects it
        joining &= running
        dropping &= running
    coefs = np.zeros((B, step, m))
    for point, (at, beta_at) in enumerate(steps, start=1):
        coefs[at, point] = beta_at
    return levels, coefs, n_points


def _where_inf(mask: np.ndarray, x: np.ndarray) -> np.ndarray:
    """``numpy.where(mask, x, inf)`` for an ``x`` with no NaN where ``mask`` holds, the same bits,
    without a branch per element (``where`` mispredicts on masks without a pattern, several times
    slower; under ``numpy.errstate(invalid="ignore")``): ``-0.0`` added where ``mask`` holds
    (exact, the sign of a zero kept), NaN elsewhere (``-0.0 / 0``), which ``fmin`` with ``inf``
    turns into ``inf``."""
    out = np.divide(-0.0, mask)
    np.add(x, out, out=out)
    return np.fmin(out, np.inf, out=out)


def _homotopy_one(
    Gram: np.ndarray, Xy: np.ndarray, c_min: np.ndarray, max_size: int | None
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """:func:`_homotopy` for a batch of one problem (``lasso_path``), bit for bit the same.

    A step of one problem is dominated by the number of numpy calls, not by their size, so it
    makes few: the same floating-point operations on the same values, the sums (the ``einsum``
    calls, :func:`_one_direction`) on the same shapes and
    layouts, hence in the same order, and the elementwise ones on stacked rows
    (:func:`_one_event`), ``P = [cov, -cov, beta]`` and ``Q = [-a, a, d]``, through exact sign
    changes (``c + cov = c - (-cov)``, ``1 - a = 1 + (-a)``, ``-beta = -0.0 - beta``, ``d =
    -0.0 + d``, ``cov - gamma a = cov + gamma (-a)``): one call serves the joins of either sign
    and the drops. The bookkeeping (event, slots, flags, step lengths) is done on scalars, which
    stay ``numpy.float64`` (a division by zero or a NaN behaves as in the arrays).
    """
    m = Xy.shape[1]
    K = m if max_size is None else min(m, max_size + 1)
    P = np.concatenate([Xy, -Xy, np.zeros((1, m))])  # cov, -cov, beta
    Q = np.zeros((3, m))  # -a, a, d: the step's direction (filled by _one_direction)
    col = np.full((3, m), -0.0)  # c, c (set at each step), -0.0 (-0.0 - beta is -beta, zeros too)
    one = np.ones((3, m))  # 1, 1, -0.0: 1 - a, 1 + a and d (-0.0 + d is d) from Q
    one[2] = -0.0
    zero_m = np.zeros(m)
    sign, shut = np.zeros(m), np.zeros((2, m))  # shut: inf on the active set, else 0 (_one_event)
    # inverse of Gram_AA, active rows of Gram, signs and components in slot order (as _homotopy)
    inv, GA, sign_slots, order = (
        np.zeros((1, K, K)),
        np.zeros((1, K, m)),
        np.zeros((1, K)),
        np.full(K, m),
    )
    slot, n_act = [0] * m, 0
    j = int(np.abs(Xy).argmax())
    c = np.abs(Xy[0, j])
    near, c_min = 1e-12 * c, c_min[0]
    cap = 2 * m + 4
    levels, coefs = np.zeros((1, cap)), np.zeros((1, cap, m))
    levels[0, 0] = c
    step, stalled = 1, 0
    running = bool(c > c_min)
    joining, barred, barred_sign = running, -1, 0.0
    while running:
        state = (Gram, P, Q, inv, GA, sign_slots, order, slot, sign, shut)
        n_act = _one_direction(*state, j, joining, n_act)
        np.add(c, shut, out=col[:2])
        event = (P, Q, col, one, c, near, sign, n_act, j if joining else -1, barred, barred_sign)
        g_join, j_join, g_drop, j_drop = _one_event(*event)
        g_end = c - c_min
        g_next = _min(g_join, g_drop)
        gamma = _min(g_next, g_end)
        stalled = stalled + 1 if gamma == 0 else 0
        P += gamma * Q  # cov - gamma a, -(cov - gamma a) (to the sign of a zero), beta + gamma d
        c = c - gamma
        ended = bool(g_end <= g_next)
        if ended:
            c = c_min
        ended = ended or bool(c <= near)
        dropping = not ended and bool(g_drop < g_join)
        joining = not ended and not dropping
        j = j_drop if dropping else j_join
        if dropping:
            P[2, j] = 0.0
        barred = j if dropping else -1
        barred_sign = sign[j]
        if step >= cap:
            levels = np.concatenate([levels, np.zeros_like(levels)], axis=1)
            coefs = np.concatenate([coefs, np.zeros_like(coefs)], axis=1)
            cap *= 2
        levels[0, step], coefs[0, step] = c, P[2]
        step += 1
        if step > 50 * m + 100 or stalled > 4 * m + 10:  # as in _homotopy: rejected by the check
            levels[0, step - 1] = np.nan
            running = False
        if max_size is not None:
            running = running and n_act <= max_size
        # beta finite: 0 beta_j is NaN where beta_j is not, and so is then their sum
        running = running and not ended and math.isfinite(c) and not math.isnan(P[2].dot(zero_m))
        joining = joining and running
    return levels, coefs, np.array([step])


def _min(a: np.float64, b: np.float64) -> np.float64:
    """``numpy.minimum(a, b)`` of two scalars, the ufunc called only where the order does not
    decide (equal values, e.g. ``0.0`` and ``-0.0``, or a NaN)."""
    if a < b:
        return a
    if b < a:
        return b
    return np.minimum(a, b)


def _one_direction(
    Gram: np.ndarray,
    P: np.ndarray,
    Q: np.ndarray,
    inv: np.ndarray,
    GA: np.ndarray,
    sign_slots: np.ndarray,
    order: np.ndarray,
    slot: list[int],
    sign: np.ndarray,
    shut: np.ndarray,
    j: int,
    joining: bool,
    n_act: int,
) -> int:
    """A step of :func:`_homotopy_one`: component ``j`` joins (or drops) the active set, the
    rank-one change of the inverse ``inv`` of ``Gram_AA`` and of the slots (in place), then the
    direction: ``Q = [-a, a, d]``. Returns the new number of active components.

    The sums are :func:`_homotopy`'s ``einsum`` calls on ``(1, ...)`` arrays of the same layouts.
    The rank-one change is the broadcast product, not the ``einsum`` of :func:`_homotopy`, which
    adds each product to a zero: the same values but for the sign of a zero product, which adds
    the same to ``inv`` (whose entries are never ``-0.0``: a sum is ``-0.0`` only of two).
    """
    K = GA.shape[1]
    s = n_act if joining else slot[j]
    k = min(K, n_act + 1) if joining else n_act
    if joining:
        g = GA[:, :, j].copy()  # (1, K), C-contiguous as GA[rows, :, j]
        u = np.zeros((1, K))
        np.einsum("bij,bj->bi", inv[:, :k], g, out=u[:, :k])
        schur = Gram[0, j, j] - np.einsum("bi,bi->b", g, u)[0]
        u[0, s] = -1.0
        z, f = u[0, :k], 1.0 / schur
    else:
        z, f = inv[0, :k, s], -1.0 / inv[0, s, s]
    zf = z * f
    inv[0, :k, :k] += zf[:, None] * z
    if joining:
        GA[0, s] = Gram[0, j]
        order[s], slot[j] = j, s
        shut[:, j] = np.inf
        cov = P[0, j]
        sign[j] = sign_slots[0, s] = 1.0 if cov > 0 else -1.0 if cov < 0 else np.sign(cov)
        n_act += 1
    else:
        last = n_act - 1
        inv[0, s, :] = inv[0, last, :]
        inv[0, :, s] = inv[0, :, last]
        inv[0, last, :] = 0.0
        inv[0, :, last] = 0.0
        GA[0, s], GA[0, last] = GA[0, last], 0.0
        sign_slots[0, s], sign_slots[0, last] = sign_slots[0, last], 0.0
        order[s] = order[last]
        slot[order[s]] = s
        order[last] = GA.shape[2]  # m: unused
        shut[:, j], sign[j], Q[2, j] = 0.0, 0.0, 0.0
        n_act = last
    dA = np.einsum("bij,bj->bi", inv[:, :k], sign_slots)
    np.einsum("bji,bj->bi", GA[:, :k], dA, out=Q[1:2])  # a
    np.negative(Q[1], out=Q[0])
    Q[2, order[:n_act]] = dA[0, :n_act]  # d (zero off the active set)
    return n_act


def _one_event(
    P: np.ndarray,
    Q: np.ndarray,
    col: np.ndarray,
    one: np.ndarray,
    c: np.float64,
    near: np.float64,
    sign: np.ndarray,
    n_act: int,
    joined: int,
    barred: int,
    barred_sign: float,
) -> tuple[np.float64, int, np.float64, int]:
    """The next event of :func:`_homotopy_one`: the step length to the first join and its
    component, and to the first drop and its component (the rules of :func:`_homotopy`, the same
    values), from the rows ``P = [cov, -cov, beta]``, ``Q = [-a, a, d]``, ``one = [1, 1, -0.0]``
    and ``col = [c, c, -0.0]``, where the first two rows of ``col`` are ``c + inf`` on the active
    set; ``n_act`` components are active, ``joined`` the one that just joined (-1 after a drop),
    ``barred`` the one that just dropped (-1 after a join) and ``barred_sign`` its former sign.

    The rows of ``(col - P) / (one + Q)`` are ``up``, ``down`` and ``zero`` of :func:`_homotopy`,
    but on the active set, where the gaps ``col - P`` are ``inf`` (or NaN), neither a join nor a
    tie: ``join[active] = inf``. Off the active set ``beta`` and ``d`` are ``0.0``, ``zero`` is
    NaN and no drop condition holds: ``zero[~active] = inf``.
    """
    num = col - P  # c - cov, c + cov, -beta
    ratio = num / (one + Q)  # up, down, zero
    pos = ratio > 0.0
    # a component with beta_j = 0 whose direction opposes its sign (it joined in a tie) leaves at
    # once: off the active set beta is 0.0 and sign 0.0, on it usually only the one just joined
    zeros = n_act - np.count_nonzero(P[2])  # active components at beta_j = 0
    if zeros == 1 and joined >= 0 and P[2, joined] == 0:
        pos[2, joined] |= Q[2, joined] * sign[joined] < 0
    elif zeros:
        pos[2] |= (P[2] == 0) & (Q[2] * sign < 0)
    R = np.where(pos, ratio, np.inf)
    tol = near if c > 1e3 * near else 0.0
    if np.fmin.reduce(num[:2], axis=None) <= tol:  # a gap at the level (NaN aside): ties, if
        np.putmask(R[:2], (num[:2] <= tol) & (Q[:2] > -1 + 1e-9), 0.0)  # a < 1 - 1e-9, a > -1 + ...
    join = np.minimum(R[0], R[1])
    if barred >= 0:
        back = ratio[1, barred] if barred_sign > 0 else ratio[0, barred]
        join[barred] = back if back > 0 else np.inf
    j_join, j_drop = int(join.argmin()), int(R[2].argmin())
    return join[j_join], j_join, R[2, j_drop], j_drop


def lasso_cvxpy(X: Any, y: Any, lam: float, *, n_samples: int | None = None) -> np.ndarray:
    """Solve (39) for one ``lambda`` with cvxpy, written exactly as in the paper.

    cvxpy does the hard part (conic reformulation of the l1 norm and an interior-point
    solver); it is slow for Monte Carlo but reads like the maths.

    Explained in the book: :doc:`/book/zhang2021/sparse`.

    Parameters
    ----------
    X : array_like
        ``(rows, m)``.
    y : array_like
        ``(rows,)``.
    lam : float
        ``lambda > 0``.
    n_samples : int, optional
        The ``N`` of the ``1/(2N)`` in (39); default ``rows``.

    Returns
    -------
    numpy.ndarray
        ``theta_hat``, shape ``(m,)``.

    Examples
    --------
    >>> import numpy as np
    >>> rng = np.random.default_rng(0)
    >>> X = rng.standard_normal((40, 6))
    >>> y = X @ [0.0, 2.0, 0.0, 0.0, -1.5, 0.0] + 0.1 * rng.standard_normal(40)
    >>> path = lasso_path(X, y)
    >>> lam = 0.5 * path.lambdas[2]                  # any lambda: the exact path has it too
    >>> bool(np.allclose(lasso_cvxpy(X, y, lam), path.coef(lam), atol=1e-5))
    True
    """
    import cvxpy as cp

    X, y = _check_xy(X, y)
    N = _norm(n_samples, X.shape[0])
    if not np.isfinite(lam) or lam <= 0:
        raise ModelError(f"lam: expected a finite lambda > 0, got {lam!r}")
    theta = cp.Variable(X.shape[1])
    objective = cp.sum_squares(X @ theta - y) / (2 * N) + lam * cp.norm1(theta)
    problem = cp.Problem(cp.Minimize(objective))
    problem.solve(solver=cp.CLARABEL)
    if problem.status not in ("optimal", "optimal_inaccurate") or theta.value is None:
        raise ModelError(f"lasso_cvxpy: solver status {problem.status!r}")
    return np.asarray(theta.value, dtype=float)


@dataclass(frozen=True)
class FlatRange:
    """The widest ``lambda`` range with a constant number of non-zero components.

    Attributes
    ----------
    low, high : float
        The range ``(low, high)`` (consecutive path breakpoints, merged when the size does not change).
    middle : float
        ``sqrt(low high)`` (``scale="log"``) or ``(low + high) / 2`` (``scale="linear"``).
    size : int
        Number of non-zero components in the range.
    support : numpy.ndarray
        Indices of the non-zero components at ``middle``.
    width : float
        ``log(high / low)`` or ``high - low``.
    scale : str
    """

    low: float
    high: float
    middle: float
    size: int
    support: np.ndarray
    width: float
    scale: str


@dataclass(frozen=True)
class FlatRanges:
    """:class:`FlatRange` of each path of a :class:`PathBatch` (:func:`flat_ranges`), as arrays.

    Attributes
    ----------
    low, high, middle, width : numpy.ndarray
        ``(B,)``, as in :class:`FlatRange`.
    size : numpy.ndarray
        ``(B,)`` integers.
    support : numpy.ndarray
        ``(B, m)`` booleans: the non-zero components at ``middle``.
    scale : str
    """

    low: np.ndarray
    high: np.ndarray
    middle: np.ndarray
    size: np.ndarray
    support: np.ndarray
    width: np.ndarray
    scale: str


def _check_rule(lambda_ratio: Any, max_size: Any) -> None:
    if not 0 < lambda_ratio < 1:
        raise ModelError(f"lambda_ratio: expected a number in (0, 1), got {lambda_ratio!r}")
    if max_size is not None and (
        isinstance(max_size, bool) or not isinstance(max_size, (int, np.integer)) or max_size < 1
    ):
        raise ModelError(f"max_size: expected a positive integer, got {max_size!r}")


def _name(b: int, single: bool) -> str:
    return "path" if single else f"paths[{b}]"


def _runs(sizes: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Maximal runs of equal values along axis 1 of ``sizes`` ``(B, n)``: row, first and one-past-last
    column of each run, in row-major order (runs never cross rows)."""
    B, n = sizes.shape
    first = np.ones((B, n + 1), bool)
    first[:, 1:n] = sizes[:, 1:] != sizes[:, :-1]  # column n: a sentinel start closing each row
    rows, cols = np.nonzero(first)
    stops = np.roll(cols, -1)  # the next start: in the same row, thanks to the sentinel
    real = cols < n
    return rows[real], cols[real], stops[real]


def _coef_at(paths: PathBatch, lam: np.ndarray) -> np.ndarray:
    """``theta_hat(lam[b])`` of each path ``(B, m)``, as :meth:`LassoPath.coef` (linear between breakpoints)."""
    a, c = paths.lambdas, paths.coefs
    rows = np.arange(len(paths))
    last = paths.n_points - 1
    i = (a >= lam[:, None]).sum(axis=1) - 1  # a[i] >= lam > a[i+1] (the padding is -inf)
    i = np.clip(i, 0, np.maximum(last - 1, 0))
    j = np.minimum(i + 1, last)
    with np.errstate(divide="ignore", invalid="ignore"):  # only in the branches not taken
        t = (a[rows, i] - lam) / (a[rows, i] - a[rows, j])
        inner = (1 - t)[:, None] * c[rows, i] + t[:, None] * c[rows, j]
    return np.where(
        (lam >= a[:, 0])[:, None],
        0.0,
        np.where((lam <= a[rows, last])[:, None], c[rows, last], inner),
    )


def flat_ranges(
    paths: PathBatch,
    *,
    scale: Scale = "log",
    lambda_ratio: float = LAMBDA_RATIO,
    max_size: int | None = None,
) -> FlatRanges:
    """:func:`flat_range` of every path of a batch at once (the same results, as arrays).

    Explained in the book: :doc:`/book/zhang2021/sparse`.

    Parameters
    ----------
    paths : PathBatch
        E.g. from :func:`lasso_path_batch`.
    scale, lambda_ratio, max_size
        As in :func:`flat_range`.

    Returns
    -------
    FlatRanges

    Raises
    ------
    ModelError
        Naming the first path with no candidate range.

    Examples
    --------
    >>> import numpy as np
    >>> rng = np.random.default_rng(0)
    >>> X = rng.standard_normal((40, 6))
    >>> y = X @ [0.0, 2.0, 0.0, 0.0, -1.5, 0.0] + 0.1 * rng.standard_normal(40)
    >>> batch = lasso_path_batch(np.stack([X, X]), np.stack([y, 2 * y]))
    >>> flats = flat_ranges(batch)
    >>> flats.size.tolist(), bool(np.isclose(flats.middle[0], flat_range(batch.path(0)).middle))
    ([2, 2], True)
    """
    return _flat_ranges(paths, scale, lambda_ratio, max_size, single=False)


def _flat_ranges(
    paths: PathBatch, scale: Any, lambda_ratio: Any, max_size: Any, *, single: bool
) -> FlatRanges:
    if scale not in ("log", "linear"):
        raise ModelError(f"scale: expected 'log' or 'linear', got {scale!r}")
    _check_rule(lambda_ratio, max_size)
    a = paths.lambdas
    B, S = a.shape
    tol, _ = paths._activity
    top = paths.coefs.shape[2] // 2 if max_size is None else int(max_size)
    sizes = paths._sizes  # of the intervals (a[i+1], a[i]) of each path
    floor = lambda_ratio * a[:, 0]
    over = sizes > top
    first_over = np.where(over.any(axis=1), over.argmax(axis=1), S - 1)
    rows = np.arange(B)
    # the window stops where the support first exceeds max_size
    floor = np.where(
        first_over < S - 1, np.maximum(floor, a[rows, np.minimum(first_over, S - 1)]), floor
    )
    sizes = np.where(np.arange(S - 1) < first_over[:, None], sizes, -1)
    # maximal ranges of constant support size: interval i (first) to stop - 1, i.e. (a[stop], a[i])
    rb, first, stop = _runs(sizes)
    size = sizes[rb, first]
    high, low = a[rb, first], np.maximum(a[rb, stop], floor[rb])
    cand = (size >= 1) & (size <= top) & (high > low)
    widths = np.full((B, max(S - 1, 1)), -np.inf)  # at the first interval of each candidate range
    widths[rb[cand], first[cand]] = (
        np.log(high[cand] / low[cand]) if scale == "log" else high[cand] - low[cand]
    )
    best = widths.argmax(axis=1)  # the first (largest lambda) on ties
    bad = np.flatnonzero(widths[rows, best] == -np.inf)
    if bad.size:
        raise ModelError(
            f"{_name(int(bad[0]), single)}: no range of lambda in the window with "
            "between 1 and max_size non-zero components"
        )
    # run of each best interval (its index among the runs of its row)
    k = np.flatnonzero(cand)[np.searchsorted(rb[cand] * S + first[cand], rows * S + best)]
    lo, h = low[k], high[k]
    mid = np.sqrt(lo * h) if scale == "log" else 0.5 * (lo + h)
    c = _coef_at(paths, mid)
    return FlatRanges(
        low=lo,
        high=h,
        middle=mid,
        size=size[k],
        support=np.abs(c) > tol[:, None],
        width=widths[rows, best],
        scale=scale,
    )


def flat_range(
    path: LassoPath,
    *,
    scale: Scale = "log",
    lambda_ratio: float = LAMBDA_RATIO,
    max_size: int | None = None,
) -> FlatRange:
    """The paper's rule for ``lambda``: the middle of the widest range of constant support size.

    Ranges are maximal runs of path intervals with the same support size, clipped to the window;
    the widest candidate wins (ties: the one at the larger ``lambda``). :func:`flat_ranges` applies
    the rule to a whole :class:`PathBatch` at once (this function is that, for a batch of one).

    Explained in the book: :doc:`/book/zhang2021/sparse`.

    Parameters
    ----------
    path : LassoPath
    scale : {"log", "linear"}
        How width and middle are measured (module docstring).
    lambda_ratio : float
        Lower end of the explored window, as a fraction of ``lambda_max`` (in ``(0, 1)``).
    max_size : int, optional
        Largest support size considered (the sparsity assumption); default ``m // 2``. The window
        also ends at the largest ``lambda`` where the support exceeds it.

    Returns
    -------
    FlatRange

    Examples
    --------
    >>> import numpy as np
    >>> rng = np.random.default_rng(0)
    >>> X = rng.standard_normal((40, 6))
    >>> y = X @ [0.0, 2.0, 0.0, 0.0, -1.5, 0.0] + 0.1 * rng.standard_normal(40)
    >>> flat = flat_range(lasso_path(X, y))
    >>> int(flat.size), [int(j) for j in flat.support]     # the two faulty components
    (2, [1, 4])
    >>> bool(flat.low < flat.middle < flat.high)
    True
    """
    fr = _flat_ranges(PathBatch.of([path]), scale, lambda_ratio, max_size, single=True)
    return FlatRange(
        low=float(fr.low[0]),
        high=float(fr.high[0]),
        middle=float(fr.middle[0]),
        size=int(fr.size[0]),
        support=np.flatnonzero(fr.support[0]),
        width=float(fr.width[0]),
        scale=scale,
    )


@dataclass(frozen=True)
class GridFlatRange:
    """The widest run of grid points with a constant number of non-zero components.

    Attributes
    ----------
    grid : numpy.ndarray
        The ``lambda`` grid, decreasing, shape ``(n_grid,)``.
    sizes : numpy.ndarray
        Support size at each grid point, shape ``(n_grid,)``; ``-1`` below the window (where the
        support has exceeded ``max_size``, or the path was stopped).
    start, stop : int
        The run is ``grid[start:stop]`` (``stop - start`` points, the width).
    middle : float
        ``grid[(start + stop - 1) // 2]``: the middle grid point of the run (for an even number
        of points, the larger ``lambda`` of the two middle ones).
    size : int
        Number of non-zero components on the run.
    support : numpy.ndarray
        Indices of the non-zero components at ``middle`` (the support of the path interval that
        holds it).
    """

    grid: np.ndarray
    sizes: np.ndarray
    start: int
    stop: int
    middle: float
    size: int
    support: np.ndarray


@dataclass(frozen=True)
class GridFlatRanges:
    """:class:`GridFlatRange` of each path of a :class:`PathBatch` (:func:`grid_flat_ranges`), as arrays.

    Attributes
    ----------
    grid, sizes : numpy.ndarray
        ``(B, n_grid)``, as in :class:`GridFlatRange`.
    start, stop, size : numpy.ndarray
        ``(B,)`` integers.
    middle : numpy.ndarray
        ``(B,)``.
    support : numpy.ndarray
        ``(B, m)`` booleans: the support of the path interval that holds ``middle``.
    """

    grid: np.ndarray
    sizes: np.ndarray
    start: np.ndarray
    stop: np.ndarray
    middle: np.ndarray
    size: np.ndarray
    support: np.ndarray


def grid_flat_range(
    path: LassoPath, n_grid: int, *, lambda_ratio: float = LAMBDA_RATIO, max_size: int | None = None
) -> GridFlatRange:
    """The flat-range rule of Zhang (2021, Sec. IV, after (39)) on a finite ``lambda`` grid.

    The grid is ``n_grid`` geometrically spaced values from ``lambda_max = path.lambdas[0]`` down to
    ``lambda_ratio * lambda_max`` (both included; Matlab's ``lasso`` builds its default grid this
    way). The Lasso path of (39) is piecewise linear in ``lambda`` with a constant support between
    consecutive breakpoints, so the support size at each grid point is read off the exact path (no
    solver). Grid points with support size 0 or above ``max_size`` are not candidates, and the
    window ends at the first grid point where the support exceeds ``max_size`` (as in
    :func:`flat_range`). The widest run of consecutive candidate points with the same size wins
    (ties: the run at the larger ``lambda``); its middle point is the ``lambda`` used. Since the
    grid is geometric, a run's length measures log width: as ``n_grid`` grows the rule tends to
    :func:`flat_range` with ``scale="log"``; a range shorter than the grid step
    ``log(1 / lambda_ratio) / (n_grid - 1)`` may hold no grid point at all.

    Explained in the book: :doc:`/book/zhang2021/sparse`.

    Parameters
    ----------
    path : LassoPath
        Exact path, e.g. from :func:`lasso_path`; it must reach ``lambda_ratio * lambda_max`` or a
        support larger than ``max_size``.
    n_grid : int
        Number of grid points, at least 3.
    lambda_ratio : float
        Lower end of the grid as a fraction of ``lambda_max``, in ``(0, 1)``.
    max_size : int, optional
        Largest support size considered; default ``m // 2``.

    Returns
    -------
    GridFlatRange

    Examples
    --------
    >>> import numpy as np
    >>> rng = np.random.default_rng(0)
    >>> X = rng.standard_normal((40, 6))
    >>> y = X @ [0.0, 2.0, 0.0, 0.0, -1.5, 0.0] + 0.1 * rng.standard_normal(40)
    >>> grid = grid_flat_range(lasso_path(X, y), 100)
    >>> int(grid.size), [int(j) for j in grid.support]
    (2, [1, 4])
    """
    g = _grid_flat_ranges(PathBatch.of([path]), n_grid, lambda_ratio, max_size, single=True)
    return GridFlatRange(
        grid=g.grid[0],
        sizes=g.sizes[0],
        start=int(g.start[0]),
        stop=int(g.stop[0]),
        middle=float(g.middle[0]),
        size=int(g.size[0]),
        support=np.flatnonzero(g.support[0]),
    )


def grid_flat_ranges(
    paths: PathBatch,
    n_grid: int,
    *,
    lambda_ratio: float = LAMBDA_RATIO,
    max_size: int | None = None,
) -> GridFlatRanges:
    """:func:`grid_flat_range` of every path of a batch at once (the same results, as arrays).

    Explained in the book: :doc:`/book/zhang2021/sparse`.

    Parameters
    ----------
    paths : PathBatch
        E.g. from :func:`lasso_path_batch`.
    n_grid, lambda_ratio, max_size
        As in :func:`grid_flat_range`.

    Returns
    -------
    GridFlatRanges

    Raises
    ------
    ModelError
        Naming the first path the rule cannot be applied to.

    Examples
    --------
    >>> import numpy as np
    >>> rng = np.random.default_rng(0)
    >>> X = rng.standard_normal((40, 6))
    >>> y = X @ [0.0, 2.0, 0.0, 0.0, -1.5, 0.0] + 0.1 * rng.standard_normal(40)
    >>> batch = lasso_path_batch(np.stack([X, X]), np.stack([y, 2 * y]))
    >>> grids = grid_flat_ranges(batch, 100)
    >>> grids.size.tolist(), int(grid_flat_range(batch.path(1), 100).size)
    ([2, 2], 2)
    """
    return _grid_flat_ranges(paths, n_grid, lambda_ratio, max_size, single=False)


def _grid_flat_ranges(
    paths: PathBatch, n_grid: Any, lambda_ratio: Any, max_size: Any, *, single: bool
) -> GridFlatRanges:
    if isinstance(n_grid, bool) or not isinstance(n_grid, (int, np.integer)) or n_grid < 3:
        raise ModelError(f"n_grid: expected an integer >= 3, got {n_grid!r}")
    _check_rule(lambda_ratio, max_size)
    a = paths.lambdas
    B, S = a.shape
    rows = np.arange(B)
    bad = np.flatnonzero((paths.n_points < 2) | ~(a[:, 0] > 0))
    if bad.size:
        raise ModelError(
            f"{_name(int(bad[0]), single)}: expected at least two breakpoints and lambda_max > 0"
        )
    top = paths.coefs.shape[2] // 2 if max_size is None else int(max_size)
    grid = a[:, :1] * _unit_grid(int(n_grid), float(lambda_ratio))  # geometric, from lambda_max
    grid[:, 0] = a[:, 0]
    _, act = paths._activity  # (B, S-1, m): support on each interval (a[i+1], a[i])
    K = paths.n_points - 1
    isz = paths._sizes
    # interval i is (a[i+1], a[i]); lambda >= a[0] has the empty support
    idx = np.empty(grid.shape, int)
    neg_a, neg_grid = -a, -grid  # ascending
    for b in range(B):  # one sorted search per path
        idx[b] = np.searchsorted(neg_a[b, : K[b] + 1], neg_grid[b], side="right") - 1
    idx = np.clip(idx, 0, (K - 1)[:, None])
    sizes = np.where(grid >= a[:, :1], 0, isz[rows[:, None], idx])  # theta_hat(lambda_max) = 0
    over = isz > top
    has_over = over.any(axis=1)
    last = a[rows, K]
    covers = last <= grid[:, -1] * (
        1 + 1e-9
    )  # the path covers the grid (up to rounding of its lower end)
    bad = np.flatnonzero(~has_over & ~covers)
    if bad.size:
        b = int(bad[0])
        raise ModelError(
            f"{_name(b, single)}: stops at lambda = {last[b]:g} > lambda_ratio * "
            f"lambda_max = {grid[b, -1]:g} with no support above max_size; compute it "
            "further (lasso_path lambda_min)"
        )
    # the window ends where the support first exceeds max_size
    end = np.where(has_over, a[rows, over.argmax(axis=1)], grid[:, -1])
    sizes = np.where(grid >= end[:, None], sizes, -1)
    rb, first, stop = _runs(sizes)  # runs of equal size
    ok = (sizes[rb, first] >= 1) & (sizes[rb, first] <= top)
    lengths = np.zeros((B, int(n_grid)), int)  # at the first point of each candidate run
    lengths[rb[ok], first[ok]] = (stop - first)[ok]
    start = lengths.argmax(axis=1)  # the first (largest lambda) on ties
    bad = np.flatnonzero(lengths[rows, start] == 0)
    if bad.size:
        raise ModelError(
            f"{_name(int(bad[0]), single)}: no grid point of the {n_grid}-point grid "
            "has between 1 and max_size non-zero components"
        )
    stop = start + lengths[rows, start]
    k = (start + stop - 1) // 2
    support = act[rows, idx[rows, k]]  # support of the interval of grid[k]
    return GridFlatRanges(
        grid=grid,
        sizes=sizes,
        start=start,
        stop=stop,
        middle=grid[rows, k],
        size=sizes[rows, start],
        support=support,
    )


@functools.lru_cache(maxsize=16)
def _unit_grid(n_grid: int, lambda_ratio: float) -> np.ndarray:
    """``n_grid`` geometrically spaced values from 1 down to ``lambda_ratio`` (cached, read-only)."""
    grid = np.geomspace(1.0, lambda_ratio, n_grid)
    grid.flags.writeable = False
    return grid


def least_squares_on_support(X: Any, y: Any, support: Any) -> np.ndarray:
    """Least-squares re-estimate of the selected components (the others set to 0), shape ``(m,)``.

    Explained in the book: :doc:`/book/zhang2021/sparse`.

    Parameters
    ----------
    X : array_like
        ``(rows, m)``.
    y : array_like
        ``(rows,)``.
    support : sequence of int
        Distinct column indices in ``[0, m)`` (no negative, Python-style, index).

    Examples
    --------
    >>> import numpy as np
    >>> X = np.array([[1.0, 0.0, 2.0], [0.0, 1.0, 1.0], [1.0, 1.0, 0.0]])
    >>> least_squares_on_support(X, X @ [2.0, 0.0, -1.0], [0, 2])
    array([ 2.,  0., -1.])
    """
    X, y = _check_xy(X, y)
    m = X.shape[1]
    try:
        idx = np.asarray(
            [integer(i, "support", low=0, high=m - 1) for i in np.ravel(np.asarray(support))],
            dtype=int,
        )
    except TypeError:
        raise ModelError(
            f"support: expected a sequence of column indices, got {support!r}"
        ) from None
    if np.unique(idx).size != idx.size:
        raise ModelError(f"support: expected distinct column indices, got {idx.tolist()}")
    theta = np.zeros(X.shape[1])
    if idx.size:
        theta[idx] = np.linalg.lstsq(X[:, idx], y, rcond=None)[0]
    return theta


@dataclass(frozen=True)
class Diagnosis:
    """Sparse fault isolation of one record: path, flat range, Lasso and least-squares estimates.

    Attributes
    ----------
    path : LassoPath
    flat : FlatRange
    support : numpy.ndarray
        Isolated faults (indices of non-zero components of ``theta``).
    theta_lasso : numpy.ndarray
        Lasso estimate at ``flat.middle``, ``(m,)`` (biased towards 0 by the penalty).
    theta_ls : numpy.ndarray
        Least-squares re-estimate on ``support``, ``(m,)``.
    """

    path: LassoPath
    flat: FlatRange
    support: np.ndarray
    theta_lasso: np.ndarray
    theta_ls: np.ndarray


def diagnose(
    X: Any,
    y: Any,
    *,
    n_samples: int | None = None,
    scale: Scale = "log",
    lambda_ratio: float = LAMBDA_RATIO,
    max_size: int | None = None,
    path: LassoPath | None = None,
) -> Diagnosis:
    """Lasso path, the flat-range rule, then least squares on the selected support (Zhang 2021, Sec. IV-V).

    Explained in the book: :doc:`/book/zhang2021/sparse`.

    Parameters
    ----------
    X, y, n_samples
        As in :func:`lasso_path`.
    scale, lambda_ratio, max_size
        As in :func:`flat_range`.
    path : LassoPath, optional
        A precomputed :func:`lasso_path` of ``X``, ``y``.

    Examples
    --------
    >>> import numpy as np
    >>> rng = np.random.default_rng(0)
    >>> X = rng.standard_normal((40, 6))
    >>> y = X @ [0.0, 2.0, 0.0, 0.0, -1.5, 0.0] + 0.1 * rng.standard_normal(40)
    >>> d = diagnose(X, y)
    >>> [int(j) for j in d.support], np.round(d.theta_ls, 1).tolist()
    ([1, 4], [0.0, 2.0, 0.0, 0.0, -1.5, 0.0])
    """
    X, y = _check_xy(X, y)
    path = lasso_path(X, y, n_samples=n_samples) if path is None else path
    flat = flat_range(path, scale=scale, lambda_ratio=lambda_ratio, max_size=max_size)
    return Diagnosis(
        path=path,
        flat=flat,
        support=flat.support,
        theta_lasso=path.coef(flat.middle),
        theta_ls=least_squares_on_support(X, y, flat.support),
    )
