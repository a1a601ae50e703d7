"""The SVO widget callback of the Rosa & Silvestre (2013) chapter."""

from __future__ import annotations

import matplotlib

matplotlib.use("Agg")

import pytest

from fdi_lib.errors import ModelError
from fdi_lib.widgets.rosa2013 import explore_svo


def test_explore_svo_draws_and_reuses_the_figure():
    fig = explore_svo()
    assert len(fig.axes) == 2
    # the template rule's mean width at N = 1 against the exact rule's (Prop. 2 on every frame:
    # test_explorable_claims.test_svo_statements)
    assert fig.axes[1].get_title().startswith("N = 1: mean width ")
    fig2 = explore_svo(delta_bound=0.1, horizon=2, noise=0.3, fig=fig)
    assert fig2 is fig and len(fig.axes) == 2


@pytest.mark.parametrize(
    "kw,msg",
    [({"delta_bound": 2.0}, "delta_bound"), ({"noise": 0.0}, "noise"), ({"horizon": 7}, "horizon")],
)
def test_explore_svo_rejects_bad_values(kw, msg):
    with pytest.raises(ModelError, match=msg):
        explore_svo(**kw)
