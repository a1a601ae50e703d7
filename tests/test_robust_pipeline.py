"""Identities of the gas-pipeline Monte Carlo headlines (issue 15).

tests/reproduce/test_zb2014_pipeline.py checks ``n + missed <= trials``, which holds for any
counts; here every run is accounted for exactly, and each rate is its count over its ``n``.
"""

import pytest

from fdi_lib.reproduce import reproduce
from fdi_lib.reproduce import zb2014_pipeline as zp

TRIALS = 30


@pytest.fixture(scope="module")
def fig7_fig8():
    zp._MC_CACHE.clear()
    out = reproduce("zb2014-fig7", trials=TRIALS), reproduce("zb2014-fig8", trials=TRIALS)
    zp._MC_CACHE.clear()
    return out


def test_every_run_is_a_false_alarm_a_miss_or_a_detection(fig7_fig8):
    r7, r8 = fig7_fig8
    h7, h8 = r7.headline, r8.headline
    detected = sum(h8["type1_rate"][f]["n"] for f in ("1", "2"))
    missed = sum(h7["missed"][f] for f in ("1", "2"))
    assert detected + missed + h7["false_alarms"] == 2 * TRIALS
    assert (
        h7["false_alarm_rate"]["count"] == h7["false_alarms"]
        and h7["false_alarm_rate"]["n"] == 2 * TRIALS
    )


def test_rates_are_counts_over_n_inside_their_intervals(fig7_fig8):
    _, r8 = fig7_fig8
    for key in ("type1_rate", "type2_rate"):
        for f in ("1", "2"):
            d = r8.headline[key][f]
            assert d["n"] == r8.headline["type1_rate"][f]["n"]  # same runs for both tests
            assert d["rate"] == pytest.approx(d["count"] / d["n"], abs=1e-15)
            lo, hi = d["ci95"]
            assert lo <= d["rate"] <= hi and hi - lo < 0.5
