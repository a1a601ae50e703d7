"""Random LTV test systems: time-varying, possibly unstable, for checking propositions numerically."""

from __future__ import annotations

import numpy as np

from fdi_lib.models import LTVModel, ltv_model

__all__ = ["random_ltv_model"]


def random_ltv_model(
    rng: np.random.Generator,
    *,
    n: int = 3,
    p: int = 1,
    l: int = 1,
    n_steps: int = 60,
    unstable: bool = True,
) -> LTVModel:
    """A random LTV model ``F_k = F + 0.05 sin(0.3 k) D_F`` (and likewise ``G_k``, ``H_k``).

    The constant part of ``F_k`` is scaled to spectral radius 1.15 (``unstable``) or 0.8;
    ``Q`` and ``R`` are random symmetric positive definite; ``P_0 = I``.

    Parameters
    ----------
    rng : numpy.random.Generator
    n, p, l : int
        State, output and input dimensions.
    n_steps : int
        Horizon.
    unstable : bool
        Whether ``F_k`` has an eigenvalue outside the unit circle.
    """
    base = rng.standard_normal((n, n))
    base *= (1.15 if unstable else 0.8) / max(abs(np.linalg.eigvals(base)))
    k = np.arange(n_steps)[:, None, None]
    F = base + 0.05 * np.sin(0.3 * k) * rng.standard_normal((1, n, n))
    G = rng.standard_normal((n, l)) + 0.1 * np.cos(0.2 * k) * rng.standard_normal((1, n, l))
    H = rng.standard_normal((p, n)) + 0.1 * np.sin(0.1 * k) * rng.standard_normal((1, p, n))
    A = rng.standard_normal((n, n))
    Q = 0.05 * (A @ A.T) + 0.01 * np.eye(n)
    B = rng.standard_normal((p, p))
    R = 0.1 * (B @ B.T) + 0.05 * np.eye(p)
    return ltv_model(F=F, G=G, H=H, Q=Q, R=R, n_steps=n_steps, P0=np.eye(n))
