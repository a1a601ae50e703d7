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


def test_template_run_cache_is_a_fresh_run_and_read_only():
    """The cached template run that the frames and horizon_study share: the bits of a fresh
    run_svo, and a caller cannot change its arrays."""
    from fdi_lib.reproduce.rosa2013 import toy_prior
    from fdi_lib.sets.svo import run_svo
    from fdi_lib.widgets.rosa2013 import _example, _template_run

    model, x, u, y, *_ = _example(0.4, 0.5, 0, 25)
    fresh = run_svo(model, u, y, toy_prior(), N=3, method="template", keep_sets=True)
    cached = _template_run(0.4, 0.5, 0, 25, 3)
    assert cached is _template_run(0.4, 0.5, 0, 25, 3)
    assert cached.empty_at == fresh.empty_at
    for name in ("lower", "upper", "n_facets", "n_vertices"):
        a = getattr(cached, name)
        assert a.tobytes() == getattr(fresh, name).tobytes()
        with pytest.raises(ValueError):
            a[0] = 0
    assert len(cached.sets) == len(fresh.sets) == len(x)
    for S, R in zip(cached.sets, fresh.sets):
        assert S.M.tobytes() == R.M.tobytes() and S.m.tobytes() == R.m.tobytes()
