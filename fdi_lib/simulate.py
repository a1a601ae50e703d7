r"""Simulation of the faulty LTV system, open or closed loop.

Zhang & Basseville (2014), eqs. (3) and (5):

.. math::

    \begin{aligned}
    X_{k+1} &= F_k X_k + G_k U_k + W_k + \Psi_k \theta, \\
    Y_k &= H_k X_k + J_k U_k + V_k + \Phi_k \theta .
    \end{aligned}

Noise is drawn first, as a :class:`Noise` record, so that exactly the same
realisation can be replayed with another ``theta`` (e.g. ``theta = 0``): this
is what makes Proposition 1 checkable to machine precision. Everything is
vectorised over an optional leading axis of independent realisations.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any, Callable

import numpy as np

from fdi_lib.errors import ModelError, NonFiniteError, ShapeError
from fdi_lib.models import FaultProfile, LTVModel, as_record
from fdi_lib.validation import array, check_finite, integer

__all__ = [
    "Noise",
    "NoiseRoots",
    "Simulation",
    "noise_roots",
    "draw_noise",
    "noise_from_standard",
    "simulate",
    "pi_controller",
    "covariance_sqrt",
]


@dataclass(frozen=True)
class Noise:
    """One or several noise realisations.

    Attributes
    ----------
    x0 : numpy.ndarray
        Initial states ``X_0``, shape ``(*batch, n)``.
    w : numpy.ndarray
        State noise ``W_k``, shape ``(*batch, N, n)``.
    v : numpy.ndarray
        Output noise ``V_k``, shape ``(*batch, N, p)``.
    """

    x0: np.ndarray
    w: np.ndarray
    v: np.ndarray

    @property
    def batch_shape(self) -> tuple[int, ...]:
        return self.x0.shape[:-1]


@dataclass(frozen=True)
class Simulation:
    """A simulated record: states ``x`` ``(*batch, N+1, n)``, outputs ``y`` ``(*batch, N, p)``,
    inputs ``u`` ``(*batch, N, l)`` and the ``noise`` that produced them."""

    x: np.ndarray
    y: np.ndarray
    u: np.ndarray
    noise: Noise


def covariance_sqrt(cov: np.ndarray) -> np.ndarray:
    """A square root ``S`` with ``S S^T = cov`` for symmetric PSD matrices ``cov`` (batched, via ``eigh``).

    ``eigh`` rather than Cholesky so that singular PSD covariances (e.g. rank-one ``Q``) work.

    Explained in the book: :doc:`/book/zb2014/signature`.

    Examples
    --------
    >>> import numpy as np
    >>> S = covariance_sqrt(np.array([[4.0, 0.0], [0.0, 0.0]]))   # singular PSD: no Cholesky
    >>> (S @ S.T).round(12).tolist()
    [[4.0, 0.0], [0.0, 0.0]]
    """
    eig, vec = np.linalg.eigh(cov)
    return vec * np.sqrt(np.clip(eig, 0.0, None))[..., None, :]


@dataclass(frozen=True)
class NoiseRoots:
    """Square roots ``S S^T = cov`` of a model's noise covariances (:func:`covariance_sqrt`).

    Attributes
    ----------
    P0 : numpy.ndarray
        Root of ``P0``, ``(n, n)``.
    Q, R : numpy.ndarray
        Roots of ``Q_k``, ``(N, n, n)``, and ``R_k``, ``(N, p, p)`` (read-only broadcasts of one root
        when the covariance is constant).
    """

    P0: np.ndarray
    Q: np.ndarray
    R: np.ndarray


def noise_roots(model: LTVModel) -> NoiseRoots:
    """The covariance roots :func:`draw_noise` uses, to compute once for many draws from ``model``.

    Explained in the book: :doc:`/book/zb2014/signature`.

    Examples
    --------
    >>> import numpy as np
    >>> from fdi_lib.models import ltv_model
    >>> m = ltv_model(F=[[0.5]], H=[[1.0]], Q=4.0, R=1.0, n_steps=3)
    >>> roots = noise_roots(m)                       # computed once, reused by every draw
    >>> n = draw_noise(m, np.random.default_rng(0), size=2, roots=roots)
    >>> float(roots.Q[0, 0, 0]), n.w.shape
    (2.0, (2, 3, 1))
    """
    N = model.n_steps

    def root(cov: np.ndarray, dim: int) -> np.ndarray:
        r = covariance_sqrt(cov[:1] if cov.strides[0] == 0 else cov)  # one root for constants
        return np.broadcast_to(r, (N, dim, dim))

    return NoiseRoots(
        P0=covariance_sqrt(model.P0), Q=root(model.Q, model.n), R=root(model.R, model.p)
    )


def draw_noise(
    model: LTVModel,
    rng: np.random.Generator,
    size: int | None = None,
    *,
    roots: NoiseRoots | None = None,
) -> Noise:
    """Draw ``X_0 ~ N(x0, P0)``, ``W_k ~ N(0, Q_k)``, ``V_k ~ N(0, R_k)``.

    Explained in the book: :doc:`/book/zb2014/signature`.

    Parameters
    ----------
    model : LTVModel
    rng : numpy.random.Generator
        The only source of randomness (no global state).
    size : int, optional
        Number of independent realisations (leading batch axis); ``None`` for one.
    roots : NoiseRoots, optional
        ``noise_roots(model)``, when drawing many times from the same model (the three ``eigh``
        are then done once); the draws are the same.

    Examples
    --------
    >>> import numpy as np
    >>> from fdi_lib.models import ltv_model
    >>> m = ltv_model(F=[[0.5]], H=[[1.0]], Q=4.0, R=1.0, n_steps=20000)
    >>> n = draw_noise(m, np.random.default_rng(0))
    >>> round(float(n.w.std()), 1), round(float(n.v.std()), 1)    # sqrt(Q), sqrt(R)
    (2.0, 1.0)
    """
    if not isinstance(rng, np.random.Generator):
        raise ModelError(f"rng: expected a numpy.random.Generator, got {type(rng).__name__}")
    batch = () if size is None else (integer(size, "size", low=1),)
    N, n, p = model.n_steps, model.n, model.p
    z0 = rng.standard_normal((*batch, n))
    zw = rng.standard_normal((*batch, N, n))
    zv = rng.standard_normal((*batch, N, p))
    return noise_from_standard(model, z0, zw, zv, roots=roots)


def noise_from_standard(
    model: LTVModel,
    z0: np.ndarray,
    zw: np.ndarray,
    zv: np.ndarray,
    *,
    roots: NoiseRoots | None = None,
) -> Noise:
    """The noise :func:`draw_noise` makes of its standard normal draws.

    ``X_0 = x0 + S_0 z0``, ``W_k = S_{Q,k} zw_k``, ``V_k = S_{R,k} zv_k`` (``S`` the roots of
    :func:`noise_roots`): draws made elsewhere (e.g. one generator per realisation, each drawing
    ``z0``, ``zw``, ``zv`` in this order, as :func:`draw_noise` does) are mapped at once.

    Explained in the book: :doc:`/book/zb2014/signature`.

    Parameters
    ----------
    model : LTVModel
    z0 : numpy.ndarray
        ``(*batch, n)``.
    zw : numpy.ndarray
        ``(*batch, N, n)``.
    zv : numpy.ndarray
        ``(*batch, N, p)``.
    roots : NoiseRoots, optional
        ``noise_roots(model)``, computed if not given.

    Returns
    -------
    Noise

    Examples
    --------
    >>> import numpy as np
    >>> from fdi_lib.models import ltv_model
    >>> m = ltv_model(F=[[0.5]], H=[[1.0]], Q=4.0, R=1.0, n_steps=3)
    >>> n = noise_from_standard(m, np.zeros(1), np.ones((3, 1)), np.ones((3, 1)))
    >>> n.w[:, 0].tolist(), n.v[:, 0].tolist()       # W_k = S_Q zw_k with S_Q = 2
    ([2.0, 2.0, 2.0], [1.0, 1.0, 1.0])
    """
    if roots is None:
        roots = noise_roots(model)
    x0 = model.x0 + z0 @ roots.P0.T
    return Noise(
        x0=x0,
        w=np.einsum("kij,...kj->...ki", roots.Q, zw),
        v=np.einsum("kij,...kj->...ki", roots.R, zv),
    )


def pi_controller(
    kp: float, ki: float, setpoint: float = 0.0
) -> Callable[[int, np.ndarray], np.ndarray]:
    """A discrete PI controller ``C(z) = kp + ki / (z - 1)`` acting on ``e_k = setpoint - y_k``.

    ``kp`` and ``ki`` are the proportional and integral gains, ``setpoint`` the reference.

    Returns a fresh stateful callback ``u_k = controller(k, y_k)`` for :func:`simulate`
    (single-output, single-input; works element-wise on a batch of realisations).
    Zhang & Basseville (2014), Section 6.1: ``kp = 0.209``, ``ki = 0.0011``, setpoint 1.

    Explained in the book: :doc:`/book/zb2014/signature`.

    Examples
    --------
    >>> import numpy as np
    >>> c = pi_controller(kp=0.5, ki=0.1, setpoint=1.0)
    >>> c(0, np.array([0.0])).tolist(), c(1, np.array([0.0])).tolist()   # the integral builds up
    ([0.5], [0.6])
    """
    state: dict[str, Any] = {"integral": None}

    def controller(k: int, y_k: np.ndarray) -> np.ndarray:
        e = setpoint - y_k[..., :1]
        if state["integral"] is None:
            state["integral"] = np.zeros_like(e)
        u = kp * e + state["integral"]
        state["integral"] = state["integral"] + ki * e
        return u

    return controller


def _controller_input(u_k: Any, k: int, shape: tuple[int, ...]) -> np.ndarray:
    """The controller's input at step ``k``, broadcast to ``shape`` ``(*batch, l)``: a typed error for a
    wrong shape or a non-finite value (which would otherwise run through every later state)."""
    if type(u_k) is np.ndarray and u_k.dtype == np.float64 and u_k.shape == shape:
        out = u_k  # the usual case: nothing to convert (closed-loop _simulate of bz 7.6 -> 5.4 ms)
    else:
        out = _broadcast_input(u_k, k, shape)
    if not np.isfinite(out).all():
        idx = tuple(int(i) for i in np.argwhere(~np.isfinite(out))[0])
        raise NonFiniteError(
            f"controller: expected a finite input u_k, got {out[idx]} at step {k}, "
            f"index {idx} of u_k"
        )
    return out


def _broadcast_input(u_k: Any, k: int, shape: tuple[int, ...]) -> np.ndarray:
    try:
        return np.broadcast_to(np.asarray(u_k, dtype=float), shape)
    except (TypeError, ValueError) as exc:
        raise ShapeError(
            f"controller: expected an input u_k broadcastable to {shape} at step {k}, got "
            f"{type(u_k).__name__} of shape {np.shape(u_k)}"
        ) from exc


def simulate(
    model: LTVModel,
    *,
    rng: np.random.Generator | None = None,
    noise: Noise | None = None,
    u: Any = None,
    controller: Callable[[int, np.ndarray], np.ndarray] | None = None,
    fault: FaultProfile | None = None,
    theta: Any = None,
    size: int | None = None,
) -> Simulation:
    """Simulate eq. (5) (eq. (3) when ``fault.Phi`` is zero).

    Explained in the book: :doc:`/book/zb2014/signature`.

    Parameters
    ----------
    model : LTVModel
    rng : numpy.random.Generator, optional
        Draws the noise (exactly one of ``rng`` and ``noise``).
    noise : Noise, optional
        A noise record to replay (e.g. from a previous :class:`Simulation`).
    u : array_like, optional
        Open-loop input, shape ``(N, l)`` (or ``(N,)`` when ``l = 1``); default zeros.
    controller : callable, optional
        Closed loop: ``u_k = controller(k, y_k)`` with ``y_k`` of shape ``(*batch, p)``
        (requires ``J_k = 0``, otherwise the loop is algebraic). Exclusive with ``u``.
    fault : FaultProfile, optional
        ``Psi_k`` and ``Phi_k``.
    theta : array_like, optional
        The fault vector, shape ``(m,)``; required with ``fault``.
    size : int, optional
        Number of realisations when drawing noise with ``rng``.

    Returns
    -------
    Simulation

    Raises
    ------
    NonFiniteError
        A NaN or infinite input ``u`` (or a replayed ``noise``), naming the argument and the first
        index, before anything is simulated; a non-finite controller output, naming the step.

    Examples
    --------
    >>> import numpy as np
    >>> from fdi_lib.models import ltv_model
    >>> m = ltv_model(F=[[0.9]], H=[[1.0]], Q=0.01, R=0.01, n_steps=50)
    >>> s = simulate(m, rng=np.random.default_rng(0), size=3)
    >>> s.x.shape, s.y.shape
    ((3, 51, 1), (3, 50, 1))
    """
    N, n, p, l = model.n_steps, model.n, model.p, model.l
    if (rng is None) == (noise is None):
        raise ModelError("simulate: give exactly one of rng (draw new noise) and noise (replay)")
    if noise is None:
        noise = draw_noise(model, rng, size)
    elif size is not None:
        raise ModelError("size: only with rng; a replayed noise record has its own batch shape")
    batch = noise.batch_shape
    if noise.w.shape != (*batch, N, n) or noise.v.shape != (*batch, N, p):
        raise ShapeError(
            f"noise: expected w {(*batch, N, n)} and v {(*batch, N, p)}, "
            f"got {noise.w.shape} and {noise.v.shape}"
        )
    for field in (
        "x0",
        "w",
        "v",
    ):  # a replayed record: a NaN would run silently through every state
        check_finite(getattr(noise, field), f"noise.{field}")
    if u is not None and controller is not None:
        raise ModelError("simulate: give u (open loop) or controller (closed loop), not both")
    if controller is not None and np.any(model.J):
        raise ModelError(
            "controller: closed loop needs J_k = 0 (a non-zero J makes the loop algebraic)"
        )
    u_arr = as_record(u, n_steps=N, width=l, name="u")  # (N, l) or per realisation (*batch, N, l)
    if fault is None:
        if theta is not None:
            raise ModelError("theta: given without a fault profile")
        state_fault = np.zeros((N, n))
        output_fault = np.zeros((N, p))
    else:
        th = array(theta, "theta", finite=False)
        if th.shape != (fault.m,):
            raise ShapeError(f"theta: expected shape ({fault.m},), got {th.shape}")
        array(th, "theta")
        if fault.Psi.shape[:2] != (N, n) or fault.Phi.shape[:2] != (N, p):
            raise ShapeError(
                f"fault: expected Psi ({N}, {n}, m) and Phi ({N}, {p}, m), "
                f"got {fault.Psi.shape} and {fault.Phi.shape}"
            )
        state_fault = fault.Psi @ th
        output_fault = fault.Phi @ th

    x = np.empty((*batch, N + 1, n))
    y = np.empty((*batch, N, p))
    us = np.broadcast_to(u_arr, (*batch, N, l)).copy()
    x[..., 0, :] = noise.x0
    F, G, H, J = model.F, model.G, model.H, model.J
    for k in range(N):
        y_k = x[..., k, :] @ H[k].T + noise.v[..., k, :] + output_fault[k]
        if controller is not None:
            us[..., k, :] = _controller_input(controller(k, y_k), k, (*batch, l))
        else:
            y_k = y_k + us[..., k, :] @ J[k].T
        y[..., k, :] = y_k
        x[..., k + 1, :] = (
            x[..., k, :] @ F[k].T + us[..., k, :] @ G[k].T + noise.w[..., k, :] + state_fault[k]
        )
    return Simulation(x=x, y=y, u=us, noise=noise)
