import numpy as np
import pytest

from fdi_lib.errors import CovarianceError, ModelError, NonFiniteError, ShapeError
from fdi_lib.models import (
    as_sequence,
    fault_profile,
    impulse_family,
    lpv_model,
    ltv_model,
    step_family,
)

F = [[0.5, 1.0], [0.0, 1.2]]
BASE = dict(F=F, G=[[0.0], [1.0]], H=[[1.0, 0.0]], Q=0.0025 * np.eye(2), R=0.0025, n_steps=5)


def test_constant_per_step_and_callable_agree():
    N = 4
    per_step = np.stack([np.array(F) * (1 + 0.1 * k) for k in range(N)])
    a = as_sequence(per_step, n_steps=N, shape=(2, 2), name="F")
    b = as_sequence(lambda k: np.array(F) * (1 + 0.1 * k), n_steps=N, shape=(2, 2), name="F")
    np.testing.assert_array_equal(a, b)
    c = as_sequence(F, n_steps=N, shape=(2, 2), name="F")
    assert c.shape == (N, 2, 2) and c.strides[0] == 0  # constant: broadcast view, no copy
    assert not c.flags.writeable


def test_dimensions_and_defaults():
    m = ltv_model(**BASE)
    assert (m.n, m.l, m.p, m.n_steps) == (2, 1, 1, 5)
    np.testing.assert_array_equal(m.J, np.zeros((5, 1, 1)))
    np.testing.assert_array_equal(m.P0, np.eye(2))
    no_input = ltv_model(F=F, H=[[1.0, 0.0]], Q=np.eye(2), R=1.0, n_steps=3)
    assert no_input.l == 0


@pytest.mark.parametrize(
    "change, error, match",
    [
        (dict(F=[[1.0, 0.0]]), ShapeError, r"F: expected square"),
        (dict(H=[[1.0, 0.0, 0.0]]), ShapeError, r"H: expected shape \(p, 2\)"),
        (dict(G=[[0.0], [1.0], [2.0]]), ShapeError, r"G: expected shape \(2, l\)"),
        (dict(Q=[[1.0, 0.5], [0.0, 1.0]]), CovarianceError, r"Q: expected a symmetric matrix"),
        (
            dict(Q=[[1.0, 0.0], [0.0, -1e-3]]),
            CovarianceError,
            r"Q: expected a positive semi-definite .* -0.001 at step 0",
        ),
        (dict(R=0.0), CovarianceError, r"R: expected a positive definite matrix"),
        (dict(n_steps=0), ModelError, r"n_steps: expected a positive integer, got 0"),
        (dict(x0=[0.0, 0.0, 0.0]), ShapeError, r"x0: expected shape \(2,\), got \(3,\)"),
        (dict(P0=-np.eye(2)), CovarianceError, r"P0: expected a positive semi-definite"),
    ],
)
def test_bad_inputs_raise_clear_errors(change, error, match):
    with pytest.raises(error, match=match):
        ltv_model(**{**BASE, **change})


def test_nan_reported_with_its_index():
    F_steps = np.broadcast_to(np.array(F), (5, 2, 2)).copy()
    F_steps[3, 1, 0] = np.nan
    with pytest.raises(
        NonFiniteError, match=r"F: expected finite values, got nan at index \(3, 1, 0\)"
    ):
        ltv_model(**{**BASE, "F": F_steps})


def test_time_varying_covariance_checked_at_every_step():
    Q = np.broadcast_to(np.eye(2), (5, 2, 2)).copy()
    Q[4] = [[1.0, 2.0], [2.0, 1.0]]  # indefinite at step 4 only
    with pytest.raises(CovarianceError, match="at step 4"):
        ltv_model(**{**BASE, "Q": Q})


def test_callable_with_wrong_shape():
    with pytest.raises(ShapeError, match=r"F\(2\): expected shape \(2, 2\), got \(3, 3\)"):
        ltv_model(**{**BASE, "F": lambda k: np.eye(2) if k < 2 else np.eye(3)})


def test_unknown_keyword_rejected():
    with pytest.raises(TypeError, match="unexpected keyword argument 'Qk'"):
        ltv_model(**BASE, Qk=1.0)


def test_lpv_model_is_affine_in_the_schedule():
    p = np.array([0.0, 1.0, 2.0, -1.0])
    m = lpv_model(
        scheduling=p,
        F0=np.eye(2) * 0.5,
        Fp=[[0.0, 0.1], [0.0, 0.0]],
        G0=[[1.0], [0.0]],
        Gp=[[0.5], [0.0]],
        H0=[[1.0, 0.0]],
        Q=np.eye(2),
        R=1.0,
    )
    for k, pk in enumerate(p):
        np.testing.assert_allclose(m.F[k], 0.5 * np.eye(2) + pk * np.array([[0, 0.1], [0, 0]]))
        np.testing.assert_allclose(m.G[k], [[1.0 + 0.5 * pk], [0.0]])
    two = lpv_model(
        scheduling=np.c_[p, p**2],
        F0=np.eye(2),
        Fp=[np.eye(2), 2 * np.eye(2)],
        H0=[[1.0, 0.0]],
        Q=np.eye(2),
        R=1.0,
    )
    np.testing.assert_allclose(two.F[2], np.eye(2) * (1 + 2 + 2 * 4))
    with pytest.raises(ShapeError, match=r"Fp: expected 2 matrices"):
        lpv_model(
            scheduling=np.c_[p, p], F0=np.eye(2), Fp=np.eye(2), H0=[[1.0, 0.0]], Q=np.eye(2), R=1.0
        )


def test_step_and_impulse_families():
    m = ltv_model(**{**BASE, "n_steps": 6})
    step = step_family(m, Psi=[[1.0], [0.0]]).profile(2)
    np.testing.assert_array_equal(step.Psi[:, 0, 0], [0, 0, 1, 1, 1, 1])
    imp = impulse_family(m).profile(3)  # delta_{r,k+1}: non-zero at k = r - 1
    np.testing.assert_array_equal(imp.Psi[:, 0, 0], [0, 0, 1, 0, 0, 0])
    np.testing.assert_array_equal(imp.Psi[2], np.eye(2))
    with pytest.raises(ModelError, match=r"onset: expected an integer in \[0, 6\], got 9"):
        impulse_family(m).profile(9)
    with pytest.raises(ModelError, match="give Psi, Phi or both"):
        fault_profile(m)
    with pytest.raises(ShapeError, match=r"Psi: expected shape \(2, 1\)"):
        fault_profile(m, Psi=np.ones((6, 3, 1)))
