import matplotlib

matplotlib.use("Agg")

import pytest

from fdi_lib.errors import ModelError
from fdi_lib.widgets.zhang2021 import explore_sparse


def test_callback_draws_and_reuses_the_figure():
    fig = explore_sparse()
    left, right = fig.axes
    assert "isolated" in right.get_title()
    diamonds = right.lines[0]
    assert len(diamonds.get_xdata()) >= 1
    again = explore_sparse(q=12, r=50.0, lam_scale=0.01, fig=fig)
    assert again is fig
    # a tiny lambda selects many more components than the 12 true ones
    assert len(fig.axes[1].lines[0].get_xdata()) > 12


def test_callback_rejects_out_of_range_values():
    with pytest.raises(ModelError, match=r"q: expected an integer in \[1, 25\], got 30"):
        explore_sparse(q=30)
    with pytest.raises(ModelError, match="lam_scale: expected a positive number"):
        explore_sparse(lam_scale=0.0)
    with pytest.raises(ModelError, match="r: expected a positive noise factor"):
        explore_sparse(r=-1.0)
