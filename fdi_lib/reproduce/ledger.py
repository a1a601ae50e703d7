"""The claims ledger: every value the four papers state, ours next to it, and a computed status.

Declaring a claim
-----------------
Each claim is declared **where it is computed**: at the registration of the reproduction that
tests it (:func:`fdi_lib.reproduce.registry.register`), in its paper module. A declaration
(:class:`Claim`) says where in the paper the value is (``location``, unique among the rows),
its units, and how it is compared (``test``, one of :data:`TESTS`): by tolerance, by our 95 %
interval at the paper's trial count, by the standard error of our estimate, by the spread of
single runs, by a stated check, or not at all (an input the book sets, our estimate of such an
input, a calibration target, a value that cannot be reproduced here). The registration also
carries the chapter, the book's seed and the surrogate role; the book's order is that of
``_toc.yml`` (:func:`fdi_lib.reproduce.book.book_order`). Adding a figure touches its paper
module and its chapter only::

    from fdi_lib.reproduce.ledger import BY_INTERVAL, IS_INPUT, Claim
    from fdi_lib.reproduce.registry import register

    @register("zb2014-fig8", paper=PAPER, title="...", default_trials=1000,
              chapter="zb2014/pipeline", surrogate=True, claims={
                  # a pattern over the paths of the result's ``paper`` dictionary
                  "type2_rate/*/rate": Claim(
                      location="Fig. 8, type II error of fault {0}", units="%", test=BY_INTERVAL,
                      cause="sec-pipeline-isolation-window", cause_glue=("pl_we_t2c{0}",),
                      cause_text="isolating up to the end of the record gives the paper's rate"),
                  "threshold_dof": Claim(location="Fig. 8, caption", units="", test=IS_INPUT)})
    def fig8(*, seed, trials, jobs): ...

A leaf of a result's ``paper`` dictionary without a matching declaration is refused
(:func:`build_ledger` with ``strict=True``, and the tests); so are two rows with the same
location, a "measured cause" whose section (``cause``) does not glue the declared
``cause_glue`` keys, and a declaration that matches no claim.

Claims and statuses
-------------------
The paper's values are read from the ``paper`` dictionary of each reproduction's result; ours
from its ``headline``. A *claim* is one leaf of a ``paper`` dictionary that states something
(``None``, ``"not stated"`` and ``"illustration, no numbers"`` state nothing); a claim listed by
two reproductions (a value of Table I also checked by ``zhang2021-lambda-rule``) is one row,
under the reproduction that runs the paper's setting (:attr:`Claim.shown_under`). Its status is
**computed** by the declared test only, never typed, and is one of the fixed vocabulary
:data:`STATUSES`:

``reproduced``
    our value equals the paper's within the claim's tolerance, satisfies the paper's inequality
    (``"< 1"``), or passes the claim's stated check (a statement such as "grows linearly in k");
``within interval``
    the paper's value lies in our 95 % interval (:data:`BY_INTERVAL`), or within ``z`` standard
    errors of our estimate (:data:`BY_STANDARD_ERROR`, the interval shown is ours ± z se);
``within spread``
    a claim about one run of the paper (a single alarm time) inside the 95 % range of our
    run-to-run distribution (headline key ``<key>_spread95``); the detail gives the percentile
    of the paper's value in it and the number of runs;
``differs, measured cause``
    the claim's declaration names a section of the book (``cause``) that *measures* why, with
    glued numbers (``cause_glue``; ``cause`` in the JSON);
``differs, hypothesis tested``
    a named alternative setting reproduces the paper's value, with its side effects measured
    and stated in the section ``hypothesis`` (``cause`` in the JSON);
``differs, bracketed``
    two of our readings bracket the paper's value but neither agrees (:attr:`Claim.bracket`):
    not a cause;
``differs, cause unknown``
    no measurement of the cause exists (the row still links to where the difference is shown,
    ``explanation``; the detail names the candidate causes measured and ruled out);
``input``
    a value the book sets (a Table 1 value, a fault amplitude, an onset): equal by construction,
    never counted as reproduced;
``input recovered``
    our estimate of a value the book sets (the onset and the fault of Figs 3-4), agreeing with
    it: shown, not counted as a reproduction;
``calibration target``
    a value a surrogate model was fitted to (close by construction);
``not computed``
    we have no value to compare (the detail says why), or the result comes from fewer Monte
    Carlo trials than the paper's count (:attr:`Reproduction.default_trials`): a stochastic
    status is only read at the paper's scale ("not computed at paper scale", e.g. the ledger
    page executed on its own with :data:`FALLBACK_TRIALS`);
``not reproducible``
    the claim cannot be checked here (the detail says why, e.g. a timing on the authors'
    MATLAB machine).

The first three are :data:`AGREES`: a figure caption says "reproduces paper Fig. N" only when
every compared row of its reproduction is one of them (:func:`figure_claim`; the rows of
:data:`SET_BY_BOOK` are not compared). The paper items of :data:`MISSION` (propositions,
figures, tables, remarks) get a state derived from their rows (:meth:`Ledger.mission`).

Surrogate models: for a reproduction registered with ``surrogate=True`` each row also says
what the paper's number is to the model (:func:`surrogate_role`): a value the surrogate was
*calibrated* to, a *prediction* of it, or an *input* set into it. A ``paper`` dictionary that
declares the lists ``paper["calibrated_to"]`` and ``paper["predictions"]`` (:data:`ROLE_KEYS`,
never claims) is the only source; the declared test (:data:`IS_INPUT`, :data:`IS_CALIBRATION`)
or ``role`` applies otherwise.

JSON
----
``python -m fdi_lib reproduce --ledger --json`` prints ``{"counts", "counts_by_paper",
"mission", "rows", "sources"}``, the same bytes on every run, at any ``--jobs`` and on a cluster
(the wall times of the runs are kept apart, :attr:`Ledger.timings`). Rows have the keys ``id``,
``paper_id`` (``zb2014``, ``zhang2021``, ``bz``, ``rosa2013``, ``windturbine``), ``key`` (the
claim's path in the ``paper`` dictionary), ``claim`` (a label naming the paper and the location:
"Zhang & Basseville 2014, Fig. 8, type I error of fault 1: ..."), ``location``, ``units``,
``test`` (the declared comparison), ``paper`` (the paper's value, in its own units and
indexing), ``ours`` (same units), ``ci95``, ``status``, ``status_detail`` (why, for every status
but ``reproduced``/``within interval``), ``cause`` (the label of the section measuring the cause
or testing the hypothesis), ``where`` (the chapter), ``explanation`` (label or document showing
the claim), ``note`` (how the status was decided: tolerance, interval, inequality, check),
``surrogate`` (``calibration``/``prediction``/``input``), ``trials`` (of our result),
``paper_trials`` (the paper's count, ``None`` for a single run) and ``source``.

Results are those of the book's settings (:func:`fdi_lib.reproduce.book.book_settings`: the seed
and trials the chapters use, without options): read from the book build's results cache
(:func:`fdi_lib.reproduce.registry.cached_run`, the chapters' own runs), else computed (Monte
Carlo reproductions with at most ``max_trials`` trials, reported per row).
"""

from __future__ import annotations

import fnmatch
import math
import numbers
import re
import time
from dataclasses import dataclass, field, replace
from typing import Any, Callable, Mapping, Sequence

from fdi_lib.errors import ModelError, UnknownReproductionError
from fdi_lib.report import NA, fmt_count, fmt_number, fmt_rate, table
from fdi_lib.reproduce.registry import ReproductionResult, cached_run, get, list_reproductions

__all__ = [
    "STATUSES",
    "ROLE_KEYS",
    "CALIBRATION",
    "PREDICTION",
    "INPUT",
    "surrogate_role",
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
    "claim_for",
    "chapter_of",
    "ours_at",
    "ci_at",
    "in_ci",
    "SET_BY_BOOK",
    "MISSION",
    "MISSION_STATES",
    "item_state",
    "DEFAULT_RTOL",
    "PAPERS",
    "Claim",
    "LedgerRow",
    "Ledger",
    "NO_VALUE",
    "claim_paths",
    "claim_status",
    "build_ledger",
    "collect_results",
    "ledger",
    "FigureClaim",
    "figure_claim",
    "glue_caption",
    "REPRODUCES",
    "COMPARE",
    "REDRAWS",
    "CAPTION_ITEMS",
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
#: Outcome of :func:`claim_status` when the numbers disagree (refined by :func:`build_ledger`
#: into :data:`DIFFERING`; never a row's status).
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
#: top-level keys, see :func:`surrogate_role`); they are not claims.
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


# ----------------------------------------------------------------------------- helpers
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


def claim_paths(paper: Mapping[str, Any], prefix: tuple[str, ...] = ()) -> list[tuple[str, ...]]:
    """Paths of the leaves of a ``paper`` dictionary that state a value (see :data:`NO_VALUE`).

    A list is a leaf (e.g. ``theta_estimate = [4, 0]``). The top-level :data:`ROLE_KEYS`
    declare roles and are skipped.
    """
    out: list[tuple[str, ...]] = []
    for k, v in paper.items():
        path = (*prefix, str(k))
        if not prefix and k in ROLE_KEYS:
            continue
        if isinstance(v, Mapping):
            out += claim_paths(v, path)
        elif not (v is None or (isinstance(v, str) and v in NO_VALUE)):
            out.append(path)
    return out


def _default_ci(headline: Mapping[str, Any], path: tuple[str, ...]) -> tuple[float, float] | None:
    parent, key = path[:-1], path[-1]
    for cpath in ((*parent, key + "_ci"), (*parent, "ci95") if key == "rate" else None):
        if cpath is not None and _has(headline, cpath):
            ci = _at(headline, cpath)
            if (
                isinstance(ci, (list, tuple))
                and len(ci) == 2
                and all(isinstance(c, numbers.Real) for c in ci)
            ):
                return float(ci[0]), float(ci[1])
    return None


def _default_spread(
    headline: Mapping[str, Any], path: tuple[str, ...]
) -> tuple[float, float] | None:
    """``<key>_spread95`` next to a single-run key: the 95 % range of our runs, else ``None``."""
    spath = (*path[:-1], path[-1] + "_spread95")
    if _has(headline, spath):
        sp = _at(headline, spath)
        if isinstance(sp, (list, tuple)) and len(sp) == 2 and all(_is_number(c) for c in sp):
            return float(sp[0]), float(sp[1])
    return None


def _default_se(headline: Mapping[str, Any], path: tuple[str, ...]) -> Any:
    """``<key>_se`` at the claim's path (the standard error of our value), else ``None``."""
    spath = (path[0] + "_se", *path[1:])
    return _at(headline, spath) if _has(headline, spath) else None


def _se_interval(ours: Any, se: Any, z: float) -> tuple[float, float] | None:
    """``ours ± z se`` of a scalar (the interval of :data:`BY_STANDARD_ERROR`), else ``None``."""
    o, e = _numbers(ours), _numbers(se)
    if o is None or e is None or len(o) != 1 or len(e) != 1:
        return None
    return o[0] - z * e[0], o[0] + z * e[0]


def _label(id: str, path: tuple[str, ...], spec: Claim) -> str:
    """The row's label: the claim's location in the paper, then what it says."""
    text = f"{spec.location}: {spec.label}" if spec.label else spec.location
    if not text.strip():
        text = f"{_fig(id)}: {' '.join(path)}"
    return text.format(*path[1:], fig=_fig(id), num=re.sub(r"^\D+", "", path[-1]))


def _spread_detail(headline: Mapping[str, Any], path: tuple[str, ...]) -> str:
    """ "the paper's run is at the 71st percentile of our 1000 runs" (keys ``<key>_paper_percentile``
    and ``spread_runs`` of the headline; what is known of them)."""
    pct = headline.get(path[-1] + "_paper_percentile") if len(path) == 1 else None
    runs = headline.get("spread_runs")
    of = f" of our {fmt_count(runs)} runs" if _is_number(runs) else " of our runs"
    if _is_number(pct):
        return f"the paper's run lies at percentile {fmt_number(pct, 2)}{of}"
    return f"the paper's run lies inside the 95 % range{of}"


def _is_number(x: Any) -> bool:
    return isinstance(x, numbers.Real) and not isinstance(x, bool)


def _numbers(x: Any) -> list[float] | None:
    """``x`` as a list of floats (a number or a list of numbers), else ``None``."""
    if _is_number(x):
        return [float(x)]
    if isinstance(x, (list, tuple)) and x and all(_is_number(v) for v in x):
        return [float(v) for v in x]
    return None


_INEQ = re.compile(r"^\s*(<=|>=|<|>)\s*([-+0-9.eE]+)\s*$")
_ABOUT = re.compile(r"^\s*about\s+([-+0-9.eE]+)\s*$")


#: The declaration :func:`claim_status` uses when given none: compared by tolerance.
_PLAIN = Claim(location="(undeclared)", units="", test=BY_TOLERANCE)


def _statement_status(
    paper: str,
    ours: Any,
    ci: tuple[float, float] | None,
    spec: Claim,
    headline: Mapping[str, Any] | None,
    spread: tuple[float, float] | None,
    se: Sequence[float] | float | None,
) -> tuple[str, str]:
    """:func:`claim_status` of a paper value given as text: an inequality (``"< x"``), ``"about
    x"`` (compared as the number ``x``) or a statement equal to ours."""
    m, a = _INEQ.match(paper), _ABOUT.match(paper)
    if m:
        vals = _numbers(ours)
        if vals is None:
            return NOT_COMPUTED, f"no number of ours to compare with {paper}"
        op, bound = m.group(1), float(m.group(2))
        holds = {
            "<": lambda v: v < bound,
            "<=": lambda v: v <= bound,
            ">": lambda v: v > bound,
            ">=": lambda v: v >= bound,
        }[op]
        return (REPRODUCED if all(holds(v) for v in vals) else DIFFERS), f"inequality {paper}"
    if a:
        return claim_status(float(a.group(1)), ours, ci, spec, headline, spread, se)
    if ours == paper:
        return REPRODUCED, "same text"
    return NOT_REPRODUCIBLE, "no check defined for this statement"


def _number_status(
    p: list[float],
    o: list[float],
    ci: tuple[float, float] | None,
    spec: Claim,
    spread: tuple[float, float] | None,
    se: Sequence[float] | float | None,
) -> tuple[str, str]:
    """:func:`claim_status` of the paper's numbers ``p`` against ours ``o`` (same length) by the
    declared test: our interval, standard error or spread, else the tolerances."""
    tol_note = f"tolerance {fmt_number(spec.rtol)} relative" + (
        f", {fmt_number(spec.atol)} absolute" if spec.atol else ""
    )
    close = all(math.isclose(a, b, rel_tol=spec.rtol, abs_tol=spec.atol) for a, b in zip(o, p))
    inside = ci is not None and len(p) == 1 and ci[0] <= p[0] <= ci[1]
    if spec.test == BY_INTERVAL:
        if ci is None:
            return NOT_COMPUTED, "no 95 % interval of ours to compare with"
        return (
            (WITHIN, "paper value inside our 95 % interval")
            if inside
            else (DIFFERS, "paper value outside our 95 % interval")
        )
    if spec.test == BY_STANDARD_ERROR:
        ses = _numbers(se)
        if ses is None or len(ses) != len(p):
            return NOT_COMPUTED, "no standard error of ours to compare with"
        note = f"within {fmt_number(spec.z)} standard errors of ours"
        if all(abs(a - b) <= spec.z * e for a, b, e in zip(o, p, ses)):
            return WITHIN, "paper value " + note
        return DIFFERS, "paper value not " + note
    if spec.test == BY_SPREAD:
        if spread is None:
            return NOT_COMPUTED, "no spread of our runs to compare with"
        if len(p) == 1 and spread[0] <= p[0] <= spread[1]:
            return WITHIN_SPREAD, "paper's single run inside the 95 % range of our runs"
        return DIFFERS, "paper's single run outside the 95 % range of our runs"
    if close:
        return REPRODUCED, tol_note
    if inside and spec.test in (ESTIMATES_INPUT, IS_CALIBRATION):
        return WITHIN, "paper value inside our 95 % interval"
    return DIFFERS, tol_note + ("; outside our 95 % interval" if ci is not None else "")


def claim_status(
    paper: Any,
    ours: Any,
    ci: tuple[float, float] | None = None,
    spec: Claim = _PLAIN,
    headline: Mapping[str, Any] | None = None,
    spread: tuple[float, float] | None = None,
    se: Sequence[float] | float | None = None,
) -> tuple[str, str]:
    """The outcome of comparing one claim with our value by its declared test, and a note saying
    how it was decided.

    The outcome is :data:`REPRODUCED`, :data:`WITHIN`, :data:`WITHIN_SPREAD`, :data:`DIFFERS`,
    :data:`NOT_COMPUTED` (we have no value, or not the statistic the test needs) or
    :data:`NOT_REPRODUCIBLE`; :func:`build_ledger` turns it into a row status (input, input
    recovered, calibration target, a difference's cause, the paper's trial count). Only the
    declared test can agree: a value close to the paper's but outside our interval differs.

    Parameters
    ----------
    paper : number, list of numbers, bool or str
        The paper's value: a number (or list), ``"< x"``-type inequality, ``"about x"``,
        or a statement checked by ``spec.check``.
    ours : any
        Our value (``None`` when we have none; with ``spec.missing``, ``None`` is a result,
        e.g. never detected, that differs from any number).
    ci : (float, float), optional
        Our 95 % interval of a scalar value (:data:`BY_INTERVAL`, :data:`ESTIMATES_INPUT`,
        :data:`IS_CALIBRATION`).
    spec : Claim
        The declaration: test, tolerances, check, or the reason the claim is not reproducible.
    headline : dict, optional
        The reproduction's headline, passed to ``spec.check``.
    spread : (float, float), optional
        95 % range of our run-to-run distribution of a single-run value (:data:`BY_SPREAD`).
    se : float or list of float, optional
        Standard error of our value, per component (:data:`BY_STANDARD_ERROR`).
    """
    if spec.reason:
        return NOT_REPRODUCIBLE, spec.reason
    if ours is None:
        if spec.missing:
            return DIFFERS, f"ours: {spec.missing}"
        return NOT_COMPUTED, "we have no value"
    if spec.check is not None:
        ok = bool(spec.check(paper, ours, headline or {}))
        return (REPRODUCED if ok else DIFFERS), spec.criterion
    if spec.value is not None:
        return claim_status(
            spec.value(paper), ours, ci, replace(spec, value=None), headline, spread, se
        )
    if isinstance(paper, str):
        return _statement_status(paper, ours, ci, spec, headline, spread, se)
    if isinstance(paper, bool) or isinstance(ours, bool):
        return (REPRODUCED if paper == ours else DIFFERS), "equality"
    p, o = _numbers(paper), _numbers(ours)
    if p is None:
        return (REPRODUCED if paper == ours else DIFFERS), "equality"
    if o is None or len(o) != len(p):
        return DIFFERS, "not comparable"
    return _number_status(p, o, ci, spec, spread, se)


# ----------------------------------------------------------------------------- declaring claims
_UNSCALED = "not computed at paper scale"
_RECOVERED = "our estimate of a value the book sets: shown, not a reproduction"


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


def claim_for(id: str, path: tuple[str, ...]) -> Claim | None:
    """The first claim declared at the registration of ``id`` whose pattern matches ``path``
    (``None``: an undeclared claim, which the tests refuse)."""
    try:
        claims = get(id).claims
    except UnknownReproductionError:
        return None
    key = "/".join(path)
    for pattern, claim in claims:
        if fnmatch.fnmatchcase(key, pattern):
            return claim
    return None


def chapter_of(id: str) -> str:
    """The book document that shows reproduction ``id`` (its registration's ``chapter``)."""
    try:
        chapter = get(id).chapter
    except UnknownReproductionError:
        chapter = ""
    return f"book/{chapter}" if chapter else "book/reproductions"


#: Variants of a figure (identifier suffix), for labels.
VARIANTS = {"rad": "elevator read per radian"}


def _fig(id: str) -> str:
    """``"zb2014-fig3"`` -> ``"Fig. 3"``, ``"zb2014-table1"`` -> ``"Table 1"``,
    ``"rosa2013-fig11-rad"`` -> ``"Fig. 11 (elevator read per radian)"``."""
    m = re.fullmatch(r"[a-z0-9]+-(fig|table)(\d+)(?:-(\w+))?", id)
    if m:
        variant = f" ({VARIANTS.get(m.group(3), m.group(3))})" if m.group(3) else ""
        return f"{'Fig.' if m.group(1) == 'fig' else 'Table'} {m.group(2)}{variant}"
    return id.split("-", 1)[-1].capitalize()


def surrogate_role(
    id: str, paper: Mapping[str, Any], path: tuple[str, ...], spec: Claim | None = None
) -> str | None:
    """What the paper value at ``path`` is to a surrogate model (``None`` if ``id`` has none).

    A ``paper`` dictionary that declares :data:`ROLE_KEYS` decides alone: its key
    ``path[0]`` listed in ``calibrated_to`` is a :data:`CALIBRATION`, in ``predictions`` a
    :data:`PREDICTION`, in neither an :data:`INPUT` (set into the model). Otherwise, for a
    reproduction registered with ``surrogate=True``, the claim's ``role``, else its test's
    (an input for :data:`IS_INPUT` and :data:`ESTIMATES_INPUT`, a calibration for
    :data:`IS_CALIBRATION`), else :data:`PREDICTION`.
    """
    if any(k in paper for k in ROLE_KEYS):
        if path[0] in paper.get("calibrated_to", ()):
            return CALIBRATION
        return PREDICTION if path[0] in paper.get("predictions", ()) else INPUT
    try:
        surrogate = get(id).surrogate
    except UnknownReproductionError:
        surrogate = False
    if not surrogate:
        return None
    if spec is None:
        return PREDICTION
    return spec.role or {IS_INPUT: INPUT, ESTIMATES_INPUT: INPUT, IS_CALIBRATION: CALIBRATION}.get(
        spec.test, PREDICTION
    )


def _order(id: str) -> tuple[int, str]:
    from fdi_lib.reproduce.book import book_order  # book imports the registry, as this module

    order = book_order()
    return (order.index(id), id) if id in order else (len(order), id)


# ----------------------------------------------------------------------------- mission
def _items(paper: str, *names: str) -> tuple[tuple[str, str, tuple[str, ...]], ...]:
    return tuple((paper, name, (name,)) for name in names)


#: The paper items the book sets out to reproduce (the propositions, figures, tables and remarks
#: listed in ``/work/shared/papers/README.md``): ``(paper_id, item, location prefixes)``; an
#: item's rows are those whose location starts with one of its prefixes (a figure drawn from a
#: table's numbers shares the table's rows).
MISSION: tuple[tuple[str, str, tuple[str, ...]], ...] = (
    *_items(
        "zb2014",
        "Prop. 1",
        "Prop. 2",
        "Fig. 1",
        "Fig. 2",
        "Fig. 3",
        "Fig. 4",
        "Table 1",
        "Fig. 5",
        "Fig. 6",
        "Fig. 7",
        "Fig. 8",
        "Fig. 9",
    ),
    *_items("zhang2021", "Prop. 1", "Prop. 2", "Fig. 2", "Fig. 3"),
    ("zhang2021", "Fig. 4", ("Fig. 4", "Table I,")),
    ("zhang2021", "Table I", ("Table I,",)),
    ("zhang2021", "Fig. 5", ("Fig. 5", "Table II,")),
    ("zhang2021", "Table II", ("Table II,",)),
    *_items("zhang2021", "Fig. 6", "Fig. 7"),
    *_items("bz", "Prop. 1", "Prop. 2", "Solution 1", "Solution 2"),
    *_items(
        "rosa2013",
        "Fig. 1",
        "Fig. 2",
        "Prop. 1",
        "Prop. 2",
        "Prop. 3",
        "Table 1",
        "Table 2",
        "Table 3",
        "Fig. 8",
        "Fig. 9",
        "Fig. 10",
        "Fig. 11",
        "Fig. 12",
        "Remark 4",
    ),
)
#: States of a paper item (:meth:`Ledger.mission`), from its rows: every compared row agrees; the
#: least explained difference among them; nothing compared.
MISSION_STATES = (
    "reproduced",
    "differs, measured cause",
    "hypothesis tested",
    "bracketed",
    "unknown",
    "values the book sets",
    "not computed",
    "not reproducible",
    "no row",
)
_ITEM_STATE = {
    DIFFERS_UNKNOWN: "unknown",
    DIFFERS_BRACKETED: "bracketed",
    DIFFERS_HYPOTHESIS: "hypothesis tested",
    DIFFERS_MEASURED: "differs, measured cause",
}


def _in_item(location: str, prefixes: tuple[str, ...]) -> bool:
    """Whether a row's location belongs to an item: it starts with a prefix ending in a comma, or
    with another prefix followed by nothing, a space, a comma or a colon (not "Fig. 10" for
    "Fig. 1")."""
    return any(
        location.startswith(p)
        if p.endswith(",")
        else location.startswith(p) and location[len(p) : len(p) + 1] in ("", " ", ",", ":")
        for p in prefixes
    )


def item_state(rows: Sequence[LedgerRow]) -> str:
    """The state of a paper item from its rows (one of :data:`MISSION_STATES`): "reproduced" when
    every compared row agrees, else the least explained difference (unknown, then bracketed, then
    hypothesis tested, then measured cause); without a compared row, what the rows are."""
    if not rows:
        return "no row"
    compared = [r for r in rows if r.status not in (*SET_BY_BOOK, NOT_COMPUTED, NOT_REPRODUCIBLE)]
    if not compared:
        statuses = {r.status for r in rows}
        return (
            "not computed"
            if NOT_COMPUTED in statuses
            else "not reproducible"
            if NOT_REPRODUCIBLE in statuses
            else "values the book sets"
        )
    for status, state in _ITEM_STATE.items():
        if any(r.status == status for r in compared):
            return state
    return "reproduced"


# ----------------------------------------------------------------------------- building
@dataclass(frozen=True)
class Ledger:
    """All rows, in book order, and where the results came from."""

    rows: tuple[LedgerRow, ...]
    sources: dict[str, str] = field(default_factory=dict)
    #: Wall time (s) of each result computed for this ledger: not part of :meth:`to_json_dict`,
    #: whose bytes are the same on every run, at any ``--jobs`` and on any cluster.
    timings: dict[str, float] = field(default_factory=dict)

    def counts(self) -> dict[str, int]:
        """Number of rows per status (every status present, possibly 0)."""
        return {s: sum(r.status == s for r in self.rows) for s in STATUSES}

    def counts_by_paper(self) -> dict[str, dict[str, int]]:
        """``{paper_id: {status: rows}}`` for the papers of :data:`PAPERS` (every status)."""
        return {
            p: {s: sum(r.status == s and r.paper_id == p for r in self.rows) for s in STATUSES}
            for p in PAPERS
        }

    def mission(self) -> list[dict[str, Any]]:
        """Each paper item of :data:`MISSION`: ``{"paper_id", "item", "state", "rows",
        "statuses"}`` (its state from :func:`item_state`, its rows' identifiers and locations,
        the number of rows per status)."""
        out = []
        for paper, item, prefixes in MISSION:
            rows = [r for r in self.rows if r.paper_id == paper and _in_item(r.location, prefixes)]
            out.append(
                {
                    "paper_id": paper,
                    "item": item,
                    "state": item_state(rows),
                    "rows": [f"{r.id}:{'/'.join(r.path)}" for r in rows],
                    "statuses": {
                        st: n for st in STATUSES if (n := sum(r.status == st for r in rows))
                    },
                }
            )
        return out

    def mission_counts(self) -> dict[str, dict[str, int]]:
        """``{paper_id: {state: items}}`` over :data:`MISSION` (every state, possibly 0)."""
        items = self.mission()
        return {
            p: {
                st: sum(i["state"] == st and i["paper_id"] == p for i in items)
                for st in MISSION_STATES
            }
            for p in dict.fromkeys(p for p, _, _ in MISSION)
        }

    def to_json_dict(self) -> dict[str, Any]:
        """``{"counts", "counts_by_paper", "mission", "rows", "sources"}``: ``reproduce --ledger
        --json`` (no wall time: the same bytes on every run)."""
        return {
            "counts": self.counts(),
            "counts_by_paper": self.counts_by_paper(),
            "mission": {"items": self.mission(), "counts_by_paper": self.mission_counts()},
            "rows": [r.to_json_dict() for r in self.rows],
            "sources": dict(self.sources),
        }

    def mission_table(self):
        """A :func:`fdi_lib.report.table`: each paper item, its state and its rows per status."""
        rows = {
            f"{PAPERS[i['paper_id']]}, {i['item']}": [
                i["state"],
                "; ".join(f"{n} {st}" for st, n in i["statuses"].items()) or "none",
            ]
            for i in self.mission()
        }
        return table(rows, ["state", "ledger rows"], index_header="paper item")

    def mission_summary(self):
        """A :func:`fdi_lib.report.table`: paper items per state (rows) and paper (columns)."""
        by = self.mission_counts()
        rows = {
            st: [*(fmt_count(by[p][st]) for p in by), fmt_count(sum(by[p][st] for p in by))]
            for st in MISSION_STATES
        }
        rows["all items"] = [*(fmt_count(sum(by[p].values())) for p in by), fmt_count(len(MISSION))]
        return table(rows, [*(PAPERS[p] for p in by), "all"], index_header="state")

    def summary(self):
        """A :func:`fdi_lib.report.table`: claims per status (rows, the first column) and paper."""
        by = self.counts_by_paper()
        c = self.counts()
        rows = {s: [*(fmt_count(by[p][s]) for p in PAPERS), fmt_count(c[s])] for s in STATUSES}
        rows["all claims"] = [
            *(fmt_count(sum(by[p].values())) for p in PAPERS),
            fmt_count(len(self.rows)),
        ]
        return table(rows, [*PAPERS.values(), "all"], index_header="status")

    def sources_table(self):
        """A :func:`fdi_lib.report.table`: where each reproduction's result came from."""
        rows = {id: [src] for id, src in sorted(self.sources.items(), key=lambda kv: _order(kv[0]))}
        return table(rows or {"none": ["no result"]}, ["result"], index_header="reproduction")

    def to_myst(self) -> str:
        """The ledger as a MyST list-table with links (``{doc}``, ``{ref}``) to the book; the
        status is the first column (the first thing seen on a phone)."""
        lines = [
            ":::{list-table}",
            ":header-rows: 1",
            ":widths: 14 30 12 20 24",
            "",
            "* - status",
            "  - claim (paper)",
            "  - paper",
            "  - ours",
            "  - why, where",
        ]
        for r in self.rows:
            rate = _is_rate_claim(r)
            why = [_md(r.status_detail)] if r.status_detail else []
            if r.cause:
                why.append(
                    (
                        "hypothesis tested in "
                        if r.status == DIFFERS_HYPOTHESIS
                        else "cause measured in "
                    )
                    + _link(r.cause)
                )
            if (r.explain or r.where) != r.cause:
                why.append(f"shown in {_link(r.explain or r.where)}")
            if r.note:
                why.append(_md(r.note))
            lines += [
                f"* - {r.status}",
                f"  - {_md(r.claim)}",
                f"  - {_md(_fmt(r.paper, rate=rate, digits=6))}",
                f"  - {_md(_fmt(r.ours, r.ci, rate=rate))}"
                + (f" ({_md(r.role)})" if r.role else ""),
                f"  - {'; '.join(why)}",
            ]
        lines.append(":::")
        return "\n".join(lines)


def _md(text: str) -> str:
    return (
        str(text).replace("|", "\\|").replace("*", "\\*").replace("_", "\\_").replace("<", "&lt;")
    )


def _link(target: str) -> str:
    if "/" in target:
        return f"{{doc}}`/{target}`"
    if target.startswith("fig-"):
        return f"{{numref}}`{target}`"
    return f"{{ref}}`{target}`"


def _is_rate(x: Any) -> bool:
    return _is_number(x) and 0.0 <= float(x) <= 1.0


def _is_rate_claim(r: LedgerRow) -> bool:
    """A rate (a fraction with its interval, its key naming a rate): paper and ours in %."""
    return (
        "rate" in "/".join(r.path)
        and r.ci is not None
        and _is_rate(r.ours)
        and (_is_rate(r.paper) or isinstance(r.paper, str))
        and _is_rate(r.ci[0])
        and _is_rate(r.ci[1])
    )


def _fmt(
    v: Any, ci: tuple[float, float] | None = None, *, rate: bool = False, digits: int = 4
) -> str:
    """A cell: rates in % (with the interval if given), numbers with ``digits`` digits (and the
    interval), lists in brackets. The paper's and our cells of a row use the same ``rate``."""
    if v is None:
        return NA
    if isinstance(v, bool):
        return "yes" if v else "no"
    if isinstance(v, str):
        return v
    if rate and _is_rate(v):
        return fmt_rate(float(v), None if ci is None else (float(ci[0]), float(ci[1])), digits=3)
    if _is_number(v):
        out = fmt_number(v, digits)
        if ci is not None:
            out += f" [{fmt_number(ci[0], 3)}, {fmt_number(ci[1], 3)}]"
        return out
    if isinstance(v, (list, tuple)):
        return "[" + ", ".join(_fmt(x, digits=digits) for x in v) + "]"
    if isinstance(v, Mapping):
        return ", ".join(f"{k}: {_fmt(x)}" for k, x in v.items())
    return str(v)


def _paper_trials(id: str) -> int | None:
    """The paper's Monte Carlo trial count of reproduction ``id`` (``None``: a single run, or
    no count in the paper)."""
    try:
        return get(id).default_trials
    except UnknownReproductionError:
        return None


def _owner(id: str, path: tuple[str, ...], spec: Claim) -> tuple[str, tuple[str, ...]]:
    """Where the claim ``id:path`` is listed (itself unless ``spec.shown_under``)."""
    if not spec.shown_under:
        return id, path
    return spec.shown_under, spec.same_path(path) if spec.same_path else path


def _also_note(res: ReproductionResult, path: tuple[str, ...], spec: Claim) -> str:
    """What a second reproduction checking the same claim finds (shown in the owner's row)."""
    try:
        ours = spec.ours(res.headline, path) if spec.ours else _at(res.headline, path)
    except KeyError:
        return ""
    ci = spec.ci(res.headline, path) if spec.ci else _default_ci(res.headline, path)
    trials = res.settings.get("trials")
    rate = "rate" in path[0] and ci is not None and _is_rate(ours)
    value = spec.missing if ours is None and spec.missing else _fmt(ours, ci, rate=rate)
    return (
        f"also checked by {res.id}"
        + (f" on {fmt_count(trials)} trial" + "s" * (trials != 1) if trials else "")
        + f": {value}"
    )


def _row_status(
    outcome: str,
    how: str,
    *,
    spec: Claim,
    role: str | None,
    paper: Any,
    ours: Any,
    headline: Mapping[str, Any],
    path: tuple[str, ...],
    trials: int | None,
    paper_trials: int | None,
) -> tuple[str, str, str | None]:
    """The row status, its detail and its link (a cause or a hypothesis), from ``outcome``."""
    agrees = outcome in AGREES
    if agrees and (role == INPUT or spec.test == IS_INPUT):
        if spec.test == ESTIMATES_INPUT:
            return INPUT_RECOVERED, _RECOVERED, None
        return INPUT_VALUE, "a value the book sets, equal by construction", None
    if outcome == NOT_REPRODUCIBLE:
        return NOT_REPRODUCIBLE, how, None
    if paper_trials is not None and (trials is None or trials < paper_trials):
        n = "?" if trials is None else fmt_count(trials)
        return (
            NOT_COMPUTED,
            f"{_UNSCALED}: {n} of the paper's {fmt_count(paper_trials)} trials",
            None,
        )
    if outcome == NOT_COMPUTED:
        return NOT_COMPUTED, how, None
    if agrees and spec.test == ESTIMATES_INPUT:
        return INPUT_RECOVERED, _RECOVERED, None
    if agrees and (role == CALIBRATION or spec.test == IS_CALIBRATION):
        return CALIBRATION_TARGET, "the surrogate was calibrated to this value", None
    if outcome == WITHIN_SPREAD:
        return WITHIN_SPREAD, _spread_detail(headline, path), None
    if outcome != DIFFERS:
        return outcome, "", None
    if spec.cause:
        return DIFFERS_MEASURED, spec.cause_text, spec.cause
    if spec.hypothesis:
        return DIFFERS_HYPOTHESIS, spec.hypothesis_text, spec.hypothesis
    if spec.bracket is not None and spec.bracket(paper, ours, headline, path):
        return DIFFERS_BRACKETED, spec.bracket_text, None
    return (
        DIFFERS_UNKNOWN,
        (
            f"ruled out by measurement: {spec.ruled_out}"
            if spec.ruled_out
            else "no measurement of the cause yet"
        ),
        None,
    )


def _ledger_row(
    id: str,
    res: ReproductionResult,
    path: tuple[str, ...],
    spec: Claim,
    *,
    strict: bool,
    notes: list[str],
    source: str,
    trials: int | None,
    paper_trials: int | None,
) -> LedgerRow:
    """The row of :func:`build_ledger` for the claim at ``path`` of ``res.paper``, declared by
    ``spec`` (``notes``: what other claims' rows say of this one; ``source``: how ``res`` was
    obtained)."""
    paper = _at(res.paper, path)
    label = _label(id, path, spec)
    ours, missing = None, ""
    try:
        ours = spec.ours(res.headline, path) if spec.ours else _at(res.headline, path)
    except KeyError as exc:
        if strict:
            raise ModelError(f"ledger: {id} has no value of ours for {exc}") from None
        missing = f"our value ({exc}) is missing"
    ci = spec.ci(res.headline, path) if spec.ci else _default_ci(res.headline, path)
    se = spec.se(res.headline, path) if spec.se else _default_se(res.headline, path)
    outcome, how = claim_status(
        paper, ours, ci, spec, res.headline, _default_spread(res.headline, path), se
    )
    if ci is None and spec.test == BY_STANDARD_ERROR and _numbers(ours) and _numbers(se):
        ci = _se_interval(ours, se, spec.z)
    if missing and outcome not in (NOT_REPRODUCIBLE,):
        outcome, how = NOT_COMPUTED, missing
    if strict and outcome == NOT_REPRODUCIBLE and not spec.reason:
        raise ModelError(f"ledger: {id}:{'/'.join(path)} needs a rule ({how})")
    role = surrogate_role(id, res.paper, path, spec)
    status, detail, cause = _row_status(
        outcome,
        how,
        spec=spec,
        role=role,
        paper=paper,
        ours=ours,
        headline=res.headline,
        path=path,
        trials=trials,
        paper_trials=paper_trials,
    )
    note = "; ".join([how] + notes) if how != detail else "; ".join(notes)
    return LedgerRow(
        id=id,
        path=path,
        label=label,
        paper=paper,
        ours=spec.missing if ours is None and spec.missing and not missing else ours,
        ci=ci,
        status=status,
        where=chapter_of(id),
        explain=spec.explain or (chapter_of(id) if status not in AGREES else None),
        note=note,
        role=role,
        trials=trials,
        source=source,
        status_detail=detail,
        cause=cause,
        paper_trials=paper_trials,
        units=spec.units,
        test=spec.test,
        location=spec.location.format(*path[1:], fig=_fig(id), num=re.sub(r"^\D+", "", path[-1])),
    )


def build_ledger(
    results: Mapping[str, ReproductionResult],
    *,
    strict: bool = False,
    sources: Mapping[str, str] | None = None,
    own_readings: bool = False,
) -> Ledger:
    """The ledger of the given results (one per reproduction id), rows in book order.

    Parameters
    ----------
    results : mapping of id to ReproductionResult
        E.g. from :func:`collect_results`.
    strict : bool
        Raise :class:`~fdi_lib.errors.ModelError` for a claim whose our value cannot be
        found or a text claim without a check (the tests use ``strict=True``); otherwise such
        a claim is listed as "not computed" with the reason.
    sources : mapping of id to str, optional
        Where each result came from (shown in the JSON).
    own_readings : bool
        List a result's other readings of claims shown under another reproduction (rules with
        ``shown_under`` and ``same_path``, e.g. the λ-rule study, the per-radian UAV figures) as
        its own rows: the rows of that result's figure (:func:`figure_claim`), not the ledger's.
    """
    also: dict[tuple[str, tuple[str, ...]], list[str]] = {}
    for id, res in results.items():
        for path in claim_paths(res.paper):
            spec = claim_for(id, path) or _PLAIN
            owner = _owner(id, path, spec)
            if spec.same_path and owner[0] != id and (note := _also_note(res, path, spec)):
                also.setdefault(owner, []).append(note)
    rows: list[LedgerRow] = []
    for id in sorted(results, key=_order):
        res = results[id]
        paper_trials = _paper_trials(id)
        trials = res.settings.get("trials", res.settings.get("trials_per_fault"))
        trials = None if trials is None else int(trials)
        for path in claim_paths(res.paper):
            spec = claim_for(id, path)
            if spec is None:
                if strict:
                    raise ModelError(
                        f"ledger: {id}:{'/'.join(path)} has no claim declared at its "
                        f"registration (register(..., claims=...))"
                    )
                spec = _PLAIN
            if spec.shown_under and not (own_readings and spec.same_path and spec.figure_reading):
                continue
            rows.append(
                _ledger_row(
                    id,
                    res,
                    path,
                    spec,
                    strict=strict,
                    notes=also.get((id, path), []),
                    source=(sources or {}).get(id, "computed"),
                    trials=trials,
                    paper_trials=paper_trials,
                )
            )
    return Ledger(rows=tuple(rows), sources=dict(sources or {}))


def collect_results(
    *,
    max_trials: int | None = None,
    ids: Sequence[str] | None = None,
    use_cache: bool = True,
    jobs: int = 1,
) -> tuple[dict[str, ReproductionResult], dict[str, str], dict[str, float]]:
    """A result per reproduction at the book's settings (:func:`fdi_lib.reproduce.book.book_settings`,
    the seed and trials the chapters use, without options): the run the build cached, else a
    fresh one.

    Parameters
    ----------
    max_trials : int, optional
        Cap on the Monte Carlo trials of a *fresh* run (cached results keep theirs); ``None``
        runs the paper's count.
    ids : sequence of str, optional
        Restrict to these identifiers (default: all registered).
    use_cache : bool
        Read the build's run first (:func:`~fdi_lib.reproduce.registry.cached_run`).
    jobs : int
        Cores of a fresh run (no result depends on it).

    Returns
    -------
    results, sources, timings : dict, dict, dict
        The results; per id, ``"cached ..."`` or ``"computed ..."`` with the seed and trial
        count used (the same text on every run); per id computed here, its wall time in seconds
        (kept apart: it changes from run to run).
    """
    from fdi_lib.reproduce.book import book_settings  # book imports this module's registry

    wanted = [r.id for r in list_reproductions()] if ids is None else list(ids)
    results, sources, timings = {}, {}, {}
    for id in wanted:
        book = book_settings(id)
        hit = cached_run(id, seed=book.seed, trials=book.trials) if use_cache else None
        if hit is not None:
            results[id] = hit
            sources[id] = (
                f"cached in this build (seed {book.seed}"
                + (
                    f", {fmt_count(book.trials)} trial" + "s" * (book.trials != 1)
                    if book.trials
                    else ""
                )
                + ")"
            )
            continue
        trials = book.trials
        if max_trials is not None and trials is not None and trials > max_trials:
            trials = max_trials
        t0 = time.perf_counter()
        results[id] = get(id)(seed=book.seed, trials=trials, jobs=jobs)
        timings[id] = time.perf_counter() - t0
        sources[id] = (
            f"computed here (seed {book.seed}"
            + ("" if trials is None else f", {fmt_count(trials)} trial" + "s" * (trials != 1))
            + ")"
        )
    return results, sources, timings


def ledger(*, max_trials: int | None = None, strict: bool = False, jobs: int = 1) -> Ledger:
    """The ledger of every registered reproduction (see :func:`collect_results`)."""
    results, sources, timings = collect_results(max_trials=max_trials, jobs=jobs)
    return replace(build_ledger(results, strict=strict, sources=sources), timings=timings)


# ----------------------------------------------------------------------------- captions
#: Caption verbs (:func:`figure_claim`): every compared claim agrees; some do not; nothing to
#: compare (an illustration without numbers, or only values the book sets).
REPRODUCES, COMPARE, REDRAWS = "reproduces", "compare with", "redraws"
#: Differences named in a caption before "and n more".
CAPTION_ITEMS = 2


@dataclass(frozen=True)
class FigureClaim:
    """What a figure caption may say about its paper figure (:func:`figure_claim`).

    Attributes
    ----------
    verb : str
        :data:`REPRODUCES` when every compared ledger row of the reproduction is in
        :data:`AGREES` (the rows of :data:`SET_BY_BOOK`, inputs, our estimates of them and
        calibration targets, are not compared), :data:`REDRAWS` when no row is compared,
        :data:`COMPARE` otherwise.
    differs : str
        Empty, or ``"; differs: ..."`` naming briefly what does not agree (the first
        :data:`CAPTION_ITEMS` differences, then counts), to close the caption's parenthesis
        after the reproduction's identifier.
    rows : tuple of LedgerRow
        The reproduction's ledger rows.
    """

    verb: str
    differs: str
    rows: tuple[LedgerRow, ...]


def _short(r: LedgerRow) -> str:
    """The row's label without its figure or table ("Fig. N, ", "Table I (text): "): the caption
    names it."""
    return re.sub(r"^(Fig\.|Table) [^,:( ]+( \([^)]*\))?[,:] ?", "", r.label)


def _difference(r: LedgerRow) -> str:
    rate = _is_rate_claim(r)
    if r.status in DIFFERING:
        return f"{_short(r)}: paper {_fmt(r.paper, rate=rate)}, ours {_fmt(r.ours, rate=rate)}"
    return f"{_short(r)}: {r.status_detail or r.status}"


def figure_claim(result: ReproductionResult) -> FigureClaim:
    """The caption verb of the figure that plots ``result``, from its ledger rows.

    Built from ``build_ledger({result.id: result}, own_readings=True)``: the same rules, trial
    counts and causes as the claims ledger. Claims listed under another reproduction
    (``shown_under``) belong to that figure, except this result's own reading of them
    (``same_path``: the per-radian UAV figures), which its figure shows.
    """
    rows = build_ledger({result.id: result}, own_readings=True).rows
    compared = [r for r in rows if r.status not in SET_BY_BOOK]
    if not compared:
        return FigureClaim(REDRAWS, "", rows)
    bad = [r for r in compared if r.status not in AGREES]
    if not bad:
        return FigureClaim(REPRODUCES, "", rows)
    unscaled = [r for r in bad if r.status_detail.startswith(_UNSCALED)]
    shown = [r for r in bad if r not in unscaled]
    parts = []
    if shown:
        items = [_difference(r) for r in shown[:CAPTION_ITEMS]]
        if len(shown) > CAPTION_ITEMS:
            items.append(f"{fmt_count(len(shown) - CAPTION_ITEMS)} more in the claims ledger")
        parts.append("differs: " + "; ".join(items))
    if unscaled:  # not a difference: no status at all until the paper's trial count is run
        parts.append(
            f"{fmt_count(len(unscaled))} claim{'s' * (len(unscaled) > 1)} "
            + unscaled[0].status_detail
        )
    return FigureClaim(COMPARE, "; " + "; ".join(parts), rows)


def glue_caption(result: ReproductionResult) -> FigureClaim:
    """Glue the caption words of ``result``'s figure for its ``mystnb: figure: caption:``.

    Keys ``caption-<id>-verb`` (:attr:`FigureClaim.verb`) and ``caption-<id>-differs``
    (:attr:`FigureClaim.differs`), used as ``{glue:text}`caption-<id>-verb` paper Fig. N of
    {cite:t}`key` (<id>{glue:text}`caption-<id>-differs`)``. Returns the claim.
    """
    from fdi_lib.report import glue

    claim = figure_claim(result)
    glue(f"caption-{result.id}-verb", claim.verb, display=False)
    glue(f"caption-{result.id}-differs", claim.differs, display=False)
    return claim
