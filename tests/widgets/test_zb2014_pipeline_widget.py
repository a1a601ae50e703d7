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
