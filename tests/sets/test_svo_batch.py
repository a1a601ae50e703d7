"""Many template SVOs stepped together (:class:`TemplateBatch`) against one observer at a time."""

from __future__ import annotations

import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

from fdi_lib.errors import ModelError, ShapeError
from fdi_lib.reproduce import rosa2013 as R
from fdi_lib.reproduce import rosa2013_uav as RU
from fdi_lib.sets import Polytope
from fdi_lib.sets.svo import (
    ModelSequence,
    SVOModel,
    TemplateBatch,
    run_architecture_i,
    run_architecture_i_many,
    run_svo,
    run_svo_many,
)
from fdi_lib.systems import eclipse_uav as uav

from tests.sets.test_svo_props import random_system, simulate

X0 = Polytope.box([-1.0, -1.0], [1.0, 1.0])
ROOT = Path(__file__).resolve().parents[2]


def _constant(model: SVOModel, T: int) -> ModelSequence:
    """``model`` at every one of T steps, as a ModelSequence."""
    rep = lambda a: np.repeat(a[None], T, axis=0)  # noqa: E731
    return ModelSequence(
        A=rep(model.A),
        B=rep(model.B),
        C=model.C,
        L=model.L,
        noise=model.noise,
        A_unc=rep(model.A_unc),
        B_unc=rep(model.B_unc),
    )


def _records(seed: int, count: int, T: int = 25):
    """Random 2-D systems and records; every other one with a sensor fault from k = 10."""
    rng = np.random.default_rng(seed)
    models, us, ys = [], [], []
    for i in range(count):
        m = random_system(rng)
        _, u, y = simulate(m, rng, T, fault=(10, 1.5) if i % 2 else None)
        models.append(m)
        us.append(u)
        ys.append(y)
    return models, np.stack(us), np.stack(ys)


def test_model_sequence_steps_equal_the_direct_models():
    rng = np.random.default_rng(3)
    m = random_system(rng)
    A2 = np.concatenate(
        [m.A_unc, 0.05 * rng.standard_normal((1, 2, 2))]
    )  # two uncertain directions
    direct = SVOModel(A=m.A, B=m.B, C=m.C, L=m.L, noise=m.noise, A_unc=A2, B_unc=m.B_unc)
    seq = _constant(direct, 4)
    step = seq(2)
    for name in ("A", "B", "C", "L", "noise", "A_unc", "B_unc", "C_unc"):
        np.testing.assert_array_equal(getattr(step, name), getattr(direct, name))
    np.testing.assert_array_equal(step.vertex_matrices(), direct.vertex_matrices())
    # the vertex matrices against a brute-force sum over the sign vectors of the cube
    brute = [m.A + s1 * A2[0] + s2 * A2[1] for s1 in (-1, 1) for s2 in (-1, 1)]
    np.testing.assert_allclose(step.vertex_matrices(), brute, rtol=0, atol=1e-15)
    assert len(seq) == 4


def test_model_sequence_and_batch_reject_bad_input():
    m = random_system(np.random.default_rng(0))
    with pytest.raises(ShapeError, match=r"A: expected a 3-D array"):
        ModelSequence(A=m.A, B=m.B[None], C=m.C, L=m.L, noise=m.noise)
    with pytest.raises(ShapeError, match=r"B: expected shape \(2, 2, n_u\)"):
        ModelSequence(A=np.stack([m.A] * 2), B=m.B[None], C=m.C, L=m.L, noise=m.noise)
    with pytest.raises(ModelError, match=r"noise: expected 1 non-negative bounds"):
        ModelSequence(A=m.A[None], B=m.B[None], C=m.C, L=m.L, noise=np.array([-1.0]))
    seq = _constant(m, 3)
    with pytest.raises(ModelError, match=r"k: expected a step in \[0, 3\), got 3"):
        seq(3)
    with pytest.raises(ModelError, match=r"models\[0\]: expected a ModelSequence, got SVOModel"):
        TemplateBatch([m], np.zeros((1, 3, 1)), np.zeros((1, 4, 1)), X0)
    with pytest.raises(ShapeError, match=r"models\[0\]: expected at least 5 steps"):
        TemplateBatch([seq], np.zeros((1, 5, 1)), np.zeros((1, 6, 1)), X0)
    with pytest.raises(ShapeError, match=r"u, models: expected u of shape \(1, 3, n_u\)"):
        TemplateBatch([seq], np.zeros((1, 2, 1)), np.zeros((1, 4, 1)), X0)
    bank = TemplateBatch([seq], np.zeros((1, 3, 1)), np.zeros((1, 4, 1)), X0)
    bank.start()
    with pytest.raises(ModelError, match=r"k: expected a sample in \[1, 3\], got 4"):
        bank.update(4)
    with pytest.raises(ModelError, match=r"last: expected a sample in \[2, 3\], got 1"):
        bank.advance(2, last=1)


def test_batch_equals_one_observer_at_a_time_on_random_systems():
    """Same alarms as run_svo, bounding boxes equal to rounding (the 1e-9 margin is far larger)."""
    models, u, y = _records(11, 16)
    many = run_svo_many([_constant(m, u.shape[1]) for m in models], u, y, X0, bounds=True)
    alarms = 0
    for i, m in enumerate(models):
        one = run_svo(m, u[i], y[i], X0)
        assert many.empty_at[i] == one.empty_at
        alarms += one.empty_at is not None
        np.testing.assert_allclose(many.lower[i], one.lower, rtol=0, atol=1e-12)
        np.testing.assert_allclose(many.upper[i], one.upper, rtol=0, atol=1e-12)
    assert alarms >= 4  # the faulty records do raise alarms: the comparison covers both outcomes


def test_each_observer_is_independent_of_its_batch():
    """Bit for bit: an observer alone, or in a batch of any size, gives the same sets."""
    models, u, y = _records(5, 6)
    seqs = [_constant(m, u.shape[1]) for m in models]
    whole = run_svo_many(seqs, u, y, X0, bounds=True)
    for i in (0, 3):
        alone = run_svo_many(seqs[i : i + 1], u[i : i + 1], y[i : i + 1], X0, bounds=True)
        assert alone.empty_at[0] == whole.empty_at[i]
        np.testing.assert_array_equal(alone.lower[0], whole.lower[i])
        np.testing.assert_array_equal(alone.upper[0], whole.upper[i])


def _small_template_run():
    """:func:`run_svo_many` on two short random records (the compiled basis route)."""
    models, u, y = _records(5, 2)
    return run_svo_many([_constant(m, u.shape[1]) for m in models], u, y, X0)


#: A new process: what numba compiles (not loads from its disk cache) in a small template run.
_COMPILED_IN_A_NEW_PROCESS = """
from numba.core import event
from fdi_lib.sets.svo import _template_run
from tests.sets.test_svo_batch import _small_template_run
with event.install_recorder("numba:compile") as rec:
    _small_template_run()
print(len(_template_run.overloads), sorted({e.data["dispatcher"].__qualname__ for _, e in rec.buffer}))
"""


def test_a_new_process_compiles_nothing_for_the_template_route():
    """With numba's disk cache written (by this process's run), another process runs the compiled
    template route compiling nothing: its typed list of groups is built in cached functions
    (``numba.typed.List(...)`` in Python compiled the list's methods in every process, 0.7 s)."""
    _small_template_run()
    done = subprocess.run(
        [sys.executable, "-c", _COMPILED_IN_A_NEW_PROCESS],
        cwd=ROOT,
        capture_output=True,
        text=True,
        check=True,
        timeout=600,
    )
    assert done.stdout.strip() == "1 []"  # _template_run loaded from the cache, nothing compiled


def test_architecture_i_batch_equals_one_bank_at_a_time_on_the_uav():
    runs = uav.simulate_many(
        [
            ("alpha", "hard"),
            ("alpha", "step"),
            ("elevator", "step"),
            ("dynamics", "soft"),
            ("none", "step"),
        ],
        [np.random.default_rng(s) for s in range(5)],
        duration=1.5,
    )
    nominal = [uav.svo_models(r, "nominal") for r in runs]
    faults = [{f: uav.svo_models(r, f) for f in uav.FAULTS} for r in runs]
    many = run_architecture_i_many(
        nominal, faults, np.stack([r.u for r in runs]), np.stack([r.y for r in runs]), R.UAV_X0
    )
    for r, n, f, res in zip(runs, nominal, faults, many):
        assert res == run_architecture_i(n, f, r.u, r.y, R.UAV_X0)
    assert many[0].isolated == "alpha" and many[4].detection_step is None


def test_uav_study_is_the_same_for_any_number_of_jobs():
    one = RU.uav_study(4, 1, 1, duration=0.9)
    assert one == RU.uav_study(4, 1, 2, duration=0.9)
    assert sum(r["detection"] is not None for r in one) >= 3


def test_staged_banks_equal_banks_on_the_whole_records():
    """_bank_outcomes runs the fault banks on a first stretch of the records, then the undecided ones
    again: the outcomes are those of run_architecture_i on each whole record."""
    runs = uav.simulate_many(
        [("alpha", "step"), ("alpha", "soft"), ("elevator", "hard"), ("elevator", "soft")],
        [np.random.default_rng(s) for s in range(4)],
        duration=3.5,
    )
    staged = RU._bank_outcomes(runs)
    dets = [o["detection"] for o in staged]
    assert max(dets) > 2 * np.median(dets)  # one bank is still undecided after the first stretch
    for r, o in zip(runs, staged):
        nominal = uav.svo_models(r, "nominal")
        ref = run_architecture_i(
            nominal, {f: uav.svo_models(r, f) for f in uav.FAULTS}, r.u, r.y, R.UAV_X0
        )
        assert (o["detection"], o["isolation"], o["isolated"], o["empty_at"]) == (
            ref.detection_step,
            ref.isolation_step,
            ref.isolated,
            dict(ref.empty_at),
        )


def test_support_max_is_dot_then_max_bit_for_bit():
    """The compiled support bound equals the elementwise products of ``_dot`` and a ``max`` over
    the live vertices, to the last bit (the batch's sets do not change with the kernel)."""
    from fdi_lib.sets.svo import _dot, _support_max

    rng = np.random.default_rng(5)
    DPhi = rng.normal(size=(7, 4, 6, 3)) * 10.0 ** rng.integers(-3, 4, size=(7, 4, 6, 1))
    V = rng.normal(size=(7, 3, 9))  # a vertex per column
    F = rng.random((7, 9)) < 0.6
    F[:, 0] = True
    ref = np.stack(
        [_dot(DPhi[a][:, None], V[a].T[F[a]][None]).reshape(-1, 6).max(axis=0) for a in range(7)]
    )
    rows = np.arange(7)
    assert np.array_equal(_support_max(DPhi, rows, V, F, rows), ref)
    # observers share their model's products and are picked by row, in any order
    pick = np.array([4, 0, 4])
    assert np.array_equal(_support_max(DPhi[[0, 4]], np.array([1, 0, 1]), V, F, pick), ref[pick])
    DPhi[2, 1, 3, 0] = np.nan  # a NaN propagates, as in numpy's max
    assert np.isnan(_support_max(DPhi, rows, V, F, rows)[2, 3])


def _stepped(models, u, y, X0, array_route: bool):
    """A TemplateBatch run to the end (every observer), by the array route if asked; its vertices
    (the live ones, in order) and alive masks after every step."""
    bank = TemplateBatch(models, u, y, X0)
    if array_route:
        for g in bank._groups:
            g["bases"] = None
    bank.start()
    out = []
    for k in range(1, bank.T + 1):
        bank.update(k)
        sets = [(np.swapaxes(g["V"], 1, 2)[g["F"]], g["F"].copy()) for g in bank._groups]
        out.append((bank.alive.copy(), sets))
    return out


def test_compiled_step_equals_the_array_route_bit_for_bit():
    """TemplateBatch.update (the compiled basis route, vertices in place) gives the sets of the array
    route (_dot products, _vertices_many) to the last bit, with sets emptied on the way."""
    models, u, y = _records(7, 12)
    seqs = [_constant(m, u.shape[1]) for m in models]
    runs = uav.simulate_many(
        [("alpha", "step"), ("elevator", "hard")],
        [np.random.default_rng(s) for s in range(2)],
        duration=0.6,
    )
    uav_models = [uav.svo_models(r, f) for r in runs for f in ("nominal", *uav.FAULTS)]
    per = 1 + len(uav.FAULTS)
    uav_u = np.repeat(np.stack([r.u for r in runs]), per, axis=0)
    uav_y = np.repeat(np.stack([r.y for r in runs]), per, axis=0)
    for args in ((seqs, u, y, X0), (uav_models, uav_u, uav_y, R.UAV_X0)):
        fused = _stepped(*args, array_route=False)
        ref = _stepped(*args, array_route=True)
        assert not fused[-1][0].all()  # some sets emptied: both outcomes are compared
        for (alive_f, sets_f), (alive_r, sets_r) in zip(fused, ref):
            assert np.array_equal(alive_f, alive_r)
            for (Vf, Ff), (Vr, Fr) in zip(sets_f, sets_r):
                assert np.array_equal(Ff, Fr[:, : Ff.shape[1]]) and not Fr[:, Ff.shape[1] :].any()
                assert np.array_equal(Vf, Vr)


def _advanced(models, u, y, X0):
    """A TemplateBatch run to the end by :meth:`TemplateBatch.advance` (from one set with no
    feasible basis to the next); the step reached, the masks of the sets emptied there and
    alive, and the live vertices after each call."""
    bank = TemplateBatch(models, u, y, X0)
    bank.start()
    out, k = [], 1
    while k <= bank.T and bank.alive.any():
        k, emptied = bank.advance(k)
        out.append(
            (
                k,
                emptied,
                bank.alive.copy(),
                [np.swapaxes(g["V"], 1, 2)[g["F"]] for g in bank._groups],
            )
        )
        k += 1
    return out


def test_advance_equals_one_step_at_a_time_bit_for_bit():
    """TemplateBatch.advance (many steps in one compiled loop, D A_v once for a model the same at
    every step, a chunk at a time for a time-varying one) stops where a set has no feasible basis
    and gives the sets of update, one step at a time, to the last bit."""
    models, u, y = _records(11, 7, 30)
    seqs = [_constant(m, u.shape[1]) for m in models]
    runs = uav.simulate_many(
        [("alpha", "step"), ("elevator", "hard")],
        [np.random.default_rng(s) for s in range(2)],
        duration=1.0,
    )
    uav_models = [uav.svo_models(r, f) for r in runs for f in ("nominal", *uav.FAULTS)]
    per = 1 + len(uav.FAULTS)
    uav_u = np.repeat(np.stack([r.u for r in runs]), per, axis=0)
    uav_y = np.repeat(np.stack([r.y for r in runs]), per, axis=0)
    for args, invariant in (
        ((seqs, u, y, X0), True),
        ((uav_models, uav_u, uav_y, R.UAV_X0), False),
    ):
        assert all((g["DPhi"] is not None) == invariant for g in TemplateBatch(*args)._groups)
        fused = _advanced(*args)
        ref = _stepped(*args, array_route=False)
        assert len(fused) < len(ref)  # several steps per call
        assert any(e.any() for _, e, _, _ in fused)  # some sets emptied on the way
        for k, emptied, alive, sets in fused:
            alive_r, sets_r = ref[k - 1]
            assert np.array_equal(alive, alive_r)
            if k > 1:
                assert np.array_equal(emptied, ref[k - 2][0] & ~alive_r)
            for V, (Vr, _) in zip(sets, sets_r):
                assert np.array_equal(V.view(np.uint64), Vr.view(np.uint64))


def _box_records(seed: int, count: int, n: int, T: int = 30):
    """Random n-D systems measured in every coordinate (``C`` diagonal: every set is a box), one
    A and one B uncertainty, and records; every other one with a sensor fault from k = 12, one
    without measurement noise (flat boxes)."""
    rng = np.random.default_rng(seed)
    models, us, ys = [], [], []
    for i in range(count):
        A = rng.standard_normal((n, n))
        A *= rng.uniform(0.6, 0.95) / max(abs(np.linalg.eigvals(A)))
        A1, B1 = 0.1 * rng.standard_normal((1, n, n)), 0.1 * rng.standard_normal((1, n, 1))
        B, C = rng.standard_normal((n, 1)), np.diag(rng.choice([0.5, 1.0, 2.0], n))
        noise = 0.0 if i == 1 else rng.uniform(0.05, 0.2)
        m = SVOModel(
            A=A, B=B, C=C, L=np.diag(rng.uniform(0.01, 0.1, n)), noise=noise, A_unc=A1, B_unc=B1
        )
        x, u = rng.uniform(-0.5, 0.5, n), rng.uniform(-1, 1, (T, 1))
        y = np.empty((T + 1, n))
        for k in range(T + 1):
            y[k] = C @ x + noise * rng.uniform(-1, 1, n) + (1.5 if i % 2 and k >= 12 else 0.0)
            if k < T:
                d = rng.uniform(-1, 1, 2)
                x = (A + d[0] * A1[0]) @ x + (B + d[1] * B1[0]) @ u[k]
                x = x + m.L @ rng.uniform(-1, 1, n)
        models.append(_constant(m, T))
        us.append(u)
        ys.append(y)
    return models, np.stack(us), np.stack(ys)


@pytest.mark.parametrize("n", [2, 3])
def test_box_route_equals_the_vertex_route_bit_for_bit(n, monkeypatch):
    """Sets whose normals are all +-e_i are boxes: their corners and supports by the box route
    (:func:`_basic_box`, :func:`_support_box`: 2 n products per direction) are the bits of the
    basis route over every vertex and of the array route, step by step and by ``advance``, with
    flat boxes and sets emptied on the way."""
    from fdi_lib.sets import svo

    models, u, y = _box_records(n, 8, n)
    X0n = Polytope.box(-np.ones(n), np.ones(n))
    bank = TemplateBatch(models, u, y, X0n)
    assert all(g["route"][5].shape[0] == n for g in bank._groups)  # the box route applies
    boxed = _stepped(models, u, y, X0n, array_route=False)
    advanced = _advanced(models, u, y, X0n)
    ref = _stepped(models, u, y, X0n, array_route=True)
    monkeypatch.setattr(svo, "_box_route", lambda b: svo._NO_BOX)
    vertices = _stepped(models, u, y, X0n, array_route=False)
    assert not boxed[-1][0].all() and boxed[-1][0].any()  # some sets emptied, some not
    for run in (boxed, vertices):
        for (alive, sets), (alive_r, sets_r) in zip(run, ref):
            assert np.array_equal(alive, alive_r)
            for (V, F), (Vr, Fr) in zip(sets, sets_r):
                assert np.array_equal(F, Fr[:, : F.shape[1]]) and not Fr[:, F.shape[1] :].any()
                assert np.array_equal(V.view(np.uint64), Vr.view(np.uint64))
    for k, _, alive, sets in advanced:
        assert np.array_equal(alive, ref[k - 1][0])
        for V, (Vr, _) in zip(sets, ref[k - 1][1]):
            assert np.array_equal(V.view(np.uint64), Vr.view(np.uint64))


def test_box_route_tables_and_its_limits():
    """:func:`_box_route` gives each corner's coordinates as the basis inverses do, and declines
    normals that are not +-e_i (a skewed strip) or a box open on one side; :func:`_basic_box`
    gives :func:`_basic_one`'s bits (zero bounds, a flat box, a box, no corner) and hands
    it an infinite bound; :func:`_support_box`
    hands a NaN product to the vertex route, which propagates it as ``max`` does."""
    from fdi_lib.sets.polytope import _bases
    from fdi_lib.sets.svo import (
        _NO_BOX,
        _basic_box,
        _basic_one,
        _basic_work,
        _box_route,
        _inv_t,
        _support_into,
        _support_max,
    )

    D = np.vstack([np.eye(3), -np.eye(3)])
    M = np.vstack([D, np.diag([2.0, 1.0, 0.5])])
    b = _bases(M.tobytes(), *M.shape)
    side, normal, sign, axis, unit, corner = _box_route(b)
    mu = np.arange(1.0, 1.0 + len(b.U))
    corners = np.einsum("kij,kj->ki", b.inv, mu[b.idx])  # (K, n): each basis solved
    rows = np.arange(3)[:, None]
    assert np.array_equal((sign * mu[normal])[rows, side].T, corners)
    assert np.array_equal(unit[:, None] * np.eye(3)[axis], b.U)
    assert (side[rows, corner] == [0, 1]).all()
    invT, work = _inv_t(b.inv), _basic_work(len(b.U), len(b.idx), 3)
    X, Xr = np.empty((3, 8)), np.empty((3, 8))
    F, Fr = np.empty(8, dtype=bool), np.empty(8, dtype=bool)
    route = (side, normal, sign, axis, unit, corner)
    m0 = np.zeros(len(M))  # every bound 0 (a corner's -0.0 is 0.0, as the bases' sums give)
    flat = np.r_[1.0, 2.0, 3.0, -1.0, -2.0, -3.0, 4.0, 4.0, 4.0]  # x0 in [1, 1]
    empty = np.r_[1.0, 2.0, 3.0, -1.5, 0.0, 0.0, 4.0, 4.0, 4.0]  # x0 in [1.5, 1]: no corner
    box = np.r_[0.1, 0.7, 1 / 3, 0.3, 0.2, 0.1, 1.3, 0.25, 0.05]  # bounds from both rows
    for m, status in ((m0, 2), (flat, 2), (box, 2), (empty, 0), (-np.ones(len(M)), 0)):
        assert _basic_box(m, b.norms, b.pad, b.zero, route, X, F, work) == status
        assert _basic_one(m, b.norms, b.pad, b.idx, invT, b.U, b.zero, Xr, Fr, work) == (status > 0)
        assert np.array_equal(F, Fr) and np.array_equal(X.view(np.uint64), Xr.view(np.uint64))
    inf = np.where(np.isin(np.arange(len(M)), (0, 6)), np.inf, 0.0)  # both rows of +e_0
    assert _basic_box(inf, b.norms, b.pad, b.zero, route, X, F, work) == -1  # to _basic_one
    skew = np.vstack([D, [[1.0, 1.0, 0.0]]])
    open_box = np.vstack([np.eye(3), -np.eye(3)[:2]])
    for Mx in (skew, open_box):
        bx = _bases(Mx.tobytes(), *Mx.shape)
        assert bx is None or _box_route(bx) is _NO_BOX
    rng = np.random.default_rng(2)
    V = np.ascontiguousarray(corners.T[None].repeat(2, axis=0))  # two boxes, their 8 corners
    F = np.ones((2, 8), dtype=bool)
    DPhi = rng.normal(size=(1, 2, 6, 3))
    DPhi[0, 1, 4, 2] = np.nan
    rows2, mi = np.arange(2), np.zeros(2, dtype=np.int64)
    out = np.empty((2, 6))
    scratch = (np.empty((3, 8)), np.empty(8), np.empty(8, dtype=np.int64))
    _support_into(out, scratch, DPhi, mi, V, F, rows2, corner, np.array([True, False]))
    ref = _support_max(DPhi, mi, V, F, rows2)
    assert np.array_equal(out, ref, equal_nan=True) and np.isnan(out[:, 4]).all()
    DPhi[0, 1, 4, 2] = 0.5
    _support_into(out, scratch, DPhi, mi, V, F, rows2, corner, np.ones(2, dtype=bool))
    assert np.array_equal(out, _support_max(DPhi, mi, V, F, rows2))
