"""Widget callback of the gas pipeline chapter."""

import matplotlib

matplotlib.use("Agg")

import pytest  # noqa: E402

from fdi_lib.errors import ModelError  # noqa: E402
from fdi_lib.reproduce.zb2014_pipeline import single_run  # noqa: E402
from fdi_lib.widgets.zb2014_pipeline import DEFAULTS, explore_pipeline  # noqa: E402


def test_defaults_reproduce_fig5_run_and_redraw_into_same_figure():
    fig = explore_pipeline()
    run = single_run(seed=DEFAULTS["seed"], fault=1)
    assert f"delay {run.detection_delay_min:g} min" in fig.axes[0].get_title()
    fig2 = explore_pipeline(
        fault_size_e5=-4.0, fault=2, threshold=20.0, window=100, seed=1, fig=fig
    )
    assert fig2 is fig and "fault 2" in fig.axes[0].get_title()


@pytest.mark.parametrize(
    "kwargs, message",
    [
        ({"fault_size_e5": 1.0}, "fault_size_e5"),
        ({"window": 5}, "window"),
        ({"threshold": 0.0}, "threshold"),
    ],
)
def test_bad_slider_values(kwargs, message):
    with pytest.raises(ModelError, match=message):
        explore_pipeline(**kwargs)


def test_book_window_uses_the_setup_detector_with_the_same_statistics():
    # at w = 160 the runs reuse the set-up's windowed GLR: the statistics and onsets of a fresh one
    import numpy as np

    from fdi_lib.glr import glr_window
    from fdi_lib.reproduce.zb2014_pipeline import pipeline_setup
    from fdi_lib.widgets.zb2014_pipeline import pipeline_run

    st = pipeline_setup()
    for size in (-2.0, -6.0):
        run = pipeline_run(size, window=160)
        fresh = glr_window(run.innovations[:, None], st.model, st.gains, st.input_family, 160)
        np.testing.assert_array_equal(run.statistic, fresh.statistic)
        np.testing.assert_array_equal(run.onset, fresh.onset)
