import matplotlib

matplotlib.use("Agg")

import numpy as np
import pytest

from fdi_lib.errors import ModelError
from fdi_lib.widgets.zb2014 import DEFAULTS, explore_glr


def test_callback_draws_innovation_and_glr_and_reuses_the_figure():
    fig = explore_glr(**DEFAULTS)
    top, bottom = fig.axes
    assert len(top.lines[0].get_ydata()) == 500
    stat = np.asarray(bottom.lines[0].get_ydata(), dtype=float)
    assert np.nanmax(stat[201:]) > DEFAULTS["threshold"]  # fault of size 1.5 is detected
    assert "alarm after" in top.get_title()
    again = explore_glr(fault_size=0.0, fig=fig)
    assert again is fig and "alarm after" not in fig.axes[0].get_title()


def test_callback_rejects_out_of_range_values():
    with pytest.raises(ModelError, match=r"window: expected an integer in \[5, 200\], got 1"):
        explore_glr(window=1)
    with pytest.raises(ModelError, match="threshold: expected a positive number"):
        explore_glr(threshold=0.0)
