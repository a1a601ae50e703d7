r"""Linear time-varying (LTV) and linear parameter-varying (LPV) state-space models.

The model of Zhang & Basseville (2014), eqs. (1), (3) and (5):

.. math::

    \begin{aligned}
    X_{k+1} &= F_k X_k + G_k U_k + W_k + \Psi_k \theta, & W_k &\sim \mathcal N(0, Q_k), \\
    Y_k &= H_k X_k + J_k U_k + V_k + \Phi_k \theta, & V_k &\sim \mathcal N(0, R_k).
    \end{aligned}

Every time-varying matrix may be given as a constant, a per-step array of
shape ``(n_steps, rows, cols)`` or a callable ``k -> (rows, cols)``. It is
materialised once, on the horizon ``k = 0 .. n_steps-1``, and validated up
front (shapes, finiteness, symmetric PSD :math:`Q_k`, symmetric PD :math:`R_k`), so
that the filters and tests can use vectorised array code without re-checking.
Constant matrices are stored as read-only broadcast views (no copies).
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any, Literal

import numpy as np

from fdi_lib.errors import ModelError, ShapeError
from fdi_lib.validation import array, check_finite, covariance, integer

__all__ = [
    "LTVModel",
    "ltv_model",
    "lpv_model",
    "as_sequence",
    "as_record",
    "FaultProfile",
    "FaultFamily",
    "fault_profile",
    "step_family",
    "impulse_family",
]

MatrixLike = Any  # array_like | Callable[[int], array_like]


def as_sequence(
    value: MatrixLike, *, n_steps: int, shape: tuple[int, ...], name: str
) -> np.ndarray:
    """Materialise a constant / per-step / callable matrix on ``k = 0 .. n_steps-1``.

    Explained in the book: :doc:`/book/notation`.

    Parameters
    ----------
    value : array_like or callable
        Constant of shape ``shape``, per-step array of shape ``(n_steps, *shape)``,
        or callable ``k -> array`` of shape ``shape``. A scalar is accepted for a
        ``(1, 1)`` or ``(1,)`` shape.
    n_steps : int
        Horizon length.
    shape : tuple of int
        Expected shape of one step.
    name : str
        Argument name used in error messages.

    Returns
    -------
    numpy.ndarray
        Read-only array of shape ``(n_steps, *shape)`` (a broadcast view for constants).

    Examples
    --------
    >>> import numpy as np
    >>> as_sequence([[2.0]], n_steps=3, shape=(1, 1), name="F").ravel().tolist()   # a constant
    [2.0, 2.0, 2.0]
    >>> as_sequence(lambda k: [[k]], n_steps=3, shape=(1, 1), name="F").ravel().tolist()
    [0.0, 1.0, 2.0]
    """
    if callable(value):
        steps = []
        for k in range(n_steps):
            vk = array(value(k), f"{name}({k})", finite=False)
            if vk.shape != shape and not (vk.ndim == 0 and int(np.prod(shape)) == 1):
                raise ShapeError(f"{name}({k}): expected shape {shape}, got {vk.shape}")
            steps.append(vk.reshape(shape))
        arr = np.stack(steps) if steps else np.zeros((0, *shape))
    else:
        try:
            arr = np.asarray(value, dtype=float)
        except (TypeError, ValueError) as exc:
            raise ModelError(
                f"{name}: expected an array, a per-step array or a callable of k, "
                f"got {type(value).__name__}"
            ) from exc
        if arr.ndim == 0 and int(np.prod(shape)) == 1:
            arr = arr.reshape(shape)
        if arr.shape == shape:
            arr = np.broadcast_to(arr, (n_steps, *shape))
        elif arr.shape != (n_steps, *shape):
            raise ShapeError(
                f"{name}: expected shape {shape} (constant) or {(n_steps, *shape)} "
                f"(per step), got {arr.shape}"
            )
    check_finite(arr, name)
    arr = np.asarray(arr)
    if arr.flags.writeable and arr.base is None:
        arr.setflags(write=False)
    return arr


def as_record(value: Any, *, n_steps: int, width: int, name: str) -> np.ndarray:
    """Validate a data record ``value`` (inputs or outputs) of shape ``(*batch, n_steps, width)``.

    ``width`` is the number of columns, ``name`` the argument named in errors. ``None`` gives
    zeros ``(n_steps, width)``; a 1-D array of length ``n_steps`` is accepted when ``width == 1``. Raises :class:`ShapeError` or :class:`NonFiniteError` (with the index).

    Explained in the book: :doc:`/book/notation`.

    Examples
    --------
    >>> as_record([1.0, 2.0, 3.0], n_steps=3, width=1, name="y").shape   # 1-D accepted for width 1
    (3, 1)
    >>> as_record(None, n_steps=2, width=2, name="u").tolist()            # no input: zeros
    [[0.0, 0.0], [0.0, 0.0]]
    """
    if value is None:
        return np.zeros((n_steps, width))
    arr = array(value, name, finite=False)
    if arr.ndim == 1 and width == 1:
        arr = arr[:, None]
    if arr.ndim < 2 or arr.shape[-2:] != (n_steps, width):
        raise ShapeError(f"{name}: expected shape (..., {n_steps}, {width}), got {np.shape(value)}")
    check_finite(arr, name)
    return arr


@dataclass(frozen=True)
class LTVModel:
    """A validated LTV model on a finite horizon (Zhang & Basseville 2014, eq. (1)).

    Attributes
    ----------
    F, G, H, J, Q, R : numpy.ndarray
        Shapes ``(N, n, n)``, ``(N, n, l)``, ``(N, p, n)``, ``(N, p, l)``,
        ``(N, n, n)``, ``(N, p, p)``; read-only.
    x0 : numpy.ndarray
        Mean of the initial state, shape ``(n,)``.
    P0 : numpy.ndarray
        Covariance of the initial state, shape ``(n, n)``.

    Build it with :func:`ltv_model` or :func:`lpv_model`, which validate.
    """

    F: np.ndarray
    G: np.ndarray
    H: np.ndarray
    J: np.ndarray
    Q: np.ndarray
    R: np.ndarray
    x0: np.ndarray
    P0: np.ndarray

    @property
    def n_steps(self) -> int:
        return self.F.shape[0]

    @property
    def n(self) -> int:
        """State dimension."""
        return self.F.shape[1]

    @property
    def l(self) -> int:  # noqa: E743 - the paper's name for the input dimension
        """Input dimension."""
        return self.G.shape[2]

    @property
    def p(self) -> int:
        """Output dimension."""
        return self.H.shape[1]


def ltv_model(
    *,
    F: MatrixLike,
    H: MatrixLike,
    Q: MatrixLike,
    R: MatrixLike,
    n_steps: int,
    G: MatrixLike | None = None,
    J: MatrixLike | None = None,
    x0: Any = None,
    P0: Any = None,
) -> LTVModel:
    """Build and validate an :class:`LTVModel`.

    Explained in the book: :doc:`/book/zb2014/signature`.

    Parameters
    ----------
    F : array_like or callable
        State matrices ``F_k``, shape ``(n, n)`` per step.
    H : array_like or callable
        Output matrices ``H_k``, shape ``(p, n)`` per step.
    Q, R : array_like or callable
        State and output noise covariances; ``Q_k`` symmetric PSD ``(n, n)``,
        ``R_k`` symmetric positive definite ``(p, p)``.
    n_steps : int
        Horizon ``N``: matrices are materialised for ``k = 0 .. N-1``.
    G, J : array_like or callable, optional
        Input matrices ``(n, l)`` and ``(p, l)``; default: no input (``l = 0``)
        and ``J_k = 0``.
    x0 : array_like, optional
        Initial state mean ``(n,)``, default zeros.
    P0 : array_like, optional
        Initial state covariance ``(n, n)``, symmetric PSD, default identity.

    Examples
    --------
    >>> import numpy as np
    >>> m = ltv_model(F=[[0.5, 1.0], [0.0, 1.2]], G=[[0.0], [1.0]], H=[[1.0, 0.0]],
    ...               Q=0.0025 * np.eye(2), R=0.0025, n_steps=10)
    >>> (m.n, m.l, m.p, m.n_steps)
    (2, 1, 1, 10)
    """
    n_steps = integer(n_steps, "n_steps", low=1)
    F_first = array(F(0) if callable(F) else F, "F", finite=False)
    if F_first.ndim not in (2, 3) or F_first.shape[-1] != F_first.shape[-2]:
        raise ShapeError(
            f"F: expected square matrices (n, n) or (N, n, n), got shape {F_first.shape}"
        )
    n = F_first.shape[-1]
    H_first = array(H(0) if callable(H) else H, "H", finite=False)
    if H_first.ndim not in (2, 3) or H_first.shape[-1] != n:
        raise ShapeError(f"H: expected shape (p, {n}) or (N, p, {n}), got {H_first.shape}")
    p = H_first.shape[-2]
    if G is None:
        l = 0
        Gs = np.zeros((n_steps, n, 0))
    else:
        G_first = array(G(0) if callable(G) else G, "G", finite=False)
        if G_first.ndim not in (2, 3) or G_first.shape[-2] != n:
            raise ShapeError(f"G: expected shape ({n}, l) or (N, {n}, l), got {G_first.shape}")
        l = G_first.shape[-1]
        Gs = as_sequence(G, n_steps=n_steps, shape=(n, l), name="G")
    Fs = as_sequence(F, n_steps=n_steps, shape=(n, n), name="F")
    Hs = as_sequence(H, n_steps=n_steps, shape=(p, n), name="H")
    Js = (
        np.broadcast_to(np.zeros((p, l)), (n_steps, p, l))
        if J is None
        else as_sequence(J, n_steps=n_steps, shape=(p, l), name="J")
    )
    Qs = as_sequence(Q, n_steps=n_steps, shape=(n, n), name="Q")
    Rs = as_sequence(R, n_steps=n_steps, shape=(p, p), name="R")
    covariance(Qs, "Q", definite=False)
    covariance(Rs, "R", definite=True)
    x0a = np.zeros(n) if x0 is None else array(x0, "x0", finite=False)
    if x0a.shape != (n,):
        raise ShapeError(f"x0: expected shape ({n},), got {x0a.shape}")
    check_finite(x0a, "x0")
    P0a = np.eye(n) if P0 is None else array(P0, "P0", finite=False)
    if P0a.shape != (n, n):
        raise ShapeError(f"P0: expected shape ({n}, {n}), got {P0a.shape}")
    check_finite(P0a, "P0")
    covariance(P0a[None], "P0", definite=False)
    return LTVModel(F=Fs, G=Gs, H=Hs, J=Js, Q=Qs, R=Rs, x0=x0a, P0=P0a)


def lpv_model(
    *,
    scheduling: Any,
    F0: Any,
    H0: Any,
    Q: MatrixLike,
    R: MatrixLike,
    Fp: Any = None,
    G0: Any = None,
    Gp: Any = None,
    Hp: Any = None,
    J0: Any = None,
    Jp: Any = None,
    x0: Any = None,
    P0: Any = None,
) -> LTVModel:
    """Build an LTV model from affine LPV matrices, e.g. ``F_k = F0 + sum_i Fp[i] p_k[i]``.

    Zhang & Basseville (2014), eq. (53), generalised to several scheduling parameters.

    Explained in the book: :doc:`/book/zb2014/pipeline`.

    Parameters
    ----------
    scheduling : array_like
        Scheduling signal ``p_k``, shape ``(N,)`` (one parameter) or ``(N, q)``.
    F0, G0, H0, J0 : array_like
        Constant parts.
    Fp, Gp, Hp, Jp : array_like or sequence of array_like, optional
        Parameter-dependent parts: one matrix (``q = 1``) or a sequence of ``q`` matrices.
    Q, R, x0, P0
        As in :func:`ltv_model`.

    Examples
    --------
    >>> import numpy as np
    >>> p = np.linspace(0.0, 1.0, 4)                       # scheduling p_k, N = 4
    >>> m = lpv_model(scheduling=p, F0=[[0.5]], Fp=[[0.2]], H0=[[1.0]], Q=1.0, R=1.0)
    >>> m.F[:, 0, 0].round(3).tolist()                      # F_k = 0.5 + 0.2 p_k
    [0.5, 0.567, 0.633, 0.7]
    """
    p_sched = array(scheduling, "scheduling", finite=False)
    if p_sched.ndim == 1:
        p_sched = p_sched[:, None]
    if p_sched.ndim != 2 or p_sched.shape[0] < 1:
        raise ShapeError(f"scheduling: expected shape (N,) or (N, q), got {np.shape(scheduling)}")
    check_finite(p_sched, "scheduling")
    n_steps, q = p_sched.shape

    def affine(name: str, base: Any, parts: Any) -> np.ndarray | None:
        if base is None:
            return None
        b = array(base, f"{name}0", finite=False)
        if parts is None:
            return b
        plist = (
            [np.asarray(parts, dtype=float)]
            if np.ndim(parts) == b.ndim
            else [np.asarray(x, dtype=float) for x in parts]
        )
        if len(plist) != q:
            raise ShapeError(
                f"{name}p: expected {q} matrices (one per scheduling parameter), got {len(plist)}"
            )
        for i, part in enumerate(plist):
            if part.shape != b.shape:
                raise ShapeError(
                    f"{name}p[{i}]: expected shape {b.shape} (as {name}0), got {part.shape}"
                )
        return b + np.einsum("kq,qij->kij", p_sched, np.stack(plist))

    return ltv_model(
        F=affine("F", F0, Fp),
        G=affine("G", G0, Gp),
        H=affine("H", H0, Hp),
        J=affine("J", J0, Jp),
        Q=Q,
        R=R,
        n_steps=n_steps,
        x0=x0,
        P0=P0,
    )


@dataclass(frozen=True)
class FaultProfile:
    """Known fault profiles ``Psi_k`` (state) and ``Phi_k`` (output) of eq. (5).

    Attributes
    ----------
    Psi : numpy.ndarray
        Shape ``(N, n, m)``.
    Phi : numpy.ndarray
        Shape ``(N, p, m)`` (zeros when the fault acts on the state only, eq. (3)).
    """

    Psi: np.ndarray
    Phi: np.ndarray

    @property
    def m(self) -> int:
        """Dimension of the fault vector ``theta``."""
        return self.Psi.shape[2]

    @property
    def has_output_fault(self) -> bool:
        return bool(np.any(self.Phi))


def fault_profile(
    model: LTVModel,
    *,
    Psi: MatrixLike | None = None,
    Phi: MatrixLike | None = None,
    m: int | None = None,
) -> FaultProfile:
    """Validate fault profiles against ``model`` (either may be omitted, not both).

    ``m`` (the dimension of ``theta``) is inferred from ``Psi`` or ``Phi``.

    Explained in the book: :doc:`/book/zb2014/signature`.

    Examples
    --------
    >>> m = ltv_model(F=[[0.9]], H=[[1.0]], Q=1.0, R=1.0, n_steps=10)
    >>> prof = fault_profile(m, Psi=[[1.0]])        # a state fault; Phi defaults to zero
    >>> prof.Psi.shape, prof.Phi.shape, float(abs(prof.Phi).max())
    ((10, 1, 1), (10, 1, 1), 0.0)
    """
    N, n, p = model.n_steps, model.n, model.p
    if Psi is None and Phi is None:
        raise ModelError("fault_profile: give Psi, Phi or both")
    if m is None:
        first = Psi if Psi is not None else Phi
        arr = array(
            first(0) if callable(first) else first,
            "Psi" if Psi is not None else "Phi",
            finite=False,
        )
        if arr.ndim not in (2, 3):
            raise ShapeError(
                f"{'Psi' if Psi is not None else 'Phi'}: expected a matrix (rows, m) or "
                f"(N, rows, m), got shape {arr.shape}"
            )
        m = arr.shape[-1]
    Psis = (
        np.broadcast_to(np.zeros((n, m)), (N, n, m))
        if Psi is None
        else as_sequence(Psi, n_steps=N, shape=(n, m), name="Psi")
    )
    Phis = (
        np.broadcast_to(np.zeros((p, m)), (N, p, m))
        if Phi is None
        else as_sequence(Phi, n_steps=N, shape=(p, m), name="Phi")
    )
    return FaultProfile(Psi=Psis, Phi=Phis)


@dataclass(frozen=True)
class FaultFamily:
    """A family of jump profiles ``Psi_k(r)``, ``Phi_k(r)`` indexed by the unknown onset ``r``.

    ``kind == "step"``: eq. (4), ``Psi_k(r) = Psi~_k 1{k >= r}`` and likewise ``Phi``;
    the first innovation affected is ``eps_{r+1}`` (``eps_r`` for an output fault).
    ``kind == "impulse"``: ``Psi_k(r) = Psi~_k delta_{r,k+1}`` (Willsky-Jones, eq. (A.1));
    the state jumps at time ``r`` and the first innovation affected is ``eps_r``.

    ``Psi_tilde`` is ``(N, n, m)`` and ``Phi_tilde`` ``(N, p, m)``, shared by all realisations;
    or, for a profile that differs per realisation (a step family whose ``Psi~_k`` is a
    realisation's own input, :func:`step_family` with a leading batch axis), ``(*batch, N, n, m)``
    and ``(*batch, N, p, m)``, with ``batch`` that of the innovations the GLR tests it on
    (:func:`fdi_lib.glr.glr_window`).
    """

    kind: Literal["step", "impulse"]
    Psi_tilde: np.ndarray
    Phi_tilde: np.ndarray

    @property
    def m(self) -> int:
        return self.Psi_tilde.shape[-1]

    @property
    def batch_shape(self) -> tuple[int, ...]:
        """Leading shape of per-realisation profiles; ``()`` for a family shared by all realisations."""
        return tuple(self.Psi_tilde.shape[:-3])

    def profile(self, onset: int) -> FaultProfile:
        """The profile for onset ``r = onset`` (time indices ``0 .. N-1``) of a shared family."""
        if self.batch_shape:
            raise ModelError(
                f"profile: expected a family shared by all realisations, got per-realisation "
                f"profiles of batch shape {self.batch_shape} (build one family per realisation)"
            )
        N = self.Psi_tilde.shape[0]
        if not isinstance(onset, (int, np.integer)) or not 0 <= onset <= N:
            raise ModelError(f"onset: expected an integer in [0, {N}], got {onset!r}")
        k = np.arange(N)
        mask = (k >= onset) if self.kind == "step" else (k + 1 == onset)
        return FaultProfile(
            Psi=self.Psi_tilde * mask[:, None, None], Phi=self.Phi_tilde * mask[:, None, None]
        )


def step_family(
    model: LTVModel, *, Psi: MatrixLike | None = None, Phi: MatrixLike | None = None
) -> FaultFamily:
    """Step (jump) faults of eq. (4) with known profiles ``Psi`` = ``Psi~_k`` and/or ``Phi`` = ``Phi~_k``.

    Both are validated against ``model`` as in :func:`fault_profile`. Either may instead be an
    array of per-realisation profiles, ``(*batch, N, n, m)`` for ``Psi`` or ``(*batch, N, p, m)``
    for ``Phi`` (4-d or more; e.g. a profile made of each realisation's input): the family then
    has ``batch_shape == batch`` (two such arrays must agree on it; the other profile, if shared,
    applies to every realisation) and is tested on innovations ``(*batch, N, p)`` of that same
    batch shape, all realisations in one pass (:func:`fdi_lib.glr.glr_window`).

    Explained in the book: :doc:`/book/zb2014/glr`.

    Examples
    --------
    >>> m = ltv_model(F=[[0.9]], H=[[1.0]], Q=1.0, R=1.0, n_steps=6)
    >>> fam = step_family(m, Psi=[[1.0]])
    >>> fam.profile(onset=4).Psi[:, 0, 0].tolist()  # Psi_k(r) = Psi~_k 1{k >= r}
    [0.0, 0.0, 0.0, 0.0, 1.0, 1.0]
    """
    batched = {
        name: array(value, name)
        for name, value in (("Psi", Psi), ("Phi", Phi))
        if value is not None and not callable(value) and np.ndim(value) > 3
    }
    if not batched:
        prof = fault_profile(model, Psi=Psi, Phi=Phi)
        return FaultFamily(kind="step", Psi_tilde=prof.Psi, Phi_tilde=prof.Phi)
    N, rows = model.n_steps, {"Psi": model.n, "Phi": model.p}
    for name, arr in batched.items():
        if arr.shape[-3:-1] != (N, rows[name]):
            raise ShapeError(
                f"{name}: expected per-realisation profiles (*batch, {N}, {rows[name]}, m), "
                f"got shape {arr.shape}"
            )
    (first, a), *rest = batched.items()
    batch, m = a.shape[:-3], a.shape[-1]
    for name, arr in rest:
        if arr.shape[:-3] != batch or arr.shape[-1] != m:
            raise ShapeError(
                f"{name}: expected shape {(*batch, N, rows[name], m)} (the batch and m of "
                f"{first}), got {arr.shape}"
            )
    out = {}
    for name, value in (("Psi", Psi), ("Phi", Phi)):
        shape = (rows[name], m)
        if name in batched:
            arr = batched[name].view()
            arr.setflags(write=False)
        elif value is None:
            arr = np.broadcast_to(np.zeros(shape), (*batch, N, *shape))
        else:  # shared by every realisation
            arr = np.broadcast_to(
                as_sequence(value, n_steps=N, shape=shape, name=name), (*batch, N, *shape)
            )
        out[name] = arr
    return FaultFamily(kind="step", Psi_tilde=out["Psi"], Phi_tilde=out["Phi"])


def impulse_family(model: LTVModel, *, Psi: MatrixLike | None = None) -> FaultFamily:
    """Impulsive faults ``Psi_k = Psi~_k delta_{r,k+1}`` of ``model``; ``Psi`` is ``Psi~_k``, default
    ``Psi~ = I`` (Willsky-Jones, ``m = n``).

    Explained in the book: :doc:`/book/zb2014/signature`.

    Examples
    --------
    >>> m = ltv_model(F=[[0.9]], H=[[1.0]], Q=1.0, R=1.0, n_steps=6)
    >>> impulse_family(m).profile(onset=4).Psi[:, 0, 0].tolist()   # delta_{r,k+1}: only k = 3
    [0.0, 0.0, 0.0, 1.0, 0.0, 0.0]
    """
    prof = fault_profile(model, Psi=np.eye(model.n) if Psi is None else Psi)
    return FaultFamily(kind="impulse", Psi_tilde=prof.Psi, Phi_tilde=prof.Phi)
