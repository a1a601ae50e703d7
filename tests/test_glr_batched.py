"""Windowed GLR with a fault profile per realisation (a batched ``step_family``), against the
same test run once per realisation with that realisation's own family."""

import numpy as np
import pytest

import fdi_lib.glr as glr
from conftest import make_random_ltv
from fdi_lib.errors import ModelError, NonFiniteError, ShapeError
from fdi_lib.filters import kalman_filter, kalman_gains
from fdi_lib.glr import WindowedGLR, glr_window
from fdi_lib.models import impulse_family, step_family
from fdi_lib.simulate import simulate

N, n, p, W, S = 40, 3, 2, 9, 1
KEYS = ("statistic", "onset", "theta_hat", "C_hat", "d_hat")


def _setup(batch, m, seed=0, missing=None):
    """A random LTV model, its gains, innovations ``(*batch, N, p)`` and random per-realisation
    profiles ``Psi`` ``(*batch, N, n, m)``, ``Phi`` ``(*batch, N, p, m)``; the first realisation's
    profiles are zero (no information: its statistic must be 0, never NaN)."""
    rng = np.random.default_rng(seed)
    model = make_random_ltv(rng, n=n, p=p, n_steps=N)
    gains = kalman_gains(model, missing=missing)
    y = simulate(model, rng=rng, size=int(np.prod(batch))).y.reshape(*batch, N, p)
    if missing is not None:
        y[..., missing, :] = np.nan
    eps = kalman_filter(model, y, gains=gains).innovations
    Psi = rng.standard_normal((*batch, N, n, m))
    Phi = rng.standard_normal((*batch, N, p, m))
    Psi.reshape(-1, N, n, m)[0] = 0.0
    Phi.reshape(-1, N, p, m)[0] = 0.0
    return model, gains, eps, Psi, Phi


def _loop(eps, model, gains, Psi, Phi, **kw):
    """Reference: one glr_window per realisation, each with its own (shared-profile) family."""
    batch = eps.shape[:-2]
    flat = [
        glr_window(
            eps.reshape(-1, N, p)[b],
            model,
            gains,
            step_family(
                model,
                Psi=Psi.reshape(-1, N, n, Psi.shape[-1])[b],
                Phi=Phi.reshape(-1, N, p, Phi.shape[-1])[b],
            ),
            W,
            S,
            **kw,
        )
        for b in range(int(np.prod(batch)))
    ]
    return {
        key: np.stack([getattr(r, key) for r in flat]).reshape(*batch, *getattr(flat[0], key).shape)
        for key in KEYS
    }


def _assert_same(res, ref):
    for key in KEYS:
        got = getattr(res, key)
        assert got.shape == ref[key].shape, key
        if key == "onset":
            np.testing.assert_array_equal(got, ref[key])
        else:  # 1e-10 relative; the absolute floor is rounding of entries O(1e2) that cancel to ~0
            np.testing.assert_allclose(
                got, ref[key], rtol=1e-10, atol=1e-12, equal_nan=True, err_msg=key
            )


@pytest.mark.parametrize("batch, m", [((5,), 1), ((2, 3), 2)])
def test_per_realisation_family_equals_one_call_per_realisation(batch, m):
    model, gains, eps, Psi, Phi = _setup(batch, m)
    fam = step_family(model, Psi=Psi, Phi=Phi)
    assert fam.batch_shape == batch and fam.m == m
    res = glr_window(eps, model, gains, fam, W, S)
    _assert_same(res, _loop(eps, model, gains, Psi, Phi))
    # the zero profile carries no information: statistic 0 and theta_hat 0 (C^+ = 0), not NaN
    zero = res.statistic.reshape(-1, N)[0]
    assert np.all(zero[S:] == 0.0) and np.all(np.isnan(zero[:S]))
    assert np.all(res.theta_hat.reshape(-1, N, m)[0, S:] == 0.0)
    assert np.all(np.isfinite(res.statistic[..., S:]))
    # the other realisations do see their profiles
    assert np.all(res.statistic.reshape(-1, N)[1:, S:].max(axis=-1) > 0)
    # start=: the same outputs from start on, bit for bit, the samples before start - W + 1
    # not read (the scores of onsets never admissible from start on)
    for start in (20, 35):
        part = glr_window(eps, model, gains, fam, W, S, start=start)
        for key in KEYS:  # realisations flattened, samples from start on
            got, ref = (getattr(r, key) for r in (part, res))
            np.testing.assert_array_equal(
                got.reshape(-1, *got.shape[len(batch) :])[:, start:],
                ref.reshape(-1, *ref.shape[len(batch) :])[:, start:],
                err_msg=key,
            )
        assert np.all(np.isnan(part.statistic[..., :start]))
        assert np.all(part.onset[..., :start] == -1)


def test_a_shared_profile_broadcasts_against_per_realisation_ones():
    """Psi per realisation, Phi shared (per step): Phi applies to every realisation."""
    model, gains, eps, Psi, Phi = _setup((4,), 1, seed=1)
    fam = step_family(model, Psi=Psi, Phi=Phi[0])
    assert fam.Phi_tilde.shape == (4, N, p, 1)
    _assert_same(
        glr_window(eps, model, gains, fam, W, S),
        _loop(eps, model, gains, Psi, np.broadcast_to(Phi[0], Phi.shape)),
    )
    fam = step_family(model, Psi=Psi)  # no output fault at all
    _assert_same(
        glr_window(eps, model, gains, fam, W, S), _loop(eps, model, gains, Psi, np.zeros_like(Phi))
    )


def test_online_updates_and_shared_detector_with_per_realisation_profiles():
    model, gains, eps, Psi, Phi = _setup((3,), 2, seed=2)
    fam = step_family(model, Psi=Psi, Phi=Phi)
    ref = _loop(eps, model, gains, Psi, Phi)
    det = WindowedGLR(model, gains, fam, W, S, batch_shape=(3,))
    for k in range(N):
        l_k, r_k, th, C_hat, d_hat = det.update(eps[:, k])
        np.testing.assert_allclose(
            l_k, ref["statistic"][:, k], rtol=1e-10, atol=1e-12, equal_nan=True
        )
        np.testing.assert_array_equal(r_k, ref["onset"][:, k])
        np.testing.assert_allclose(
            th, ref["theta_hat"][:, k], rtol=1e-10, atol=1e-12, equal_nan=True
        )
        np.testing.assert_allclose(
            C_hat, ref["C_hat"][:, k], rtol=1e-10, atol=1e-12, equal_nan=True
        )
    template = WindowedGLR(model, gains, fam, W, S, batch_shape=(3,))
    _assert_same(glr_window(eps, model, gains, fam, W, S, shared=template), ref)


def test_missing_samples_with_per_realisation_profiles():
    """NaN innovations: dropped in every realisation (sample by sample), dropped in some (groups of
    realisations, each with its rows of the family), skipped by the gains (block evaluation)."""
    model, gains, eps, Psi, Phi = _setup((4,), 2, seed=3)
    fam = step_family(model, Psi=Psi, Phi=Phi)
    same = eps.copy()
    same[:, [13, 15]] = np.nan
    differ = same.copy()
    differ[2, 22] = np.nan
    for e in (same, differ):
        _assert_same(glr_window(e, model, gains, fam, W, S), _loop(e, model, gains, Psi, Phi))
    skipped = np.zeros(N, dtype=bool)
    skipped[[10, 11, 30]] = True
    model, gains, eps, Psi, Phi = _setup((4,), 2, seed=4, missing=skipped)
    assert np.all(np.isnan(eps[:, skipped]))
    fam = step_family(model, Psi=Psi, Phi=Phi)
    _assert_same(glr_window(eps, model, gains, fam, W, S), _loop(eps, model, gains, Psi, Phi))


def test_blocks_of_realisations_within_the_memory_budget(monkeypatch):
    """A budget smaller than the batch's arrays, m = 3 (whose Jacobi sweeps the stack of matrices
    sets): blocks of realisations, the same results."""
    model, gains, eps, Psi, Phi = _setup((7,), 3, seed=5)
    fam = step_family(model, Psi=Psi, Phi=Phi)
    whole = glr_window(eps, model, gains, fam, W, S)
    per = 8 * N * W * 3 * (n + 3 * p + 12)
    monkeypatch.setattr(glr, "_PER_REALISATION_BYTES", 3 * per)  # blocks of 3, 3 and 1
    calls = []
    real = glr.WindowedGLR.__init__

    def spy(self, *args, **kwargs):
        calls.append(kwargs.get("batch_shape"))
        real(self, *args, **kwargs)

    monkeypatch.setattr(glr.WindowedGLR, "__init__", spy)
    blocked = glr_window(eps, model, gains, fam, W, S)
    assert calls == [(3,), (3,), (1,)]
    _assert_same(
        blocked, {key: getattr(whole, key) for key in KEYS}
    )  # rounding differs with the block


@pytest.mark.parametrize("m, start", [(1, 0), (1, 15), (2, 0)])
def test_blocks_of_samples_within_the_memory_budget(monkeypatch, m, start):
    """A budget smaller than the batch's arrays, m outside 3..4: all realisations in one pass, the
    detector's arrays by blocks of samples (3/7 of the record), the same bits as with the whole
    record in one block; the blocks of realisations taken before agree to rounding (their last block,
    one realisation, takes other products). With ``start``, the blocks begin at the first sample
    read, ``start - W + 1``, and the outputs keep their bits."""
    model, gains, eps, Psi, Phi = _setup((7,), m, seed=6)
    fam = step_family(model, Psi=Psi, Phi=Phi)
    whole = glr_window(eps, model, gains, fam, W, S, start=start)
    per = 8 * N * W * m * (n + 3 * p + 4 * m)
    monkeypatch.setattr(glr, "_PER_REALISATION_BYTES", 3 * per)
    sizes = []
    real = glr.WindowedGLR._shared_blocks

    def spy(self, size, first=0):
        sizes.append((self._B, size, first))
        return real(self, size, first)

    monkeypatch.setattr(glr.WindowedGLR, "_shared_blocks", spy)
    blocked = glr_window(eps, model, gains, fam, W, S, start=start)
    assert sizes == [(7, 3 * N // 7, max(0, start - W + 1))]  # from the first sample read
    realisations = glr._grouped_glr_window(
        eps, np.arange(7) // 3, model, gains, fam, W, S, None, start, True
    )
    for key in KEYS:
        assert getattr(blocked, key).tobytes() == getattr(whole, key).tobytes(), key
    _assert_same(blocked, {key: getattr(realisations, key) for key in KEYS})


def test_blocks_of_samples_are_cut_to_the_cache_size(monkeypatch):
    """Blocks of samples hold _SAMPLE_BLOCK_BYTES of the realisations' arrays when that is less than
    the budget (here one realisation's worth: N / 7 samples of 7 realisations), the same bits."""
    model, gains, eps, Psi, Phi = _setup((7,), 2, seed=9)
    fam = step_family(model, Psi=Psi, Phi=Phi)
    whole = glr_window(eps, model, gains, fam, W, S, start=15)
    per = 8 * N * W * 2 * (n + 3 * p + 8)
    monkeypatch.setattr(glr, "_PER_REALISATION_BYTES", 3 * per)
    monkeypatch.setattr(glr, "_SAMPLE_BLOCK_BYTES", per)
    sizes = []
    real = glr.WindowedGLR._shared_blocks

    def spy(self, size, first=0):
        sizes.append(size)
        return real(self, size, first)

    monkeypatch.setattr(glr.WindowedGLR, "_shared_blocks", spy)
    blocked = glr_window(eps, model, gains, fam, W, S, start=15)
    assert sizes == [N // 7]
    for key in KEYS:
        assert getattr(blocked, key).tobytes() == getattr(whole, key).tobytes(), key


@pytest.mark.parametrize("blocks", [False, True])
def test_a_family_without_output_faults_skips_their_terms_bit_for_bit(monkeypatch, blocks):
    """Phi~ = 0 (per-realisation, shared step and impulse families): the detector skips the terms
    that add zeros (glr._has_output_faults false); the same bits as with them, outputs and the
    detector's arrays; ``blocks``: the per-realisation arrays by blocks of samples, from start."""
    model, gains, eps, Psi, Phi = _setup((5,), 1, seed=8)
    per = 8 * N * W * (n + 3 * p + 4)
    if blocks:
        monkeypatch.setattr(glr, "_PER_REALISATION_BYTES", 2 * per)
    families = (step_family(model, Psi=Psi), step_family(model, Psi=Psi[1]))
    families += (impulse_family(model, Psi=Psi[1]),)
    assert glr._has_output_faults(step_family(model, Psi=Psi, Phi=Phi))

    def run(fam):
        det = WindowedGLR(model, gains, fam, W, S, batch_shape=(5,))
        res = glr_window(eps, model, gains, fam, W, S, start=15 if blocks else 0)
        return [getattr(res, k) for k in KEYS] + [det._sig_wT, det._Cs, det._root]

    skipped = []
    for fam in families:
        assert not glr._has_output_faults(fam)
        skipped.append(run(fam))
    monkeypatch.setattr(glr, "_has_output_faults", lambda family: True)  # the zeros added
    for fam, got in zip(families, skipped):
        for a, b in zip(got, run(fam)):
            assert a.shape == b.shape and a.tobytes() == b.tobytes()


def test_shape_errors_of_per_realisation_profiles():
    model, gains, eps, Psi, Phi = _setup((3,), 1, seed=6)
    with pytest.raises(
        ShapeError, match=rf"Psi: expected per-realisation profiles \(\*batch, {N}, {n}, m\)"
    ):
        step_family(model, Psi=Psi[:, :, :2])
    with pytest.raises(
        ShapeError, match=rf"Phi: expected per-realisation profiles \(\*batch, {N}, {p}, m\)"
    ):
        step_family(model, Phi=Phi[:, :-1])
    with pytest.raises(
        ShapeError, match=r"Phi: expected shape \(3, 40, 2, 1\) \(the batch and m of Psi\)"
    ):
        step_family(model, Psi=Psi, Phi=Phi[:2])
    with pytest.raises(ShapeError, match=r"Phi: expected shape \(3, 40, 2, 1\)"):
        step_family(model, Psi=Psi, Phi=np.concatenate([Phi, Phi], axis=-1))
    fam = step_family(model, Psi=Psi, Phi=Phi)
    for bad in (eps[:2], eps[0], np.stack([eps, eps])):
        with pytest.raises(
            ShapeError, match=r"family: expected per-realisation profiles of batch shape"
        ):
            glr_window(bad, model, gains, fam, W, S)
    with pytest.raises(
        ShapeError,
        match=r"batch shape \(2,\) \(that of the innovations\) or a shared "
        r"family, got batch shape \(3,\)",
    ):
        WindowedGLR(model, gains, fam, W, S, batch_shape=(2,))
    det = WindowedGLR(model, gains, fam, W, S, batch_shape=(3,))
    with pytest.raises(
        ShapeError, match=r"family: expected per-realisation profiles of batch shape \(4,\)"
    ):
        det.fresh((4,))
    with pytest.raises(ModelError, match=r"profile: expected a family shared by all realisations"):
        fam.profile(3)
    bad = Psi.copy()
    bad[1, 5, 0, 0] = np.inf
    with pytest.raises(
        NonFiniteError, match=r"Psi: expected finite values, got inf at index \(1, 5, 0, 0\)"
    ):
        step_family(model, Psi=bad)


@pytest.mark.parametrize("m", [1, 2, 3])
def test_score_terms_are_the_bits_of_the_products_they_replace(m):
    """WindowedGLR._score_terms: with per-realisation profiles, the sum over the outputs written out
    has the bits of the einsum it replaces; with a shared family, one (w m, p) @ (p, B) product per
    sample those of w products (m, p) @ (p, B) (for m = 1, gemv: kept as w products)."""
    model, gains, eps, Psi, Phi = _setup((4,), m, seed=3)
    e_w = np.random.default_rng(1).standard_normal((N, p, 4))
    e_w[3, 0] = -0.0
    own = WindowedGLR(model, gains, step_family(model, Psi=Psi, Phi=Phi), W, batch_shape=(4,))
    ref = np.einsum("kpwbm,kpb->kwmb", own._sig_wT, e_w)
    assert own._score_terms(own._sig_wT, e_w).tobytes() == np.ascontiguousarray(ref).tobytes()
    shared = WindowedGLR(model, gains, step_family(model, Psi=Psi[0], Phi=Phi[1]), W)
    ref = shared._sig_wT @ e_w[:, None]
    got = shared._score_terms(shared._sig_wT, e_w)
    assert np.ascontiguousarray(got).tobytes() == ref.tobytes()


def test_one_parameter_shortcuts_are_the_bits_of_the_general_forms():
    """m = 1: the pseudo-inverse root without eigenvectors, the per-realisation projection as one
    product per entry and the statistic as a square have the bits of the general forms they skip
    (V diag(inv)^(1/2) with V = 1, the einsums), zeros of either sign, zero, negative, infinite and
    NaN informations included."""
    rng = np.random.default_rng(4)
    C = rng.gamma(1.0, size=(6, 5, 1, 1))
    C.reshape(-1)[:6] = (0.0, -1e-3, np.inf, np.nan, 1e-320, -0.0)
    V, inv = glr._pinv_factors(C)
    ref = V * np.sqrt(inv)[..., None, :]
    assert glr._pinv_root(C).tobytes() == ref.tobytes()
    root = glr._pinv_root(C)[:, :, None]  # (K, w, B = 1, 1, 1): per realisation
    d = rng.standard_normal((6, 5, 1, 1))
    d.reshape(-1)[6:9] = (-0.0, 0.0, -2.0)
    own = object.__new__(WindowedGLR)
    own._per_realisation = True
    q = own._project(root, d)
    assert q.tobytes() == np.einsum("...bji,...jb->...ib", root, d).tobytes()
    ref = np.einsum("kwmb,kwmb->kwb", q, q)
    assert WindowedGLR._quadratic(q).tobytes() == ref.tobytes()
    q2 = rng.standard_normal((6, 5, 2, 3))  # m = 2: the einsum itself
    assert WindowedGLR._quadratic(q2).tobytes() == np.einsum("kwmb,kwmb->kwb", q2, q2).tobytes()
