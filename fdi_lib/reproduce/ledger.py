"""The claims ledger: every value the four papers state, ours next to it, and a computed status.

Declaring a claim
-----------------
Each claim is declared **where it is computed**: at the registration of the reproduction that
tests it (:func:`fdi_lib.reproduce.registry.register`), in its paper module. A declaration
(:class:`~fdi_lib.reproduce.ledger_claims.Claim`) says where in the paper the value is
(``location``, unique among the rows), its units, and how it is compared (``test``, one of
:data:`~fdi_lib.reproduce.ledger_claims.TESTS`): by tolerance, by our 95 % interval at the paper's
trial count, by the standard error of our estimate, by the spread of single runs, by a stated check,
or not at all (an input the book sets, our estimate of such an input, a calibration target, a value
that cannot be reproduced here). The registration also carries the chapter, the book's seed and the
surrogate role; the book's order is that of
``_toc.yml`` (:func:`fdi_lib.reproduce.book.book_order`). Adding a figure touches its paper
module and its chapter only::

    from fdi_lib.reproduce.ledger_claims import BY_INTERVAL, IS_INPUT, Claim
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
under the reproduction that runs the paper's setting
(:attr:`~fdi_lib.reproduce.ledger_claims.Claim.shown_under`). Its status is
**computed** by the declared test only, never typed, and is one of the fixed vocabulary
:data:`~fdi_lib.reproduce.ledger_claims.STATUSES`:

``reproduced``
    our value equals the paper's within the claim's tolerance, satisfies the paper's inequality
    (``"< 1"``), or passes the claim's stated check (a statement such as "grows linearly in k");
``within interval``
    the paper's value lies in our 95 % interval
    (:data:`~fdi_lib.reproduce.ledger_claims.BY_INTERVAL`), or within ``z`` standard errors of our
    estimate (:data:`~fdi_lib.reproduce.ledger_claims.BY_STANDARD_ERROR`, the interval shown is ours
    ± z se);
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
    two of our readings bracket the paper's value but neither agrees
    (:attr:`~fdi_lib.reproduce.ledger_claims.Claim.bracket`): not a cause;
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
    page executed on its own with :data:`~fdi_lib.reproduce.ledger_claims.FALLBACK_TRIALS`);
``not reproducible``
    the claim cannot be checked here (the detail says why, e.g. a timing on the authors'
    MATLAB machine).

The first three are :data:`~fdi_lib.reproduce.ledger_claims.AGREES`: a figure caption says
"reproduces paper Fig. N" only when every compared row of its reproduction is one of them
(:func:`~fdi_lib.reproduce.views.ledger.figure_claim`; the rows of
:data:`~fdi_lib.reproduce.ledger_claims.SET_BY_BOOK` are not compared). The paper items of
:data:`~fdi_lib.reproduce.ledger_status.MISSION` (propositions, figures, tables, remarks) get a
state derived from their rows (:meth:`Ledger.mission`).

Surrogate models: for a reproduction registered with ``surrogate=True`` each row also says
what the paper's number is to the model (:func:`~fdi_lib.reproduce.ledger_status.surrogate_role`): a
value the surrogate was
*calibrated* to, a *prediction* of it, or an *input* set into it. A ``paper`` dictionary that
declares the lists ``paper["calibrated_to"]`` and ``paper["predictions"]``
(:data:`~fdi_lib.reproduce.ledger_claims.ROLE_KEYS`, never claims) is the only source; the declared
test (:data:`~fdi_lib.reproduce.ledger_claims.IS_INPUT`,
:data:`~fdi_lib.reproduce.ledger_claims.IS_CALIBRATION`) or ``role`` applies otherwise.

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

import re
import time
from dataclasses import dataclass, field, replace
from typing import Any, Mapping, Sequence

from fdi_lib.errors import ModelError, UnknownReproductionError
from fdi_lib.report import NA, fmt_count, fmt_number, fmt_rate, table, text_pieces
from fdi_lib.reproduce.ledger_claims import (
    AGREES,
    BY_STANDARD_ERROR,
    CALIBRATION,
    CALIBRATION_TARGET,
    DIFFERS,
    DIFFERS_BRACKETED,
    DIFFERS_HYPOTHESIS,
    DIFFERS_MEASURED,
    DIFFERS_UNKNOWN,
    ESTIMATES_INPUT,
    INPUT,
    INPUT_RECOVERED,
    INPUT_VALUE,
    IS_CALIBRATION,
    IS_INPUT,
    NOT_COMPUTED,
    NOT_REPRODUCIBLE,
    PAPERS,
    STATUSES,
    WITHIN_SPREAD,
    Claim,
    LedgerRow,
    _at,
)
from fdi_lib.reproduce.ledger_status import (
    _PLAIN,
    MISSION,
    MISSION_STATES,
    _default_ci,
    _default_se,
    _default_spread,
    _fig,
    _in_item,
    _is_number,
    _label,
    _numbers,
    _order,
    _se_interval,
    _spread_detail,
    chapter_of,
    claim_for,
    claim_paths,
    claim_status,
    item_state,
    surrogate_role,
)
from fdi_lib.reproduce.registry import ReproductionResult, cached_run, get, list_reproductions

__all__ = ["Ledger", "build_ledger", "collect_results", "ledger"]

_UNSCALED = "not computed at paper scale"
_RECOVERED = "our estimate of a value the book sets: shown, not a reproduction"


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
        """``{paper_id: {status: rows}}`` for the papers of
        :data:`~fdi_lib.reproduce.ledger_claims.PAPERS` (every status)."""
        return {
            p: {s: sum(r.status == s and r.paper_id == p for r in self.rows) for s in STATUSES}
            for p in PAPERS
        }

    def mission(self) -> list[dict[str, Any]]:
        """Each paper item of :data:`~fdi_lib.reproduce.ledger_status.MISSION`: ``{"paper_id",
        "item", "state", "rows", "statuses"}`` (its state from
        :func:`~fdi_lib.reproduce.ledger_status.item_state`, its rows' identifiers and locations,
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
        """``{paper_id: {state: items}}`` over :data:`~fdi_lib.reproduce.ledger_status.MISSION`
        (every state, possibly 0)."""
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
    """A claim's text as MyST: special characters escaped, the names from the code as code and the
    symbols as maths (:func:`fdi_lib.report.text_pieces`; the JSON keeps the text as written)."""
    render = {
        "text": lambda p: (
            p.replace("|", "\\|").replace("*", "\\*").replace("_", "\\_").replace("<", "&lt;")
        ),
        "code": lambda p: f"`{p}`",
        "math": lambda p: f"${p}$",
    }
    return "".join(render[kind](piece) for kind, piece in text_pieces(text))


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
        its own rows: the rows of that result's figure
        (:func:`~fdi_lib.reproduce.views.ledger.figure_claim`), not the ledger's.
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
    """A result per reproduction at the book's settings
    (:func:`fdi_lib.reproduce.book.book_settings`, the seed and trials the chapters use, without
    options): the run the build cached, else a fresh one.

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
