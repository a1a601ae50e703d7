"""The wind-turbine methods are records of one registry (issue 34, point 3).

A fifth method is one new :class:`fdi_lib.windturbine.Method`: registered here (a toy that compares
the two sensors of each duplicated measurement), it appears in the scoreboard's JSON, its figure and
the false-alarm study without any other edit, and the four methods' numbers do not move. The
registry that replaced the label dictionaries and the dispatch tables left the scoreboard's and the
accommodation study's ``--json`` byte-identical (``--trials 2``: SHA-256 9fc4385f... before and
after); their texts are recorded in ``tests/data/json_identity_windturbine.json``, compared by
``tests/test_json_identity.py``.
"""

from __future__ import annotations

import json

import numpy as np
import pytest
import scipy.stats

from fdi_lib import windturbine as W
from fdi_lib.errors import ModelError

pytest.importorskip("numba")

#: The redundant sensors (indices in ``W.SENSORS``): the toy method compares each pair.
PAIRS = ((0, 1), (2, 3), (4, 5), (6, 7), (8, 9))


def _pair_statistics(d: W.Design, inputs: W.MethodInputs) -> tuple[list[np.ndarray], list[float]]:
    """``|y_m1 - y_m2| / sqrt(sigma_m1^2 + sigma_m2^2)`` per pair, against the normal quantile of
    the design's per-sample level."""
    sigma = d.constants.sigma
    stats = [
        np.abs(inputs.y[..., i] - inputs.y[..., j]) / np.hypot(sigma[i], sigma[j]) for i, j in PAIRS
    ]
    h = float(scipy.stats.norm.isf(d.alpha_sample / (2 * len(PAIRS))))
    return stats, [h] * len(stats)


def _pair_diagnose(d: W.Design, inputs: W.MethodInputs) -> W.MethodOutcome:
    """Detection by :func:`_pair_statistics` with the public scoring functions; no isolation."""
    stats, thr = _pair_statistics(d, inputs)
    scored = [
        W.score_alarms(W.alarm_onsets(st > h, d.warmup), d.onset, d.warmup)
        for st, h in zip(stats, thr)
    ]
    big = np.iinfo(np.int64).max
    post = np.stack([np.where(s[2] < 0, big, s[2]) for s in scored])
    first = post.min(axis=0)
    detect = np.where(first == big, -1, first)
    B = inputs.y.shape[0]
    return W.MethodOutcome(
        false_alarm=np.any([s[1] for s in scored], axis=0),
        detect=detect,
        subsystem=np.full(B, -1),
        isolated=np.zeros((B, len(W.CANDIDATES)), dtype=bool),
        isolate_step=np.full(B, -1),
        peak=np.max([st[:, d.onset :].max(axis=-1) / h for st, h in zip(stats, thr)], axis=0),
    )


def _names_nothing(expected: frozenset[str]) -> bool:
    return False


TOY = W.Method(
    name="pairs",
    label="sensor pairs",
    diagnose=_pair_diagnose,
    alarms=W.statistic_alarms(_pair_statistics),
    tests=tuple(f"{W.SENSORS[i]} - {W.SENSORS[j]}" for i, j in PAIRS),
    nameable=_names_nothing,
    style=W.PlotStyle("C4", "s"),
)


def test_the_registry_is_one_record_per_method():
    assert list(W.METHODS) == ["zb2014", "zhang2021", "bz", "rosa2013"]
    for name, m in W.METHODS.items():
        assert isinstance(m, W.Method) and m.name == name
    labels = [m.label for m in W.METHODS.values()]
    colours = [m.style.color for m in W.METHODS.values()]
    assert len(set(labels)) == len(labels) and len(set(colours)) == len(colours)
    assert [n for n, m in W.METHODS.items() if m.bounded] == ["rosa2013"]
    with pytest.raises(AttributeError):
        W.METHODS["zb2014"].label = "x"  # frozen
    on = {name: m.tests_on("drive_train") for name, m in W.METHODS.items()}
    assert on == {
        "zb2014": ("drive_train",),
        "zhang2021": ("drive_train",),
        "bz": ("drive_train parametric", "drive_train energy"),
        "rosa2013": (),  # its bank reads every subsystem
    }
    assert W.METHODS["bz"].tests_on("blade2") == ("blade2 parametric", "blade2 energy")
    with pytest.raises(ModelError, match="subsystem: expected one of"):
        W.METHODS["zb2014"].tests_on("drive")


@pytest.fixture(scope="module")
def plain():
    """The scoreboard's JSON at two realisations, the four methods."""
    from fdi_lib.reproduce import reproduce

    return reproduce("windturbine-scoreboard", trials=2).to_json()


def test_a_fifth_method_is_one_record_and_moves_no_other_number(monkeypatch, plain):
    """Registered, the toy is in every table of the scoreboard, its figure and its false alarms;
    the four methods' entries are those of the run without it."""
    from fdi_lib.reproduce import reproduce

    monkeypatch.setitem(W.METHODS, TOY.name, TOY)
    r = reproduce("windturbine-scoreboard", trials=2)
    h = json.loads(r.to_json())["headline"]
    base = json.loads(plain)["headline"]
    # the fastest method and the best upper bound are the only keys that read across methods:
    # brute force over the five
    for fid, fast in h.pop("fastest_method").items():
        full = {
            m: v["detection_time_mean_s"]
            for m, v in h["faults"][fid]["methods"].items()
            if v["detected"] == 2
        }
        assert fast is None if not full else fast["detection_time_mean_s"] == min(full.values())
    for fid, e in h["faults"].items():
        assert list(e["methods"]) == [*W.METHODS], fid
        v = e["methods"].pop("pairs")
        assert v["isolation_correct"] == 0.0 and v["not_isolated"] == v["detected"], fid
        if fid == "F1":  # a pitch sensor stuck 5 deg away: the pair of blade 1 disagrees at once
            assert v["detected"] == 2 and v["detection_time_mean_s"] < 0.1
        assert e == base["faults"][fid], fid
    for key in ("false_alarms", "requirement_met"):
        assert list(h[key]) == [*W.METHODS], key
        h[key].pop("pairs")
    del h["best_detection_upper_s"], base["fastest_method"], base["best_detection_upper_s"]
    assert h == base
    from fdi_lib.reproduce.views.windturbine import plot_scoreboard

    fig = plot_scoreboard(r)
    legend = [t.get_text() for t in fig.legends[0].get_texts()]
    assert legend == [m.label for m in W.METHODS.values()] + ["required"]
    import matplotlib.pyplot as plt

    plt.close(fig)
