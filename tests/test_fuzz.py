"""Property-based fuzzing of the public API (issue 15).

Random shapes, dtypes, NaN/inf placements, non-symmetric and indefinite matrices, bad
keyword values: every call either returns finite, well-shaped output (NaN only where the
missing-data policy of :mod:`fdi_lib.validation` documents it) or raises a subclass of
:class:`fdi_lib.errors.FDIError`. Any other exception (numpy, scipy, a RuntimeWarning made an
error by the test configuration) fails the test. A scalar argument outside its documented range
(a window longer than the record, a probability of 1.5, start > stop, a negative seed, ...) must
raise a typed error: returning anything, finite or not, fails the test (issue 21).
Deterministic profile (tests/conftest.py).
"""

from __future__ import annotations

import numpy as np
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from fdi_lib.errors import FDIError
from fdi_lib.filters import kalman_filter, kalman_gains
from fdi_lib.glr import first_alarm, glr_known_profile, glr_window
from fdi_lib.isolation import information, minmax_isolation, minmax_statistic
from fdi_lib.kitanidis import kitanidis_filter, kitanidis_gains
from fdi_lib.models import fault_profile, ltv_model, step_family
from fdi_lib.montecarlo import binomial_ci, trial_seeds
from fdi_lib.nonparametric import energy_statistic, energy_threshold
from fdi_lib.rls import rls_track
from fdi_lib.sets import Polytope
from fdi_lib.signatures import fault_signature
from fdi_lib.simulate import simulate
from fdi_lib.sparse import lasso_path, least_squares_on_support, regression_data

FUZZ = settings(max_examples=100, deadline=None, suppress_health_check=[HealthCheck.too_slow])

SPECIAL = [np.nan, np.inf, -np.inf]
MUTATIONS = [
    "none",
    "none",
    "none",
    "nan",
    "inf",
    "shape",
    "int",
    "float32",
    "bool",
    "text",
    "none_value",
]


@st.composite
def matrix(draw, shape, kind="any"):
    """An array of ``shape`` (``kind``: 'any', 'cov' symmetric PSD, 'pd' definite), then maybe mutated."""
    a = np.array(
        draw(
            st.lists(
                st.floats(-3, 3, allow_nan=False),
                min_size=int(np.prod(shape)),
                max_size=int(np.prod(shape)),
            )
        ),
        dtype=float,
    ).reshape(shape)
    if kind in ("cov", "pd") and len(shape) >= 2 and shape[-1] == shape[-2]:
        a = a @ np.swapaxes(a, -1, -2) + (0.5 if kind == "pd" else 0.0) * np.eye(shape[-1])
        variant = draw(st.sampled_from(["ok", "ok", "asym", "indefinite"]))
        if variant == "asym" and shape[-1] > 1:
            a[..., 0, -1] += 1.0
        elif variant == "indefinite":
            a = a - (np.abs(a).max() + 1.0) * np.eye(shape[-1])
    mutation = draw(st.sampled_from(MUTATIONS))
    if mutation in ("nan", "inf") and a.size:
        idx = tuple(draw(st.integers(0, s - 1)) for s in a.shape)
        a[idx] = np.nan if mutation == "nan" else draw(st.sampled_from([np.inf, -np.inf]))
    elif mutation == "shape":
        a = np.zeros(
            tuple(s + draw(st.integers(-1, 1)) for s in shape) + draw(st.sampled_from([(), (2,)]))
        )
        a = np.abs(a)
    elif mutation == "int":
        a = np.round(a).astype(int)
    elif mutation == "float32":
        a = a.astype(np.float32)
    elif mutation == "bool":
        a = a > 0
    elif mutation == "text":
        return "abc"
    elif mutation == "none_value":
        return None
    return a


def attempt(fn, invalid=None):
    """Call ``fn``: its value, or None when it raised an FDIError; anything else fails the test.

    ``invalid`` (a description of an argument outside its range, or None): then the call must
    raise an FDIError; a returned value fails the test.
    """
    try:
        out = fn()
    except FDIError:
        return None
    assert not invalid, f"accepted an argument outside its range: {invalid}"
    return out


def is_int(v):
    return isinstance(v, (int, np.integer)) and not isinstance(v, (bool, np.bool_))


def out_of(v, low=None, high=None):
    """Whether ``v`` is not an integer in ``[low, high]``."""
    return not is_int(v) or (low is not None and v < low) or (high is not None and v > high)


def bad_real(v, low, high, low_open=False, high_open=False):
    """Whether ``v`` is not a finite real number in the interval."""
    if (
        isinstance(v, (bool, np.bool_))
        or not isinstance(v, (int, float, np.number))
        or not np.isfinite(v)
    ):
        return True
    return v < low or v > high or (low_open and v == low) or (high_open and v == high)


def why(**conditions):
    """The names of the conditions that hold (``None`` when none do)."""
    return ", ".join(name for name, bad in conditions.items() if bad) or None


def assert_finite(x, name, allow_nan=None):
    x = np.asarray(x, dtype=float)
    bad = ~np.isfinite(x)
    if allow_nan is not None:
        bad &= ~(np.isnan(x) & allow_nan)
    assert not bad.any(), f"{name}: non-finite output at {np.argwhere(bad)[:3].tolist()}"


dims = st.integers(1, 3)
horizon = st.integers(1, 12)


@st.composite
def model_inputs(draw):
    n, p, N = draw(dims), draw(dims), draw(horizon)
    return dict(
        F=draw(matrix((n, n))),
        H=draw(matrix((p, n))),
        Q=draw(matrix((n, n), "cov")),
        R=draw(matrix((p, p), "pd")),
        n_steps=draw(st.sampled_from([N, N, N, 0, -1, True, 2.5])),
        x0=draw(st.one_of(st.none(), matrix((n,)))),
        P0=draw(st.one_of(st.none(), matrix((n, n), "cov"))),
    )


def good_model(draw):
    n, p, N = draw(dims), draw(dims), draw(st.integers(3, 12))
    rng = np.random.default_rng(draw(st.integers(0, 2**16)))
    return ltv_model(
        F=0.5 * rng.standard_normal((n, n)) / np.sqrt(n),
        H=rng.standard_normal((p, n)),
        Q=np.eye(n),
        R=np.eye(p),
        n_steps=N,
    )


@FUZZ
@given(model_inputs())
def test_fuzz_ltv_model_and_kalman(kwargs):
    steps = kwargs["n_steps"]
    m = attempt(lambda: ltv_model(**kwargs), why(**{f"n_steps={steps!r}": out_of(steps, 1)}))
    if m is None:
        return
    g = attempt(lambda: kalman_gains(m))
    if g is None:
        return
    for arr, name in ((g.K, "K"), (g.P, "P"), (g.Sigma, "Sigma")):
        assert_finite(arr, name)


@FUZZ
@given(st.data())
def test_fuzz_filters_and_glr(data):
    draw = data.draw
    m = good_model(draw)
    N, p, n = m.n_steps, m.p, m.n
    g = kalman_gains(m)
    batch = draw(st.sampled_from([(), (2,)]))
    y = draw(matrix((*batch, N, p)))
    x0 = draw(st.one_of(st.none(), matrix((n,))))
    kf = attempt(lambda: kalman_filter(m, y, gains=g, x0=x0))
    if kf is not None:
        missing = np.isnan(np.asarray(y, dtype=float)).any(axis=-1)
        assert kf.innovations.shape == np.shape(y) if np.ndim(y) > 1 else True
        assert_finite(kf.innovations, "innovations", allow_nan=missing[..., None])
        assert_finite(kf.x_pred, "x_pred")
        eps = kf.innovations
    else:
        eps = np.zeros((*batch, N, p))
    m_dim = draw(dims)
    sig = draw(matrix((N, p, m_dim)))
    res = attempt(lambda: glr_known_profile(eps, g, sig))
    if res is not None:
        assert res.statistic.shape == eps.shape[:-1]
        assert_finite(res.statistic, "glr statistic")
        thr, first = (
            draw(st.sampled_from([3.0, np.nan, -1.0])),
            draw(st.sampled_from([0, N, -3, N + 1, True])),
        )
        alarm = attempt(
            lambda: first_alarm(res.statistic, thr, first),
            why(threshold_nan=np.isnan(thr), start_out_of_0_N=out_of(first, 0, N)),
        )
        assert alarm is None or np.all((alarm >= -1) & (alarm < N))
    fam = step_family(m, Psi=np.ones((n, 1)))
    window = draw(st.sampled_from([1, 2, N, N + 1, 0, 2.0]))
    min_samples = draw(st.sampled_from([None, 0, 1, -1]))
    bad_window = out_of(window, 1, N)
    w = attempt(
        lambda: glr_window(eps, m, g, fam, window, min_samples),
        why(
            window_out_of_1_N=bad_window,
            min_samples_out_of_0_window_minus_1=not bad_window
            and min_samples is not None
            and out_of(min_samples, 0, window - 1),
        ),
    )
    if w is not None:
        defined = w.onset >= 0
        assert_finite(w.statistic, "window statistic", allow_nan=~defined)
        assert_finite(w.theta_hat, "window theta", allow_nan=~defined[..., None])
        alarm = attempt(lambda: first_alarm(w.statistic, 5.0))
        assert alarm is not None, (
            "first_alarm rejected a windowed statistic with only a warm-up NaN"
        )
    start, stop = draw(st.integers(-1, N)), draw(st.integers(0, N + 1))
    info = attempt(
        lambda: information(eps, sig, g, start, stop),
        why(
            start_out_of_0_N_minus_1=out_of(start, 0, N - 1),
            stop_out_of_start_plus_1_N=out_of(stop, start + 1, N),
        ),
    )
    if info is not None:
        assert_finite(info[0], "F")
        assert_finite(info[1], "zeta")


@FUZZ
@given(st.data())
def test_fuzz_minmax(data):
    draw = data.draw
    m = draw(dims)
    F = draw(matrix((m, m), "pd"))
    zeta = draw(matrix((m,)))
    a = draw(st.sampled_from([[0], [m - 1], [0, 0], [m], [-1], [], [0.5]]))
    bad_a = not a or len(set(a)) != len(a) or any(out_of(i, 0, m - 1) for i in a)
    stat = attempt(lambda: minmax_statistic(F, zeta, a), why(**{f"a={a}": bad_a}))
    if stat is not None:
        assert_finite(stat, "minmax")
        assert float(stat) >= -1e-9 * (1 + np.abs(np.asarray(zeta, float)).max() ** 2)
    alpha = draw(st.sampled_from([0.01, 0.0, 1.5, np.nan]))
    attempt(
        lambda: minmax_isolation(F, zeta, [[0]], alpha=alpha),
        why(**{f"alpha={alpha}": bad_real(alpha, 0, 1, True, True)}),
    )


@FUZZ
@given(st.data())
def test_fuzz_energy_and_rls(data):
    draw = data.draw
    N, p = draw(st.integers(1, 15)), draw(dims)
    r = draw(matrix((N, p)))
    L = draw(st.sampled_from(["ok", "neg", "upper"]))
    chol = np.broadcast_to(np.eye(p), (N, p, p)).copy()
    if L == "neg":
        chol[0, 0, 0] = -1.0
    elif L == "upper" and p > 1:
        chol[0, 0, 1] = 1.0
    window = draw(st.sampled_from([1, N, N + 1, 0, 3.0, True]))
    en = attempt(
        lambda: energy_statistic(r, chol, window),
        why(**{f"window={window!r}": out_of(window, 1, N)}),
    )
    if en is not None:
        assert en.shape == (N,)
        assert_finite(en[window - 1 :], "energy after warm-up")
    w_thr, alpha = draw(st.sampled_from([1, 0, 3])), draw(st.sampled_from([0.01, 0.0, 2.0, np.nan]))
    thr = attempt(
        lambda: energy_threshold(w_thr, p, alpha),
        why(
            **{
                f"window={w_thr}": out_of(w_thr, 1),
                f"alpha={alpha}": bad_real(alpha, 0, 1, True, True),
            }
        ),
    )
    assert thr is None or np.isfinite(thr)
    m = draw(dims)
    M = draw(matrix((N, p, m)))
    S = draw(matrix((N, p, p), "pd"))
    lam = draw(st.sampled_from([0.9, 1.0, 0.0, 1.5, np.nan, True]))
    theta0 = draw(st.one_of(st.none(), matrix((m,))))
    res = attempt(
        lambda: rls_track(r, M, S, lam=lam, theta0=theta0),
        why(**{f"lam={lam!r}": bad_real(lam, 0, 1, low_open=True)}),
    )
    if res is not None:
        assert_finite(res.theta_hat, "theta_hat")
        assert res.theta_hat.shape == (N, m)


@FUZZ
@given(st.data())
def test_fuzz_sparse(data):
    draw = data.draw
    rows, m = draw(st.integers(1, 10)), draw(st.integers(1, 4))
    X = draw(matrix((rows, m)))
    y = draw(matrix((rows,)))
    max_size = draw(st.sampled_from([None, 1, 0, -2, 1.5]))
    lambda_min = draw(st.sampled_from([0.0, 0.5, 1.0, -0.1, np.nan]))
    path = attempt(
        lambda: lasso_path(X, y, max_size=max_size, lambda_min=lambda_min),
        why(
            **{
                f"max_size={max_size}": max_size is not None and out_of(max_size, 1),
                f"lambda_min={lambda_min}": bad_real(lambda_min, 0, 1, high_open=True),
            }
        ),
    )
    if path is not None:
        assert_finite(path.coefs, "coefs")
        assert_finite(path.lambdas, "lambdas")
    support = draw(st.sampled_from([[], [0], [-1], [m], [0, 0], [0.5], "a"]))
    # the columns X has (a mutated shape may have more or fewer than m): the range of a support
    cols = X.shape[1] if isinstance(X, np.ndarray) and X.ndim == 2 else m
    bad_support = (
        isinstance(support, str)
        or len(set(support)) != len(support)
        or any(out_of(i, 0, cols - 1) for i in support)
    )
    th = attempt(
        lambda: least_squares_on_support(X, y, support),
        why(**{f"support={support!r}": bad_support}),
    )
    if th is not None:
        assert th.shape == (cols,)
        assert_finite(th, "least squares")
    N, p = draw(st.integers(1, 6)), draw(dims)
    residuals, on_residual = draw(matrix((N, p))), draw(matrix((N, p, m)))
    start = draw(st.sampled_from([0, 1, N, -1]))
    reg = attempt(
        lambda: regression_data(residuals, on_residual, start=start),
        why(**{f"start={start} (N={N})": out_of(start, 0, N - 1)}),
    )
    if reg is not None:
        assert_finite(reg.X, "X")
        assert_finite(reg.y, "y")


@FUZZ
@given(st.data())
def test_fuzz_simulate_signature_kitanidis(data):
    draw = data.draw
    m = good_model(draw)
    n, N = m.n, m.n_steps
    k_m = draw(dims)
    prof = attempt(lambda: fault_profile(m, Psi=draw(matrix((n, k_m)))))
    theta = draw(matrix((k_m,)))
    seed = draw(st.sampled_from([0, 7, -1, 1.5, "abc"]))
    size = draw(st.sampled_from([None, 2, 0, 1.5]))
    sim = attempt(
        lambda: simulate(
            m,
            rng=np.random.default_rng(trial_seeds(seed, 1)[0]),
            fault=prof,
            theta=theta if prof is not None else None,
            size=size,
        ),
        why(
            **{
                f"seed={seed!r}": out_of(seed, 0),
                f"size={size}": size is not None and out_of(size, 1),
            }
        ),
    )
    if sim is not None:
        assert_finite(sim.y, "y")
    if prof is not None:
        sig = fault_signature(m, kalman_gains(m), prof)
        assert_finite(sig.Gamma, "Gamma")
    E = draw(matrix((n, 1)))
    kg = attempt(lambda: kitanidis_gains(m, E))
    if kg is not None:
        y = draw(matrix((N, m.p)))
        res = attempt(lambda: kitanidis_filter(m, y, gains=kg))
        if res is not None:
            missing = np.isnan(np.asarray(y, dtype=float)).any(axis=-1)
            assert_finite(res.innovations, "kitanidis innovations", allow_nan=missing[:, None])
            assert_finite(res.x_filt, "x_filt")


@FUZZ
@given(st.data())
def test_fuzz_small_helpers(data):
    draw = data.draw
    k, n = draw(st.sampled_from([0, 3, -1, 11, 2.5])), draw(st.sampled_from([10, 0, True]))
    level = draw(st.sampled_from([0.95, 1.5, 0.0, np.nan]))
    ci = attempt(
        lambda: binomial_ci(k, n, level=level),
        why(
            **{
                f"trials={n!r}": out_of(n, 1),
                f"successes={k!r}": out_of(k, 0, n if is_int(n) else None),
                f"level={level}": bad_real(level, 0, 1, True, True),
            }
        ),
    )
    if ci is not None:
        assert 0.0 <= ci[0] <= ci[1] <= 1.0
    d = draw(dims)
    lo = draw(matrix((d,)))
    box = attempt(
        lambda: Polytope.box(
            lo, np.asarray(lo, dtype=float) + 1.0 if not isinstance(lo, (str, type(None))) else lo
        )
    )
    if box is not None:
        assert_finite(box.vertices(), "vertices")
