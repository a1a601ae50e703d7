"""References of the zhang2021/sparse exercises (instructor only)."""

from __future__ import annotations

import numpy as np

from fdi_lib.exercises._reference import Mistake, Reference


def _n_supports(d: dict, sizes: range) -> int:
    import scipy.special

    return int(sum(scipy.special.comb(d["m"], j, exact=True) for j in sizes))


def _sparse2_gains(d: dict):
    from fdi_lib.kitanidis import kitanidis_gains
    from fdi_lib.models import ltv_model

    m = ltv_model(F=d["F"], H=d["H"], Q=d["Q"], R=d["R"], P0=d["P0"], n_steps=d["k"] + 1)
    return kitanidis_gains(m, d["E"])


def _sparse3_ref(d: dict) -> float:
    from fdi_lib.sparse import lasso_path

    return float(lasso_path(d["X"], d["y"], n_samples=d["n_samples"]).lambdas[0])


def _sparse4_range(d: dict):
    from fdi_lib.sparse import flat_range, lasso_path

    path = lasso_path(d["X"], d["y"], n_samples=d["n_samples"])
    return flat_range(path, lambda_ratio=d["lambda_ratio"], max_size=d["max_size"])


def _sparse5_ref(d: dict) -> np.ndarray:
    from fdi_lib.sparse import diagnose

    return diagnose(d["X"], d["y"], n_samples=d["n_samples"]).theta_ls


def _sparse5_lasso(d: dict) -> np.ndarray:
    from fdi_lib.sparse import diagnose

    return diagnose(d["X"], d["y"], n_samples=d["n_samples"]).theta_lasso


_HALF = (
    "This is half of lambda_max. Dividing by the N p = 2N rows of X (scikit-learn's "
    "normalisation), or keeping the 1/2 of the squared loss in the optimality condition, gives "
    "this same number here because p = 2: (39) divides by the N time samples, and the 1/2 "
    "cancels against the derivative of the square."
)

REFERENCES = {
    "sparse-1": Reference(
        lambda d: _n_supports(d, range(d["q_max"] + 1)),
        (
            Mistake(
                lambda d: _n_supports(d, range(d["q_max"], d["q_max"] + 1)),
                "This counts the supports of size exactly q_max.",
            ),
            Mistake(
                lambda d: _n_supports(d, range(1, d["q_max"] + 1)),
                "The empty support (no fault) is a hypothesis too.",
            ),
        ),
    ),
    "sparse-2": Reference(
        lambda d: _sparse2_gains(d).K[d["k"]],
        (
            Mistake(
                lambda d: _sparse2_gains(d).K_kalman[d["k"]],
                "This is the Kalman gain K_1: the Kitanidis gain adds the correction along H_1 E_0.",
            ),
        ),
        one_call=("fdi_lib.kitanidis.kitanidis_gains",),
    ),
    "sparse-3": Reference(
        _sparse3_ref,
        (
            Mistake(lambda d: float(np.abs(d["X"].T @ d["y"]).max()) / d["X"].shape[0], _HALF),
            Mistake(
                lambda d: float(np.abs(d["X"].T @ d["y"]).max()),
                "This is ||X^T y||_inf without the normalisation of (39): divide by the number of "
                "time samples N.",
            ),
        ),
        one_call=("fdi_lib.sparse.lasso_path", "fdi_lib.sparse.diagnose"),
    ),
    "sparse-4": Reference(
        lambda d: _sparse4_range(d).middle,
        (
            Mistake(
                lambda d: 0.5 * (_sparse4_range(d).low + _sparse4_range(d).high),
                "This is an arithmetic middle (the linear reading): the book's rule measures width "
                "by log(high / low) and takes the geometric mean sqrt(low high) of the widest range.",
            ),
        ),
        one_call=("fdi_lib.sparse.flat_range", "fdi_lib.sparse.flat_ranges"),
    ),
    "sparse-5": Reference(
        _sparse5_ref,
        (
            Mistake(
                _sparse5_lasso,
                "These are the Lasso values at the chosen lambda, shrunk towards zero: "
                "refit by least squares on the support.",
            ),
        ),
        one_call=("fdi_lib.sparse.diagnose",),
    ),
}
