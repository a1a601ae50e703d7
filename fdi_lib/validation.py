"""Input validation shared by every public function, and the policy for missing and non-finite data.

Policy
------
*A NaN measurement means "missing"; nothing else may be non-finite.*

* Measurements and the quantities computed sample by sample from them (outputs ``y``,
  innovations, residuals) may contain NaN: a sample (time step) with a NaN in any of
  its components is **missing as a whole**, and is handled explicitly:

  - the filters know the missing samples: :func:`fdi_lib.filters.kalman_gains` and
    :func:`fdi_lib.kitanidis.kitanidis_gains` take the pattern (``missing=``, booleans
    ``(N,)``) and set ``K_k = 0``, ``P_{k|k} = P_k`` there (as ``filterpy``'s
    ``KalmanFilter.update(None)``), so that the later gains, the innovation covariances
    ``Sigma_k``, the closed-loop matrices ``A_k = F_k`` and hence the fault signatures
    (:func:`fdi_lib.signatures.fault_signature`, the windowed GLR's ``Gamma_k(r)``) are those
    of the record actually observed. :func:`fdi_lib.filters.kalman_filter` and
    :func:`fdi_lib.kitanidis.kitanidis_filter` compute such gains from ``y`` by default
    (all realisations must then miss the same samples); they predict without updating
    (``Xhat_{k|k} = Xhat_k``) and return a NaN innovation, which marks the sample for the
    tests downstream. A NaN in ``y`` at a sample that given gains observe is a
    :class:`~fdi_lib.errors.NonFiniteError`: gains of the complete record on a record with
    gaps keep an update that did not happen (a biased fault estimate, issue 21). The
    Kitanidis filter rejects, at the first sample after a gap, the unknown inputs pending
    since the gap;
  - the GLR tests (:func:`fdi_lib.glr.glr_known_profile`, :func:`fdi_lib.glr.glr_window`,
    :class:`fdi_lib.glr.WindowedGLR`), :func:`fdi_lib.isolation.information` and
    :func:`fdi_lib.nonparametric.energy_statistic` skip a NaN sample: its innovation and its
    signature rows contribute nothing to the sums. Given these gains (and their
    ``Sigma_chol`` for the energy), the sums are exactly those of the observed samples. They
    require NaN at the samples the gains skip (a finite value there comes from another
    filter: :class:`~fdi_lib.errors.ModelError`); a NaN at a sample the gains observe (an
    innovation dropped after the filter used it) is skipped too, which leaves the other
    innovations and their signatures unchanged. The energy of a window with missing
    samples is a sum of fewer terms, so the chi-square threshold of the full window is
    conservative;
  - the statistics stay finite.

  Functions that cannot skip a sample (RLS tracking, regression data for the Lasso,
  set-valued observers) raise :class:`~fdi_lib.errors.NonFiniteError` naming the argument
  and the first bad index.
* An infinite measurement, and any non-finite model matrix, covariance, parameter,
  threshold or fault vector, is a :class:`~fdi_lib.errors.NonFiniteError` naming the
  argument and the first bad index. A recursion that diverges (Riccati, Kitanidis, RLS)
  raises a typed error naming the step.
* No statistic is NaN without an error, with one documented exception: the windowed
  statistics (:func:`fdi_lib.glr.glr_window`, :func:`fdi_lib.nonparametric.energy_statistic`)
  are NaN on their warm-up, before the first admissible onset or full window.
  :func:`fdi_lib.glr.first_alarm` accepts such a leading warm-up and raises
  :class:`~fdi_lib.errors.NonFiniteError` for any NaN after it (and for a record that is NaN
  throughout): NaN is never read as "no alarm".

Every error is a subclass of :class:`~fdi_lib.errors.FDIError` and names the argument,
what was expected and what was received.
"""

from __future__ import annotations

import numbers
from typing import Any

import numpy as np
import scipy.linalg

from fdi_lib.errors import CovarianceError, ModelError, NonFiniteError, ShapeError

__all__ = [
    "COV_RTOL",
    "check_finite",
    "measurements",
    "missing_samples",
    "missing_pattern",
    "common_pattern",
    "gains_missing",
    "check_missing_known",
    "check_skipped",
    "integer",
    "real",
    "probability",
    "seed",
    "covariance",
    "array",
    "check_gains",
    "initial_state",
    "cholesky",
    "cho_solve",
    "solve_triangular",
]

#: Relative tolerance of the symmetry and positive semi-definiteness checks.
COV_RTOL = 1e-9


def check_finite(arr: np.ndarray, name: str) -> None:
    """Raise :class:`NonFiniteError` naming ``name`` and the first non-finite index of ``arr``.

    Explained in the book: :doc:`/book/notation`.

    Examples
    --------
    >>> import numpy as np
    >>> check_finite(np.array([1.0, np.inf]), "y")
    Traceback (most recent call last):
        ...
    fdi_lib.errors.NonFiniteError: y: expected finite values, got inf at index (1,)
    """
    arr = np.asarray(arr)
    if arr.dtype.kind not in "fc":
        return
    if arr.size > 4096:  # fast path: a finite sum has no NaN or inf term (no temporary array)
        with np.errstate(over="ignore", invalid="ignore"):
            if np.isfinite(np.add.reduce(arr, axis=None)):
                return
    if not np.all(np.isfinite(arr)):
        idx = tuple(int(i) for i in np.argwhere(~np.isfinite(arr))[0])
        raise NonFiniteError(f"{name}: expected finite values, got {arr[idx]} at index {idx}")


def array(value: Any, name: str, *, ndim: int | None = None, finite: bool = True) -> np.ndarray:
    """``value`` as a float array (typed errors for objects, strings, wrong ``ndim`` or non-finite).

    Explained in the book: :doc:`/book/notation`.

    Examples
    --------
    >>> array([1, 2], "u").dtype
    dtype('float64')
    >>> array([[1.0, 2.0]], "u", ndim=1)
    Traceback (most recent call last):
        ...
    fdi_lib.errors.ShapeError: u: expected a 1-d array, got shape (1, 2)
    """
    if value is None or np.iscomplexobj(value):
        raise ShapeError(f"{name}: expected a real numeric array, got {type(value).__name__}")
    try:
        arr = np.asarray(value, dtype=float)
    except (TypeError, ValueError) as exc:
        raise ShapeError(f"{name}: expected a numeric array, got {type(value).__name__}") from exc
    if ndim is not None and arr.ndim != ndim:
        raise ShapeError(f"{name}: expected a {ndim}-d array, got shape {arr.shape}")
    if finite:
        check_finite(arr, name)
    return arr


def missing_samples(arr: np.ndarray, name: str) -> np.ndarray:
    """Missing samples of a measurement-like array ``(..., N, p)``: rows with a NaN.

    Returns a boolean array ``(..., N)``; raises :class:`NonFiniteError` for an infinite value.

    Explained in the book: :doc:`/book/notation`.

    Examples
    --------
    >>> import numpy as np
    >>> missing_samples(np.array([[1.0, 2.0], [np.nan, 0.0]]), "y").tolist()   # a NaN in a row
    [False, True]
    """
    inf = np.isinf(arr)
    if inf.any():
        idx = tuple(int(i) for i in np.argwhere(inf)[0])
        raise NonFiniteError(
            f"{name}: expected finite values or NaN (missing), got {arr[idx]} at index {idx}"
        )
    return np.isnan(arr).any(axis=-1)


def missing_pattern(value: Any, n_steps: int, name: str = "missing") -> np.ndarray:
    """A missing-sample pattern: booleans ``(n_steps,)``, ``True`` where the sample is missing.

    ``None`` means fully observed. Returns a read-only boolean array.

    Explained in the book: :doc:`/book/notation`.

    Examples
    --------
    >>> missing_pattern(None, 3).tolist()
    [False, False, False]
    >>> missing_pattern([1, 3], 4)                     # indices are not a pattern
    Traceback (most recent call last):
        ...
    fdi_lib.errors.ModelError: missing: expected booleans (True: missing), got dtype int64
    """
    if value is None:
        out = np.zeros(n_steps, dtype=bool)
    else:
        arr = np.asarray(value)
        if arr.dtype != bool:
            raise ModelError(f"{name}: expected booleans (True: missing), got dtype {arr.dtype}")
        if arr.shape != (n_steps,):
            raise ShapeError(
                f"{name}: expected shape ({n_steps},), one pattern for the record, got {arr.shape}"
            )
        out = arr.copy()
    out.flags.writeable = False
    return out


def common_pattern(missing: np.ndarray, name: str) -> np.ndarray:
    """The one missing-sample pattern ``(N,)`` shared by all realisations of ``missing`` ``(..., N)``.

    Gains depend on the missing samples, so realisations that miss different samples cannot share
    them: :class:`NonFiniteError` naming the first realisation that differs.

    Explained in the book: :doc:`/book/notation`.

    Examples
    --------
    >>> import numpy as np
    >>> common_pattern(np.array([[False, True], [False, True]]), "y").tolist()
    [False, True]
    >>> common_pattern(np.array([[False, True], [False, False]]), "y")
    Traceback (most recent call last):
        ...
    fdi_lib.errors.NonFiniteError: y: expected the same missing samples in every realisation ...
    """
    flat = missing.reshape(-1, missing.shape[-1])
    if flat.shape[0] == 0:
        return np.zeros(missing.shape[-1], dtype=bool)
    differ = (flat != flat[0]).any(axis=-1)
    if differ.any():
        b = int(np.argmax(differ))
        k = int(np.argmax(flat[b] != flat[0]))
        raise NonFiniteError(
            f"{name}: expected the same missing samples in every realisation (the gains depend on them), "
            f"got realisation {np.unravel_index(b, missing.shape[:-1])} differing from the first at "
            f"sample {k}: filter each pattern with its own gains (missing=...)"
        )
    return flat[0]


def gains_missing(gains: Any) -> np.ndarray:
    """The missing samples ``(N,)`` the filter ``gains`` were computed for (all ``False``: none).

    Explained in the book: :doc:`/book/notation`.

    Examples
    --------
    >>> from fdi_lib.models import ltv_model
    >>> from fdi_lib.filters import kalman_gains
    >>> m = ltv_model(F=[[0.5]], H=[[1.0]], Q=1.0, R=1.0, n_steps=3)
    >>> gains_missing(kalman_gains(m, missing=[False, True, False])).tolist()
    [False, True, False]
    """
    miss = getattr(gains, "missing", None)
    return np.zeros(np.shape(gains.Sigma)[0], dtype=bool) if miss is None else miss


def check_missing_known(missing: np.ndarray, gains: Any, name: str) -> None:
    """Raise :class:`NonFiniteError` if a sample of ``missing`` ``(..., N)`` is observed in ``gains``.

    A filter skips a sample only where its gains say so (``K_k = 0``, ``P_{k|k} = P_k``): a sample
    missing in the data but not in the gains would leave the gains, the innovation covariances and
    the fault signatures those of an update that did not happen (a biased fault estimate).

    Explained in the book: :doc:`/book/notation`.

    Examples
    --------
    >>> import numpy as np
    >>> from fdi_lib.models import ltv_model
    >>> from fdi_lib.filters import kalman_gains
    >>> m = ltv_model(F=[[0.5]], H=[[1.0]], Q=1.0, R=1.0, n_steps=3)
    >>> check_missing_known(np.array([False, True, False]), kalman_gains(m), "y")
    Traceback (most recent call last):
        ...
    fdi_lib.errors.NonFiniteError: y: a sample missing (NaN) at index (1,) is observed in the gains: ...
    """
    unknown = missing & ~gains_missing(gains)
    if unknown.any():
        idx = tuple(int(i) for i in np.argwhere(unknown)[0])
        raise NonFiniteError(
            f"{name}: a sample missing (NaN) at index {idx} is observed in the gains: compute the gains "
            f"for the missing samples (kalman_gains(model, missing=...) or kitanidis_gains(model, E, "
            f"missing=...), with missing = numpy.isnan(y).any(axis=-1))"
        )


def check_skipped(missing: np.ndarray, gains: Any, name: str) -> None:
    """Raise :class:`ModelError` if ``name`` (innovations) is finite at a sample the ``gains`` skip.

    ``missing`` ``(..., N)`` marks the NaN samples of ``name``. A filter run with these gains
    returns NaN there: a finite value comes from another filter, whose innovation covariances and
    fault signatures are not those of ``gains``.

    Explained in the book: :doc:`/book/notation`.

    Examples
    --------
    >>> import numpy as np
    >>> from fdi_lib.models import ltv_model
    >>> from fdi_lib.filters import kalman_gains
    >>> m = ltv_model(F=[[0.5]], H=[[1.0]], Q=1.0, R=1.0, n_steps=3)
    >>> g = kalman_gains(m, missing=[False, True, False])
    >>> check_skipped(np.array([False, False, False]), g, "innovations")
    Traceback (most recent call last):
        ...
    fdi_lib.errors.ModelError: innovations: expected NaN at index (1,), a sample the gains skip ...
    """
    skipped = gains_missing(gains)
    if skipped.any():
        bad = skipped & ~missing
        if bad.any():
            idx = tuple(int(i) for i in np.argwhere(bad)[0])
            raise ModelError(
                f"{name}: expected NaN at index {idx}, a sample the gains skip (missing), got a "
                f"finite value: innovations and gains of different filters"
            )


def measurements(
    value: Any, *, n_steps: int, width: int, name: str
) -> tuple[np.ndarray, np.ndarray]:
    """A measurement record ``(*batch, n_steps, width)`` where NaN marks a missing sample.

    A 1-D array of length ``n_steps`` is accepted when ``width == 1``. Returns the array and
    the boolean mask ``(*batch, n_steps)`` of missing samples.

    Explained in the book: :doc:`/book/notation`.

    Examples
    --------
    >>> import numpy as np
    >>> y, missing = measurements([1.0, np.nan, 3.0], n_steps=3, width=1, name="y")
    >>> y.shape, missing.tolist()                      # NaN: a missing sample, not an error
    ((3, 1), [False, True, False])
    """
    arr = array(value, name, finite=False)
    if arr.ndim == 1 and width == 1:
        arr = arr[:, None]
    if arr.ndim < 2 or arr.shape[-2:] != (n_steps, width):
        raise ShapeError(f"{name}: expected shape (..., {n_steps}, {width}), got {np.shape(value)}")
    return arr, missing_samples(arr, name)


def integer(value: Any, name: str, *, low: int | None = None, high: int | None = None) -> int:
    """An integer in ``[low, high]`` (``bool`` and integral floats are rejected).

    Explained in the book: :doc:`/book/notation`.

    Examples
    --------
    >>> integer(3, "window", low=1)
    3
    >>> integer(True, "window")
    Traceback (most recent call last):
    ...
    fdi_lib.errors.ModelError: window: expected an integer, got True (bool)
    """
    if isinstance(value, np.ndarray) and value.ndim == 0:  # a 0-d array counts as its scalar
        value = value[()]
    if isinstance(value, (bool, np.bool_)) or not isinstance(value, numbers.Integral):
        raise ModelError(f"{name}: expected an integer, got {value!r} ({type(value).__name__})")
    value = int(value)
    if (low is not None and value < low) or (high is not None and value > high):
        if high is None:
            kind = {0: "a non-negative integer", 1: "a positive integer"}.get(
                low, f"an integer >= {low}"
            )
            raise ModelError(f"{name}: expected {kind}, got {value!r}")
        if low is None:
            raise ModelError(f"{name}: expected an integer <= {high}, got {value!r}")
        raise ModelError(f"{name}: expected an integer in [{low}, {high}], got {value!r}")
    return int(value)


def real(
    value: Any,
    name: str,
    *,
    low: float | None = None,
    high: float | None = None,
    low_open: bool = False,
    high_open: bool = False,
    what: str = "a number",
) -> float:
    """A finite real number in the given (closed or open) interval; ``what`` names it in errors.

    Explained in the book: :doc:`/book/notation`.

    Examples
    --------
    >>> real(2.5, "threshold", low=0.0)
    2.5
    >>> real(-1, "threshold", low=0.0)
    Traceback (most recent call last):
        ...
    fdi_lib.errors.ModelError: threshold: expected a number in [0, inf], got -1
    """
    if isinstance(value, np.ndarray) and value.ndim == 0:  # a 0-d array counts as its scalar
        value = value[()]
    if isinstance(value, (bool, np.bool_)) or not isinstance(value, numbers.Real):
        raise ModelError(f"{name}: expected {what}, got {value!r} ({type(value).__name__})")
    x = float(value)
    if not np.isfinite(x):
        raise NonFiniteError(f"{name}: expected a finite number, got {x}")
    bad = (low is not None and (x <= low if low_open else x < low)) or (
        high is not None and (x >= high if high_open else x > high)
    )
    if bad:
        lo = "-inf" if low is None else f"{low:g}"
        hi = "inf" if high is None else f"{high:g}"
        raise ModelError(
            f"{name}: expected {what} in {'(' if low_open else '['}{lo}, {hi}"
            f"{')' if high_open else ']'}, got {value!r}"
        )
    return x


def probability(value: Any, name: str) -> float:
    """A probability in the open interval ``(0, 1)``.

    Explained in the book: :doc:`/book/notation`.

    Examples
    --------
    >>> probability(0.05, "alpha")
    0.05
    >>> probability(1.0, "alpha")
    Traceback (most recent call last):
        ...
    fdi_lib.errors.ModelError: alpha: expected a probability in (0, 1), got 1.0
    """
    return real(value, name, low=0.0, high=1.0, low_open=True, high_open=True, what="a probability")


def seed(value: Any, name: str = "seed") -> int:
    """A root seed for :class:`numpy.random.SeedSequence`: a non-negative integer.

    Explained in the book: :doc:`/book/notation`.

    Examples
    --------
    >>> seed(2014)
    2014
    >>> seed(-3)
    Traceback (most recent call last):
        ...
    fdi_lib.errors.ModelError: seed: expected a non-negative integer, got -3
    """
    return integer(value, name, low=0)


def covariance(arr: np.ndarray, name: str, *, definite: bool) -> None:
    """Check symmetric positive (semi-)definite matrices ``(N, m, m)``; the error names the step.

    A broadcast constant (stride 0 on the first axis) is checked once.

    Explained in the book: :doc:`/book/notation`.

    Examples
    --------
    >>> import numpy as np
    >>> covariance(np.array([[[1.0, 2.0], [0.0, 1.0]]]), "Q", definite=False)
    Traceback (most recent call last):
        ...
    fdi_lib.errors.CovarianceError: Q: expected a symmetric matrix, got asymmetry 2 at step 0
    """
    arr = np.asarray(arr, dtype=float)
    check_finite(arr, name)
    steps = arr[:1] if arr.strides[0] == 0 else arr
    if steps.size == 0:
        return
    scale = np.maximum(1.0, np.abs(steps).max(axis=(-2, -1)))
    asym = np.abs(steps - np.swapaxes(steps, -1, -2)).max(axis=(-2, -1))
    bad = np.nonzero(asym > COV_RTOL * scale)[0]
    if bad.size:
        k = int(bad[0])
        raise CovarianceError(
            f"{name}: expected a symmetric matrix, got asymmetry {asym[k]:.3g} at step {k}"
        )
    eig = np.linalg.eigvalsh(steps)
    emin = eig[:, 0]
    limit = COV_RTOL * np.maximum(1.0, eig[:, -1]) if not definite else 0.0
    bad = np.nonzero(emin <= limit if definite else emin < -limit)[0]
    if bad.size:
        k = int(bad[0])
        kind = "positive definite" if definite else "positive semi-definite"
        raise CovarianceError(
            f"{name}: expected a {kind} matrix, got smallest eigenvalue {emin[k]:.6g} at step {k}"
        )


def check_gains(model: Any, gains: Any, name: str = "gains") -> None:
    """Check that filter ``gains`` (``K`` ``(N, n, p)``, ``Sigma_chol`` ``(N, p, p)``) belong to ``model``.

    Gains of a longer or differently shaped model are an error, never silently truncated.

    Explained in the book: :doc:`/book/notation`.

    Examples
    --------
    >>> from fdi_lib.models import ltv_model
    >>> from fdi_lib.filters import kalman_gains
    >>> short = ltv_model(F=[[0.5]], H=[[1.0]], Q=1.0, R=1.0, n_steps=3)
    >>> long = ltv_model(F=[[0.5]], H=[[1.0]], Q=1.0, R=1.0, n_steps=5)
    >>> check_gains(long, kalman_gains(short))
    Traceback (most recent call last):
        ...
    fdi_lib.errors.ShapeError: gains: expected gains with K of shape (5, 1, 1) for this model, got ...
    """
    shape = (model.n_steps, model.n, model.p)
    if np.shape(getattr(gains, "K", None)) != shape or np.shape(
        getattr(gains, "Sigma_chol", None)
    ) != (model.n_steps, model.p, model.p):
        raise ShapeError(
            f"{name}: expected gains with K of shape {shape} for this model, got "
            f"{type(gains).__name__} with K {np.shape(getattr(gains, 'K', None))}"
        )


def initial_state(model: Any, x0: Any, name: str = "x0") -> np.ndarray:
    """``x0`` (default ``model.x0``) checked to be a finite vector of shape ``(n,)`` (no broadcasting).

    Explained in the book: :doc:`/book/notation`.

    Examples
    --------
    >>> from fdi_lib.models import ltv_model
    >>> m = ltv_model(F=[[0.5]], H=[[1.0]], Q=1.0, R=1.0, n_steps=3)
    >>> initial_state(m, None).tolist()              # the model's x0
    [0.0]
    >>> initial_state(m, [1.0, 2.0])
    Traceback (most recent call last):
        ...
    fdi_lib.errors.ShapeError: x0: expected shape (1,), got (2,)
    """
    if x0 is None:
        return model.x0
    x = array(x0, name, finite=False)
    if x.shape != (model.n,):
        raise ShapeError(f"{name}: expected shape ({model.n},), got {x.shape}")
    check_finite(x, name)
    return x


def cholesky(
    S: np.ndarray, *, step: int, what: str, name: str = "model"
) -> tuple[np.ndarray, bool]:
    """``scipy.linalg.cho_factor(S, lower=True)`` inside a recursion, with typed errors naming the step.

    A non-finite ``S`` means the recursion ``what`` diverged (:class:`NonFiniteError`); a matrix
    that is not positive definite raises :class:`CovarianceError`.

    Explained in the book: :doc:`/book/notation`.

    Examples
    --------
    >>> import numpy as np
    >>> cholesky(np.array([[4.0]]), step=0, what="Riccati")[0].tolist()
    [[2.0]]
    >>> cholesky(np.array([[1.0, 0.0], [0.0, -1.0]]), step=7, what="Riccati")
    Traceback (most recent call last):
        ...
    fdi_lib.errors.CovarianceError: model: Riccati lost positive definiteness at step 7 ...
    """
    if not np.all(np.isfinite(S)):
        raise NonFiniteError(f"{name}: {what} diverged (non-finite values at step {step})")
    # finite: checked above. LAPACK's potrf as cho_factor calls it (its upper triangle not
    # cleaned), without scipy's per-call argument handling: most of the call on a small matrix
    (potrf,) = scipy.linalg.get_lapack_funcs(("potrf",), (S,))
    c, info = potrf(S, lower=True, overwrite_a=False, clean=False)
    if info > 0:
        raise CovarianceError(
            f"{name}: {what} lost positive definiteness at step {step} (expected a "
            f"positive definite matrix, smallest eigenvalue "
            f"{np.linalg.eigvalsh(S)[0]:.3g})"
        )
    return c, True  # (info < 0, an illegal argument: excluded by f2py's checks)


def cho_solve(c: np.ndarray, b: np.ndarray) -> np.ndarray:
    """``scipy.linalg.cho_solve((c, True), b, check_finite=False)`` inside a recursion: ``S^{-1} b``
    from the factor ``c`` of :func:`cholesky`, ``b`` ``(p,)`` or ``(p, m)`` finite and not empty.

    The same LAPACK call (potrs), so the same bits, without scipy's per-call argument handling
    (five times the solve itself on the recursions' small matrices).

    Explained in the book: :doc:`/book/notation`.

    Examples
    --------
    >>> import numpy as np
    >>> c, _ = cholesky(np.array([[4.0, 2.0], [2.0, 5.0]]), step=0, what="Riccati")
    >>> cho_solve(c, np.array([6.0, 7.0])).tolist()
    [1.0, 1.0]
    """
    (potrs,) = scipy.linalg.get_lapack_funcs(("potrs",), (c, b))
    return potrs(c, b, lower=True, overwrite_b=False)[0]  # (its info: an illegal argument)


def solve_triangular(
    a: np.ndarray, b: np.ndarray, *, lower: bool = False, trans: bool = False
) -> np.ndarray:
    """``scipy.linalg.solve_triangular(a, b, trans, lower, check_finite=False)`` inside a
    recursion: ``a^{-1} b`` (``trans``: ``a^{-T} b``), ``a`` ``(p, p)`` triangular, ``b`` ``(p,)``
    or ``(p, m)``, both finite and not empty.

    The same LAPACK call as scipy's (trtrs; on ``a^T``, the other triangle and the other
    transposition, when ``a`` is not in Fortran order), so the same bits, without its per-call
    argument handling (ten times the solve itself on the recursions' small matrices).

    Explained in the book: :doc:`/book/notation`.

    Examples
    --------
    >>> import numpy as np
    >>> solve_triangular(np.array([[2.0, 0.0], [1.0, 1.0]]), np.array([2.0, 3.0]), lower=True)
    array([1., 2.])
    >>> solve_triangular(np.array([[1.0, 0.0], [0.0, 0.0]]), np.ones(2), lower=True)
    Traceback (most recent call last):
        ...
    numpy.linalg.LinAlgError: singular matrix: resolution failed at diagonal 1
    """
    (trtrs,) = scipy.linalg.get_lapack_funcs(("trtrs",), (a, b))
    if a.flags.f_contiguous:
        x, info = trtrs(a, b, overwrite_b=False, lower=lower, trans=trans, unitdiag=False)
    else:  # trtrs reads Fortran order: the transposed system, as scipy solves it
        x, info = trtrs(a.T, b, overwrite_b=False, lower=not lower, trans=not trans, unitdiag=False)
    if info > 0:
        raise np.linalg.LinAlgError(f"singular matrix: resolution failed at diagonal {info - 1}")
    return x
