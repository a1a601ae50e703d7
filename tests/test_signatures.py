"""Propositions 1 and 2 of Zhang & Basseville (2014), and Appendix A, checked numerically."""

import numpy as np
from hypothesis import given, settings
from hypothesis import strategies as st

from fdi_lib.filters import kalman_filter, kalman_gains
from fdi_lib.models import fault_profile, impulse_family
from fdi_lib.signatures import fault_signature, revisited_gamma, willsky_jones
from fdi_lib.simulate import simulate
from conftest import make_random_ltv


def _prop_check(seed: int, n: int, p: int, m_dim: int, with_output_fault: bool) -> float:
    rng = np.random.default_rng(seed)
    model = make_random_ltv(rng, n=n, p=p, l=1, n_steps=40, unstable=True)
    Psi = rng.standard_normal((40, n, m_dim))
    Phi = rng.standard_normal((40, p, m_dim)) if with_output_fault else None
    prof = fault_profile(model, Psi=Psi, Phi=Phi)
    theta = rng.standard_normal(m_dim)
    u = rng.standard_normal((40, 1))
    faulty = simulate(model, rng=rng, u=u, fault=prof, theta=theta)
    healthy = simulate(model, noise=faulty.noise, u=u)
    gains = kalman_gains(model)
    eps = kalman_filter(model, faulty.y, u, gains=gains).innovations
    eps0 = kalman_filter(model, healthy.y, u, gains=gains).innovations
    sig = fault_signature(model, gains, prof)
    # The open loop is unstable: the outputs (and the rounding of eps, a difference of large
    # numbers) scale with max |Y_k|, so the identity is checked relative to the data size.
    scale = 1.0 + max(np.abs(faulty.y).max(), np.abs(healthy.y).max())
    return float(np.abs(eps - eps0 - sig.on_innovation @ theta).max() / scale)


@settings(max_examples=25, deadline=None)
@given(seed=st.integers(0, 10_000), n=st.integers(1, 4), p=st.integers(1, 3), m=st.integers(1, 4))
def test_proposition_1_state_faults(seed, n, p, m):
    assert _prop_check(seed, n, p, m, with_output_fault=False) < 1e-12


@settings(max_examples=25, deadline=None)
@given(seed=st.integers(0, 10_000), n=st.integers(1, 4), p=st.integers(1, 3), m=st.integers(1, 4))
def test_proposition_2_state_and_output_faults(seed, n, p, m):
    assert _prop_check(seed, n, p, m, with_output_fault=True) < 1e-12


def test_proposition_holds_in_closed_loop():
    from fdi_lib.systems import zb2014_unstable as ex

    model = ex.unstable_model(300)
    prof = impulse_family(model).profile(120)
    theta = np.array([1.5, -0.5])
    faulty = simulate(
        model, rng=np.random.default_rng(0), controller=ex.controller(), fault=prof, theta=theta
    )
    healthy = simulate(model, noise=faulty.noise, controller=ex.controller())
    assert (
        np.abs(faulty.u - healthy.u).max() > 0.1
    )  # the fault changes the input through the loop...
    g = kalman_gains(model)
    d = (
        kalman_filter(model, faulty.y, faulty.u, gains=g).innovations
        - kalman_filter(model, healthy.y, healthy.u, gains=g).innovations
    )
    sig = fault_signature(model, g, prof)
    np.testing.assert_allclose(d, sig.on_innovation @ theta, atol=1e-13)  # ...not the innovation


def test_gamma_is_bounded_for_unstable_f_and_wj_alpha_is_not():
    from fdi_lib.systems import zb2014_unstable as ex

    model = ex.unstable_model(400)
    g = kalman_gains(model)
    gam = fault_signature(model, g, impulse_family(model).profile(10)).Gamma
    wj = willsky_jones(model, g, 10)
    assert np.linalg.norm(gam, 2, axis=(1, 2)).max() < 2.0
    assert np.linalg.norm(gam[-1], 2) < 1e-100
    growth = np.log(np.linalg.norm(wj.alpha[-1], 2) / np.linalg.norm(wj.alpha[-101], 2)) / 100
    np.testing.assert_allclose(growth, np.log(1.2), rtol=1e-6)  # the unstable eigenvalue


def test_revisited_recursion_equals_gamma_and_wj_rho_equals_h_gamma(random_ltv):
    model = random_ltv(np.random.default_rng(11), n=3, p=2, n_steps=30, unstable=False)
    g = kalman_gains(model)
    for r in (1, 7, 20):
        gam = fault_signature(model, g, impulse_family(model).profile(r)).Gamma
        np.testing.assert_allclose(revisited_gamma(model, g, r), gam, atol=1e-14)
        wj = willsky_jones(model, g, r)
        np.testing.assert_allclose(wj.rho, model.H @ gam[:-1], atol=1e-10)
