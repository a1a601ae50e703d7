"""The wind-turbine explorable reads its thresholds from the design's function and its labels and
colours from the method registry (issue 34, point 3)."""

from __future__ import annotations

import matplotlib

matplotlib.use("Agg")

import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402
import pytest  # noqa: E402
import scipy.stats  # noqa: E402

from fdi_lib import windturbine as W  # noqa: E402
from fdi_lib.widgets.windturbine import explore_windturbine, mean_signal_delays  # noqa: E402


def test_detection_thresholds_in_closed_form():
    st, c = W.Settings(), W.plant_constants()
    alpha = st.false_alarms_per_hour * c.Ts / 3600.0
    t = W.detection_thresholds(st, c.Ts, m=3, p=2)
    assert t.glr == pytest.approx(scipy.stats.chi2.isf(alpha / st.window, 3), rel=1e-9)
    assert t.lasso == pytest.approx(scipy.stats.norm.isf(alpha / 6), rel=1e-9)
    assert t.energy == pytest.approx(scipy.stats.chi2.isf(alpha, 2 * st.window), rel=1e-9)


def test_svo_sees_an_offset_beyond_its_two_noise_bands_at_once():
    st, c = W.Settings(), W.plant_constants()
    band = 2 * st.svo_sigmas * c.sigma[0]
    d = mean_signal_delays([0.99 * band, 1.01 * band])
    assert np.isnan(d["rosa2013"][0]) and d["rosa2013"][1] == pytest.approx(c.Ts)
    for m in ("zb2014", "zhang2021", "bz"):  # a larger offset is never seen later
        big = mean_signal_delays([2.0, 4.0])[m]
        assert big[1] <= big[0], m


def test_curves_are_labelled_and_coloured_by_the_registry():
    fig = explore_windturbine(1.0, 1.0)
    ax = fig.axes[0]
    lines = {ln.get_label(): ln for ln in ax.get_lines() if not ln.get_label().startswith("_")}
    assert list(lines) == [m.label for m in W.METHODS.values()]
    for m in W.METHODS.values():
        assert matplotlib.colors.same_color(lines[m.label].get_color(), m.style.color)
    plt.close(fig)
