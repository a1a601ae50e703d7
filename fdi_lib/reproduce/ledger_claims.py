"""The declarations of the claims ledger (:mod:`fdi_lib.reproduce.ledger`): the statuses a
row may have, the tests a claim is compared by, :class:`Claim` (declared at a reproduction's
registration), :class:`LedgerRow` and the helpers that read our value in a headline.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any, Callable, Mapping, Sequence

from fdi_lib.errors import ModelError

__all__ = [
    "STATUSES",
    "ROLE_KEYS",
    "CALIBRATION",
    "PREDICTION",
    "INPUT",
    "FALLBACK_TRIALS",
    "REPRODUCED",
    "WITHIN",
    "WITHIN_SPREAD",
    "DIFFERS",
    "DIFFERS_MEASURED",
    "DIFFERS_UNKNOWN",
    "INPUT_VALUE",
    "CALIBRATION_TARGET",
    "NOT_COMPUTED",
    "NOT_REPRODUCIBLE",
    "AGREES",
    "DIFFERING",
    "DIFFERS_BRACKETED",
    "DIFFERS_HYPOTHESIS",
    "INPUT_RECOVERED",
    "TESTS",
    "BY_TOLERANCE",
    "BY_INTERVAL",
    "BY_STANDARD_ERROR",
    "BY_SPREAD",
    "BY_CHECK",
    "IS_INPUT",
    "ESTIMATES_INPUT",
    "IS_CALIBRATION",
    "NOT_CHECKABLE",
    "shown_under",
    "ours_at",
    "ci_at",
    "in_ci",
    "SET_BY_BOOK",
    "DEFAULT_RTOL",
    "PAPERS",
    "Claim",
    "LedgerRow",
    "NO_VALUE",
]

REPRODUCED, WITHIN, WITHIN_SPREAD = "reproduced", "within interval", "within spread"
DIFFERS_MEASURED, DIFFERS_UNKNOWN = "differs, measured cause", "differs, cause unknown"
DIFFERS_BRACKETED, DIFFERS_HYPOTHESIS = "differs, bracketed", "differs, hypothesis tested"
INPUT_VALUE, INPUT_RECOVERED, CALIBRATION_TARGET = "input", "input recovered", "calibration target"
NOT_COMPUTED, NOT_REPRODUCIBLE = "not computed", "not reproducible"
#: The statuses of a row, in the order of the summaries.
STATUSES = (
    REPRODUCED,
    WITHIN,
    WITHIN_SPREAD,
    DIFFERS_MEASURED,
    DIFFERS_HYPOTHESIS,
    DIFFERS_BRACKETED,
    DIFFERS_UNKNOWN,
    INPUT_VALUE,
    INPUT_RECOVERED,
    CALIBRATION_TARGET,
    NOT_COMPUTED,
    NOT_REPRODUCIBLE,
)
#: Statuses under which our result agrees with the paper's claim.
AGREES = (REPRODUCED, WITHIN, WITHIN_SPREAD)
#: Statuses of a difference.
DIFFERING = (DIFFERS_MEASURED, DIFFERS_HYPOTHESIS, DIFFERS_BRACKETED, DIFFERS_UNKNOWN)
#: Statuses of a value the book sets (never a reproduction, never compared in a caption).
SET_BY_BOOK = (INPUT_VALUE, INPUT_RECOVERED, CALIBRATION_TARGET)
#: Outcome of :func:`~fdi_lib.reproduce.ledger_status.claim_status` when the numbers disagree
#: (refined by :func:`~fdi_lib.reproduce.ledger.build_ledger` into :data:`DIFFERING`; never a row's
#: status).
DIFFERS = "differs"
#: Relative tolerance of "reproduced" for a number without its own tolerance.
DEFAULT_RTOL = 1e-3
#: Monte Carlo trials of a run the ledger makes itself when no cached result exists (the book
#: page executed on its own); a book build reads the chapters' results instead. Fewer trials
#: than the paper's give "not computed" rows.
FALLBACK_TRIALS = 2
#: Paper values that state nothing (not claims).
NO_VALUE = (None, "not stated", "illustration, no numbers")
#: Keys of a ``paper`` dictionary that declare the surrogate role of its other keys (lists of
#: top-level keys, see :func:`~fdi_lib.reproduce.ledger_status.surrogate_role`); they are not
#: claims.
ROLE_KEYS = ("calibrated_to", "predictions")
#: The papers (``paper_id``, the prefix of a reproduction identifier) and how rows name them.
PAPERS = {
    "zb2014": "Zhang & Basseville 2014",
    "zhang2021": "Zhang 2021",
    "bz": "Basseville & Zhang 2015",
    "rosa2013": "Rosa & Silvestre 2013",
    "windturbine": "Wind-turbine benchmark (Odgaard et al.)",
}

#: Surrogate roles of a paper value: the model was fitted to it, computes it, or takes it as given.
CALIBRATION, PREDICTION, INPUT = "calibration", "prediction", "input"

#: How a claim is compared (:attr:`Claim.test`): by tolerance (``rtol``/``atol``, an inequality
#: "< 1", an equality); by our 95 % interval (the paper's value inside it, at the paper's trial
#: count); by the standard error of our estimate (the paper's value within :attr:`Claim.z`
#: standard errors, headline key ``<key>_se``); by the spread of single runs (the paper's one run
#: inside the 95 % range of ours, ``<key>_spread95``); by a stated check (:attr:`Claim.check`, a
#: qualitative statement); a value the book sets (an input: never compared); our estimate of a
#: value the book sets (``input recovered`` when it agrees by tolerance or interval, never a
#: reproduction); a value a surrogate was fitted to (calibration target); or not at all (a
#: :attr:`Claim.reason` says why).
BY_TOLERANCE, BY_INTERVAL, BY_STANDARD_ERROR, BY_SPREAD, BY_CHECK = (
    "tolerance",
    "95 % interval",
    "standard error",
    "spread of single runs",
    "check",
)
IS_INPUT, ESTIMATES_INPUT, IS_CALIBRATION, NOT_CHECKABLE = (
    "input",
    "estimate of an input",
    "calibration target",
    "not reproducible",
)
TESTS = (
    BY_TOLERANCE,
    BY_INTERVAL,
    BY_STANDARD_ERROR,
    BY_SPREAD,
    BY_CHECK,
    IS_INPUT,
    ESTIMATES_INPUT,
    IS_CALIBRATION,
    NOT_CHECKABLE,
)


@dataclass(frozen=True, kw_only=True)
class Claim:
    """The declaration of one paper claim (or of a family, by a path pattern), at its
    reproduction's registration (``register(..., claims={pattern: Claim(...)})``).

    Attributes
    ----------
    location : str
        Where the paper states it, precise enough to be unique among the rows ("Table II, success
        rate at r = {0}"); ``{0}``, ``{1}`` ... are the parts of the claim's path after the first
        key, ``{fig}`` the figure of the identifier, ``{num}`` the number in the last part. Two rows
        with the same location fail the tests.
    units : str
        The paper's units of the value ("ms", "%", "dB"; ``""`` for a pure number or a statement).
    test : str
        How it is compared, one of :data:`TESTS`.
    label : str
        What is claimed, after the location ("type I error of the minmax test").
    rtol, atol : float
        Tolerance of :data:`BY_TOLERANCE` (and of inputs and calibration targets).
    z : float
        Standard errors of :data:`BY_STANDARD_ERROR` (1.96: a 95 % interval).
    check : callable, optional
        ``check(paper_value, ours, headline) -> bool`` of :data:`BY_CHECK`; ``criterion`` says
        in words what it tests.
    value : callable, optional
        ``value(paper_text) -> number``: the number a text claim states (``"0 (Prop. 2)"``).
    ours : callable, optional
        ``ours(headline, path) -> value`` when our value is not ``headline`` at the same path.
    ci : callable, optional
        ``ci(headline, path) -> (low, high) or None``; default: ``<key>_ci`` next to the key,
        or ``ci95`` next to a ``rate``.
    se : callable, optional
        ``se(headline, path) -> float or list``; default: ``<key>_se`` at the same path.
    explain : str, optional
        Label (``sec-...``, ``fig-...``) or document (``book/...``) where the claim is shown
        and discussed; default: the chapter of the reproduction. Not a cause.
    cause : str, optional
        Label of the section that *measures* the cause of a difference ("differs, measured
        cause"); ``cause_glue`` are the glue keys of that section's measurement (a test reads the
        section and fails when one is not glued there); ``cause_text`` says what was measured.
    bracket : callable, optional
        ``bracket(paper_value, ours, headline, path) -> bool``: two of our readings bracket the
        paper's value ("differs, bracketed", not a cause); ``bracket_text`` names the readings.
    hypothesis : str, optional
        Label of the section where a named alternative setting reproduces the paper's value with
        its side effects measured ("differs, hypothesis tested"); ``hypothesis_glue`` and
        ``hypothesis_text`` as for the cause.
    ruled_out : str
        Candidate causes measured and excluded, for a difference whose cause is unknown.
    missing : str, optional
        What our value ``None`` means (e.g. "not detected in the 6 s record"): a result that
        differs from a number. Without it, ``None`` means we have no value ("not computed").
    reason : str, optional
        Why the claim is not reproducible (test :data:`NOT_CHECKABLE`).
    role : str, optional
        :data:`INPUT`, :data:`CALIBRATION` or :data:`PREDICTION` (default) for a surrogate
        reproduction whose ``paper`` dictionary does not declare :data:`ROLE_KEYS`.
    shown_under : str, optional
        Identifier under which the same claim is listed (results sharing one ``paper`` dict,
        or the same paper value checked twice); ``same_path(path)`` gives its path there when
        it differs. The claim is then one row, at that place, and needs no location here;
        ``figure_reading`` says whether this reproduction's figure still judges its own reading
        (the per-radian UAV figures) or leaves the claim to the other figure (the §6.4 detection
        time that Figs 8-10 repeat).
    """

    location: str
    units: str
    test: str
    label: str = ""
    rtol: float = DEFAULT_RTOL
    atol: float = 0.0
    z: float = 1.96
    check: Callable[[Any, Any, Mapping[str, Any]], bool] | None = None
    criterion: str = ""
    value: Callable[[Any], Any] | None = None
    ours: Callable[[Mapping[str, Any], tuple[str, ...]], Any] | None = None
    ci: Callable[[Mapping[str, Any], tuple[str, ...]], Any] | None = None
    se: Callable[[Mapping[str, Any], tuple[str, ...]], Any] | None = None
    explain: str | None = None
    cause: str | None = None
    cause_glue: tuple[str, ...] = ()
    cause_text: str = ""
    bracket: Callable[[Any, Any, Mapping[str, Any], tuple[str, ...]], bool] | None = None
    bracket_text: str = ""
    hypothesis: str | None = None
    hypothesis_glue: tuple[str, ...] = ()
    hypothesis_text: str = ""
    ruled_out: str = ""
    missing: str | None = None
    reason: str | None = None
    role: str | None = None
    shown_under: str | None = None
    same_path: Callable[[tuple[str, ...]], tuple[str, ...]] | None = None
    figure_reading: bool = True

    def __post_init__(self) -> None:
        if self.test not in TESTS:
            raise ModelError(f"Claim.test: expected one of {list(TESTS)}, got {self.test!r}")
        if (self.test == NOT_CHECKABLE) != bool(self.reason):
            raise ModelError(
                f"Claim.reason: expected a reason exactly for test {NOT_CHECKABLE!r}, "
                f"got test {self.test!r} with reason {self.reason!r}"
            )
        if self.test == BY_CHECK and self.check is None:
            raise ModelError(f"Claim.check: test {BY_CHECK!r} needs a check function, got None")
        if not self.shown_under and not self.location.strip():
            raise ModelError("Claim.location: expected where the paper states it, got ''")


def shown_under(
    id: str, same_path: Callable[[tuple[str, ...]], tuple[str, ...]] | None = None, **kwargs: Any
) -> Claim:
    """The declaration of a claim listed under reproduction ``id`` (its row is there)."""
    return Claim(
        location="",
        units="",
        test=kwargs.pop("test", BY_TOLERANCE),
        shown_under=id,
        same_path=same_path,
        **kwargs,
    )


@dataclass(frozen=True)
class LedgerRow:
    """One claim: the paper's value, ours, the computed status and its links."""

    id: str
    path: tuple[str, ...]
    label: str
    paper: Any
    ours: Any
    ci: tuple[float, float] | None
    status: str
    where: str
    explain: str | None
    note: str
    role: str | None
    trials: int | None
    source: str
    status_detail: str = ""
    cause: str | None = None
    paper_trials: int | None = None
    location: str = ""
    units: str = ""
    test: str = ""

    @property
    def paper_id(self) -> str:
        """The paper (a key of :data:`PAPERS`)."""
        return self.id.split("-", 1)[0]

    @property
    def claim(self) -> str:
        """The label naming its paper ("Zhang & Basseville 2014, Fig. 8: ...")."""
        return f"{PAPERS.get(self.paper_id, self.paper_id)}, {self.label}"

    def to_json_dict(self) -> dict[str, Any]:
        """JSON-serialisable form (``--ledger --json``; keys in the module docstring)."""
        from fdi_lib.reproduce.registry import _jsonable

        return _jsonable(
            {
                "id": self.id,
                "paper_id": self.paper_id,
                "key": "/".join(self.path),
                "claim": self.claim,
                "paper": self.paper,
                "ours": self.ours,
                "ci95": None if self.ci is None else list(self.ci),
                "status": self.status,
                "status_detail": self.status_detail,
                "cause": self.cause,
                "where": self.where,
                "explanation": self.explain,
                "note": self.note,
                "surrogate": self.role,
                "trials": self.trials,
                "paper_trials": self.paper_trials,
                "source": self.source,
                "location": self.location,
                "units": self.units,
                "test": self.test,
            }
        )


def _at(d: Any, path: Sequence[str]) -> Any:
    for k in path:
        if not isinstance(d, Mapping) or k not in d:
            raise KeyError("/".join(path))
        d = d[k]
    return d


def _has(d: Any, path: Sequence[str]) -> bool:
    try:
        _at(d, path)
    except KeyError:
        return False
    return True


def ours_at(*keys: str) -> Callable[[Mapping[str, Any], tuple[str, ...]], Any]:
    """For :attr:`Claim.ours`: our value at ``keys`` followed by the claim path after its first
    key (``ours_at("success_rate", "log")`` reads ``success_rate/log/q15`` for
    ``success_rate/q15``)."""
    return lambda h, path: _at(h, (*keys, *path[1:]))


def ci_at(*keys: str) -> Callable[[Mapping[str, Any], tuple[str, ...]], Any]:
    """For :attr:`Claim.ci`: the interval at ``keys`` followed by the claim path after its first
    key (tables with one ``ci95`` dictionary per column, possibly per reading of a rule)."""

    def ci(h: Mapping[str, Any], path: tuple[str, ...]) -> tuple[float, float] | None:
        at = (*keys, *path[1:])
        v = _at(h, at) if _has(h, at) else None
        return None if v is None else (float(v[0]), float(v[1]))

    return ci


def in_ci(key: str) -> Callable[[Any, Any, Mapping[str, Any]], bool]:
    """For :attr:`Claim.check`: our value lies in the 95 % interval ``headline[key + "_ci"]``."""

    def check(paper: Any, ours: Any, h: Mapping[str, Any]) -> bool:
        lo, hi = h[key + "_ci"]
        return lo <= float(ours) <= hi

    return check
