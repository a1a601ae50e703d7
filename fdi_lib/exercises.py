"""The book's exercises: a registry, the data each one gives, and a checker students can call.

Every exercise of the book has an entry here (:data:`EXERCISES`): its identifier (``"glr-3"``),
the chapter that states it, a title, a difficulty (``"warm-up"``, ``"core"`` or
``"challenge"``), an estimated time, and, for a *checkable* exercise, what to hand in and the
tolerance used. The chapters call

>>> from fdi_lib.exercises import check, exercise_data
>>> data = exercise_data("glr-1")       # the numbers the exercise works on
>>> check("glr-1", None)                # a starter cell: nothing computed yet
glr-1: no answer yet. Replace `answer = None` by the 1 - alpha quantile of chi2(m) (a number).

:func:`check` compares an answer with a reference computed here by library code (seeded, never
typed) and explains what is wrong without revealing the answer: the shape, a transpose, the
sign, the order of magnitude, which entries are off, or a known mistake of that exercise (wrong
degrees of freedom, off-by-one window, missing transpose, ...). An unknown identifier raises
:class:`UnknownExerciseError`, an answer that is not a finite real number or array raises
:class:`AnswerError`.

:func:`strip_solutions` removes the gated solution blocks of a chapter (the student edition,
``make student``); :func:`exercise_table` is the table of the instructor's page.
"""

from __future__ import annotations

import difflib
import functools
import math
import re
from dataclasses import dataclass, field
from typing import Any, Callable

import numpy as np

from fdi_lib.errors import FDIError, ModelError

__all__ = ["Exercise", "Mistake", "CheckResult", "ExerciseData", "EXERCISES", "CHAPTERS",
           "DIFFICULTIES", "UnknownExerciseError", "AnswerError", "get_exercise", "exercises",
           "exercise_data", "check", "exercise_table", "counts_table", "COURSE_PLAN", "plan_table",
           "strip_solutions", "ChapterExercise",
           "parse_chapter", "exercises_section", "code_cells", "words", "solution_fingerprints"]

#: Difficulty labels, in increasing order.
DIFFICULTIES = ("warm-up", "core", "challenge")

#: Chapters with exercises: document path under ``book/`` -> title (as in the table of contents).
CHAPTERS = {
    "zb2014/signature": "Fault signature on the Kalman innovation",
    "zb2014/glr": "GLR and minmax tests",
    "zb2014/pipeline": "Leak detection on a gas pipeline",
    "zhang2021/sparse": "Sparse fault isolation",
    "bz/parametric-nonparametric": "Parametric and non-parametric faults",
    "rosa2013/svo": "Set-valued observers",
}


class UnknownExerciseError(FDIError, KeyError):
    """No exercise is registered under the requested identifier."""

    def __str__(self) -> str:  # KeyError quotes its message otherwise
        return str(self.args[0]) if self.args else ""


class AnswerError(FDIError, ValueError):
    """An answer cannot be compared with anything: not a real number or array, or not finite."""


# ----------------------------------------------------------------------------- registry types
@dataclass(frozen=True)
class Mistake:
    """A typical wrong answer of one exercise and the hint shown when a student gives it.

    Attributes
    ----------
    answer : callable
        ``data -> value``: the wrong answer, computed from the exercise data like the reference.
    hint : str
        What went wrong, without the correct value.
    """

    answer: Callable[[dict], Any]
    hint: str


@dataclass(frozen=True)
class Exercise:
    """One exercise of the book.

    Attributes
    ----------
    id : str
        Identifier, ``"<chapter prefix>-<number>"``; the exercise's label in the chapter is
        ``"ex-" + id``.
    chapter : str
        Document path under ``book/`` (a key of :data:`CHAPTERS`).
    title : str
        Title printed in the chapter.
    difficulty : str
        One of :data:`DIFFICULTIES`.
    minutes : int
        Estimated working time for a student who has read the chapter.
    answer : str or None
        What :func:`check` expects (e.g. ``"array of shape (2,): [eps_0, eps_1]"``); ``None``
        for an exercise whose answer is an explanation (not checkable).
    rtol, atol : float
        Tolerance of :func:`check`: ``|answer - reference| <= atol + rtol |reference|`` entrywise.
    """

    id: str
    chapter: str
    title: str
    difficulty: str
    minutes: int
    answer: str | None = None
    rtol: float = 1e-6
    atol: float = 0.0
    data: Callable[[], dict] | None = field(default=None, repr=False, compare=False)
    reference: Callable[[dict], Any] | None = field(default=None, repr=False, compare=False)
    mistakes: tuple[Mistake, ...] = field(default=(), repr=False, compare=False)

    @property
    def checkable(self) -> bool:
        """Whether :func:`check` can verify an answer."""
        return self.reference is not None

    @property
    def integer(self) -> bool:
        """Whether the answer is a count (integers): tolerance ``rtol = 0, atol = 0.5``."""
        return self.rtol == 0 and self.atol == 0.5

    @property
    def tolerance(self) -> str:
        """The tolerance in words."""
        if self.rtol == 0 and self.atol == 0:
            return "exact"
        if self.integer:
            return "exact (integers)"
        parts = []
        if self.rtol:
            parts.append(f"relative {self.rtol:g}")
        if self.atol:
            parts.append(f"absolute {self.atol:g}")
        return " + ".join(parts)


class ExerciseData(dict):
    """The data of an exercise: a dict whose display lists ``name = value`` lines."""

    def __repr__(self) -> str:
        lines = []
        for key, val in self.items():
            if hasattr(val, "n_steps"):  # a model: its dimensions, not its matrices
                text = f"{type(val).__name__}(n={val.n}, p={val.p}, N={val.n_steps})"
            elif isinstance(val, np.ndarray):
                text = np.array2string(val, precision=6, suppress_small=False, separator=", ")
                text = text.replace("\n", "\n" + " " * (len(key) + 3))
            else:
                text = repr(val)
            lines.append(f"{key} = {text}")
        return "\n".join(lines)


@dataclass(frozen=True)
class CheckResult:
    """Outcome of :func:`check`; true when the answer is accepted, displayed as its message."""

    exercise_id: str
    passed: bool
    message: str

    def __bool__(self) -> bool:
        return self.passed

    def __repr__(self) -> str:
        return self.message

    __str__ = __repr__


# ----------------------------------------------------------------------------- exercise data
def _ltv(**kw: Any):
    from fdi_lib.models import ltv_model

    return ltv_model(**kw)


def _unstable(n_steps: int):
    from fdi_lib.systems import zb2014_unstable as ex

    return ex.unstable_model(n_steps)


def _gains(model):
    from fdi_lib.filters import kalman_gains

    return kalman_gains(model)


def _signature(model, **profile: Any) -> np.ndarray:
    from fdi_lib.models import fault_profile
    from fdi_lib.signatures import fault_signature

    return fault_signature(model, _gains(model), fault_profile(model, **profile))


# -- Fault signature on the Kalman innovation (zb2014/signature)
def _sig1_data() -> dict:
    from fdi_lib.systems import zb2014_unstable as ex

    return {"F": ex.F.copy(), "H": ex.H.copy(), "Q": ex.Q.copy(), "R": ex.R.copy(), "P0": ex.Q.copy(),
            "x0": np.array([0.05, 0.1]), "y": np.array([0.12, 0.31])}


def _sig1_model(d: dict):
    return _ltv(F=d["F"], H=d["H"], Q=d["Q"], R=d["R"], P0=d["P0"], x0=d["x0"], n_steps=2)


def _sig1_ref(d: dict) -> np.ndarray:
    from fdi_lib.filters import kalman_filter

    return kalman_filter(_sig1_model(d), d["y"][:, None]).innovations[:, 0]


def _sig1_no_f(d: dict) -> np.ndarray:
    g = _gains(_sig1_model(d))
    eps0 = d["y"][0] - d["H"] @ d["x0"]
    x1 = d["x0"] + g.K[0] @ eps0            # the update, but no propagation by F_0
    return np.array([eps0[0], (d["y"][1] - d["H"] @ x1)[0]])


def _sig1_prior_gain(d: dict) -> np.ndarray:
    # gain from P0 with F_0 K_0 replaced by K_0 in the predictor
    g = _gains(_sig1_model(d))
    eps0 = d["y"][0] - d["H"] @ d["x0"]
    x1 = d["F"] @ d["x0"] + g.K[0] @ eps0
    return np.array([eps0[0], (d["y"][1] - d["H"] @ x1)[0]])


def _sig2_data() -> dict:
    m = _unstable(4)
    return {"model": m, "Psi": np.eye(2), "k": 3}


def _sig2_ref(d: dict) -> np.ndarray:
    return _signature(d["model"], Psi=d["Psi"]).Gamma[d["k"]]


def _sig2_open_loop(d: dict) -> np.ndarray:
    F = d["model"].F[0]
    G = np.zeros((2, 2))
    for _ in range(d["k"]):
        G = F @ G + d["Psi"]
    return G


def _sig3_data() -> dict:
    return {"model": _unstable(5), "Phi": np.ones((1, 1)), "k_max": 4}


def _sig3_ref(d: dict) -> np.ndarray:
    return _signature(d["model"], Phi=d["Phi"]).on_innovation[: d["k_max"] + 1, 0, 0]


def _sig3_no_fk(d: dict) -> np.ndarray:
    return np.ones(d["k_max"] + 1)


def _sig4_data() -> dict:
    return {"model": _unstable(500), "Psi": np.eye(2)}


def _sig4_ref(d: dict) -> np.ndarray:
    return _signature(d["model"], Psi=d["Psi"]).on_innovation[-1, 0]


def _sig4_open_loop(d: dict) -> np.ndarray:
    m = d["model"]
    return (m.H[0] @ np.linalg.inv(np.eye(2) - m.F[0]))[0]


def _sig5_data() -> dict:
    return {"model": _unstable(500), "onset": 101, "k_first": 300, "k_last": 499}


def _sig5_slope(d: dict, log: Callable[[np.ndarray], np.ndarray]) -> float:
    from fdi_lib.signatures import willsky_jones

    m = d["model"]
    alpha = willsky_jones(m, _gains(m), d["onset"]).alpha
    k = np.arange(d["k_first"], d["k_last"] + 1)
    norms = np.linalg.norm(alpha[k], ord=2, axis=(1, 2))
    return float(np.polyfit(k, log(norms), 1)[0])


# -- GLR and minmax tests (zb2014/glr)
def _glr1_data() -> dict:
    return {"alpha": 0.01, "m": 2}


def _chi2_ppf(q: float, dof: float) -> float:
    import scipy.stats

    return float(scipy.stats.chi2.ppf(q, dof))


def _glr2_data() -> dict:
    return {"C": np.array([[4.0, 1.0], [1.0, 2.0]]), "d": np.array([2.0, -1.0])}


def _glr2_ref(d: dict) -> np.ndarray:
    from fdi_lib.glr import quadratic_form

    stat, theta = quadratic_form(d["C"], d["d"])
    return np.concatenate([[stat], theta])


def _glr2_no_inverse(d: dict) -> np.ndarray:
    return np.concatenate([[d["d"] @ d["C"] @ d["d"]], d["C"] @ d["d"]])


def _glr3_data() -> dict:
    from fdi_lib.systems.random_ltv import random_ltv_model

    rng = np.random.default_rng(2015)
    model = random_ltv_model(rng, n=3, p=1, n_steps=60)
    return {"model": model, "Psi": rng.standard_normal((60, 3, 2)), "theta": np.array([0.5, 0.0]),
            "alpha": 0.05}


def _glr3_answer(d: dict, dof: int) -> np.ndarray:
    import scipy.stats

    from fdi_lib.glr import glr_known_profile

    m = d["model"]
    g = _gains(m)
    S = _signature(m, Psi=d["Psi"]).on_innovation
    C = glr_known_profile(np.zeros((m.n_steps, m.p)), g, S).C[-1]
    lam = float(d["theta"] @ C @ d["theta"])
    threshold = _chi2_ppf(1 - d["alpha"], dof)
    return np.array([lam, float(scipy.stats.ncx2.sf(threshold, dof, lam))])


def _glr4_data() -> dict:
    rng = np.random.default_rng(41)
    B = rng.standard_normal((3, 3))
    return {"F": B @ B.T + np.eye(3), "zeta": 2.0 * rng.standard_normal(3), "a": [0]}


def _glr4_ref(d: dict) -> float:
    from fdi_lib.isolation import minmax_statistic

    return float(minmax_statistic(d["F"], d["zeta"], d["a"]))


def _glr5_data() -> dict:
    return {"k": 150, "w": 100, "s": 2}


def _glr5_count(d: dict, extra: int) -> int:
    # eq. (37): candidate onsets k - w + 1 <= r <= k - s
    return int(np.arange(d["k"] - d["w"] + 1, d["k"] - d["s"] + 1 + extra).size)


# -- Leak detection on a gas pipeline (zb2014/pipeline)
def _pipe1_data() -> dict:
    return {"alpha": 0.01, "dim_theta_a": 1}


def _pipe2_data() -> dict:
    from fdi_lib.systems import gas_pipeline as gp

    mats = gp.pipeline_matrices("designed")
    return {"F": mats.F0.copy(), "H": mats.H0.copy(), "G0": mats.G0.copy(), "Gp": mats.Gp.copy()}


def _pipe2_ref(d: dict) -> np.ndarray:
    from fdi_lib.systems import gas_pipeline as gp

    mats = gp.pipeline_matrices("designed")
    return np.array([mats.J0[0, 0], mats.Jp[0, 0]])


def _pipe3_data() -> dict:
    from fdi_lib.reproduce import zb2014_pipeline as zp

    st = zp.pipeline_setup()
    return {"signature": st.known_signature, "Sigma": st.gains.Sigma, "first": 300, "last": 349}


def _pipe3_answer(d: dict, extra: int) -> float:
    S = d["signature"][d["first"]: d["last"] + 1 + extra]
    W = np.linalg.inv(d["Sigma"][d["first"]: d["last"] + 1 + extra])
    F = np.einsum("kpi,kpq,kqj->ij", S, W, S)
    return float(1.0 - F[0, 1] ** 2 / (F[0, 0] * F[1, 1]))


def _pipe4_data() -> dict:
    from fdi_lib.reproduce import zb2014_pipeline as zp
    from fdi_lib.systems import gas_pipeline as gp

    st = zp.pipeline_setup()
    return {"signature": st.known_signature, "Sigma": st.gains.Sigma, "start": zp.FAULT_ONSET,
            "stop": gp.N_STEPS, "theta": zp.fault_theta(2), "threshold": zp.MINMAX_THRESHOLD}


def _pipe4_ref(d: dict) -> np.ndarray:
    from fdi_lib.reproduce import zb2014_pipeline as zp

    pw = zp.known_onset_isolation_power(start=d["start"], stop=d["stop"],
                                        alpha_threshold=d["threshold"])["2"]
    return np.array([pw["noncentrality"], pw["power"]])


def _pipe4_no_rejection(d: dict) -> np.ndarray:
    import scipy.stats

    S = d["signature"][d["start"]: d["stop"]]
    W = np.linalg.inv(d["Sigma"][d["start"]: d["stop"]])
    F = np.einsum("kpi,kpq,kqj->ij", S, W, S)
    lam = float(d["theta"][1] ** 2 * F[1, 1])
    return np.array([lam, float(scipy.stats.ncx2.sf(d["threshold"], 1, lam))])


def _pipe5_data() -> dict:
    return {"false_alarms": 7, "runs": 2000}


def _pipe5_ref(d: dict) -> np.ndarray:
    from fdi_lib.montecarlo import binomial_ci

    return np.array(binomial_ci(d["false_alarms"], d["runs"]))


def _pipe5_wald(d: dict) -> np.ndarray:
    p = d["false_alarms"] / d["runs"]
    h = 1.959963984540054 * math.sqrt(p * (1 - p) / d["runs"])
    return np.array([p - h, p + h])


# -- Sparse fault isolation (zhang2021/sparse)
def _sparse1_data() -> dict:
    return {"m": 50, "q_max": 5}


def _n_supports(d: dict, sizes: range) -> int:
    import scipy.special

    return int(sum(scipy.special.comb(d["m"], j, exact=True) for j in sizes))


def _sparse2_data() -> dict:
    return {"F": np.array([[0.8, 0.2], [0.0, 0.6]]), "H": np.eye(2), "Q": 0.1 * np.eye(2),
            "R": 0.2 * np.eye(2), "P0": np.eye(2), "E": np.array([[1.0], [0.5]]), "k": 1}


def _sparse2_gains(d: dict):
    from fdi_lib.kitanidis import kitanidis_gains

    m = _ltv(F=d["F"], H=d["H"], Q=d["Q"], R=d["R"], P0=d["P0"], n_steps=d["k"] + 1)
    return kitanidis_gains(m, d["E"])


def _sparse_regression() -> dict:
    rng = np.random.default_rng(2021)
    N, p, m = 40, 2, 8
    X = rng.standard_normal((N * p, m))
    theta = np.zeros(m)
    theta[[2, 5]] = [1.0, -0.7]
    y = X @ theta + 0.5 * rng.standard_normal(N * p)
    return {"X": X, "y": y, "n_samples": N}


def _sparse3_ref(d: dict) -> float:
    from fdi_lib.sparse import lasso_path

    return float(lasso_path(d["X"], d["y"], n_samples=d["n_samples"]).lambdas[0])


def _sparse4_data() -> dict:
    from fdi_lib.sparse import lasso_path

    d = _sparse_regression()
    path = lasso_path(d["X"], d["y"], n_samples=d["n_samples"])
    return {"lambdas": path.lambdas, "sizes": path.support_sizes(), "lambda_ratio": 1e-4,
            "max_size": d["X"].shape[1] // 2}


def _sparse4_path(d: dict):
    from fdi_lib.sparse import lasso_path

    r = _sparse_regression()
    return lasso_path(r["X"], r["y"], n_samples=r["n_samples"])


def _sparse4_answer(d: dict) -> float:
    from fdi_lib.sparse import flat_range

    return flat_range(_sparse4_path(d), lambda_ratio=d["lambda_ratio"], max_size=d["max_size"]).middle


def _sparse4_arithmetic(d: dict) -> float:
    from fdi_lib.sparse import flat_range

    fr = flat_range(_sparse4_path(d), lambda_ratio=d["lambda_ratio"], max_size=d["max_size"])
    return 0.5 * (fr.low + fr.high)


def _sparse5_ref(d: dict) -> np.ndarray:
    from fdi_lib.sparse import diagnose

    return diagnose(d["X"], d["y"], n_samples=d["n_samples"]).theta_ls


def _sparse5_lasso(d: dict) -> np.ndarray:
    from fdi_lib.sparse import diagnose

    return diagnose(d["X"], d["y"], n_samples=d["n_samples"]).theta_lasso


# -- Parametric and non-parametric faults (bz/parametric-nonparametric)
def _bz1_data() -> dict:
    return {"M": np.array([[1.0, 0.5], [0.0, 2.0]]), "Sigma": 0.5 * np.eye(2), "P0": np.eye(2),
            "lam": 0.9, "eps": np.array([0.3, -0.4])}


def _bz1_answer(d: dict, lam: float) -> np.ndarray:
    from fdi_lib.rls import rls_track

    return rls_track(d["eps"][None], d["M"][None], d["Sigma"][None], lam=lam, P0=d["P0"]).theta_hat[0]


def _bz2_data() -> dict:
    from fdi_lib.systems import bz_example as ex

    return {"model": ex.bz_model(200), "E": ex.E.copy(), "impulse_at": 100, "level": 1e-6}


def _bz2_ref(d: dict) -> np.ndarray:
    from fdi_lib.nonparametric import kitanidis_predictor_gains, nonparametric_signature

    m = d["model"]
    f = np.zeros((m.n_steps, 1))
    f[d["impulse_at"]] = 1.0
    out = []
    for g in (kitanidis_predictor_gains(m, d["E"]), _gains(m)):
        z = nonparametric_signature(m, g, d["E"], f)
        out.append(int(np.count_nonzero(np.abs(z).max(axis=1) > d["level"])))
    return np.array(out)


def _bz_gains(d: dict):
    from fdi_lib.kitanidis import kitanidis_gains

    return kitanidis_gains(d["model"], d["E"])


def _bz3_data() -> dict:
    from fdi_lib.systems import bz_example as ex

    m = ex.bz_model(20)
    kg = _bz_gains({"model": m, "E": ex.E})
    k = 10
    return {"Sigma": kg.Sigma[k], "HE": m.H[k] @ ex.E, "eps": np.array([0.05, -0.02, 0.04]),
            "model": m, "E": ex.E.copy(), "k": k}


def _bz3_ref(d: dict) -> float:
    from fdi_lib.nonparametric import rejection_projection

    T = rejection_projection(d["model"], _bz_gains(d))[d["k"]]
    return float(np.sum((T @ d["eps"]) ** 2))


def _bz3_unwhitened(d: dict) -> float:
    import scipy.linalg

    Nk = scipy.linalg.null_space(d["HE"].T)
    return float(np.sum((Nk.T @ d["eps"]) ** 2))


def _bz4_data() -> dict:
    from fdi_lib.systems import bz_example as ex

    return {"model": ex.bz_model(20), "E": ex.E.copy(), "k": 10}


def _bz4_ref(d: dict) -> np.ndarray:
    from fdi_lib.nonparametric import kitanidis_lag_covariance

    return kitanidis_lag_covariance(d["model"], _bz_gains(d), 1)[d["k"]]


def _bz5_data() -> dict:
    return {"window": 20, "p_reduced": 2, "alpha": 1e-4}


def _bz5_ref(d: dict) -> float:
    from fdi_lib.nonparametric import energy_threshold

    return energy_threshold(d["window"], d["p_reduced"], d["alpha"])


# -- Set-valued observers (rosa2013/svo)
def _svo1_data() -> dict:
    return {"X_lower": np.array([-1.0, -1.0]), "X_upper": np.array([1.0, 1.0]),
            "A": np.array([[0.9, 0.5], [0.0, 0.8]]), "L": 0.1 * np.eye(2), "C": np.array([[1.0, 0.0]]),
            "noise": 0.1, "y_next": np.array([1.2])}


def _svo1_answer(d: dict, disturbance: bool = True, strip: bool = True) -> np.ndarray:
    from fdi_lib.sets import Polytope

    P = Polytope.box(d["X_lower"], d["X_upper"]).linear_map(d["A"])
    if disturbance:
        P = P.minkowski_box(d["L"])
    if strip:
        P = P.intersect_strip(d["C"], d["y_next"], d["noise"])
    lo, hi = P.bounding_box()
    return np.array([lo[0], hi[0], lo[1], hi[1]])


def _svo2_data() -> dict:
    return {"x_lower": 0.99, "x_upper": 1.01, "A": 1.0, "A_unc": 0.5, "noise": 0.1, "y0": 1.0,
            "y_next": 1.3}


def _svo2_answer(d: dict, strip: bool = True) -> np.ndarray:
    from fdi_lib.sets import Polytope
    from fdi_lib.sets.svo import SetValuedObserver, SVOModel

    model = SVOModel(A=[[d["A"]]], A_unc=[[[d["A_unc"]]]], C=[[1.0]], noise=d["noise"] if strip else 1e6)
    svo = SetValuedObserver(Polytope.box([d["x_lower"]], [d["x_upper"]]), method="exact")
    svo.start(model, np.array([d["y0"]]))
    X = svo.update(model, np.zeros(0), np.array([d["y_next"]]))
    lo, hi = X.bounding_box()
    return np.array([lo[0], hi[0]])


def _svo3_data() -> dict:
    return {"square_lower": np.array([-1.0, -1.0]), "square_upper": np.array([1.0, 1.0]),
            "A_plus": np.array([[1.0, 0.0], [0.5, 1.0]]), "A_minus": np.array([[1.0, 0.0], [-0.5, 1.0]])}


def _svo3_sets(d: dict):
    from fdi_lib.sets import Polytope

    sq = Polytope.box(d["square_lower"], d["square_upper"])
    return sq.linear_map(d["A_plus"]), sq.linear_map(d["A_minus"])


def _svo3_answer(d: dict, kind: str) -> float:
    from fdi_lib.sets.polytope import convex_hull

    P, M = _svo3_sets(d)
    hull = convex_hull([P, M]).volume()
    union = P.volume() + M.volume() - P.intersect(M).volume()
    return {"gap": hull - union, "hull": hull, "no_overlap": hull - P.volume() - M.volume()}[kind]


def _svo4_data() -> dict:
    return {"x_lower": -0.2, "x_upper": 0.2, "A": 0.9, "L": 0.05, "noise": 0.1}


def _svo4_answer(d: dict, disturbance: bool = True, noise: bool = True) -> float:
    from fdi_lib.sets import Polytope

    P = Polytope.box([d["x_lower"]], [d["x_upper"]]).linear_map([[d["A"]]])
    if disturbance:
        P = P.minkowski_box([[d["L"]]])
    return float(P.support([[1.0]])[0] + (d["noise"] if noise else 0.0))


def _svo5_data() -> dict:
    return {"N": 3, "n_A": 2}


def _svo5_answer(d: dict) -> int:
    from fdi_lib.sets.svo import SVOModel

    model = SVOModel(A=np.eye(2), C=np.eye(2), A_unc=np.zeros((d["n_A"], 2, 2)))
    return int(model.vertex_matrices().shape[0] ** d["N"])


# ----------------------------------------------------------------------------- the registry
def _ex(id: str, chapter: str, title: str, difficulty: str, minutes: int, **kw: Any) -> Exercise:
    return Exercise(id=id, chapter=chapter, title=title, difficulty=difficulty, minutes=minutes, **kw)


_SIG, _GLR, _PIPE = "zb2014/signature", "zb2014/glr", "zb2014/pipeline"
_SPARSE, _BZ, _SVO = "zhang2021/sparse", "bz/parametric-nonparametric", "rosa2013/svo"
_DOF_HINT = "This is the quantile for another number of degrees of freedom: count the components tested."

_LIST = [
    # -- zb2014/signature
    _ex("sig-1", _SIG, "Kalman innovation by hand", "warm-up", 10,
        answer="array of shape (2,): [eps_0, eps_1]", rtol=1e-9, data=_sig1_data, reference=_sig1_ref,
        mistakes=(Mistake(_sig1_no_f, "eps_1 looks like the prediction skipped F_0: the predictor is "
                                      "X_1 = F_0 (X_0 + K_0 eps_0)."),
                  Mistake(_sig1_prior_gain, "eps_1 looks like the predictor X_1 = F_0 X_0 + K_0 eps_0: the "
                                            "gain of the predictor is F_0 K_0, not K_0."))),
    _ex("sig-2", _SIG, "The signature recursion for a constant bias", "warm-up", 10,
        answer="array of shape (2, 2): Gamma_3", rtol=1e-9, data=_sig2_data, reference=_sig2_ref,
        mistakes=(Mistake(_sig2_open_loop, "This is the recursion with F_k in place of F_k (I - K_k H_k): "
                                           "the signature filter runs on the closed-loop predictor."),)),
    _ex("sig-3", _SIG, "A sensor bias", "core", 15,
        answer="array of shape (5,): H_k Gamma_k + Phi_k for k = 0..4", rtol=1e-9, data=_sig3_data,
        reference=_sig3_ref,
        mistakes=(Mistake(_sig3_no_fk, "This ignores the term -F_k K_k Phi_k of Proposition 2: the filter "
                                       "partly absorbs a sensor bias into its state estimate."),)),
    _ex("sig-4", _SIG, "What one sensor sees of two faults", "core", 15,
        answer="array of shape (2,): the steady-state row vector v", rtol=1e-6, data=_sig4_data,
        reference=_sig4_ref,
        mistakes=(Mistake(_sig4_open_loop, "This uses (I - F)^{-1}: the steady state of the signature "
                                           "filter involves the closed-loop matrix A = F (I - K H)."),)),
    _ex("sig-5", _SIG, "How fast the Willsky-Jones matrix grows", "core", 10,
        answer="a number: the slope of log10 ||alpha_k(101)|| per sample", rtol=1e-4, data=_sig5_data,
        reference=lambda d: _sig5_slope(d, np.log10),
        mistakes=(Mistake(lambda d: _sig5_slope(d, np.log), "This is the slope of the natural logarithm; "
                                                            "the figure uses log10."),)),
    _ex("sig-6", _SIG, "The identity with the wrong gains", "challenge", 25),
    # -- zb2014/glr
    _ex("glr-1", _GLR, "A threshold for a false-alarm probability", "warm-up", 5,
        answer="the 1 - alpha quantile of chi2(m) (a number)", rtol=1e-6, data=_glr1_data,
        reference=lambda d: _chi2_ppf(1 - d["alpha"], d["m"]),
        mistakes=(Mistake(lambda d: _chi2_ppf(1 - d["alpha"], d["m"] - 1), _DOF_HINT),
                  Mistake(lambda d: _chi2_ppf(1 - d["alpha"], d["m"] + 1), _DOF_HINT),
                  Mistake(lambda d: _chi2_ppf(d["alpha"], d["m"]),
                          "This is the lower quantile: the false alarms are the upper tail, "
                          "P(l > threshold) = alpha."))),
    _ex("glr-2", _GLR, "GLR statistic and estimate by hand", "warm-up", 10,
        answer="array of shape (3,): [l, theta_hat_1, theta_hat_2]", rtol=1e-9, data=_glr2_data,
        reference=_glr2_ref,
        mistakes=(Mistake(_glr2_no_inverse, "This uses C where C^{-1} belongs: l = d^T C^{-1} d and "
                                            "theta_hat = C^{-1} d."),)),
    _ex("glr-3", _GLR, "Non-centrality and detection probability", "core", 20,
        answer="array of shape (2,): [non-centrality, detection probability]", rtol=1e-6,
        data=_glr3_data, reference=lambda d: _glr3_answer(d, 2),
        mistakes=(Mistake(lambda d: _glr3_answer(d, 1), "The detection probability uses 1 degree of "
                                                        "freedom: the GLR tests all m = 2 components."),)),
    _ex("glr-4", _GLR, "The minmax statistic by the explicit regression", "core", 15,
        answer="a number: l_a", rtol=1e-9, data=_glr4_data, reference=_glr4_ref,
        mistakes=(Mistake(lambda d: d["zeta"][0] ** 2 / d["F"][0, 0],
                          "This is zeta_a^2 / F_aa: the nuisance was set to zero instead of being "
                          "regressed out."),
                  Mistake(lambda d: d["zeta"] @ np.linalg.solve(d["F"], d["zeta"]),
                          "This is the GLR for the whole of theta: the minmax statistic subtracts the "
                          "part explained by theta_b."))),
    _ex("glr-5", _GLR, "Counting the candidate onsets", "warm-up", 5,
        answer="an integer: the number of candidate onsets r at time k", rtol=0.0, atol=0.5,
        data=_glr5_data, reference=lambda d: _glr5_count(d, 0),
        mistakes=(Mistake(lambda d: _glr5_count(d, 1), "Off by one: the candidates are "
                                                      "k - w + 1 <= r <= k - s, both ends included."),
                  Mistake(lambda d: _glr5_count(d, -1), "Off by one: the candidates are "
                                                       "k - w + 1 <= r <= k - s, both ends included."))),
    _ex("glr-6", _GLR, "Why the windowed statistic is not chi-square", "challenge", 30),
    # -- zb2014/pipeline
    _ex("pipe-1", _PIPE, "Where 6.6349 comes from", "warm-up", 5,
        answer="the threshold of a 1 % test on one component (a number)", rtol=1e-6, data=_pipe1_data,
        reference=lambda d: _chi2_ppf(1 - d["alpha"], d["dim_theta_a"]),
        mistakes=(Mistake(lambda d: _chi2_ppf(1 - d["alpha"], 2),
                          "This is the chi2(2) quantile, the paper text's slip: each minmax test "
                          "focuses on dim theta_a = 1 component."),)),
    _ex("pipe-2", _PIPE, "Mass balance fixes the feed-through", "warm-up", 10,
        answer="array of shape (2,): [J_0, J_p]", rtol=1e-9, data=_pipe2_data, reference=_pipe2_ref),
    _ex("pipe-3", _PIPE, "How collinear are the two leaks?", "core", 15,
        answer="a number: 1 - cos^2 over k = 300..349", rtol=1e-6, data=_pipe3_data,
        reference=lambda d: _pipe3_answer(d, 0),
        mistakes=(Mistake(lambda d: _pipe3_answer(d, 1), "Off by one: k = 300, ..., 349 is 50 samples, "
                                                        "the slice [300:350]."),)),
    _ex("pipe-4", _PIPE, "Power of the isolation test with the onset known", "core", 20,
        answer="array of shape (2,): [non-centrality, power] for fault 2", rtol=1e-6, data=_pipe4_data,
        reference=_pipe4_ref,
        mistakes=(Mistake(_pipe4_no_rejection, "This uses F_aa: the minmax test only keeps the information "
                                               "F_a* = F_aa - F_ab^2 / F_bb left after rejecting the "
                                               "nuisance."),)),
    _ex("pipe-5", _PIPE, "Are 7 false alarms in 2000 runs surprising?", "core", 10,
        answer="array of shape (2,): [low, high], fractions", rtol=1e-6, data=_pipe5_data,
        reference=_pipe5_ref,
        mistakes=(Mistake(lambda d: 100 * _pipe5_ref(d), "These look like percentages: give fractions."),
                  Mistake(_pipe5_wald, "This is the normal (Wald) approximation, poor for 7 events: use "
                                       "the exact Clopper-Pearson interval."))),
    _ex("pipe-6", _PIPE, "Why centring the pressure helps isolation", "challenge", 25),
    # -- zhang2021/sparse
    _ex("sparse-1", _SPARSE, "How many hypotheses without the Lasso?", "warm-up", 10,
        answer="an integer: supports of size at most q_max", rtol=0.0, atol=0.5, data=_sparse1_data,
        reference=lambda d: _n_supports(d, range(d["q_max"] + 1)),
        mistakes=(Mistake(lambda d: _n_supports(d, range(d["q_max"], d["q_max"] + 1)),
                          "This counts the supports of size exactly q_max."),
                  Mistake(lambda d: _n_supports(d, range(1, d["q_max"] + 1)),
                          "The empty support (no fault) is a hypothesis too."))),
    _ex("sparse-2", _SPARSE, "The Kitanidis gain at k = 1", "warm-up", 15,
        answer="array of shape (2, 2): K-bar_1", rtol=1e-8, data=_sparse2_data,
        reference=lambda d: _sparse2_gains(d).K[d["k"]],
        mistakes=(Mistake(lambda d: _sparse2_gains(d).K_kalman[d["k"]],
                          "This is the Kalman gain K_1: the Kitanidis gain adds the correction along "
                          "H_1 E_0."),)),
    _ex("sparse-3", _SPARSE, "lambda_max and the normalisation", "core", 10,
        answer="a number: lambda_max in the normalisation of (39)", rtol=1e-8, data=_sparse_regression,
        reference=_sparse3_ref,
        mistakes=(Mistake(lambda d: float(np.abs(d["X"].T @ d["y"]).max()) / d["X"].shape[0],
                          "This divides by the number of rows N p; (39) divides by the number of "
                          "time samples N."),)),
    _ex("sparse-4", _SPARSE, "The flat-range rule on a given path", "core", 20,
        answer="a number: the lambda chosen by the rule (log width)", rtol=1e-8, data=_sparse4_data,
        reference=_sparse4_answer,
        mistakes=(Mistake(_sparse4_arithmetic, "This is an arithmetic middle (the linear reading): the "
                                               "book's rule measures width by log(high / low) and takes "
                                               "the geometric mean sqrt(low high) of the widest range."),)),
    _ex("sparse-5", _SPARSE, "Undo the shrinkage", "core", 15,
        answer="array of shape (8,): least squares on the selected support, zeros elsewhere", rtol=1e-8,
        data=_sparse_regression, reference=_sparse5_ref,
        mistakes=(Mistake(_sparse5_lasso, "These are the Lasso values at the chosen lambda, shrunk towards "
                                          "zero: refit by least squares on the support."),)),
    _ex("sparse-6", _SPARSE, "Greedy selection instead of the Lasso", "challenge", 30),
    # -- bz/parametric-nonparametric
    _ex("bz-1", _BZ, "One RLS step by hand", "warm-up", 10,
        answer="array of shape (2,): theta_hat_1", rtol=1e-9, data=_bz1_data,
        reference=lambda d: _bz1_answer(d, d["lam"]),
        mistakes=(Mistake(lambda d: _bz1_answer(d, 1.0), "This is the step without forgetting: "
                                                       "S_1 = lambda Sigma_1 + M_1 P_0 M_1^T."),)),
    _ex("bz-2", _BZ, "How long an impulse of f stays on the innovation", "warm-up", 10,
        answer="array of shape (2,): samples affected [Kitanidis, Kalman]", rtol=0.0, atol=0.5,
        data=_bz2_data, reference=_bz2_ref),
    _ex("bz-3", _BZ, "The whitened rejection", "core", 15,
        answer="a number: ||T_k eps||^2", rtol=1e-8, data=_bz3_data, reference=_bz3_ref,
        mistakes=(Mistake(_bz3_unwhitened, "This projection is not whitened: T_k must also satisfy "
                                           "T_k Sigma_k T_k^T = I."),)),
    _ex("bz-4", _BZ, "Lag-one covariance of the Kitanidis innovation", "core", 15,
        answer="array of shape (3, 3): Cov(eps_11, eps_10)", rtol=1e-8, atol=1e-14, data=_bz4_data,
        reference=_bz4_ref),
    _ex("bz-5", _BZ, "The threshold of the energy test", "warm-up", 5,
        answer="a number: the chi-square threshold", rtol=1e-8, data=_bz5_data, reference=_bz5_ref,
        mistakes=(Mistake(lambda d: _chi2_ppf(1 - d["alpha"], d["window"]),
                          "Degrees of freedom: the window sums w vectors of p components each."),
                  Mistake(lambda d: _chi2_ppf(1 - d["alpha"], d["p_reduced"]),
                          "Degrees of freedom: the window sums w vectors of p components each."))),
    _ex("bz-6", _BZ, "As many sensors as unknown inputs", "challenge", 25),
    # -- rosa2013/svo
    _ex("svo-1", _SVO, "One SVO step on a box", "warm-up", 15,
        answer="array of shape (4,): [x1 min, x1 max, x2 min, x2 max]", rtol=1e-6, atol=1e-8,
        data=_svo1_data, reference=_svo1_answer,
        mistakes=(Mistake(lambda d: _svo1_answer(d, disturbance=False),
                          "The disturbance is missing: add the Minkowski sum with L [-1, 1]^2."),
                  Mistake(lambda d: _svo1_answer(d, strip=False),
                          "The measurement is missing: intersect with the strip |y - C x| <= nbar."))),
    _ex("svo-2", _SVO, "Hull first, then strip", "warm-up", 10,
        answer="array of shape (2,): [lower, upper] of the set X(k+1)", rtol=1e-6, atol=1e-8,
        data=_svo2_data, reference=_svo2_answer,
        mistakes=(Mistake(lambda d: _svo2_answer(d, strip=False),
                          "This is the hull of the vertex predictions alone: intersect it with the "
                          "measurement strip."),)),
    _ex("svo-3", _SVO, "The price of convexification", "core", 15,
        answer="a number: area of the hull minus area of the union", rtol=1e-6, data=_svo3_data,
        reference=lambda d: _svo3_answer(d, "gap"),
        mistakes=(Mistake(lambda d: _svo3_answer(d, "hull"), "This is the area of the hull: subtract the "
                                                            "area of the union."),
                  Mistake(lambda d: _svo3_answer(d, "no_overlap"), "The two sets overlap: the area of the "
                                                                  "union counts the overlap once."))),
    _ex("svo-4", _SVO, "The smallest jump seen in one step", "core", 15,
        answer="a number: the smallest y(k+1) > 0 that empties the set", rtol=1e-6, data=_svo4_data,
        reference=_svo4_answer,
        mistakes=(Mistake(lambda d: _svo4_answer(d, disturbance=False),
                          "The disturbance L d(k) widens the prediction too."),
                  Mistake(lambda d: _svo4_answer(d, noise=False),
                          "The noise bound widens the measurement strip too."))),
    _ex("svo-5", _SVO, "How many vertex propagations", "warm-up", 5,
        answer="an integer: the number of Delta-vertex sequences", rtol=0.0, atol=0.5, data=_svo5_data,
        reference=_svo5_answer,
        mistakes=(Mistake(lambda d: d["N"] * 2 ** d["n_A"], "The parameters may sit at a different vertex at "
                                                           "each of the N steps: the counts multiply."),)),
    _ex("svo-6", _SVO, "Which true Delta breaks the paper's order?", "challenge", 25),
]

#: All exercises, by identifier, in book order.
EXERCISES: dict[str, Exercise] = {e.id: e for e in _LIST}


def get_exercise(exercise_id: str) -> Exercise:
    """The :class:`Exercise` registered as ``exercise_id``.

    Raises
    ------
    UnknownExerciseError
        With the closest registered identifiers.
    """
    if not isinstance(exercise_id, str):
        raise UnknownExerciseError(f"exercise_id: expected a string such as 'glr-3', "
                                   f"got {type(exercise_id).__name__} {exercise_id!r}")
    if exercise_id not in EXERCISES:
        close = difflib.get_close_matches(exercise_id, list(EXERCISES), n=3)
        hint = f"; did you mean {', '.join(repr(c) for c in close)}?" if close else ""
        raise UnknownExerciseError(f"exercise_id: no exercise {exercise_id!r}{hint} "
                                   f"(known: {', '.join(EXERCISES)})")
    return EXERCISES[exercise_id]


def exercises(chapter: str | None = None) -> list[Exercise]:
    """All exercises, or those of one chapter (a key of :data:`CHAPTERS`), in book order."""
    if chapter is not None and chapter not in CHAPTERS:
        raise ModelError(f"chapter: expected one of {list(CHAPTERS)}, got {chapter!r}")
    return [e for e in _LIST if chapter is None or e.chapter == chapter]


def exercise_data(exercise_id: str) -> ExerciseData:
    """The data an exercise works on (a fresh copy; seeded, identical on every call).

    Returns an empty :class:`ExerciseData` for an exercise that brings no data of its own.
    """
    ex = get_exercise(exercise_id)
    raw = ex.data() if ex.data is not None else {}
    return ExerciseData({k: np.array(v) if isinstance(v, np.ndarray) else v for k, v in raw.items()})


@functools.lru_cache(maxsize=None)
def _expected(exercise_id: str) -> np.ndarray:
    ex = EXERCISES[exercise_id]
    ref = np.array(ex.reference(exercise_data(exercise_id)), dtype=float)
    ref.setflags(write=False)
    return ref


@functools.lru_cache(maxsize=None)
def _mistake_answers(exercise_id: str) -> tuple[np.ndarray, ...]:
    ex = EXERCISES[exercise_id]
    return tuple(np.array(m.answer(exercise_data(exercise_id)), dtype=float) for m in ex.mistakes)


# ----------------------------------------------------------------------------- checking
def _as_answer(answer: Any, exercise_id: str) -> np.ndarray:
    if isinstance(answer, (str, bytes, dict, set)):
        raise AnswerError(f"answer: expected a real number or array for {exercise_id!r}, "
                          f"got {type(answer).__name__}")
    try:
        arr = np.array(answer)
    except (TypeError, ValueError) as exc:
        raise AnswerError(f"answer: expected a real number or array for {exercise_id!r}, "
                          f"got {type(answer).__name__} that numpy cannot read ({exc})") from None
    if arr.dtype == object or arr.dtype.kind not in "biuf":
        raise AnswerError(f"answer: expected real numbers for {exercise_id!r}, got an array of "
                          f"{'complex numbers' if arr.dtype.kind == 'c' else arr.dtype}")
    arr = arr.astype(float)
    if not np.all(np.isfinite(arr)):
        idx = tuple(int(i) for i in np.argwhere(~np.isfinite(arr))[0]) if arr.ndim else ()
        where = f" at index {list(idx)}" if idx else ""
        raise AnswerError(f"answer: expected finite numbers for {exercise_id!r}, got "
                          f"{float(arr[idx]) if idx else float(arr)}{where}")
    return arr


def _close(a: np.ndarray, ref: np.ndarray, ex: Exercise) -> np.ndarray:
    with np.errstate(over="ignore"):  # |a - ref| beyond the float range (1e308 against -1e308): inf, not close
        return np.abs(a - ref) <= ex.atol + ex.rtol * np.abs(ref)


def _scalar_diagnosis(a: float, ref: float, ex: Exercise) -> str:
    if ref != 0 and a != 0 and np.sign(a) != np.sign(ref):
        return "it has the wrong sign"
    if a == 0:
        return "it is zero, and should not be"
    if ref == 0:
        return "it should be zero"
    # the ratio's decades as a difference of logarithms: a / ref itself under- or overflows for
    # answers such as 5e-324 or 1e308 (the smallest subnormal, the largest decade of a double)
    decades = math.log10(abs(a)) - math.log10(abs(ref))
    if abs(decades) >= 0.95:
        word = "large" if decades > 0 else "small"
        return f"it is too {word} by about a factor 10^{abs(round(decades))}"
    ratio = abs(a / ref)
    if abs(ratio - 1) <= 0.1:
        return f"it is close (within 10 %) but outside the tolerance ({ex.tolerance})"
    return f"it is too {'large' if ratio > 1 else 'small'}, with the right sign and order of magnitude"


def _index_text(idx: tuple[int, ...]) -> str:
    return "[" + ", ".join(str(i) for i in idx) + "]"


def check(exercise_id: str, answer: Any) -> CheckResult:
    """Check a student's answer to a checkable exercise.

    Parameters
    ----------
    exercise_id : str
        E.g. ``"glr-3"``; :data:`EXERCISES` lists them.
    answer : float, array_like or None
        The student's result. ``None`` (the starter cells' placeholder) is accepted and
        reported as "no answer yet".

    Returns
    -------
    CheckResult
        True when every entry is within the exercise's tolerance of the reference; its message
        says what is wrong otherwise (shape, transpose, sign, order of magnitude, which entries,
        or a known mistake), never the reference value.

    Raises
    ------
    UnknownExerciseError
        ``exercise_id`` is not registered.
    ModelError
        The exercise is not checkable (its answer is an explanation).
    AnswerError
        ``answer`` is not a finite real number or array.

    Examples
    --------
    >>> check("glr-5", 98)
    glr-5: correct (tolerance: exact (integers)).
    >>> check("glr-5", 99)
    glr-5: not yet. Off by one: the candidates are k - w + 1 <= r <= k - s, both ends included.
    """
    ex = get_exercise(exercise_id)
    if not ex.checkable:
        raise ModelError(f"exercise_id: {exercise_id!r} has no checkable answer (it asks for an "
                         "explanation): compare with its solution")
    if answer is None:
        return CheckResult(exercise_id, False,
                           f"{exercise_id}: no answer yet. Replace `answer = None` by {ex.answer}.")
    a = _as_answer(answer, exercise_id)
    ref = _expected(exercise_id)
    fail = lambda msg: CheckResult(exercise_id, False, f"{exercise_id}: not yet. {msg}")  # noqa: E731
    if a.size == 1 and ref.size == 1:
        a = a.reshape(ref.shape)
    if a.shape != ref.shape:
        msg = f"Expected {ex.answer}; got shape {a.shape}."
        if a.ndim == 2 and a.T.shape == ref.shape and np.all(_close(a.T, ref, ex)):
            msg += " It matches once transposed: look for a missing or extra transpose."
        elif a.size == ref.size and np.all(_close(a.reshape(ref.shape), ref, ex)):
            msg += f" The numbers are right: reshape to {ref.shape}."
        return fail(msg)
    if ex.integer and not np.all(a == np.round(a)):
        idx = tuple(int(i) for i in np.argwhere(a != np.round(a))[0])
        where = f" (entry {_index_text(idx)})" if a.ndim else ""
        return fail(f"Expected {ex.answer}; got {float(a[idx])!r}{where}, which is not a whole number "
                    "(a count is an integer).")
    ok = _close(a, ref, ex)
    if np.all(ok):
        return CheckResult(exercise_id, True, f"{exercise_id}: correct (tolerance: {ex.tolerance}).")
    for wrong, mistake in zip(_mistake_answers(exercise_id), ex.mistakes):
        if wrong.shape == a.shape and np.all(_close(a, wrong, ex)):
            return fail(mistake.hint)
    if ref.size == 1:
        return fail(f"The value is off: {_scalar_diagnosis(float(a.ravel()[0]), float(ref.ravel()[0]), ex)}.")
    if a.ndim == 2 and a.shape[0] == a.shape[1] and np.all(_close(a.T, ref, ex)):
        return fail("It matches the transpose of the expected matrix: look for a missing or extra transpose.")
    if np.all(_close(-a, ref, ex)):
        return fail("Every entry has the wrong sign.")
    bad = [tuple(int(i) for i in idx) for idx in np.argwhere(~ok)]
    if len(bad) == 1:
        idx = bad[0]
        why = _scalar_diagnosis(float(a[idx]), float(ref[idx]), ex)
        return fail(f"Entry {_index_text(idx)} is off ({why}); the rest matches.")
    shown = ", ".join(_index_text(i) for i in bad[:4]) + (", ..." if len(bad) > 4 else "")
    return fail(f"{len(bad)} of {a.size} entries are off: {shown} (tolerance: {ex.tolerance}).")


# ----------------------------------------------------------------------------- book helpers
def exercise_table():
    """All exercises as a :func:`fdi_lib.report.table` (the instructor's page)."""
    from fdi_lib.report import table

    rows = {e.id: [CHAPTERS[e.chapter], e.title, e.difficulty, f"{e.minutes} min",
                   "yes" if e.checkable else "no (explanation)"] for e in _LIST}
    return table(rows, ["chapter", "title", "difficulty", "time", "checkable"], index_header="exercise")


def counts_table():
    """Number of exercises per chapter and difficulty, checkable ones and total time (a report table)."""
    from fdi_lib.report import table

    rows = {}
    for chapter, title in CHAPTERS.items():
        exs = exercises(chapter)
        rows[title] = ([sum(e.difficulty == d for e in exs) for d in DIFFICULTIES]
                       + [sum(e.checkable for e in exs), len(exs), f"{sum(e.minutes for e in exs)} min"])
    every = list(EXERCISES.values())
    rows["all chapters"] = ([sum(e.difficulty == d for e in every) for d in DIFFICULTIES]
                            + [sum(e.checkable for e in every), len(every),
                               f"{sum(e.minutes for e in every)} min"])
    return table(rows, [*DIFFICULTIES, "checkable", "total", "time"], index_header="chapter")


#: A suggested course of eight weeks: (topic, chapters read, exercises set), each exercise once.
COURSE_PLAN: tuple[tuple[str, tuple[str, ...], tuple[str, ...]], ...] = (
    ("Kalman innovation and fault signatures", ("zb2014/signature",), ("sig-1", "sig-2", "sig-3")),
    ("Boundedness and identifiability", ("zb2014/signature",), ("sig-4", "sig-5", "sig-6")),
    ("GLR test with a known profile", ("zb2014/glr",), ("glr-1", "glr-2", "glr-3")),
    ("Unknown onset and minmax isolation", ("zb2014/glr",), ("glr-5", "glr-4", "glr-6")),
    ("Case study: leaks on a gas pipeline", ("zb2014/pipeline",),
     ("pipe-1", "pipe-2", "pipe-3", "pipe-4", "pipe-5", "pipe-6")),
    ("Sparse isolation with the Lasso", ("zhang2021/sparse",),
     ("sparse-1", "sparse-2", "sparse-3", "sparse-4", "sparse-5", "sparse-6")),
    ("Unknown inputs: parametric and non-parametric faults", ("bz/parametric-nonparametric",),
     ("bz-1", "bz-5", "bz-2", "bz-3", "bz-4", "bz-6")),
    ("Set membership: set-valued observers", ("rosa2013/svo",),
     ("svo-1", "svo-2", "svo-5", "svo-3", "svo-4", "svo-6")),
)


def plan_table():
    """:data:`COURSE_PLAN` as a report table, with the estimated time of each week's exercises."""
    from fdi_lib.report import table

    rows = {}
    for week, (topic, chapters, ids) in enumerate(COURSE_PLAN, start=1):
        exs = [get_exercise(i) for i in ids]
        core = sum(e.minutes for e in exs if e.difficulty != "challenge")
        extra = sum(e.minutes for e in exs if e.difficulty == "challenge")
        rows[f"week {week}"] = [topic, "; ".join(CHAPTERS[c] for c in chapters),
                                ", ".join(f"{e.id} ({e.minutes} min)" for e in exs),
                                f"{core} min", f"{extra} min"]
    return table(rows, ["topic", "chapter", "exercises (estimated time)", "warm-up and core",
                        "challenge"], index_header="week")


_FENCE = re.compile(r"^(?P<fence>`{3,}|:{3,})\{(?P<name>[a-z-]+)\}")


def strip_solutions(text: str) -> str:
    """Remove every solution from a MyST chapter: the gated blocks ``solution-start`` ...
    ``solution-end`` (with the code cells between them) and plain ``solution`` directives.

    Everything else (exercises, their starter cells) is kept byte for byte. Raises
    :class:`ModelError` on a ``solution-start`` without its ``solution-end``.
    """
    lines = text.splitlines(keepends=True)
    out: list[str] = []
    i = 0
    while i < len(lines):
        m = _FENCE.match(lines[i])
        if m and m["name"] == "solution-start":
            j = i + 1
            while j < len(lines) and not (_FENCE.match(lines[j]) and _FENCE.match(lines[j])["name"] == "solution-end"):
                j += 1
            if j == len(lines):
                raise ModelError(f"text: solution-start at line {i + 1} has no solution-end")
            fence = _FENCE.match(lines[j])["fence"]
            j += 1
            while j < len(lines) and lines[j].strip() != fence:   # the closing fence of solution-end
                j += 1
            i = j + 1
            while i < len(lines) and not lines[i].strip() and out and not out[-1].strip():
                i += 1   # no run of blank lines where the block was
            continue
        if m and m["name"] == "solution":
            fence = m["fence"]
            j = i + 1
            while j < len(lines) and lines[j].rstrip() != fence:
                j += 1
            i = j + 1
            continue
        out.append(lines[i])
        i += 1
    return "".join(out)


# ----------------------------------------------------------------------------- reading chapters
@dataclass(frozen=True)
class ChapterExercise:
    """One exercise as written in a chapter (gated syntax, title ``"<id> · <difficulty> · <title>"``,
    label ``"ex-<id>"``, unnumbered: the identifier is the exercise's name everywhere).

    Attributes
    ----------
    id : str
        The identifier of the label (``"ex-" + id``); :func:`parse_chapter` checks that the title
        starts with the same.
    difficulty : str
        The difficulty in the title.
    title : str
    exercise : str
        The MyST text between ``exercise-start`` and ``exercise-end`` (statement, starter cells).
    solution : str
        The text between ``solution-start`` and ``solution-end`` (``""`` if there is none).
    solution_options : str
        The option lines of ``solution-start`` (e.g. ``":class: dropdown"``).
    """

    id: str
    difficulty: str
    title: str
    exercise: str
    solution: str
    solution_options: str


_EXERCISE_RE = re.compile(r"^```\{exercise-start\} (?P<tid>[a-z0-9-]+) · (?P<diff>[a-z-]+) · (?P<title>[^\n]*)\n"
                          r":label: ex-(?P<id>[a-z0-9-]+)\n(?P<opts>(?::[^\n]*\n)*)```\n"
                          r"(?P<body>.*?)^```\{exercise-end\}\n```$", re.S | re.M)
_SOLUTION_RE = re.compile(r"^```\{solution-start\} ex-(?P<id>[a-z0-9-]+)\n(?P<opts>(?::[^\n]*\n)*)```\n"
                          r"(?P<body>.*?)^```\{solution-end\}\n```$", re.S | re.M)
_CELL_RE = re.compile(r"^```\{code-cell\} ipython3\n(?P<body>.*?)^```$", re.S | re.M)


def parse_chapter(text: str) -> list[ChapterExercise]:
    """The exercises of a chapter in the gated syntax, in order, each with its solution."""
    solutions = {m["id"]: m for m in _SOLUTION_RE.finditer(text)}
    out = []
    for m in _EXERCISE_RE.finditer(text):
        if m["tid"] != m["id"]:
            raise ModelError(f"text: exercise titled {m['tid']!r} has the label 'ex-{m['id']}'")
        sol = solutions.get(m["id"])
        out.append(ChapterExercise(id=m["id"], difficulty=m["diff"], title=m["title"].strip(),
                                   exercise=m["body"], solution=sol["body"] if sol else "",
                                   solution_options=sol["opts"] if sol else ""))
    return out


def exercises_section(text: str) -> str:
    """The ``## Exercises`` section of a chapter (up to the next ``## `` heading); ``""`` if none."""
    m = re.search(r"^## Exercises\n", text, re.M)
    if m is None:
        return ""
    end = re.search(r"^## ", text[m.end():], re.M)
    return text[m.start(): m.end() + end.start()] if end else text[m.start():]


def code_cells(text: str) -> list[str]:
    """The sources of the ``{code-cell}`` blocks of a MyST text, without their metadata header."""
    cells = []
    for m in _CELL_RE.finditer(text):
        body = m["body"]
        if body.startswith("---\n"):
            body = body[body.index("\n---\n", 3) + 5:]
        elif body.startswith(":"):
            body = "".join(line for line in body.splitlines(keepends=True) if not line.startswith(":"))
        cells.append(body)
    return cells


# ----------------------------------------------------------------------------- student edition checks
_MATH = re.compile(r"\$\$.*?\$\$|\$[^$\n]*\$|\\\(.*?\\\)|\\\[.*?\\\]", re.S)


def words(text: str) -> list[str]:
    """The words of a MyST source, a notebook or an HTML page's text, comparable across the three.

    Maths is dropped (``$...$`` in sources, ``\\(...\\)`` in HTML), then the alphabetic words are
    kept, lower case; code keeps its identifiers, so a code line reads the same in all three.
    """
    return re.findall(r"[a-z]+", _MATH.sub(" ", text).lower())


def _shingles(ws: list[str], n: int) -> set[tuple[str, ...]]:
    return {tuple(ws[i:i + n]) for i in range(len(ws) - n + 1)}


def solution_fingerprints(full_text: str, student_text: str, n: int = 8) -> set[tuple[str, ...]]:
    """Runs of ``n`` words that occur in the solutions of ``full_text`` and nowhere in ``student_text``.

    ``student_text`` is the same chapter after :func:`strip_solutions`. A student page or notebook
    that contains one of these runs shows solution text.
    """
    keep = _shingles(words(student_text), n)
    out: set[tuple[str, ...]] = set()
    for ex in parse_chapter(full_text):
        out |= _shingles(words(ex.solution), n) - keep
    return out
