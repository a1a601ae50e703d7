"""The chapters' explorables do what their texts say.

Every frame of each explorable's grid is drawn as the build draws it (one figure reused, the
callback at each grid point) and reduced to its data by :func:`fdi_lib.explorables.figure_data`.
Then (1) every move of every slider changes the plotted data, not only a title, and (2) each
statement of the chapter's text ("things to try", and what the Explore section says the sliders
show) is checked on those data. The numbers the chapters glue come from the helpers of
:mod:`fdi_lib.widgets` (``glr_grid_alarms``, ...); they are checked here against the frames.
"""

from __future__ import annotations

import functools
import itertools

import matplotlib

matplotlib.use("Agg")

import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402
import pytest  # noqa: E402

from fdi_lib.explorables import figure_data  # noqa: E402
from fdi_lib.reproduce.bz import SOL2  # noqa: E402
from fdi_lib.widgets import bz, rosa2013, zb2014, zb2014_pipeline, zhang2021  # noqa: E402
from fdi_lib.widgets.explorables import EXPLORABLES  # noqa: E402


@functools.lru_cache(maxsize=None)
def frames(name: str) -> dict[tuple, list]:
    """figure_data of every grid point, drawn into one reused figure in the build's order."""
    callback, grid = EXPLORABLES[name]
    fig, out = None, {}
    for point in itertools.product(*grid.values()):
        fig = callback(**dict(zip(grid, point)), fig=fig)
        out[point] = figure_data(fig)
    plt.close(fig)
    return out


def _plotted(data: list) -> np.ndarray:
    """Every plotted coordinate of a frame (lines, collections, patches; no texts, no limits)."""
    parts = [np.asarray(a, float).ravel() for ax in data for group in ax[5:8] for a in group]
    return np.concatenate(parts) if parts else np.zeros(0)


@pytest.mark.parametrize("name", list(EXPLORABLES))
def test_every_slider_move_changes_the_plotted_data(name):
    """Along every slider, at every position of the others, neighbouring frames differ in their
    data by more than 1e-6 of the data's scale (a change of the title alone does not count)."""
    _, grid = EXPLORABLES[name]
    data = frames(name)
    names = list(grid)
    unchanged = []
    for j, slider in enumerate(names):
        others = [grid[n] for n in names if n != slider]
        for rest in itertools.product(*others):
            points = [tuple(rest[:j]) + (v,) + tuple(rest[j:]) for v in grid[slider]]
            for a, b in zip(points, points[1:]):
                da, db = _plotted(data[a]), _plotted(data[b])
                scale = max(np.nanmax(np.abs(da)), np.nanmax(np.abs(db)), 1e-300)
                if da.shape == db.shape and np.allclose(
                    da, db, rtol=0, atol=1e-6 * scale, equal_nan=True
                ):
                    unchanged.append((slider, a, b))
    assert not unchanged, f"{len(unchanged)} moves change no plotted data, e.g. {unchanged[:3]}"


def test_signature_statements():
    """||Gamma_k(r)|| jumps at r and decays within a few samples wherever the impulse is;
    ||alpha_k(r)|| grows along the unstable mode until the end, from a later start the later r."""
    ends = []
    for (r,), d in frames("signature").items():
        k, gamma = d[0][5][0].T
        assert k[gamma > 0].min() == r and gamma[k < r].max(initial=0.0) == 0.0
        peak = int(np.argmax(gamma))
        assert k[peak] - r <= 1
        small = np.flatnonzero((k > k[peak]) & (gamma < 0.01 * gamma[peak]))
        assert k[small[0]] - k[peak] <= 10  # "within a few samples"
        ka, alpha = d[1][5][0].T
        assert ka.min() == r and ka.max() == k.max()
        assert np.all(np.diff(alpha) > 0)  # grows until the end of the record
        ends.append(alpha[-1])
    assert np.all(np.diff(ends) < 0)  # later impulse, later start, smaller at the end


def _glr_frame(d):
    k, stat = d[1][5][0].T
    threshold = d[1][5][1][0, 1]
    above = np.flatnonzero(stat > threshold)
    return stat, threshold, (int(k[above[0]]) if above.size else None), above.size


def test_glr_statements():
    """Shrinking the fault removes the alarm; a shorter window shortens the plateau of l_k but
    moves neither the alarm nor the peak of l_k (the chapter's text, with its glued numbers)."""
    grid, data = zb2014.GLR_GRID, frames("GLR")
    facts = zb2014.glr_grid_alarms()
    onset = zb2014.DEFAULTS["onset"]
    for size in grid["fault_size"]:
        alarms, aboves, peaks = [], [], []
        for w in grid["window"]:
            stat, thr, alarm, above = _glr_frame(data[(size, w)])
            assert thr == facts["threshold"]
            np.testing.assert_array_equal(stat, zb2014.glr_run(size, window=w).glr.statistic)
            assert facts["delay"][(size, w)] == (None if alarm is None else alarm - onset)
            assert facts["above"][(size, w)] == above
            alarms.append(alarm), aboves.append(above), peaks.append(np.nanmax(stat))
        assert len(set(alarms)) == 1  # the window does not move the alarm
        np.testing.assert_allclose(peaks, peaks[0], rtol=1e-12)  # nor the peak of l_k
        if alarms[0] is not None:
            assert np.all(np.diff(aboves) > 0)  # a shorter window, a shorter plateau
            assert all(abs(a - w) <= 5 for a, w in zip(aboves, grid["window"]))
    with_alarm = [
        s for s in grid["fault_size"] if _glr_frame(data[(s, grid["window"][0])])[2] is not None
    ]
    assert with_alarm and min(with_alarm) > grid["fault_size"][1]  # the small faults raise none
    assert with_alarm == [s for s in grid["fault_size"] if s >= min(with_alarm)]


def test_pipeline_statements():
    """The default frame is the run of Fig. 5; a smaller change alarms later or not at all; at
    -2e-5 the short windows raise no alarm, because the alarm needs more samples than they hold."""
    from fdi_lib.reproduce.book import book_run
    from fdi_lib.systems import gas_pipeline as gp

    grid, data, W = zb2014_pipeline.GRID, frames("pipeline"), zb2014_pipeline
    delays = W.pipeline_grid_delays()
    for (c, w), d in data.items():
        np.testing.assert_array_equal(d[1][5][0][:, 1], W.pipeline_run(c, window=w).statistic)
    fig5 = book_run("zb2014-fig5").data["run"]
    # the same run, up to rounding (the explorable's GLRs are computed for several sizes at once)
    np.testing.assert_allclose(
        data[(W.DEFAULTS["fault_size_e5"], W.DEFAULTS["window"])][1][5][0][:, 1],
        fig5.statistic,
        rtol=1e-9,
        atol=1e-9,
        equal_nan=True,
    )
    w0, c0 = W.DEFAULTS["window"], W.DEFAULTS["fault_size_e5"]
    column = [delays[(c, w0)] for c in grid["fault_size_e5"]]  # from -10e-5 to 0
    alarmed = [d for d in column if d is not None]
    assert column[: len(alarmed)] == alarmed and np.all(np.diff(alarmed) > 0)
    assert column[-1] is None and len(alarmed) < len(column) - 1  # -1e-5 and 0: no alarm
    row = [delays[(c0, w)] for w in grid["window"]]
    quiet = [w for w, d in zip(grid["window"], row) if d is None]
    assert quiet and quiet == list(grid["window"][: len(quiet)])  # the short windows, only
    first = grid["window"][len(quiet)]
    assert len({d for d in row if d is not None}) == 1
    assert max(quiet) < delays[(c0, first)] / gp.TS_MIN <= first


def _sparse_frame(d):
    lam = d[0][5][0][0, 0]
    span = d[0][7][1][:, 0]
    support = set(d[1][5][0][:, 0].astype(int))
    truth = set(d[1][5][2][:, 0].astype(int))
    position = "below" if lam < span.min() else "above" if lam > span.max() else "in"
    return position, len(support - truth), len(truth - support), span.max() / span.min()


def test_sparse_statements():
    """Below the flat range false alarms appear (more the smaller lambda), above it true faults
    are lost; the flat range is shorter at large q; from q = 10 up the rule does not isolate."""
    grid, data = zhang2021.GRID, frames("sparse")
    facts = zhang2021.sparse_grid_facts()
    for q in grid["q"]:
        rows = [_sparse_frame(data[(q, s)]) for s in grid["lam_scale"]]
        for s, (pos, fa, miss, ratio) in zip(grid["lam_scale"], rows):
            assert (pos, fa, miss) == (
                facts["position"][(q, s)],
                facts["false_alarms"][(q, s)],
                facts["missed"][(q, s)],
            )
            np.testing.assert_allclose(ratio, facts["flat_ratio"][q], rtol=1e-9)
            if pos == "above":
                assert miss >= 1
        below = [fa for pos, fa, _, _ in rows if pos == "below"]
        assert below and below[0] > 0 and np.all(np.diff(below) <= 0)
        rule = rows[grid["lam_scale"].index(1.0)]
        assert below[0] > rule[1]
        assert (rule[1] + rule[2] > 0) == (q >= 10)
    ratios = facts["flat_ratio"]
    assert min(ratios[q] for q in grid["q"] if q <= 5) > max(
        ratios[q] for q in grid["q"] if q >= 10
    )


def test_bz_statements():
    """With f = 0 the GLR crosses its threshold on the drift alone; f does not move the GLR;
    lambda towards 1 makes theta_hat lag the drift and the RLS error energy rise."""
    grid, data = bz.GRID, frames("parametric/non-parametric")
    onset = SOL2["f_onset"]
    for lam in grid["lam"]:
        glr0 = data[(0.0, lam)][2][5][0][:, 1]
        thr = data[(0.0, lam)][2][5][1][0, 1]
        assert np.flatnonzero(glr0 > thr).size and np.flatnonzero(glr0 > thr)[0] < onset
        for f in grid["f_size"]:
            np.testing.assert_allclose(data[(f, lam)][2][5][0][:, 1], glr0, rtol=1e-12, atol=1e-12)
    lags, energies = [], []
    window = slice(*SOL2["tracking_range"])
    for lam in grid["lam"]:
        d = data[(0.0, lam)]
        true0, hat0, true1, hat1 = (line[:, 1] for line in d[0][5][:4])
        lags.append(
            [
                np.mean(np.sign(t[window][-1]) * (t[window] - h[window]))
                for t, h in ((true0, hat0), (true1, hat1))
            ]
        )
        energies.append(np.mean(d[1][5][0][SOL2["drift_onset"] : onset, 1]))
    assert np.all(np.diff(np.asarray(lags), axis=0) > 0)  # each component lags more
    assert np.all(np.diff(energies) > 0)


def test_svo_statements():
    """The horizon narrows the template rule's bounds, which always contain the exact rule's and
    the true state; the exact rule gains nothing from N; N = 5, 6 give the N = 4 sets from the
    bound 0.4 up (the slider stops at 4)."""
    from fdi_lib.reproduce.rosa2013 import toy_prior
    from fdi_lib.sets.svo import run_svo

    grid, data = rosa2013.GRID, frames("SVO")
    shown = {}
    for db in grid["delta_bound"]:
        widths = []
        for n in grid["horizon"]:
            d = data[(db, n)][1]
            (_, true), (_, lo_exact), (_, hi_exact) = (
                line.T for line in (d[5][2], d[5][0], d[5][1])
            )
            band = d[6][0]
            k = np.arange(true.size)
            lo = np.array([band[np.isclose(band[:, 0], i), 1].min() for i in k])
            hi = np.array([band[np.isclose(band[:, 0], i), 1].max() for i in k])
            assert np.all(lo <= lo_exact + 1e-7) and np.all(hi >= hi_exact - 1e-7)
            assert np.all(lo <= true + 1e-7) and np.all(true <= hi + 1e-7)
            widths.append(np.mean(hi - lo))
            shown[(db, n)] = (widths[-1], np.mean(hi_exact - lo_exact))
            if n > 1:
                np.testing.assert_array_equal(d[5][0], data[(db, 1)][1][5][0])  # exact: any N
        assert np.all(np.diff(widths) < 0)
    study = rosa2013.horizon_study(delta_bounds=(0.4,), horizons=(1, 2, 3, 4, 5, 6))
    assert study["exact_gap"] < 1e-6 and study["template_inside"]
    for n in (1, 4):  # the glued widths are those the frames show
        np.testing.assert_allclose(
            shown[(0.4, n)], (study["template_width"][0.4][n], study["exact_width"][0.4]), rtol=1e-9
        )
    for db in grid["delta_bound"][2:]:
        model, x, u, y, *_ = rosa2013._example(db, 0.5, 0, 25)
        runs = [run_svo(model, u, y, toy_prior(), N=n, method="template") for n in (4, 5, 6)]
        for r in runs[1:]:
            np.testing.assert_allclose(r.lower, runs[0].lower, rtol=0, atol=1e-9)
            np.testing.assert_allclose(r.upper, runs[0].upper, rtol=0, atol=1e-9)
