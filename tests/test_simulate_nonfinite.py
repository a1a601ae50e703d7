"""A non-finite input never reaches the simulation (issue 21): typed errors naming the argument and
the index, raised before any state is computed."""

from __future__ import annotations

import numpy as np
import pytest

import fdi_lib.simulate as sim_mod
from fdi_lib.errors import NonFiniteError, ShapeError
from fdi_lib.models import ltv_model
from fdi_lib.simulate import Noise, pi_controller, simulate


@pytest.fixture
def model():
    return ltv_model(
        F=[[0.9, 0.1], [0.0, 0.8]],
        G=[[1.0], [0.5]],
        H=[[1.0, 0.0]],
        Q=0.01 * np.eye(2),
        R=0.01,
        n_steps=6,
    )


@pytest.fixture
def no_state_computed(monkeypatch):
    """Fail if the simulation loop starts (it allocates the state array ``x`` with np.empty)."""
    real = np.empty

    class Guarded:
        def __getattr__(self, name):
            return getattr(np, name)

        @staticmethod
        def empty(shape, *args, **kwargs):
            if len(shape) >= 2:
                raise AssertionError("the simulation started with a non-finite input")
            return real(shape, *args, **kwargs)

    monkeypatch.setattr(sim_mod, "np", Guarded())


@pytest.mark.parametrize(
    "shape, where, size", [((6, 1), (3, 0), None), ((6,), (3,), None), ((2, 6, 1), (1, 3, 0), 2)]
)
@pytest.mark.parametrize("bad", [np.nan, np.inf])
def test_a_non_finite_open_loop_input_is_refused_with_its_index(
    model, shape, where, size, bad, no_state_computed
):
    u = np.zeros(shape)
    u[where] = bad
    reported = where if len(shape) > 1 else (*where, 0)  # a 1-D u is read as one column
    index = r"\(" + ", ".join(map(str, reported)) + r"\)"
    with pytest.raises(
        NonFiniteError, match=rf"u: expected finite values, got {bad} at index {index}"
    ):
        simulate(model, rng=np.random.default_rng(0), u=u, size=size)


def test_a_replayed_noise_record_with_nan_is_refused(model, no_state_computed):
    base = sim_mod.draw_noise(model, np.random.default_rng(1))
    w = base.w.copy()
    w[2, 1] = np.nan
    with pytest.raises(
        NonFiniteError, match=r"noise.w: expected finite values, got nan at index \(2, 1\)"
    ):
        simulate(model, noise=Noise(x0=base.x0, w=w, v=base.v))
    with pytest.raises(
        NonFiniteError, match=r"noise.x0: expected finite values, got inf at index \(0,\)"
    ):
        simulate(model, noise=Noise(x0=np.array([np.inf, 0.0]), w=base.w, v=base.v))


def test_a_controller_output_that_is_not_finite_stops_at_its_step(model):
    """The closed loop's u_k is computed inside the loop: a NaN there used to run silently through
    every later state and output."""

    def nan_at_3(k, y):
        return np.full(y.shape[:-1] + (1,), np.nan if k == 3 else 0.0)

    with pytest.raises(
        NonFiniteError, match=r"controller: expected a finite input u_k, got nan at step 3"
    ):
        simulate(model, rng=np.random.default_rng(0), controller=nan_at_3, size=2)
    with pytest.raises(
        ShapeError, match=r"controller: expected an input u_k broadcastable to \(2, 1\) at step 0"
    ):
        simulate(model, rng=np.random.default_rng(0), controller=lambda k, y: np.zeros(3), size=2)
    ok = simulate(
        model, rng=np.random.default_rng(0), controller=pi_controller(0.2, 0.01, 1.0), size=2
    )
    assert np.all(np.isfinite(ok.y)) and np.all(np.isfinite(ok.u))
