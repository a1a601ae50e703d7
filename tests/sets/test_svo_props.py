"""Propositions 2-3 of Rosa & Silvestre (2013) as seeded property tests, plus the SVO's edge cases."""

from __future__ import annotations

import numpy as np
import pytest

from fdi_lib.errors import (
    EmptySetError,
    ModelError,
    ShapeError,
    UnboundedSetError,
    UnsoundOptionWarning,
)
from fdi_lib.sets import Polytope
from fdi_lib.sets.svo import (
    SetValuedObserver,
    SVOModel,
    run_architecture_i,
    run_architecture_ii,
    run_svo,
)


def random_system(rng: np.random.Generator, c_unc: bool = False):
    """A random stable 2-D system with one A uncertainty, one B uncertainty and (optionally) C uncertainty."""
    A = rng.standard_normal((2, 2))
    A *= rng.uniform(0.6, 0.95) / max(abs(np.linalg.eigvals(A)))
    A1 = 0.1 * rng.standard_normal((2, 2))
    B = rng.standard_normal((2, 1))
    B1 = 0.1 * rng.standard_normal((1, 2, 1))
    C = np.array([[1.0, rng.uniform(-0.5, 0.5)]])
    C1 = 0.05 * rng.standard_normal((1, 1, 2)) if c_unc else None
    L = np.diag(rng.uniform(0.01, 0.1, 2))
    return SVOModel(
        A=A, B=B, C=C, L=L, noise=rng.uniform(0.05, 0.2), A_unc=A1[None], B_unc=B1, C_unc=C1
    )


def simulate(model: SVOModel, rng: np.random.Generator, T: int, fault=None):
    """Every uncertainty drawn uniformly inside its bound (Delta, d, n), optional additive sensor fault."""
    x = np.zeros((T + 1, 2))
    x[0] = rng.uniform(-0.5, 0.5, 2)
    u = rng.uniform(-1, 1, (T, 1))
    for k in range(T):
        A = model.A + rng.uniform(-1, 1) * model.A_unc[0]
        B = model.B + rng.uniform(-1, 1) * model.B_unc[0]
        x[k + 1] = A @ x[k] + B @ u[k] + model.L @ rng.uniform(-1, 1, 2)
    y = np.empty((T + 1, 1))
    for k in range(T + 1):
        C = model.C + (rng.uniform(-1, 1) * model.C_unc[0] if model.C_unc.shape[0] else 0)
        y[k] = C @ x[k] + model.noise * rng.uniform(-1, 1)
    if fault is not None:
        y[fault[0] :] += fault[1]
    return x, u, y


X0 = Polytope.box([-1.0, -1.0], [1.0, 1.0])


@pytest.mark.parametrize("method,N", [("template", 1), ("template", 2), ("exact", 1), ("exact", 2)])
def test_prop2_containment_and_prop3_no_false_alarm(method, N):
    """Prop. 2: x(k) in X̂(k) for all k; hence Prop. 3 never fires on healthy data."""
    rng = np.random.default_rng(2013 + N + 7 * (method == "exact"))
    runs = 12 if method == "exact" else 25
    for _ in range(runs):
        model = random_system(rng)
        x, u, y = simulate(model, rng, T=25)
        res = run_svo(model, u, y, X0, N=N, method=method, keep_sets=True)
        assert res.empty_at is None
        assert all(S.contains(x[k], 1e-7) for k, S in enumerate(res.sets))


def test_output_uncertainty_relaxation_keeps_the_true_state():
    rng = np.random.default_rng(8)
    for _ in range(15):
        model = random_system(rng, c_unc=True)
        x, u, y = simulate(model, rng, T=25)
        res = run_svo(model, u, y, X0, keep_sets=True)
        assert res.empty_at is None
        assert all(S.contains(x[k], 1e-7) for k, S in enumerate(res.sets))


def test_fault_far_outside_bounds_detected_at_first_visible_sample():
    rng = np.random.default_rng(5)
    for _ in range(10):
        model = random_system(rng)
        k0 = 12
        bias = 10.0 * (float(model.noise[0]) + 1.0)
        x, u, y = simulate(model, rng, T=20, fault=(k0, bias))
        assert run_svo(model, u, y, X0).empty_at == k0


def test_paper_literal_hull_can_exclude_the_true_state():
    """co_v{Prop(v) ∩ S} (strip before hull) misses x(k+1) = 1 when Delta = 0; ours keeps it."""
    model = SVOModel(A=np.array([[1.0]]), A_unc=np.array([[[0.5]]]), C=np.array([[1.0]]), noise=0.1)
    X = Polytope.box([0.99], [1.01])
    y0, y1 = np.array([1.0]), np.array([1.0])  # true x(0) = 1, Delta = 0, x(1) = 1
    literal = SetValuedObserver(X, method="exact", strip_before_hull=True)
    literal.start(model, y0)
    with pytest.warns(UnsoundOptionWarning, match="strip_before_hull=True"):
        assert literal.update(model, np.zeros(0), y1) is None  # a false alarm, announced
    ours = SetValuedObserver(X, method="exact")
    ours.start(model, y0)
    assert ours.update(model, np.zeros(0), y1).contains(np.array([1.0]))


def test_architectures_isolate_a_sensor_bias():
    rng = np.random.default_rng(11)
    model = random_system(rng)
    bias = 3.0
    x, u, y = simulate(model, rng, T=30, fault=(10, bias))
    sensor = SVOModel(
        A=model.A,
        B=model.B,
        C=model.C,
        L=model.L,
        noise=model.noise + bias + 0.1,
        A_unc=model.A_unc,
        B_unc=model.B_unc,
    )
    big_dist = SVOModel(
        A=model.A,
        B=model.B,
        C=model.C,
        L=model.L * 1.5,
        noise=model.noise,
        A_unc=model.A_unc,
        B_unc=model.B_unc,
    )
    res = run_architecture_i(model, {"sensor": sensor, "process": big_dist}, u, y, X0)
    assert res.detection_step == 10 and res.isolated == "sensor" and res.isolation_step == 10
    res2 = run_architecture_ii(model, sensor, {"sensor": sensor, "process": big_dist}, u, y, X0)
    assert res2.detection_step == 10 and res2.isolated == "sensor"


def test_bad_inputs():
    model = SVOModel(A=np.eye(2), C=np.array([[1.0, 0.0]]), noise=0.1)
    with pytest.raises(EmptySetError, match="X0: the initial set"):
        SetValuedObserver(Polytope(np.array([[1.0, 0.0], [-1.0, 0.0]]), np.array([-1.0, -1.0])))
    with pytest.raises(UnboundedSetError, match="X0: the initial set .* unbounded"):
        SetValuedObserver(Polytope(np.array([[1.0, 0.0], [0.0, 1.0]]), np.array([1.0, 1.0])))
    with pytest.raises(ModelError, match="N: expected a positive integer"):
        SetValuedObserver(X0, N=0)
    with pytest.raises(ModelError, match="method: expected"):
        SetValuedObserver(X0, method="fast")
    with pytest.raises(ShapeError, match=r"C: expected 2 columns"):
        SVOModel(A=np.eye(2), C=np.ones((1, 3)))
    with pytest.raises(ShapeError, match=r"A_unc: expected shape \(n_A, 2, 2\)"):
        SVOModel(A=np.eye(2), C=np.ones((1, 2)), A_unc=np.ones((1, 3, 3)))
    with pytest.raises(ShapeError, match=r"noise: expected a scalar or shape \(1,\)"):
        SVOModel(A=np.eye(2), C=np.ones((1, 2)), noise=[0.1, 0.2])
    with pytest.raises(ShapeError, match=r"model: expected state dimension 2"):
        SetValuedObserver(X0).start(SVOModel(A=np.eye(3), C=np.ones((1, 3))), np.zeros(1))
    with pytest.raises(ShapeError, match=r"u: expected 3 rows"):
        run_svo(
            SVOModel(A=np.eye(2), B=np.ones((2, 1)), C=np.array([[1.0, 0.0]])),
            np.zeros((2, 1)),
            np.zeros((4, 1)),
            X0,
        )
    svo = SetValuedObserver(X0)
    svo.start(model, np.zeros(1))
    with pytest.raises(ShapeError, match=r"y_next: expected shape \(1,\)"):
        svo.update(model, np.zeros(0), np.zeros(2))


def test_fault_models_of_tables_1_2_contain_the_healthy_and_the_faulty_plant():
    from fdi_lib.sets.svo import (
        actuator_effectiveness_model,
        dynamics_entry_model,
        sensor_bias_model,
    )

    rng = np.random.default_rng(21)
    model = random_system(rng)
    act = actuator_effectiveness_model(model, 0, lowest=0.5)
    # gains 1 (healthy) and 0.5 (faulty) are the two vertices of the new uncertainty
    cols = {round(float(s), 12) for s in (act.B[:, 0] + act.B_unc[-1][:, 0]) / model.B[:, 0]}
    cols |= {round(float(s), 12) for s in (act.B[:, 0] - act.B_unc[-1][:, 0]) / model.B[:, 0]}
    assert cols == {1.0, 0.5}
    sen = sensor_bias_model(model, 0, bound=2.0)
    assert sen.noise[0] == pytest.approx(model.noise[0] + 2.0)
    lo, hi = sorted([model.A[1, 0], 1.3 * model.A[1, 0]])
    dyn = dynamics_entry_model(model, 1, 0, lo, hi)
    ends = sorted([dyn.A[1, 0] - dyn.A_unc[-1][1, 0], dyn.A[1, 0] + dyn.A_unc[-1][1, 0]])
    np.testing.assert_allclose(ends, [lo, hi], rtol=1e-12)
    assert dyn.vertex_matrices().shape == (4, 2, 2)
    with pytest.raises(ModelError, match="lowest: expected a gain in"):
        actuator_effectiveness_model(model, 0, lowest=1.5)
    with pytest.raises(ModelError, match="output_index"):
        sensor_bias_model(model, 3, bound=1.0)
    # a 50 % actuator fault: the nominal SVO may fire, the fault-model SVO must not
    x = np.zeros((31, 2))
    u = rng.uniform(-1, 1, (30, 1))
    for k in range(30):
        gain = 1.0 if k < 10 else 0.5
        x[k + 1] = (
            (model.A + rng.uniform(-1, 1) * model.A_unc[0]) @ x[k]
            + (model.B + rng.uniform(-1, 1) * model.B_unc[0]) @ (gain * u[k])
            + model.L @ rng.uniform(-1, 1, 2)
        )
    y = x @ model.C.T + model.noise * rng.uniform(-1, 1, (31, 1))
    res = run_svo(act, u, y, X0, keep_sets=True)
    assert res.empty_at is None and all(S.contains(x[k], 1e-7) for k, S in enumerate(res.sets))


@pytest.mark.parametrize("method", ["exact", "template"])
def test_state_scaling_gives_the_same_sets(method):
    """z = x / s inside the observer: the sets mapped back equal the unscaled ones (the round-off
    margins, 1e-9 relative per step, are applied in different units: supports agree to 1e-6)."""
    rng = np.random.default_rng(21)
    model = random_system(rng, c_unc=True)
    x, u, y = simulate(model, rng, 12)
    X0 = Polytope.box([-1, -1], [1, 1])
    s = np.array([1e-3, 10.0])
    D = np.array([[np.cos(a), np.sin(a)] for a in np.linspace(0, 2 * np.pi, 16, endpoint=False)])
    # the template rule with the same directions in x (the default ones would follow the scaled C)
    T = np.vstack([np.eye(2), -np.eye(2), D])
    a = run_svo(model, u, y, X0, method=method, template=T, keep_sets=True)
    b = run_svo(model, u, y, X0, method=method, template=T, keep_sets=True, scale=s)
    assert a.empty_at == b.empty_at
    for Sa, Sb in zip(a.sets, b.sets):
        np.testing.assert_allclose(Sa.support(D), Sb.support(D), rtol=1e-6, atol=1e-7)
    np.testing.assert_allclose(a.lower, b.lower, rtol=1e-6, atol=1e-7)
    with pytest.raises(ModelError, match="scale: expected 2 positive numbers"):
        SetValuedObserver(X0, scale=[1.0, 0.0])


def test_exact_rule_runs_on_the_uav_and_contains_the_true_state():
    """The paper's exact update on the UAV model (n = 4), scaled: no numerical error, x(k) inside."""
    from fdi_lib.reproduce.rosa2013 import UAV_X0
    from fdi_lib.systems import eclipse_uav as uav

    run = uav.simulate("none", "step", rng=np.random.default_rng(0), duration=0.02)
    res = run_svo(
        uav.svo_models(run, "nominal"),
        run.u,
        run.y,
        UAV_X0,
        method="exact",
        scale=uav.svo_scale(),
        keep_sets=True,
    )
    assert res.empty_at is None
    assert all(S.contains(run.x[k], 1e-9) for k, S in enumerate(res.sets))
    tmpl = run_svo(uav.svo_models(run, "nominal"), run.u, run.y, UAV_X0)
    assert np.all(res.lower >= tmpl.lower - 1e-9) and np.all(res.upper <= tmpl.upper + 1e-9)


def test_joint_horizon_is_inside_the_separate_one_and_contains_the_state():
    """Eq. (3) with shared disturbances (LPs) against the row-by-row projection (closed form)."""
    from fdi_lib.reproduce.rosa2013_studies import healthy_record, random_system

    rng = np.random.default_rng(8)
    m0 = random_system(rng)
    m = SVOModel(A=m0.A, B=m0.B, C=m0.C, L=m0.L, noise=m0.noise, B_unc=m0.B_unc)  # A known: sound
    x, u, y = healthy_record(m0, rng, 5)
    x = np.zeros_like(x)
    x[0] = rng.uniform(-0.5, 0.5, 2)
    for k in range(5):
        x[k + 1] = (
            m.A @ x[k]
            + (m.B + rng.uniform(-1, 1) * m.B_unc[0]) @ u[k]
            + m.L @ rng.uniform(-1, 1, 2)
        )
    y = x @ m.C.T + m.noise * rng.uniform(-1, 1, (6, 1))
    X0 = Polytope.box([-1, -1], [1, 1])
    D = np.array([[np.cos(a), np.sin(a)] for a in np.linspace(0, 2 * np.pi, 12, endpoint=False)])
    a = run_svo(m, u, y, X0, N=2, template=D, keep_sets=True)
    b = run_svo(m, u, y, X0, N=2, template=D, keep_sets=True, joint=True)
    assert b.empty_at is None
    assert all(S.contains(x[k], 1e-7) for k, S in enumerate(b.sets))
    gaps = np.array([Sa.support(D) - Sb.support(D) for Sa, Sb in zip(a.sets, b.sets)])
    assert gaps.min() > -1e-7 and gaps.max() > 1e-6  # never looser, tighter somewhere


def test_joint_horizon_can_lose_the_true_state_when_a_is_uncertain():
    """The counter-example the book shows: with an uncertain A, the joint form raised a false alarm."""
    from fdi_lib.reproduce.rosa2013_studies import horizon_comparison

    out = horizon_comparison(2013, runs=3, steps=6, horizons=(2,))[2]
    assert out["alarms"] >= 1 and out["outside"] >= 1


def test_exact_horizon_equals_the_hull_over_all_vertex_sequences():
    """The exact rule's recursion (one step per level) against eq. (3)-(4) by brute force: every
    sequence of Delta-vertices over the horizon, every disturbance corner, one hull per level, then
    the intersection with the strip, whose support is found by linear programming (HiGHS)."""
    import itertools

    from scipy.optimize import linprog
    from scipy.spatial import ConvexHull

    rng = np.random.default_rng(17)
    model = random_system(rng)
    x, u, y = simulate(model, rng, T=7)
    N = 3
    svo = SetValuedObserver(X0, N=N, method="exact")
    sets = [svo.start(model, y[0])]
    D = np.array([[np.cos(a), np.sin(a)] for a in np.linspace(0, 2 * np.pi, 24, endpoint=False)])
    signs = np.array(list(itertools.product((-1.0, 1.0), repeat=3)))
    Avs = [model.A + s * model.A_unc[0] for s in (-1.0, 1.0)]
    for k in range(7):
        sets.append(svo.update(model, u[k], y[k + 1]))
        rows, rhs = [model.C, -model.C], [model.noise + y[k + 1], model.noise - y[k + 1]]
        for j in range(min(N, k + 1)):
            pts_all = []
            for seq in itertools.product(range(2), repeat=j + 1):
                pts = sets[k - j].vertices()
                for step, a in zip(range(k - j, k + 1), seq):
                    # disturbance L d and input uncertainty B_1 u(step) Delta_b: corners of their box
                    corners = signs @ np.column_stack([model.L, model.B_unc[0] @ u[step]]).T
                    pts = (
                        (pts @ Avs[a].T + model.B @ u[step])[:, None, :] + corners[None]
                    ).reshape(-1, 2)
                pts_all.append(pts)
            eq = ConvexHull(np.vstack(pts_all)).equations
            rows.append(eq[:, :2])
            rhs.append(-eq[:, 2])
        A_ub, b_ub = np.vstack(rows), np.concatenate(rhs)
        brute = np.array(
            [-linprog(-d, A_ub=A_ub, b_ub=b_ub, bounds=[(None, None)] * 2).fun for d in D]
        )
        np.testing.assert_allclose(sets[-1].support(D), brute, rtol=0, atol=1e-7)
        assert sets[-1].contains(x[k + 1], 1e-9)
