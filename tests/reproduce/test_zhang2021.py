"""Reproductions of Zhang (2021): contract, smoke runs at reduced trials, statistical consistency."""

import json

import matplotlib

matplotlib.use("Agg")

import numpy as np
import pytest

from fdi_lib.montecarlo import binomial_ci, run_monte_carlo
from fdi_lib.reproduce.registry import get, reproduce
from fdi_lib.reproduce.zhang2021 import example1_chunk, snr_db, snr_variants
from functools import partial


def test_fig2_fig3_single_trial_contract():
    f2 = reproduce("zhang2021-fig2")
    f3 = reproduce("zhang2021-fig3")
    json.loads(f2.to_json())
    assert set(f2.headline) >= {"flat_range", "flat_size", "flat_range_linear"}
    assert set(f3.headline) >= {"flat_range", "support", "true_support"}
    assert f2.headline["flat_range"] == f3.headline["flat_range"]
    lo, hi = f3.headline["flat_range"]
    assert 0 < lo < hi
    assert len(f3.headline["true_support"]) == 5
    # the paper's claims for its Fig. 3: the flat range finds the true support, the same for
    # every lambda in it; least squares on it is close to 1, the Lasso is shrunk
    assert f3.headline["support"] == f3.headline["true_support"]
    assert f3.headline["same_support_in_range"]
    np.testing.assert_allclose(f3.headline["theta_ls"], 1.0, atol=0.1)
    assert max(f3.headline["lasso_mid"]) < min(f3.headline["theta_ls"])
    get("zhang2021-fig2").plot(f2)
    get("zhang2021-fig3").plot(f3)


def test_tables_smoke_at_reduced_trials():
    t1 = reproduce("zhang2021-table1", trials=6, jobs=1)
    assert set(t1.headline["success_rate"]) == {str(q) for q in range(5, 26)}
    assert set(t1.paper["success_rate"]) == set(t1.headline["success_rate"])
    t2 = reproduce("zhang2021-table2", trials=6, jobs=1)
    assert set(t2.headline["snr_db"]) == set(t2.paper["snr_db"])
    assert "0.5" in t2.headline["success_rate"] and "200" in t2.headline["success_rate"]
    for g in (50, 200):  # the grid reading of the rule: added keys, same columns
        assert set(t1.headline[f"success_rate_grid{g}"]) == set(t1.headline["success_rate"])
        assert set(t2.headline[f"success_rate_grid{g}"]) == set(t2.headline["success_rate"])
    json.loads(t1.to_json())
    json.loads(t2.to_json())
    get("zhang2021-table1").plot(t1)
    get("zhang2021-table2").plot(t2)


def test_small_monte_carlo_is_consistent_and_job_independent():
    """200 trials at q = 5: the rate is high and its 95 % interval contains the paper's 99.5 %;
    results do not depend on the number of jobs."""
    fn = partial(example1_chunk, q=5, r=0.5)
    a = run_monte_carlo(fn, 200, seed=11, jobs=1, chunk_size=50)
    b = run_monte_carlo(fn, 200, seed=11, jobs=2, chunk_size=70)
    np.testing.assert_array_equal(a["success_log"], b["success_log"])
    k = int(a["success_log"].sum())
    lo, hi = binomial_ci(k, 200)
    assert lo <= 0.995 <= hi or k == 200
    assert k / 200 > 0.9
    # the grid readings of the rule (50 and 200 lambdas) are recorded on the same trials
    for g in (50, 200):
        np.testing.assert_array_equal(a[f"success_grid{g}"], b[f"success_grid{g}"])
        assert a[f"success_grid{g}"].shape == a["success_log"].shape
        assert np.mean(a[f"success_grid{g}"] == a["success_log"]) > 0.95


def test_snr_definition():
    rng = np.random.default_rng(0)
    v = rng.standard_normal((2, 101, 2))
    sig = 10.0 * np.sin(0.3 * np.arange(101))[None, :, None]
    s = snr_db(sig + v, v)
    for b in range(2):
        for i in range(2):
            yy, vv = sig[0, 1:, 0] + v[b, 1:, i], v[b, 1:, i]
            expected = 10 * np.log10(
                np.mean((yy - yy.mean()) ** 2) / np.mean((vv - vv.mean()) ** 2)
            )
            assert s[b, i] == pytest.approx(expected, rel=1e-12)
    variants = snr_variants(sig + v, v)
    np.testing.assert_allclose(variants["var(Y) / var(V)"], s)


def test_example2_surrogate_pipeline_contract_and_collinearity():
    """Figs 6-7 on the surrogate pipeline: the leak profile (48), and the documented finding that
    delayed-input columns are nearly collinear (the support found is a single merged component)."""
    from fdi_lib.reproduce.zhang2021_example2 import EX2_M, example2_setup

    model, u, Psi = example2_setup()
    assert Psi.shape == (500, 2, EX2_M) and np.all(Psi[:, 1] == 0)
    np.testing.assert_array_equal(Psi[20, 0, 9], -u[10])  # column j (1-based 10) is -u_{k-10}
    np.testing.assert_array_equal(Psi[3, 0, 9], -u[0])  # before the record: u_j = u_0
    np.testing.assert_allclose(model.Q[0], [[3.31, -2.18], [-2.18, 1.44]])
    f6 = reproduce("zhang2021-fig6")
    f7 = reproduce("zhang2021-fig7")
    json.loads(f6.to_json())
    json.loads(f7.to_json())
    assert f7.headline["true_support"] == [9, 14]
    # the paper's own indexing ("the 10-th and the 15-th components"), ours beside it
    assert f7.paper["support_1based"] == f7.paper["true_support_1based"] == [10, 15]
    assert "support" not in f7.paper and "true_support" not in f7.paper
    assert f7.headline["true_support_1based"] == [10, 15]
    assert f7.headline["support_1based"] == [j + 1 for j in f7.headline["support"]]
    assert f6.headline["min_neighbour_correlation"] > 0.999
    # On the physical surrogate the signature filter is short: the correlation comes from the
    # smooth input, not from a long filter.
    assert f6.headline["signature_taps_90"] <= 5
    assert f6.paper["calibrated_to"] == [] and f7.paper["calibrated_to"] == []
    # whatever is selected, its least-squares values add up to the total leak 2e-4 (collinearity)
    assert sum(f7.headline["theta_ls"]) == pytest.approx(2e-4, rel=0.05)
    get("zhang2021-fig6").plot(f6)
    get("zhang2021-fig7").plot(f7)


def test_lambda_rule_chunk_oracle_bounds_every_rule_and_matches_an_independent_solver():
    """The log reading on the full path equals the Table I chunk (windowed path); the oracle is an
    upper bound for every reading; and it agrees with scikit-learn's coordinate-descent Lasso
    solved at the middle of every interval of the path (an independent solver)."""
    from sklearn.linear_model import Lasso

    from fdi_lib.montecarlo import trial_rngs, trial_seeds
    from fdi_lib.reproduce.zhang2021 import example1_regression
    from fdi_lib.reproduce.zhang2021_lambda import RULE_READINGS, lambda_rule_chunk
    from fdi_lib.sparse import lasso_path
    from fdi_lib.systems import zhang2021_example1 as ex

    seeds = trial_seeds(5, 12)
    a = lambda_rule_chunk(seeds, q=15, r=0.5)
    b = example1_chunk(seeds, q=15, r=0.5)
    np.testing.assert_array_equal(a["log"], b["success_log"])
    np.testing.assert_array_equal(a["linear"], b["success_linear"])
    for k in ("log", "linear", "grid20", "grid100"):  # the readings of the raw path
        assert not np.any(a[k] & ~a["oracle"]), k
    for k in ("standardised", "matlab"):  # a scaled path has its own oracle
        assert not np.any(a[k] & ~a[f"oracle_{k}"]), k
    assert set(RULE_READINGS) <= set(a)
    assert 0 < a["oracle"].sum() < 12  # both outcomes occur on these trials
    tr = ex.draw_trials(ex.example1_model(), trial_rngs(seeds), q=15)
    reg, _ = example1_regression(tr)
    rows = reg.X.shape[1]
    for i in range(4):
        X, y, true = reg.X[i], reg.y[i], np.flatnonzero(tr.theta[i])
        lam = lasso_path(X, y, n_samples=reg.n_samples).lambdas
        mids = np.sqrt(lam[:-1] * np.maximum(lam[1:], 1e-3 * lam[0]))
        found = False
        for m in mids:
            fit = Lasso(
                alpha=m * reg.n_samples / rows, fit_intercept=False, tol=1e-12, max_iter=100000
            )
            coef = fit.fit(X, y).coef_
            found |= np.array_equal(np.flatnonzero(np.abs(coef) > 1e-6), true)
        assert found == a["oracle"][i], i


def _on_path_by_coordinate_descent(X, y, lambdas, n_samples, *, intercept=False):
    """Supports of scikit-learn's coordinate-descent Lasso at the middle of every interval of a path."""
    from sklearn.linear_model import Lasso

    mids = np.sqrt(lambdas[:-1] * np.maximum(lambdas[1:], 1e-3 * lambdas[0]))
    out = []
    for m in mids:
        fit = Lasso(
            alpha=m * n_samples / X.shape[0], fit_intercept=intercept, tol=1e-12, max_iter=100000
        )
        out.append(np.flatnonzero(np.abs(fit.fit(X, y).coef_) > 1e-6))
    return out


def test_scaled_regressors():
    from fdi_lib.errors import ModelError
    from fdi_lib.reproduce.zhang2021_lambda import scaled_regressors

    rng = np.random.default_rng(0)
    X, y = 3.0 + rng.standard_normal((2, 40, 5)) * [1, 2, 3, 4, 5], rng.standard_normal((2, 40))
    Xr, yr = scaled_regressors(X, y, "raw")
    assert Xr is X and yr is y
    Xs, ys = scaled_regressors(X, y, "standardised")
    np.testing.assert_allclose(np.sqrt((Xs**2).mean(axis=1)), 1.0, rtol=1e-12)
    assert ys is y
    Xm, ym = scaled_regressors(X, y, "matlab")  # Matlab's lasso: centred, unit variance, intercept
    from sklearn.preprocessing import StandardScaler

    np.testing.assert_allclose(Xm[1], StandardScaler().fit_transform(X[1]), atol=1e-12)
    np.testing.assert_allclose(ym[1], y[1] - y[1].mean(), atol=1e-12)
    with pytest.raises(ModelError, match="path: expected one of"):
        scaled_regressors(X, y, "unit")


def test_a_scaled_path_can_solve_what_the_raw_oracle_excludes():
    """The book's claim (sec-zhang2021-oracles): on some trial the log rule on the unit-RMS path
    selects the true support although no lambda gives it on the raw path; checked on that trial
    with scikit-learn's coordinate descent, on the raw path and on the Matlab-style path (whose
    centring sklearn's intercept does)."""
    from sklearn.linear_model import Lasso

    from fdi_lib.montecarlo import trial_rngs, trial_seeds
    from fdi_lib.reproduce.zhang2021 import example1_regression
    from fdi_lib.reproduce.zhang2021_lambda import lambda_rule_chunk, scaled_regressors
    from fdi_lib.sparse import flat_range, lasso_path
    from fdi_lib.systems import zhang2021_example1 as ex

    seeds = trial_seeds(0, 80)  # the first trials of the book's q = 15 column
    a = lambda_rule_chunk(seeds, q=15, r=0.5)
    beyond = np.flatnonzero(a["standardised"] & ~a["oracle"])
    assert beyond.size >= 1
    i = int(beyond[0])
    tr = ex.draw_trials(ex.example1_model(), trial_rngs(seeds[i : i + 1]), q=15)
    reg, _ = example1_regression(tr)
    X, y, N, true = reg.X[0], reg.y[0], reg.n_samples, np.flatnonzero(tr.theta[0])
    raw = _on_path_by_coordinate_descent(X, y, lasso_path(X, y, n_samples=N).lambdas, N)
    assert not any(np.array_equal(s, true) for s in raw)
    Xs, ys = scaled_regressors(X, y, "standardised")
    lam = flat_range(lasso_path(Xs, ys, n_samples=N)).middle
    coef = (
        Lasso(alpha=lam * N / X.shape[0], fit_intercept=False, tol=1e-12, max_iter=100000)
        .fit(Xs, ys)
        .coef_
    )
    np.testing.assert_array_equal(np.flatnonzero(np.abs(coef) > 1e-6), true)
    Xm, ym = scaled_regressors(X, y, "matlab")
    mat = _on_path_by_coordinate_descent(
        Xm, y, lasso_path(Xm, ym, n_samples=N).lambdas, N, intercept=True
    )
    assert any(np.array_equal(s, true) for s in mat) == a["oracle_matlab"][i]


def test_example2_inputs_and_noise_interventions():
    from fdi_lib.errors import ModelError
    from fdi_lib.reproduce.zhang2021_example2 import (
        EX2_INTERVENTIONS,
        EX2_N,
        EX2_Q,
        EX2_R,
        example2_input,
        example2_setup,
    )
    from fdi_lib.systems import gas_pipeline as gp

    demand = gp.pipeline_input(EX2_N)
    for k in ("nominal", "state_noise", "output_noise"):
        np.testing.assert_array_equal(example2_input(k, np.random.default_rng(0)), demand)
    rel = {k: example2_input(k, np.random.default_rng(1)) / demand - 1 for k in EX2_INTERVENTIONS}
    assert np.abs(rel["white_uniform"]).max() <= 0.3 and np.abs(rel["white_uniform"]).max() > 0.29
    assert 0.27 < rel["white"].std() < 0.33  # 30 % standard deviation
    assert np.all(np.abs(np.diff(rel["white"])) > 1e-9)  # white: changes at every sample
    for k in ("steps", "steps_uniform"):
        change = np.flatnonzero(np.abs(np.diff(rel[k])) > 1e-9) + 1  # rounding of u / demand
        runs = np.diff(np.concatenate([[0], change]))
        assert runs.min() >= 10 and runs.max() <= 30, k  # held 20-60 min at 2 min per sample
    assert np.abs(rel["steps_uniform"]).max() <= 0.3
    np.testing.assert_allclose(
        example2_input("steps", np.random.default_rng(1)), demand * (1 + rel["steps"]), rtol=1e-12
    )  # the same rng, the same input
    with pytest.raises(ModelError, match="intervention: expected one of"):
        example2_input("pink", np.random.default_rng(0))
    # the model for another input and other noise levels: steady state of u_0, as the surrogate's own
    u = demand * (1 + rel["white"])
    model, u2, Psi = example2_setup(u, q_scale=1e-6, r_scale=2.0)
    ref = gp.pipeline_model(EX2_N, u=u)
    np.testing.assert_allclose(model.x0, ref.x0, rtol=1e-12)
    np.testing.assert_allclose(
        model.F[0] @ model.x0 + model.G[0, :, 0] * u[0], model.x0, rtol=1e-12
    )
    np.testing.assert_allclose(model.Q[3], 1e-6 * EX2_Q)
    np.testing.assert_allclose(model.R[3], 2.0 * EX2_R)
    np.testing.assert_array_equal(Psi[20, 0, 9], -u[10])


def test_example2_interventions_reproduction():
    """The chapter's reading of the study (sec-zhang2021-example2-causes), at the book's settings:
    white input variations separate the leaks, smaller noise does not, and steps held 20-60 min
    put the leaks on the path more often than the rule finds them."""
    from fdi_lib.reproduce.views.zhang2021 import intervention_table
    from fdi_lib.reproduce.zhang2021_example2 import EX2_INTERVENTIONS

    r = reproduce("zhang2021-example2-interventions")
    json.loads(r.to_json())
    h, n = r.headline, r.headline["records"]
    assert n == 10 and list(h["isolated"]) == list(EX2_INTERVENTIONS)
    f7 = reproduce("zhang2021-fig7")
    assert h["supports_1based"]["nominal"][0] == f7.headline["support_1based"]  # the same record
    for k in EX2_INTERVENTIONS:
        assert h["isolated"][k] <= h["on_path"][k] <= n
        assert h["isolated"][k] == sum(s == [10, 15] for s in h["supports_1based"][k])
    assert (
        h["isolated"]["nominal"]
        == h["isolated"]["state_noise"]
        == h["isolated"]["output_noise"]
        == 0
    )
    assert h["isolated"]["white"] >= 9 and h["isolated"]["white_uniform"] >= 5
    for k in ("steps", "steps_uniform"):
        assert h["isolated"][k] < h["on_path"][k]
        assert h["min_neighbour_correlation"][k] > 10 * h["min_neighbour_correlation"]["white"]
    assert "rule isolates {10, 15}" in str(intervention_table(r))


def test_initial_state_models_start_like_the_paper():
    """The filter model ignores Y_0: xhat_{0|0} = 0 and P_{0|0} = s^2 I up to 1e-9."""
    from fdi_lib.kitanidis import kitanidis_gains
    from fdi_lib.errors import ModelError
    from fdi_lib.reproduce.zhang2021_lambda import INIT_VARIANTS, initial_state_models
    from fdi_lib.systems import zhang2021_example1 as ex

    for init, s in INIT_VARIANTS.items():
        sim, filt = initial_state_models(0.5, init)
        g = kitanidis_gains(filt, ex.E)
        np.testing.assert_allclose(g.P_filt[0], s**2 * np.eye(3), atol=1e-9 * max(1.0, s**2))
        assert np.abs(g.K[0]).max() < 1e-9
        np.testing.assert_array_equal(sim.R[5], 0.5 * np.eye(2))
        np.testing.assert_array_equal(filt.R[5], sim.R[5])
    with pytest.raises(ModelError, match="init: expected one of"):
        initial_state_models(0.5, "zero")


def test_initial_state_chunk_per_initialisation_is_the_joint_one():
    """Each initialisation computed alone (one chunk function each in the pool) gives the bits of
    the joint chunk; an unknown name is refused."""
    from fdi_lib.errors import ModelError
    from fdi_lib.montecarlo import trial_seeds
    from fdi_lib.reproduce.zhang2021_lambda import INIT_VARIANTS, initial_state_chunk

    seeds = trial_seeds(1, 8)  # trials on which the two initialisations part (both rows)
    both = initial_state_chunk(seeds, q=15, r=0.5)
    assert list(both) == [f"{k}_{i}" for i in INIT_VARIANTS for k in ("log", "oracle")]
    for k in ("log", "oracle"):
        assert not np.array_equal(both[f"{k}_paper"], both[f"{k}_spread"])
    for init in INIT_VARIANTS:
        alone = initial_state_chunk(seeds, q=15, r=0.5, inits=(init,))
        assert list(alone) == [f"log_{init}", f"oracle_{init}"]
        for k, v in alone.items():
            np.testing.assert_array_equal(v, both[k])
    with pytest.raises(ModelError, match="inits: expected names of"):
        initial_state_chunk(seeds, q=15, r=0.5, inits=("paper", "zero"))


def test_lambda_rule_chunk_functions_start_short_and_cover_every_column_once():
    """The pool's first chunk (run alone by the calling process) is an initialisation's, half a
    column's; every column and initialisation has one function, with its own settings."""
    from fdi_lib.reproduce.zhang2021_lambda import (
        INIT_VARIANTS,
        _chunk_functions,
        initial_state_chunk,
        lambda_rule_chunk,
        variant_columns,
    )

    cols = variant_columns()
    fns = _chunk_functions(cols)
    assert sorted(fns) == sorted([key for key, _, _ in cols] + list(INIT_VARIANTS))
    first, *rest = fns
    assert fns[first].func is initial_state_chunk and first in INIT_VARIANTS
    assert list(fns).index(list(INIT_VARIANTS)[1]) == 3  # the other one after two columns
    for key, q, r in cols:
        assert fns[key].func is lambda_rule_chunk and fns[key].keywords == {"q": q, "r": r}
    for init in INIT_VARIANTS:
        assert fns[init].keywords == {"q": 15, "r": 0.5, "inits": (init,)}


def test_unknown_input_cannot_change_the_regression():
    from fdi_lib.reproduce.zhang2021_lambda import unknown_input_effect

    assert unknown_input_effect(trials=5) < 1e-12


def test_paper_between_readings_and_closest_snr():
    from fdi_lib.reproduce.registry import ReproductionResult
    from fdi_lib.reproduce.zhang2021 import closest_snr_reading
    from fdi_lib.reproduce.views.zhang2021 import paper_between_readings

    res = ReproductionResult(
        id="x",
        headline={
            "success_rate": {"a": 0.8, "b": 0.5, "c": 0.3},
            "success_rate_linear": {"a": 0.6, "b": 0.6, "c": 0.2},
        },
        paper={"success_rate": {"a": 0.7, "b": 0.55, "c": 0.35}},
    )
    assert paper_between_readings(res) == ["a", "b"]
    readings = {
        "one": np.array([[34.0, 32.6], [0.0, 0.0]]),
        "two": np.array([[30.0, 30.0], [11.6, 9.9]]),
    }
    assert closest_snr_reading(readings, (0.5, 100.0)) == ["one", "two"]


def test_lambda_rule_reproduction_contract():
    r = reproduce("zhang2021-lambda-rule", trials=3)
    json.loads(r.to_json())
    h = r.headline
    assert set(h["success_rate"]) == {
        "log",
        "linear",
        "grid20",
        "grid100",
        "standardised",
        "matlab",
        "oracle",
    }
    assert (
        set(h["success_rate"]["oracle"])
        == set(r.paper["success_rate"])
        == {"q9", "q15", "q25", "r100", "r200"}
    )
    assert set(h["oracle_rate"]) == {"raw", "standardised", "matlab", "union"}
    assert h["oracle_rate"]["raw"] == h["success_rate"]["oracle"]
    for c in h["oracle_rate"]["union"]:
        assert h["oracle_rate"]["union"][c] >= max(
            h["oracle_rate"][p][c] for p in ("raw", "standardised", "matlab")
        )
        assert all(
            h["beyond_raw_oracle"][k][c] == 0 for k in ("log", "linear", "grid20", "grid100")
        )
        assert h["success_rate"]["standardised"][c] <= h["oracle_rate"]["standardised"][c]
    assert set(h["init_success_rate"]) == {"paper", "spread"}
    from fdi_lib.reproduce.views.zhang2021 import initial_state_table, lambda_rule_table

    assert "oracle: true support on the path" in str(lambda_rule_table(r))
    from fdi_lib.reproduce.views.zhang2021 import oracle_table

    assert "any of the three paths" in str(oracle_table(r))
    assert "not given" in str(initial_state_table(r))


def test_reader_tables_and_counts():
    from fdi_lib.reproduce.registry import ReproductionResult
    from fdi_lib.reproduce.views.zhang2021 import (
        grid_rule_difference,
        paper_outside_ci,
        rate_table,
        snr_table,
    )

    h = {
        "success_rate": {"5": 0.99, "15": 0.46},
        "success_rate_linear": {"5": 0.98, "15": 0.41},
        "ci95": {"5": [0.98, 0.995], "15": [0.43, 0.49]},
        "success_rate_grid50": {"5": 0.99, "15": 0.47},
        "success_rate_grid200": {"5": 0.97, "15": 0.46},
    }
    res = ReproductionResult(
        id="x",
        headline=h,
        paper={"success_rate": {"5": 0.995, "15": 0.295}},
        settings={"trials": 1000},
    )
    assert paper_outside_ci(res) == (1, 1)
    assert grid_rule_difference(res) == pytest.approx(0.02)
    text = str(rate_table(res)).replace("\u00a0", " ")
    assert "q = 15" in text and "46 % [43, 49]" in text and "29.5 %" in text
    t = str(snr_table({"var(Y) / var(V)": np.array([[34.5, 32.8]])}, (0.5,)))
    assert "34.5 / 32.8" in t and "34.06 / 32.63" in t
    # each row says what its ratio compares before the maths
    assert "variances: $10 \\log_{10}" in t


def test_outputs_with_unknown_input_matches_a_direct_loop():
    from fdi_lib.models import ltv_model
    from fdi_lib.reproduce.zhang2021 import outputs_with_unknown_input
    from fdi_lib.simulate import draw_noise

    rng = np.random.default_rng(3)
    N, n, p, s, m = 8, 3, 2, 1, 4
    model = ltv_model(
        F=0.5 * np.eye(n),
        G=rng.standard_normal((n, 1)),
        H=rng.standard_normal((p, n)),
        Q=np.eye(n),
        R=np.eye(p),
        n_steps=N,
    )
    E, Psi, Phi = (
        rng.standard_normal((N, n, s)),
        rng.standard_normal((N, n, m)),
        rng.standard_normal((N, p, m)),
    )
    u, d, theta = rng.standard_normal((N, 1)), rng.standard_normal((N, s)), rng.standard_normal(m)
    noise = draw_noise(model, rng)
    y = outputs_with_unknown_input(model, E, Psi, Phi, noise=noise, u=u, d=d, theta=theta)
    x = noise.x0.copy()
    for k in range(N):
        expected = model.H[k] @ x + noise.v[k] + Phi[k] @ theta
        np.testing.assert_allclose(y[k], expected, rtol=1e-12, atol=1e-12)
        x = model.F[k] @ x + model.G[k] @ u[k] + E[k] @ d[k] + noise.w[k] + Psi[k] @ theta
