"""The claims ledger: every value the four papers state, ours next to it, and a computed status.

The paper's values are read from the registry (the ``paper`` dictionary of each
reproduction's result); our values from its ``headline``. A *claim* is one leaf of a
``paper`` dictionary that states something (``None``, ``"not stated"`` and
``"illustration, no numbers"`` state nothing); a claim listed by two reproductions (a value
of Table I also checked by ``zhang2021-lambda-rule``) is one row, under the reproduction that
runs the paper's setting (:attr:`ClaimSpec.shown_under`). Its status is **computed**, never
typed, and is one of the fixed vocabulary :data:`STATUSES`:

``reproduced``
    our value equals the paper's within the claim's tolerance (default: relative
    :data:`DEFAULT_RTOL`, the precision of a value printed with three or four significant
    digits), or satisfies the paper's inequality (``"< 1"``), or passes the claim's
    stated check (for qualitative statements such as "grows linearly in k");
``within interval``
    not equal, but the paper's value lies in our 95 % interval (stochastic claims);
``within spread``
    a claim about one run of the paper (a single alarm time), not equal to our run, but inside
    the 95 % range of our run-to-run distribution (headline key ``<key>_spread95``); the
    detail gives the percentile of the paper's value in it (``<key>_paper_percentile``) and
    the number of runs (``spread_runs``);
``differs, measured cause``
    neither, and the claim's rule names a section of the book that *measures* the cause
    (:attr:`ClaimSpec.cause`, a label; ``cause`` in the JSON);
``differs, cause unknown``
    neither, and no measurement of the cause exists (the row still links to where the
    difference is shown, ``explanation``);
``input``
    a value the book sets (a Table 1 value, a fault amplitude, an onset, a true leak
    position): equal by construction, never counted as reproduced;
``calibration target``
    a value the surrogate model was fitted to (close by construction);
``not computed``
    we have no value to compare (the detail says why), or the result comes from fewer
    Monte Carlo trials than the paper's count (:attr:`Reproduction.default_trials`): a
    stochastic status is only read from a run at the paper's scale ("not computed at paper
    scale", e.g. the ledger page executed on its own with :data:`FALLBACK_TRIALS`);
``not reproducible``
    the claim cannot be checked here (the detail says why, e.g. a timing on the authors'
    MATLAB machine).

The first three are :data:`AGREES`: a figure caption says "reproduces paper Fig. N" only when
every compared row of its reproduction is one of them (:func:`figure_claim`).

**Renamed status.** Until this schema the ledger had a single ``differs``; it is now split
into ``differs, measured cause`` and ``differs, cause unknown`` (:data:`DIFFERING`); the rows
that were ``reproduced`` because the book sets the value are now ``input`` or ``calibration
target``. ``claim_status`` still returns the plain comparison (:data:`DIFFERS`), which
:func:`build_ledger` refines.

Rows (``python -m fdi_lib reproduce --ledger --json``: ``{"counts", "counts_by_paper",
"rows", "sources"}``) have the keys ``id``, ``paper_id`` (``zb2014``, ``zhang2021``, ``bz``,
``rosa2013``), ``key`` (the claim's path in the ``paper`` dictionary), ``claim`` (a label
naming the paper: "Zhang & Basseville 2014, Fig. 8: ..."), ``paper`` (the paper's value, in
its own units and indexing), ``ours`` (same units), ``ci95``, ``status``, ``status_detail``
(why, for every status but ``reproduced``/``within interval``), ``cause`` (the label of the
measurement, ``differs, measured cause`` only), ``where`` (the chapter), ``explanation``
(label or document showing the claim), ``note`` (how the status was decided: tolerance,
inequality, check), ``surrogate`` (``calibration``/``prediction``/``input`` on a surrogate
model, see below), ``trials`` (of our result), ``paper_trials`` (the paper's count, ``None``
for a single run) and ``source``.

The ledger's own data (:data:`SPECS`) give each claim a human label, its tolerance or check,
where it is shown and what measures a difference. For reproductions on a surrogate model
each row also says what the paper's number is to the model (:func:`surrogate_role`): a value
the surrogate was *calibrated* to (``calibration``), a *prediction* of it, or an *input* set
into it (a fault size, an onset). A reproduction that declares this itself, with the lists
``paper["calibrated_to"]`` and ``paper["predictions"]`` (:data:`ROLE_KEYS`, never claims),
is the only source; :data:`SPECS` roles apply to the others. The status of a row whose
paper value is an input (by either source) is ``input``, of a calibration value that we meet
``calibration target``.
A leaf without a rule in :data:`SPECS` still appears (numbers and inequalities need no rule);
a text claim without a check appears as ``not reproducible`` with the reason "no check
defined", and the tests fail until one is written.

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

__all__ = ["STATUSES", "ROLE_KEYS", "CALIBRATION", "PREDICTION", "INPUT", "surrogate_role", "FALLBACK_TRIALS",
           "REPRODUCED", "WITHIN", "WITHIN_SPREAD", "DIFFERS", "DIFFERS_MEASURED", "DIFFERS_UNKNOWN",
           "INPUT_VALUE", "CALIBRATION_TARGET", "NOT_COMPUTED", "NOT_REPRODUCIBLE", "AGREES", "DIFFERING",
           "DEFAULT_RTOL", "PAPERS", "ClaimSpec", "LedgerRow", "Ledger", "SPECS", "BOOK_ORDER", "NO_VALUE",
           "claim_paths", "claim_status", "build_ledger", "collect_results", "ledger", "FigureClaim",
           "figure_claim", "glue_caption", "REPRODUCES", "COMPARE", "REDRAWS", "CAPTION_ITEMS"]

REPRODUCED, WITHIN, WITHIN_SPREAD = "reproduced", "within interval", "within spread"
DIFFERS_MEASURED, DIFFERS_UNKNOWN = "differs, measured cause", "differs, cause unknown"
INPUT_VALUE, CALIBRATION_TARGET = "input", "calibration target"
NOT_COMPUTED, NOT_REPRODUCIBLE = "not computed", "not reproducible"
#: The statuses of a row, in the order of the summaries.
STATUSES = (REPRODUCED, WITHIN, WITHIN_SPREAD, DIFFERS_MEASURED, DIFFERS_UNKNOWN, INPUT_VALUE,
            CALIBRATION_TARGET, NOT_COMPUTED, NOT_REPRODUCIBLE)
#: Statuses under which our result agrees with the paper's claim.
AGREES = (REPRODUCED, WITHIN, WITHIN_SPREAD)
#: Statuses of a difference.
DIFFERING = (DIFFERS_MEASURED, DIFFERS_UNKNOWN)
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
PAPERS = {"zb2014": "Zhang & Basseville 2014", "zhang2021": "Zhang 2021",
          "bz": "Basseville & Zhang 2015", "rosa2013": "Rosa & Silvestre 2013",
          "windturbine": "Wind-turbine benchmark (Odgaard et al.)"}

#: Reproductions in the order of the book (chapters in the order of the table of contents);
#: an identifier missing here comes last, in alphabetical order.
BOOK_ORDER = (
    "zb2014-fig1", "zb2014-fig2", "zb2014-fig3", "zb2014-fig4", "zb2014-table1", "zb2014-fig5",
    "zb2014-fig6", "zb2014-fig7", "zb2014-fig8", "zb2014-fig9",
    "zhang2021-fig2", "zhang2021-fig3", "zhang2021-table1", "zhang2021-table2",
    "zhang2021-lambda-rule", "zhang2021-fig6",
    "zhang2021-fig7", "zhang2021-example2-interventions",
    "bz-whiteness", "bz-solution1", "bz-solution2",
    "rosa2013-fig1", "rosa2013-fig2", "rosa2013-fig8", "rosa2013-fig9", "rosa2013-fig10",
    "rosa2013-fig11", "rosa2013-fig12", "rosa2013-fig11-rad", "rosa2013-fig12-rad",
    "rosa2013-timing", "windturbine-scoreboard", "windturbine-accommodation",
)

#: Chapter of each reproduction (by identifier prefix): where the claim is shown.
CHAPTERS = (
    ("zb2014-fig1", "book/zb2014/signature"), ("zb2014-fig2", "book/zb2014/signature"),
    ("zb2014-fig3", "book/zb2014/glr"), ("zb2014-fig4", "book/zb2014/glr"),
    ("zb2014-", "book/zb2014/pipeline"), ("zhang2021-", "book/zhang2021/sparse"),
    ("bz-", "book/bz/parametric-nonparametric"), ("rosa2013-", "book/rosa2013/svo"),
    ("windturbine-", "book/windturbine/benchmark"),
)

#: Reproductions run on a surrogate or reconstructed model (the papers' models are not public).
SURROGATE_IDS = ("zb2014-table1", "zb2014-fig5", "zb2014-fig6", "zb2014-fig7", "zb2014-fig8",
                 "zb2014-fig9", "zhang2021-fig6", "zhang2021-fig7", "rosa2013-fig8",
                 "rosa2013-fig9", "rosa2013-fig10", "rosa2013-fig11", "rosa2013-fig12",
                 "rosa2013-fig11-rad", "rosa2013-fig12-rad")
#: Surrogate roles of a paper value: the model was fitted to it, computes it, or takes it as given.
CALIBRATION, PREDICTION, INPUT = "calibration", "prediction", "input"


@dataclass(frozen=True)
class ClaimSpec:
    """The ledger's rule for the claims matching a pattern (see :data:`SPECS`).

    Attributes
    ----------
    label : str
        What the claim is, for a reader; ``{0}``, ``{1}`` ... are the parts of the path
        after the first key (e.g. the onset ``r``).
    rtol, atol : float
        Tolerance of "reproduced" for numbers.
    check : callable, optional
        ``check(paper_value, ours, headline) -> bool`` for a qualitative claim; ``criterion``
        says in words what it tests.
    value : callable, optional
        ``value(paper_text) -> number``: the number a text claim states (``"0 (Prop. 2)"``).
    ours : callable, optional
        ``ours(headline, path) -> value`` when our value is not ``headline`` at the same path.
    ci : callable, optional
        ``ci(headline, path) -> (low, high) or None``; default: ``<key>_ci`` next to the key,
        or ``ci95`` next to a ``rate``.
    explain : str, optional
        Label (``sec-...``, ``fig-...``) or document (``book/...``) where the claim is shown
        and discussed; default: the chapter of the reproduction. Not a cause.
    cause : str, optional
        Label of the section that *measures* the cause of a difference; a differing row with
        a cause is "differs, measured cause", without one "differs, cause unknown".
    cause_if : callable, optional
        ``cause_if(paper_value, ours, headline, path) -> bool``: the cause applies to this row
        only when it holds (e.g. the paper's rate lies between two readings of a rule that the
        section measures); ``cause_text`` says in words what was measured. ``ruled_out``
        names the candidate causes measured and excluded, for a difference whose cause is
        unknown.
    missing : str, optional
        What our value ``None`` means (e.g. "not detected in the 6 s record"): a result that
        differs from a number. Without it, ``None`` means we have no value ("not computed").
    reason : str, optional
        Why the claim is not reproducible (the status is then "not reproducible").
    role : str, optional
        ``"input"`` if the paper's value is set into the model, ``"calibration"`` if the model
        was fitted to it, ``"prediction"`` (default) otherwise; read for surrogate reproductions
        that do not declare :data:`ROLE_KEYS`, and ``"input"`` (status "input") for any.
    shown_under : str, optional
        Identifier under which the same claim is listed (results sharing one ``paper`` dict,
        or the same paper value checked twice); ``same_path(path)`` gives its path there when
        it differs. The claim is then one row, at that place.
    """

    label: str = ""
    rtol: float = DEFAULT_RTOL
    atol: float = 0.0
    check: Callable[[Any, Any, Mapping[str, Any]], bool] | None = None
    criterion: str = ""
    value: Callable[[Any], Any] | None = None
    ours: Callable[[Mapping[str, Any], tuple[str, ...]], Any] | None = None
    ci: Callable[[Mapping[str, Any], tuple[str, ...]], Any] | None = None
    explain: str | None = None
    cause: str | None = None
    cause_if: Callable[[Any, Any, Mapping[str, Any], tuple[str, ...]], bool] | None = None
    cause_text: str = ""
    ruled_out: str = ""
    missing: str | None = None
    reason: str | None = None
    role: str | None = None
    shown_under: str | None = None
    same_path: Callable[[tuple[str, ...]], tuple[str, ...]] | None = None


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

        return _jsonable({"id": self.id, "paper_id": self.paper_id, "key": "/".join(self.path),
                          "claim": self.claim, "paper": self.paper, "ours": self.ours,
                          "ci95": None if self.ci is None else list(self.ci), "status": self.status,
                          "status_detail": self.status_detail, "cause": self.cause,
                          "where": self.where, "explanation": self.explain, "note": self.note,
                          "surrogate": self.role, "trials": self.trials,
                          "paper_trials": self.paper_trials, "source": self.source})


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
            if (isinstance(ci, (list, tuple)) and len(ci) == 2
                    and all(isinstance(c, numbers.Real) for c in ci)):
                return float(ci[0]), float(ci[1])
    return None


def _default_spread(headline: Mapping[str, Any], path: tuple[str, ...]
                    ) -> tuple[float, float] | None:
    """``<key>_spread95`` next to a single-run key: the 95 % range of our runs, else ``None``."""
    spath = (*path[:-1], path[-1] + "_spread95")
    if _has(headline, spath):
        sp = _at(headline, spath)
        if isinstance(sp, (list, tuple)) and len(sp) == 2 and all(_is_number(c) for c in sp):
            return float(sp[0]), float(sp[1])
    return None


def _spread_detail(headline: Mapping[str, Any], path: tuple[str, ...]) -> str:
    """"the paper's run is at the 71st percentile of our 1000 runs" (keys ``<key>_paper_percentile``
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


def claim_status(paper: Any, ours: Any, ci: tuple[float, float] | None = None,
                 spec: ClaimSpec = ClaimSpec(), headline: Mapping[str, Any] | None = None,
                 spread: tuple[float, float] | None = None) -> tuple[str, str]:
    """The outcome of comparing one claim with our value, and a note saying how it was decided.

    The outcome is :data:`REPRODUCED`, :data:`WITHIN`, :data:`WITHIN_SPREAD`, :data:`DIFFERS`,
    :data:`NOT_COMPUTED` (we have no value) or :data:`NOT_REPRODUCIBLE`; :func:`build_ledger`
    turns it into a row status (input, calibration target, a difference's cause, the paper's
    trial count).

    Parameters
    ----------
    paper : number, list of numbers, bool or str
        The paper's value: a number (or list), ``"< x"``-type inequality, ``"about x"``,
        or a statement checked by ``spec.check``.
    ours : any
        Our value (``None`` when we have none; with ``spec.missing``, ``None`` is a result,
        e.g. never detected, that differs from any number).
    ci : (float, float), optional
        Our 95 % interval of a scalar value.
    spec : ClaimSpec
        Tolerances, check, or the reason the claim is not reproducible.
    headline : dict, optional
        The reproduction's headline, passed to ``spec.check``.
    spread : (float, float), optional
        95 % range of our run-to-run distribution of a single-run value.
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
        return claim_status(spec.value(paper), ours, ci, replace(spec, value=None), headline, spread)
    if isinstance(paper, str):
        m, a = _INEQ.match(paper), _ABOUT.match(paper)
        if m:
            vals = _numbers(ours)
            if vals is None:
                return NOT_COMPUTED, f"no number of ours to compare with {paper}"
            op, bound = m.group(1), float(m.group(2))
            holds = {"<": lambda v: v < bound, "<=": lambda v: v <= bound,
                     ">": lambda v: v > bound, ">=": lambda v: v >= bound}[op]
            return (REPRODUCED if all(holds(v) for v in vals) else DIFFERS), f"inequality {paper}"
        if a:
            return claim_status(float(a.group(1)), ours, ci, spec, headline, spread)
        if ours == paper:
            return REPRODUCED, "same text"
        return NOT_REPRODUCIBLE, "no check defined for this statement"
    if isinstance(paper, bool) or isinstance(ours, bool):
        return (REPRODUCED if paper == ours else DIFFERS), "equality"
    p, o = _numbers(paper), _numbers(ours)
    if p is None:
        return (REPRODUCED if paper == ours else DIFFERS), "equality"
    if o is None or len(o) != len(p):
        return DIFFERS, "not comparable"
    tol_note = f"tolerance {fmt_number(spec.rtol)} relative" + (
        f", {fmt_number(spec.atol)} absolute" if spec.atol else "")
    if all(math.isclose(a, b, rel_tol=spec.rtol, abs_tol=spec.atol) for a, b in zip(o, p)):
        return REPRODUCED, tol_note
    if ci is not None and len(p) == 1 and ci[0] <= p[0] <= ci[1]:
        return WITHIN, "paper value inside our 95 % interval"
    if spread is not None and len(p) == 1 and spread[0] <= p[0] <= spread[1]:
        return WITHIN_SPREAD, "paper's single run inside the 95 % range of our runs"
    return DIFFERS, tol_note + ("; outside our 95 % interval" if ci is not None else "") + (
        "; outside the 95 % range of our runs" if spread is not None else "")


# ----------------------------------------------------------------------------- the ledger's data
def _ours_at(*keys: str) -> Callable[[Mapping[str, Any], tuple[str, ...]], Any]:
    """Our value at ``keys`` followed by the claim path after its first key."""
    return lambda h, path: _at(h, (*keys, *path[1:]))


def _ci_of(*keys: str) -> Callable[[Mapping[str, Any], tuple[str, ...]], Any]:
    """Interval at ``keys`` followed by the claim path after its first key (tables with one
    ``ci95`` dictionary per column, possibly per reading of a rule)."""
    def ci(h: Mapping[str, Any], path: tuple[str, ...]) -> tuple[float, float] | None:
        at = (*keys, *path[1:])
        v = _at(h, at) if _has(h, at) else None
        return None if v is None else (float(v[0]), float(v[1]))
    return ci


def _count_ci(h: Mapping[str, Any], path: tuple[str, ...]) -> tuple[float, float] | None:
    """95 % interval of the false-alarm *count*: the rate's interval times the number of runs."""
    r = h.get("false_alarm_rate", {})
    ci, n = r.get("ci95"), r.get("n")
    if ci is None or n is None or None in ci:
        return None
    return ci[0] * n, ci[1] * n


def _in_ci(key: str) -> Callable[[Any, Any, Mapping[str, Any]], bool]:
    """Check: our value lies in the 95 % interval of ``headline[key]`` (no effect of f)."""
    def check(paper: Any, ours: Any, h: Mapping[str, Any]) -> bool:
        lo, hi = h[key + "_ci"]
        return lo <= float(ours) <= hi
    return check


def _between_readings(paper: Any, ours: Any, h: Mapping[str, Any], path: tuple[str, ...]) -> bool:
    """The paper's rate lies between our log-width and linear-width readings of the λ rule,
    on the same trials (a difference of reading measured by the chapter)."""
    lin = h.get("success_rate_linear", {}).get(path[-1])
    return lin is not None and min(ours, lin) <= paper <= max(ours, lin)


_READINGS_TEXT = ("the paper's rate lies between our log-width and linear-width readings of the "
                  "rule for λ on the same trials")
_RULED_OUT = ("our readings of the rule for λ (the paper's rate lies outside them), the unknown "
              "input d_k, and at q = 15 the initial state")
_UNSCALED = "not computed at paper scale"
_NOT_DETECTED = "not detected in any run of the 6 s record"
_NOT_ISOLATED = "not isolated in any run of the 6 s record"
_LOG12 = math.log10(1.2)
_WINDOW_END = 201 + 100

#: The ledger's rules, keyed by ``"id:path"`` patterns (``fnmatch``; the first match wins).
#: Labels: ``{0}``, ``{1}`` are the path parts after the first key, ``{fig}`` the figure,
#: ``{num}`` the number in the last path part (``"q15"`` -> ``15``).
SPECS: dict[str, ClaimSpec] = {
    # -- Zhang & Basseville 2014, Section 6.1
    "zb2014-fig1:unstable_eigenvalue": ClaimSpec(
        "§6.1: the unstable eigenvalue of F", explain="sec-zb-fig1-bound",
        cause="sec-zb-fig1-bound",
        cause_text="the printed F is triangular, with eigenvalues 0.5 and 1.2, and we use it; "
                   "the section checks every one-entry misprint that gives the quoted value"),
    "zb2014-fig1:gamma_norm_max/*": ClaimSpec(
        "Fig. 1: ‖Γ_k‖ stays under 1, impulse at r = {0}", explain="sec-zb-fig1-bound",
        cause="sec-zb-fig1-bound",
        cause_text="‖Γ_(r+1)‖ ≥ ‖F e₂‖ > 1 for the printed matrices, whatever P₀, Q, R"),
    "zb2014-fig2:alpha_log10_norm_final/*": ClaimSpec(
        "Fig. 2: log ‖α_k(r)‖ grows linearly in k, r = {0}", ours=_ours_at("alpha_log10_slope"),
        check=lambda p, o, h: abs(o - _LOG12) <= 0.01 * _LOG12,
        criterion="fitted slope of log₁₀‖α_k(r)‖ is log₁₀ 1.2 within 1 %"),
    "zb2014-fig*:onset_estimate": ClaimSpec(
        "{fig}: onset estimate r̂ at the peak of l_k (sums from j = r̂, see the convention)",
        explain="sec-zb-glr-onset"),
    "zb2014-fig*:glr_argmax_time": ClaimSpec(
        "{fig}: l_k is largest while the onset is in the window",
        check=lambda p, o, h: 201 <= o <= _WINDOW_END, criterion="201 ≤ argmax l_k ≤ 301"),
    "zb2014-fig*:theta_estimate": ClaimSpec(
        "{fig}: fault estimate θ̂ at the peak of l_k", explain="sec-zb-glr-figs",
        ci=lambda h, p: None, rtol=0.0, atol=0.0,
        check=lambda p, o, h: all(lo <= t <= hi for t, (lo, hi) in zip(p, h["theta_estimate_ci"])),
        criterion="each component of the paper's θ in our 95 % interval (θ̂ ± 1.96 σ from C_k(r̂))"),
    "zb2014-fig3:fault_visibility": ClaimSpec(
        "Fig. 3: the fault shows on the innovation only briefly after 201 (ours: samples "
        "above the pre-fault maximum)",
        ours=lambda h, p: h["innovation_samples_above_premax"],
        check=lambda p, o, h: o <= 10, criterion="at most 10 samples above the pre-fault max |ε_k|"),
    "zb2014-fig4:fault_visibility": ClaimSpec(
        "Fig. 4: the fault is hardly visible on the innovation (ours: largest |ε_k|/σ_k "
        "from 201)", explain="sec-zb-glr-figs",
        ours=lambda h, p: h["innovation_max_sigma_after_fault"],
        check=lambda p, o, h: o <= h["innovation_max_sigma_before_fault"],
        criterion="largest |ε_k|/σ after 201 within the pre-fault range"),
    # -- Zhang & Basseville 2014, Section 6.2 (surrogate pipeline; roles declared by the
    #    reproductions' ``calibrated_to`` / ``predictions``)
    "zb2014-table1:G0_1_nominal": ClaimSpec("Table 1: nominal G₀(1)"),
    "zb2014-table1:G0_1_fault1": ClaimSpec("Table 1: G₀(1) under fault 1"),
    "zb2014-table1:Gp_1_nominal": ClaimSpec("Table 1: nominal G_p(1)"),
    "zb2014-table1:Gp_1_fault2": ClaimSpec("Table 1: G_p(1) under fault 2"),
    "zb2014-table1:theta_fault1": ClaimSpec("Table 1: θ of fault 1"),
    "zb2014-table1:theta_fault2": ClaimSpec("Table 1: θ of fault 2"),
    "zb2014-fig5:alarm_time_min": ClaimSpec("Fig. 5: alarm time (min), one run of fault 1",
                                            explain="fig-pipeline-fig5"),
    "zb2014-fig5:onset_estimate_min": ClaimSpec("Fig. 5: onset estimate (min), one run",
                                                explain="fig-pipeline-fig5"),
    "zb2014-fig5:detection_delay_min": ClaimSpec("Fig. 5: detection delay (min), one run",
                                                 explain="fig-pipeline-fig5"),
    "zb2014-fig6:alarm_time_min": ClaimSpec(
        "Fig. 6: alarm time (min), fault 1 doubled", explain="fig-pipeline-fig6",
        cause="sec-pipeline-calibration-sensitivity",
        cause_text="the alarm time and the delay depend on the calibrated state2_scale of the "
                   "surrogate"),
    "zb2014-fig6:detection_delay_min": ClaimSpec(
        "Fig. 6: detection delay (min), fault 1 doubled", explain="fig-pipeline-fig6",
        cause="sec-pipeline-calibration-sensitivity",
        cause_text="the alarm time and the delay depend on the calibrated state2_scale of the "
                   "surrogate"),
    "zb2014-fig7:false_alarms": ClaimSpec("Fig. 7: false alarms in 2 × 1000 runs", ci=_count_ci,
                                          explain="fig-pipeline-fig7"),
    # the same claim as the count (7 of 2000 runs): one row
    "zb2014-fig7:false_alarm_rate/*": ClaimSpec(shown_under="zb2014-fig7",
                                                same_path=lambda p: ("false_alarms",)),
    "zb2014-fig7:missed/*": ClaimSpec("Fig. 7: runs in which fault {0} is never detected",
                                      explain="fig-pipeline-fig7"),
    "zb2014-fig8:type1_rate/*/rate": ClaimSpec(
        "Fig. 8: type I error of the minmax test, fault {0}", explain="fig-pipeline-fig8",
        cause="sec-pipeline-isolation-window",
        cause_text="isolating with the samples up to the alarm (the paper's §4.3) or up to the "
                   "end of the record changes the error rates"),
    "zb2014-fig8:type2_rate/*/rate": ClaimSpec(
        "Fig. 8: type II error of the minmax test, fault {0}", explain="fig-pipeline-fig8",
        cause="sec-pipeline-isolation-window",
        cause_text="isolating with the samples up to the alarm (the paper's §4.3) or up to the "
                   "end of the record changes the error rates"),
    "zb2014-fig8:threshold_dof": ClaimSpec(
        "Fig. 8: 6.6349 is a 99 % χ² quantile, 1 degree of freedom (caption) or 2 (text)",
        check=lambda p, o, h: o == 1, criterion="6.6349 is the 99 % quantile of χ²(1): the caption",
        explain="fig-pipeline-fig8", role=INPUT),
    "zb2014-fig9:glr_level_over_threshold": ClaimSpec(
        "Fig. 9: l_k after the leak, in thresholds (paper: about 50)", rtol=0.5,
        explain="fig-pipeline-fig9"),
    # -- Zhang 2021
    "zhang2021-fig2:flat_size": ClaimSpec("Fig. 2: support size on the flat range of λ"),
    "zhang2021-fig3:same_support_in_range": ClaimSpec(
        "Fig. 3: same support for every λ of the flat range"),
    "zhang2021-fig3:support_equals_true": ClaimSpec(
        "Fig. 3: the selected support is the true one",
        ours=lambda h, p: sorted(h["support"]) == sorted(h["true_support"])),
    "zhang2021-table1:success_rate/*": ClaimSpec(
        "Table I: success rate, q = {0}", ci=_ci_of("ci95"), explain="zhang2021-lambda-rule",
        cause="sec-zhang2021-oracles", cause_if=_between_readings, cause_text=_READINGS_TEXT,
        ruled_out=_RULED_OUT),
    "zhang2021-table2:success_rate/*": ClaimSpec(
        "Table II: success rate, r = {0}", ci=_ci_of("ci95"), explain="zhang2021-lambda-rule",
        cause="sec-zhang2021-oracles", cause_if=_between_readings, cause_text=_READINGS_TEXT,
        ruled_out=_RULED_OUT),
    "zhang2021-table2:snr_db/*": ClaimSpec("Table II: SNR of outputs 1 and 2 (dB), r = {0}",
                                           rtol=0.0, atol=0.5, explain="fig-zhang2021-5"),
    # the values of Tables I-II that the λ-rule study checks again on fewer trials: one row,
    # under the table (the paper's trial count)
    "zhang2021-lambda-rule:success_rate/q*": ClaimSpec(
        shown_under="zhang2021-table1", same_path=lambda p: (p[0], p[1][1:]),
        ours=_ours_at("success_rate", "log"), ci=_ci_of("ci95", "log")),
    "zhang2021-lambda-rule:success_rate/r*": ClaimSpec(
        shown_under="zhang2021-table2", same_path=lambda p: (p[0], p[1][1:]),
        ours=_ours_at("success_rate", "log"), ci=_ci_of("ci95", "log")),
    "zhang2021-fig6:flat_size": ClaimSpec(
        "Fig. 6: support size on the flat range of λ", explain="fig-zhang2021-6",
        cause="sec-zhang2021-example2-causes",
        cause_text="the input of the surrogate: interventions on the input, not on the noise, "
                   "change the selected support"),
    # in the paper's own indexing (its 10th and 15th components)
    "zhang2021-fig7:support_1based": ClaimSpec(
        "Fig. 7: selected leak parameters (1-based)", explain="fig-zhang2021-7",
        cause="sec-zhang2021-example2-causes",
        cause_text="the input of the surrogate: interventions on the input, not on the noise, "
                   "change the selected support"),
    "zhang2021-fig7:true_support_1based": ClaimSpec("Fig. 7: true leak parameters (1-based)"),
    # -- Basseville & Zhang (no numerical example in the paper: our designed one)
    "bz-whiteness:lb_reject_rate_kitanidis": ClaimSpec(
        "Prop. 2: the Kitanidis innovation is white (Ljung-Box rejects 5 % at level 5 %)",
        value=lambda p: 0.05, explain="fig-bz-whiteness", cause="fig-bz-whiteness",
        cause_text="the closed-form lag-one correlation of the Kitanidis innovation is not 0, "
                   "and the Monte Carlo estimate brackets it"),
    "bz-whiteness:lag1_corr_empirical": ClaimSpec(
        "Prop. 2: lag-1 correlation of the Kitanidis innovation is 0", value=lambda p: 0.0,
        explain="fig-bz-whiteness", cause="fig-bz-whiteness",
        cause_text="the closed-form lag-one correlation of the Kitanidis innovation is not 0, "
                   "and the Monte Carlo estimate brackets it"),
    "bz-whiteness:cov_rel_error_kitanidis": ClaimSpec(
        "eq. (45): the Kitanidis innovation has covariance H P_k Hᵀ + R_k",
        check=lambda p, o, h: o < 0.05, criterion="relative error of the empirical covariance < 5 %"),
    "bz-solution1:glr_detection_rate_theta_with_f": ClaimSpec(
        "§3.2: the GLR on the Kitanidis innovation detects θ whatever f",
        check=_in_ci("glr_detection_rate_theta"),
        criterion="detection rate with f inside the 95 % interval of the rate without f"),
    "bz-solution1:glr_alarm_rate_f_only": ClaimSpec(
        "§3.2: f alone does not raise the GLR", check=_in_ci("glr_false_alarm_rate"),
        criterion="alarm rate under f alone inside the 95 % interval of the false-alarm rate"),
    "bz-solution1:nonparametric_detection_rate_f": ClaimSpec(
        "§3.3: the energy test detects f", check=lambda p, o, h: o >= 0.95,
        criterion="detection rate of f at least 95 %"),
    "bz-solution2:tracking_rmse": ClaimSpec(
        "§4: RLS with forgetting tracks a slowly varying θ_k",
        check=lambda p, o, h: max(o) < 0.05,
        criterion="tracking RMSE below 0.05 for every forgetting factor"),
    "bz-solution2:detection_rate": ClaimSpec(
        "§4: the energy of the tracking error detects f",
        check=lambda p, o, h: min(o) >= 0.95,
        criterion="detection rate of f at least 95 % for every forgetting factor"),
    # -- Rosa & Silvestre 2013 (reconstructed UAV model; "-rad": elevator read per radian)
    "rosa2013-fig*:fault_amplitude_deg": ClaimSpec("{fig}: fault amplitude (deg)", role=INPUT),
    "rosa2013-fig*:onset_s": ClaimSpec("{fig}: fault onset (s)", role=INPUT),
    "rosa2013-fig*:ramp_s": ClaimSpec("{fig}: ramp duration (s)", role=INPUT),
    "rosa2013-fig8:detection_time_ms": ClaimSpec("{fig}: detection time (ms)",
                                                 explain="fig-rosa2013-8"),
    "rosa2013-fig9:detection_time_ms": ClaimSpec("{fig}: detection time (ms)",
                                                 explain="fig-rosa2013-9"),
    "rosa2013-fig10:detection_time_ms": ClaimSpec("{fig}: detection time (ms)",
                                                  explain="fig-rosa2013-10"),
    "rosa2013-fig11:detection_time_ms/*/*": ClaimSpec(
        "{fig}: mean detection time (ms), {0}, {1}", explain="fig-rosa2013-11",
        missing=_NOT_DETECTED),
    # the other reading of the elevator (per radian) checks the same paper claims: a note in the
    # row of the reading per degree (one row per claim), its own statuses in its caption
    "rosa2013-fig11-rad:detection_time_ms/*/*": ClaimSpec(
        "{fig}: mean detection time (ms), {0}, {1}", explain="fig-rosa2013-11-rad",
        missing=_NOT_DETECTED, shown_under="rosa2013-fig11", same_path=lambda p: p),
    "rosa2013-fig12:detection_time_ms/*/*": ClaimSpec(shown_under="rosa2013-fig11"),
    "rosa2013-fig12-rad:detection_time_ms/*/*": ClaimSpec(shown_under="rosa2013-fig11"),
    "rosa2013-fig11:isolation_time_ms/*/*": ClaimSpec(shown_under="rosa2013-fig12"),
    "rosa2013-fig11-rad:isolation_time_ms/*/*": ClaimSpec(shown_under="rosa2013-fig12"),
    "rosa2013-fig12:isolation_time_ms/*/*": ClaimSpec(
        "{fig}: mean isolation time (ms), {0}, {1}", explain="fig-rosa2013-12",
        missing=_NOT_ISOLATED),
    "rosa2013-fig12-rad:isolation_time_ms/*/*": ClaimSpec(
        "{fig}: mean isolation time (ms), {0}, {1}", explain="fig-rosa2013-12-rad",
        missing=_NOT_ISOLATED, shown_under="rosa2013-fig12", same_path=lambda p: p),
    "rosa2013-timing:step_ms": ClaimSpec(
        "Remark 4: 5 to 200 ms per SVO step (exact rule) depending on N",
        ours=lambda h, p: h.get("step_ms_exact"),
        reason="wall time of the authors' MATLAB code on their machine; ours (the exact rule, "
               "median per N) is shown for scale"),
    # -- the wind-turbine benchmark (Odgaard, Stoustrup & Kinnaert 2009/2013)
    "windturbine-scoreboard:required_detection_s/*": ClaimSpec(
        "required detection time of fault {0} (s; ours: the fastest method's 97.5th percentile)",
        ours=lambda h, p: h["best_detection_upper_s"].get(p[-1]), explain="sec-wt-scoreboard",
        missing="no method detects it in every realisation within the 10 s after its start",
        cause="sec-wt-reasons",
        cause_text="each miss and each late detection is measured against the fault's effect on the "
                   "measurements and the smallest step each detector sees"),
    "windturbine-scoreboard:published/*": ClaimSpec(
        "published results on this benchmark: {0}", ours=lambda h, p: None,
        reason="their tables are not reachable from this machine (at most an abstract in the search "
               "corpora); no number is guessed"),
    "windturbine-scoreboard:published_detection_s/cohal_mirea_2017/*/*": ClaimSpec(
        "Cohal & Mirea 2017, Table 1: delay to the {1} alarm on fault {2} (s; ours: the fastest "
        "method detecting in every realisation, its mean)",
        ours=lambda h, p: (h["fastest_method"][p[-1]] or {}).get("detection_time_mean_s"),
        explain="sec-wt-published", missing="no method detects it in every realisation",
        reason="another method's result (window statistics, on the benchmark's measured wind, which is "
               "not public): not ours to reproduce; our four methods' delays on the substitute wind are "
               "set beside it"),
}


def spec_for(id: str, path: tuple[str, ...]) -> ClaimSpec | None:
    """The first rule of :data:`SPECS` matching ``id:path`` (``None`` if none)."""
    key = f"{id}:{'/'.join(path)}"
    for pattern, spec in SPECS.items():
        if fnmatch.fnmatchcase(key, pattern):
            return spec
    return None


def chapter_of(id: str) -> str:
    """The book document that shows reproduction ``id``."""
    for prefix, doc in CHAPTERS:
        if id.startswith(prefix):
            return doc
    return "book/reproductions"


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


def surrogate_role(id: str, paper: Mapping[str, Any], path: tuple[str, ...],
                   spec: ClaimSpec = ClaimSpec()) -> str | None:
    """What the paper value at ``path`` is to a surrogate model (``None`` if ``id`` has none).

    A ``paper`` dictionary that declares :data:`ROLE_KEYS` decides alone: its key
    ``path[0]`` listed in ``calibrated_to`` is a :data:`CALIBRATION`, in ``predictions`` a
    :data:`PREDICTION`, in neither an :data:`INPUT` (set into the model). Otherwise
    ``spec.role`` (default :data:`PREDICTION`) for the ids of :data:`SURROGATE_IDS`.
    """
    if any(k in paper for k in ROLE_KEYS):
        if path[0] in paper.get("calibrated_to", ()):
            return CALIBRATION
        return PREDICTION if path[0] in paper.get("predictions", ()) else INPUT
    if id not in SURROGATE_IDS:
        return None
    return spec.role or PREDICTION


def _order(id: str) -> tuple[int, str]:
    return (BOOK_ORDER.index(id), id) if id in BOOK_ORDER else (len(BOOK_ORDER), id)


# ----------------------------------------------------------------------------- building
@dataclass(frozen=True)
class Ledger:
    """All rows, in book order, and where the results came from."""

    rows: tuple[LedgerRow, ...]
    sources: dict[str, str] = field(default_factory=dict)

    def counts(self) -> dict[str, int]:
        """Number of rows per status (every status present, possibly 0)."""
        return {s: sum(r.status == s for r in self.rows) for s in STATUSES}

    def counts_by_paper(self) -> dict[str, dict[str, int]]:
        """``{paper_id: {status: rows}}`` for the papers of :data:`PAPERS` (every status)."""
        return {p: {s: sum(r.status == s and r.paper_id == p for r in self.rows) for s in STATUSES}
                for p in PAPERS}

    def to_json_dict(self) -> dict[str, Any]:
        """``{"counts", "counts_by_paper", "rows", "sources"}``: ``reproduce --ledger --json``."""
        return {"counts": self.counts(), "counts_by_paper": self.counts_by_paper(),
                "rows": [r.to_json_dict() for r in self.rows], "sources": dict(self.sources)}

    def summary(self):
        """A :func:`fdi_lib.report.table`: claims per status (rows, the first column) and paper."""
        by = self.counts_by_paper()
        c = self.counts()
        rows = {s: [*(fmt_count(by[p][s]) for p in PAPERS), fmt_count(c[s])] for s in STATUSES}
        rows["all claims"] = [*(fmt_count(sum(by[p].values())) for p in PAPERS),
                              fmt_count(len(self.rows))]
        return table(rows, [*PAPERS.values(), "all"], index_header="status")

    def sources_table(self):
        """A :func:`fdi_lib.report.table`: where each reproduction's result came from."""
        rows = {id: [src] for id, src in sorted(self.sources.items(), key=lambda kv: _order(kv[0]))}
        return table(rows or {"none": ["no result"]}, ["result"], index_header="reproduction")

    def to_myst(self) -> str:
        """The ledger as a MyST list-table with links (``{doc}``, ``{ref}``) to the book; the
        status is the first column (the first thing seen on a phone)."""
        lines = [":::{list-table}", ":header-rows: 1", ":widths: 14 30 12 20 24", "",
                 "* - status", "  - claim (paper)", "  - paper", "  - ours", "  - why, where"]
        for r in self.rows:
            rate = _is_rate_claim(r)
            why = [_md(r.status_detail)] if r.status_detail else []
            if r.cause:
                why.append(f"cause measured in {_link(r.cause)}")
            if (r.explain or r.where) != r.cause:
                why.append(f"shown in {_link(r.explain or r.where)}")
            if r.note:
                why.append(_md(r.note))
            lines += [f"* - {r.status}", f"  - {_md(r.claim)}",
                      f"  - {_md(_fmt(r.paper, rate=rate, digits=6))}",
                      f"  - {_md(_fmt(r.ours, r.ci, rate=rate))}" + (
                          f" ({_md(r.role)})" if r.role else ""),
                      f"  - {'; '.join(why)}"]
        lines.append(":::")
        return "\n".join(lines)


def _md(text: str) -> str:
    return str(text).replace("|", "\\|").replace("*", "\\*").replace("_", "\\_").replace("<", "&lt;")


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
    return ("rate" in "/".join(r.path) and r.ci is not None and _is_rate(r.ours)
            and (_is_rate(r.paper) or isinstance(r.paper, str))
            and _is_rate(r.ci[0]) and _is_rate(r.ci[1]))


def _fmt(v: Any, ci: tuple[float, float] | None = None, *, rate: bool = False,
         digits: int = 4) -> str:
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


def _owner(id: str, path: tuple[str, ...], spec: ClaimSpec) -> tuple[str, tuple[str, ...]]:
    """Where the claim ``id:path`` is listed (itself unless ``spec.shown_under``)."""
    if not spec.shown_under:
        return id, path
    return spec.shown_under, spec.same_path(path) if spec.same_path else path


def _also_note(res: ReproductionResult, path: tuple[str, ...], spec: ClaimSpec) -> str:
    """What a second reproduction checking the same claim finds (shown in the owner's row)."""
    try:
        ours = spec.ours(res.headline, path) if spec.ours else _at(res.headline, path)
    except KeyError:
        return ""
    ci = spec.ci(res.headline, path) if spec.ci else _default_ci(res.headline, path)
    trials = res.settings.get("trials")
    rate = ("rate" in path[0] and ci is not None and _is_rate(ours))
    value = spec.missing if ours is None and spec.missing else _fmt(ours, ci, rate=rate)
    return (f"also checked by {res.id}" + (f" on {fmt_count(trials)} trial" + "s" * (trials != 1)
                                           if trials else "") + f": {value}")


def _row_status(outcome: str, how: str, *, spec: ClaimSpec, role: str | None, paper: Any,
                ours: Any, headline: Mapping[str, Any], path: tuple[str, ...],
                trials: int | None, paper_trials: int | None) -> tuple[str, str, str | None]:
    """The row status, its detail and its cause label, from the comparison ``outcome``."""
    if outcome == REPRODUCED and (role == INPUT or spec.role == INPUT):
        return INPUT_VALUE, "a value the book sets, equal by construction", None
    if outcome == NOT_REPRODUCIBLE:
        return NOT_REPRODUCIBLE, how, None
    if paper_trials is not None and (trials is None or trials < paper_trials):
        n = "?" if trials is None else fmt_count(trials)
        return (NOT_COMPUTED, f"{_UNSCALED}: {n} of the paper's "
                f"{fmt_count(paper_trials)} trials", None)
    if outcome == NOT_COMPUTED:
        return NOT_COMPUTED, how, None
    if role == CALIBRATION and outcome in AGREES:
        return CALIBRATION_TARGET, "the surrogate was calibrated to this value", None
    if outcome == WITHIN_SPREAD:
        return WITHIN_SPREAD, _spread_detail(headline, path), None
    if outcome != DIFFERS:
        return outcome, "", None
    if spec.cause and (spec.cause_if is None or spec.cause_if(paper, ours, headline, path)):
        return DIFFERS_MEASURED, spec.cause_text, spec.cause
    return DIFFERS_UNKNOWN, (f"ruled out by measurement: {spec.ruled_out}" if spec.ruled_out
                             else "no measurement of the cause yet"), None


def build_ledger(results: Mapping[str, ReproductionResult], *, strict: bool = False,
                 sources: Mapping[str, str] | None = None, own_readings: bool = False) -> Ledger:
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
            spec = spec_for(id, path) or ClaimSpec()
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
            spec = spec_for(id, path) or ClaimSpec()
            if spec.shown_under and not (own_readings and spec.same_path):
                continue
            paper = _at(res.paper, path)
            label = (spec.label or f"{_fig(id)}: {' '.join(path)}").format(
                *path[1:], fig=_fig(id), num=re.sub(r"^\D+", "", path[-1]))
            ours, missing = None, ""
            try:
                ours = spec.ours(res.headline, path) if spec.ours else _at(res.headline, path)
            except KeyError as exc:
                if strict:
                    raise ModelError(f"ledger: {id} has no value of ours for {exc}") from None
                missing = f"our value ({exc}) is missing"
            ci = spec.ci(res.headline, path) if spec.ci else _default_ci(res.headline, path)
            outcome, how = claim_status(paper, ours, ci, spec, res.headline,
                                        _default_spread(res.headline, path))
            if missing and outcome not in (NOT_REPRODUCIBLE,):
                outcome, how = NOT_COMPUTED, missing
            if strict and outcome == NOT_REPRODUCIBLE and not spec.reason:
                raise ModelError(f"ledger: {id}:{'/'.join(path)} needs a rule ({how})")
            role = surrogate_role(id, res.paper, path, spec)
            status, detail, cause = _row_status(
                outcome, how, spec=spec, role=role, paper=paper, ours=ours, headline=res.headline,
                path=path, trials=trials, paper_trials=paper_trials)
            note = "; ".join([how] + also.get((id, path), [])) if how != detail else "; ".join(
                also.get((id, path), []))
            rows.append(LedgerRow(
                id=id, path=path, label=label, paper=paper,
                ours=spec.missing if ours is None and spec.missing and not missing else ours,
                ci=ci, status=status, where=chapter_of(id),
                explain=spec.explain or (chapter_of(id) if status not in AGREES else None),
                note=note, role=role, trials=trials,
                source=(sources or {}).get(id, "computed"), status_detail=detail, cause=cause,
                paper_trials=paper_trials))
    return Ledger(rows=tuple(rows), sources=dict(sources or {}))


def collect_results(*, max_trials: int | None = None, ids: Sequence[str] | None = None,
                    use_cache: bool = True) -> tuple[dict[str, ReproductionResult], dict[str, str]]:
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

    Returns
    -------
    results, sources : dict, dict
        The results and, per id, ``"cached"`` or ``"computed"`` (with the trial count used
        and the run time).
    """
    from fdi_lib.reproduce.book import book_settings  # book imports this module's registry

    wanted = [r.id for r in list_reproductions()] if ids is None else list(ids)
    results, sources = {}, {}
    for id in wanted:
        book = book_settings(id)
        hit = cached_run(id, seed=book.seed, trials=book.trials) if use_cache else None
        if hit is not None:
            results[id] = hit
            sources[id] = f"cached in this build (seed {book.seed}" + (
                f", {fmt_count(book.trials)} trial" + "s" * (book.trials != 1)
                if book.trials else "") + ")"
            continue
        trials = book.trials
        if max_trials is not None and trials is not None and trials > max_trials:
            trials = max_trials
        t0 = time.perf_counter()
        results[id] = get(id)(seed=book.seed, trials=trials)
        sources[id] = (f"computed here (seed {book.seed}, "
                       f"{'' if trials is None else f'{trials} trials, '}"
                       f"{time.perf_counter() - t0:.1f} s)")
    return results, sources


def ledger(*, max_trials: int | None = None, strict: bool = False) -> Ledger:
    """The ledger of every registered reproduction (see :func:`collect_results`)."""
    results, sources = collect_results(max_trials=max_trials)
    return build_ledger(results, strict=strict, sources=sources)


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
        :data:`AGREES` (input and calibration rows are not compared), :data:`REDRAWS` when no
        row is compared, :data:`COMPARE` otherwise.
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
    """The row's label without its "Fig. N: " or "Table I: " prefix (the caption names it)."""
    return re.sub(r"^(Fig\.|Table) [^:]*: ", "", r.label)


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
    compared = [r for r in rows if r.status not in (INPUT_VALUE, CALIBRATION_TARGET)]
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
        parts.append(f"{fmt_count(len(unscaled))} claim{'s' * (len(unscaled) > 1)} "
                     + unscaled[0].status_detail)
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
