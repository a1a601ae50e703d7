"""Accommodation of the wind turbine's sensor faults (windturbine-accommodation): the switch rule
and the measured effects against independent recomputations."""

from __future__ import annotations

import numpy as np
import pytest

from fdi_lib import windturbine as W
from fdi_lib.errors import ModelError
from fdi_lib.reproduce import reproduce
from fdi_lib.reproduce import windturbine_accommodation as A
from fdi_lib.systems import wind_turbine as wt


def fault(i: int) -> wt.Fault:
    return next(f for f in wt.FAULTS if f.id == i)


def test_switch_rule_needs_the_faulty_sensor_and_not_its_twin():
    iso = np.zeros((4, len(W.CANDIDATES)), dtype=bool)
    c = W.CANDIDATES.index
    iso[0, c("beta1_m1")] = True  # exactly the faulty sensor
    iso[1, [c("beta1_m1"), c("actuator1")]] = True  # plus a candidate that cannot be switched
    iso[2, [c("beta1_m1"), c("beta1_m2")]] = True  # both sensors of the blade: no switch
    np.testing.assert_array_equal(A._switchable(iso, fault(1)), [True, True, False, False])
    iso5 = np.zeros((2, len(W.CANDIDATES)), dtype=bool)
    iso5[0, [c("omega_r_m2"), c("omega_g_m2")]] = True
    iso5[1, c("omega_r_m2")] = True  # half of F5's sensors
    np.testing.assert_array_equal(A._switchable(iso5, fault(5)), [True, False])


def test_accommodation_reproduction_measures_against_the_fault_free_twin():
    r = reproduce("windturbine-accommodation", trials=2)
    h, x = r.headline, r.data["raw"]
    assert (
        h["realisations"] == 2
        and h["method"] == "first"
        and sorted(h["faults"]) == [f"F{i}" for i in A.ACCOMMODATED]
    )
    for j, fid in enumerate(A.ACCOMMODATED):
        e = h["faults"][f"F{fid}"]
        iso = x["isolation_s"][:, j]
        assert e["isolated"] == int(np.isfinite(iso).sum())
        # a realisation not switched is the faulty run itself
        np.testing.assert_array_equal(
            x["accommodated"][np.isnan(iso), j], x["faulty"][np.isnan(iso), j]
        )
        assert e["faulty"]["power_kw"] == pytest.approx(x["faulty"][:, j, 0].mean(), rel=1e-12)
    # the controller reads neither rotor-speed sensor nor omega_g,m2: F4 and F5 leave the plant
    # untouched
    for fid in ("F4", "F5"):
        assert all(v == 0.0 for v in h["faults"][fid]["faulty"].values())
    # the stuck pitch sensors move the plant, and the switch takes most of it back where it is made
    for j, fid in ((0, "F1"), (2, "F3")):
        assert h["faults"][fid]["faulty"]["pitch_deg"] > 1.0
        sw = np.isfinite(x["isolation_s"][:, j])
        assert np.all(x["accommodated"][sw, j, 1] < 0.5 * x["faulty"][sw, j, 1])
    with pytest.raises(ModelError, match="method: expected 'first' or one of"):
        A.accommodation(seed=1, trials=2, jobs=1, method="best")


def test_accommodation_chunks_change_no_bit():
    """The realisations in one chunk (:data:`~fdi_lib.reproduce.windturbine_accommodation.
    CHUNK_REALISATIONS`) give the bits of one realisation per chunk: each record is computed alone."""
    import functools

    from fdi_lib.montecarlo import run_monte_carlo

    chunk = functools.partial(A.accommodation_chunk, seed=2009, method="first")
    one = run_monte_carlo(chunk, 2, seed=2009, chunk_size=A.CHUNK_REALISATIONS)
    apart = run_monte_carlo(chunk, 2, seed=2009, chunk_size=1)
    assert one.keys() == apart.keys()
    for k in one:
        np.testing.assert_array_equal(one[k], apart[k])
