"""References of the rosa2013/svo exercises (instructor only)."""

from __future__ import annotations

import numpy as np

from fdi_lib.exercises._reference import Mistake, Reference


def _svo1_answer(d: dict, disturbance: bool = True, strip: bool = True) -> np.ndarray:
    from fdi_lib.sets import Polytope

    P = Polytope.box(d["X_lower"], d["X_upper"]).linear_map(d["A"])
    if disturbance:
        P = P.minkowski_box(d["L"])
    if strip:
        P = P.intersect_strip(d["C"], d["y_next"], d["noise"])
    lo, hi = P.bounding_box()
    return np.array([lo[0], hi[0], lo[1], hi[1]])


def _svo1_intervals(d: dict) -> np.ndarray:
    """Box arithmetic: the prediction's bounding box, then the strip cut on x1 alone."""
    from fdi_lib.sets import Polytope

    lo, hi = (
        Polytope.box(d["X_lower"], d["X_upper"])
        .linear_map(d["A"])
        .minkowski_box(d["L"])
        .bounding_box()
    )
    y, nb = float(d["y_next"][0]), d["noise"]
    return np.array([max(lo[0], y - nb), min(hi[0], y + nb), lo[1], hi[1]])


def _svo2_answer(d: dict, strip: bool = True) -> np.ndarray:
    from fdi_lib.sets import Polytope
    from fdi_lib.sets.svo import SetValuedObserver, SVOModel

    model = SVOModel(
        A=[[d["A"]]], A_unc=[[[d["A_unc"]]]], C=[[1.0]], noise=d["noise"] if strip else 1e6
    )
    svo = SetValuedObserver(Polytope.box([d["x_lower"]], [d["x_upper"]]), method="exact")
    svo.start(model, np.array([d["y0"]]))
    X = svo.update(model, np.zeros(0), np.array([d["y_next"]]))
    lo, hi = X.bounding_box()
    return np.array([lo[0], hi[0]])


def _svo3_answer(d: dict, kind: str) -> float:
    from fdi_lib.sets import Polytope
    from fdi_lib.sets.polytope import convex_hull

    sq = Polytope.box(d["square_lower"], d["square_upper"])
    P, M = sq.linear_map(d["A_plus"]), sq.linear_map(d["A_minus"])
    hull = convex_hull([P, M]).volume()
    union = P.volume() + M.volume() - P.intersect(M).volume()
    return {"gap": hull - union, "hull": hull, "no_overlap": hull - P.volume() - M.volume()}[kind]


def _svo4_answer(d: dict, disturbance: bool = True, noise: bool = True) -> float:
    from fdi_lib.sets import Polytope

    P = Polytope.box([d["x_lower"]], [d["x_upper"]]).linear_map([[d["A"]]])
    if disturbance:
        P = P.minkowski_box([[d["L"]]])
    return float(P.support([[1.0]])[0] + (d["noise"] if noise else 0.0))


def _svo5_answer(d: dict) -> int:
    from fdi_lib.sets.svo import SVOModel

    model = SVOModel(A=np.eye(2), C=np.eye(2), A_unc=np.zeros((d["n_A"], 2, 2)))
    return d["T"] * int(model.vertex_matrices().shape[0] ** d["N"])


REFERENCES = {
    "svo-1": Reference(
        _svo1_answer,
        (
            Mistake(
                lambda d: _svo1_answer(d, disturbance=False),
                "The disturbance is missing: add the Minkowski sum with L [-1, 1]^2.",
            ),
            Mistake(
                lambda d: _svo1_answer(d, strip=False),
                "The measurement is missing: intersect with the strip |y - C x| <= nbar.",
            ),
            Mistake(
                _svo1_intervals,
                "The bounds of x2 ignore the measurement: box (interval) arithmetic loses the coupling "
                "between the states that the polytope A X keeps. Intersect the strip with the "
                "polytope itself, then take its bounding box.",
            ),
        ),
    ),
    "svo-2": Reference(
        _svo2_answer,
        (
            Mistake(
                lambda d: _svo2_answer(d, strip=False),
                "This is the hull of the vertex predictions alone: intersect it with the measurement "
                "strip.",
            ),
        ),
    ),
    "svo-3": Reference(
        lambda d: _svo3_answer(d, "gap"),
        (
            Mistake(
                lambda d: _svo3_answer(d, "hull"),
                "This is the area of the hull: subtract the area of the union.",
            ),
            Mistake(
                lambda d: _svo3_answer(d, "no_overlap"),
                "The two sets overlap: the area of the union counts the overlap once.",
            ),
        ),
    ),
    "svo-4": Reference(
        _svo4_answer,
        (
            Mistake(
                lambda d: _svo4_answer(d, disturbance=False),
                "The disturbance L d(k) widens the prediction too.",
            ),
            Mistake(
                lambda d: _svo4_answer(d, noise=False),
                "The noise bound widens the measurement strip too.",
            ),
        ),
    ),
    "svo-5": Reference(
        _svo5_answer,
        (
            Mistake(
                lambda d: d["T"] * d["N"] * 2 ** d["n_A"],
                "The parameters may sit at a different vertex at each "
                "of the N steps: the counts multiply.",
            ),
        ),
    ),
}
