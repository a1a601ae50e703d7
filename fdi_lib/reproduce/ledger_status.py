"""The status of one claim of the claims ledger (:mod:`fdi_lib.reproduce.ledger`): the paper's
value compared with ours by the declared test (:func:`claim_status`), the claim a reproduction
declares for a path (:func:`claim_for`), the surrogate role of a value, and the paper items the
book sets out to reproduce with their states (:data:`MISSION`, :func:`item_state`).
"""

from __future__ import annotations

import fnmatch
import math
import numbers
import re
from dataclasses import replace
from typing import Any, Mapping, Sequence

from fdi_lib.errors import UnknownReproductionError
from fdi_lib.report import fmt_count, fmt_number
from fdi_lib.reproduce.ledger_claims import (
    BY_INTERVAL,
    BY_SPREAD,
    BY_STANDARD_ERROR,
    BY_TOLERANCE,
    CALIBRATION,
    DIFFERS,
    DIFFERS_BRACKETED,
    DIFFERS_HYPOTHESIS,
    DIFFERS_MEASURED,
    DIFFERS_UNKNOWN,
    ESTIMATES_INPUT,
    INPUT,
    IS_CALIBRATION,
    IS_INPUT,
    NO_VALUE,
    NOT_COMPUTED,
    NOT_REPRODUCIBLE,
    PREDICTION,
    REPRODUCED,
    ROLE_KEYS,
    SET_BY_BOOK,
    WITHIN,
    WITHIN_SPREAD,
    Claim,
    LedgerRow,
    _at,
    _has,
)
from fdi_lib.reproduce.registry import get

__all__ = [
    "surrogate_role",
    "claim_for",
    "chapter_of",
    "MISSION",
    "MISSION_STATES",
    "item_state",
    "claim_paths",
    "claim_status",
]


def claim_paths(paper: Mapping[str, Any], prefix: tuple[str, ...] = ()) -> list[tuple[str, ...]]:
    """Paths of the leaves of a ``paper`` dictionary that state a value (see
    :data:`~fdi_lib.reproduce.ledger_claims.NO_VALUE`).

    A list is a leaf (e.g. ``theta_estimate = [4, 0]``). The top-level
    :data:`~fdi_lib.reproduce.ledger_claims.ROLE_KEYS` declare roles and are skipped.
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
    """``ours ± z se`` of a scalar (the interval of
    :data:`~fdi_lib.reproduce.ledger_claims.BY_STANDARD_ERROR`), else ``None``."""
    o, e = _numbers(ours), _numbers(se)
    if o is None or e is None or len(o) != 1 or len(e) != 1:
        return None
    return o[0] - z * e[0], o[0] + z * e[0]


def _label(id: str, path: tuple[str, ...], spec: Claim) -> str:
    """The row's label: the claim's location in the paper, then what it says. A claim shown
    under another reproduction, read again here (``same_path``), has the label of its row there:
    a figure's caption names the claim, not its JSON path."""
    text = f"{spec.location}: {spec.label}" if spec.label else spec.location
    if not text.strip() and spec.shown_under and spec.same_path:
        owner_path = spec.same_path(path)
        owner = claim_for(spec.shown_under, owner_path)
        if owner is not None and not owner.shown_under:
            return _label(spec.shown_under, owner_path, owner)
    if not text.strip():
        text = f"{_fig(id)}: {' '.join(path)}"
    return text.format(*path[1:], fig=_fig(id), num=re.sub(r"^\D+", "", path[-1]))


def _spread_detail(headline: Mapping[str, Any], path: tuple[str, ...]) -> str:
    """ "the paper's run is at the 71st percentile of our 1000 runs" (keys
    ``<key>_paper_percentile`` and ``spread_runs`` of the headline; what is known of them)."""
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

    The outcome is :data:`~fdi_lib.reproduce.ledger_claims.REPRODUCED`,
    :data:`~fdi_lib.reproduce.ledger_claims.WITHIN`,
    :data:`~fdi_lib.reproduce.ledger_claims.WITHIN_SPREAD`,
    :data:`~fdi_lib.reproduce.ledger_claims.DIFFERS`,
    :data:`~fdi_lib.reproduce.ledger_claims.NOT_COMPUTED` (we have no value, or not the statistic
    the test needs) or
    :data:`~fdi_lib.reproduce.ledger_claims.NOT_REPRODUCIBLE`;
    :func:`~fdi_lib.reproduce.ledger.build_ledger` turns it into a row status (input, input
    recovered, calibration target, a difference's cause, the paper's trial count). Only the declared
    test can agree: a value close to the paper's but outside our interval differs.

    Parameters
    ----------
    paper : number, list of numbers, bool or str
        The paper's value: a number (or list), ``"< x"``-type inequality, ``"about x"``,
        or a statement checked by ``spec.check``.
    ours : any
        Our value (``None`` when we have none; with ``spec.missing``, ``None`` is a result,
        e.g. never detected, that differs from any number).
    ci : (float, float), optional
        Our 95 % interval of a scalar value (:data:`~fdi_lib.reproduce.ledger_claims.BY_INTERVAL`,
        :data:`~fdi_lib.reproduce.ledger_claims.ESTIMATES_INPUT`,
        :data:`~fdi_lib.reproduce.ledger_claims.IS_CALIBRATION`).
    spec : Claim
        The declaration: test, tolerances, check, or the reason the claim is not reproducible.
    headline : dict, optional
        The reproduction's headline, passed to ``spec.check``.
    spread : (float, float), optional
        95 % range of our run-to-run distribution of a single-run value
        (:data:`~fdi_lib.reproduce.ledger_claims.BY_SPREAD`).
    se : float or list of float, optional
        Standard error of our value, per component
        (:data:`~fdi_lib.reproduce.ledger_claims.BY_STANDARD_ERROR`).
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

    A ``paper`` dictionary that declares :data:`~fdi_lib.reproduce.ledger_claims.ROLE_KEYS` decides
    alone: its key
    ``path[0]`` listed in ``calibrated_to`` is a
    :data:`~fdi_lib.reproduce.ledger_claims.CALIBRATION`, in ``predictions`` a
    :data:`~fdi_lib.reproduce.ledger_claims.PREDICTION`, in neither an
    :data:`~fdi_lib.reproduce.ledger_claims.INPUT` (set into the model). Otherwise, for a
    reproduction registered with ``surrogate=True``, the claim's ``role``, else its test's (an input
    for :data:`~fdi_lib.reproduce.ledger_claims.IS_INPUT` and
    :data:`~fdi_lib.reproduce.ledger_claims.ESTIMATES_INPUT`, a calibration for
    :data:`~fdi_lib.reproduce.ledger_claims.IS_CALIBRATION`), else
    :data:`~fdi_lib.reproduce.ledger_claims.PREDICTION`.
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


def _order(id: str) -> tuple[int, tuple[int, int, str]]:
    """Sort key of ``id`` in the book's order (:func:`~fdi_lib.reproduce.book.book_key`; from its
    own registration: a caption's ledger of one figure imports no other reproduction's module),
    an identifier that is not registered after every registered one."""
    from fdi_lib.reproduce.book import book_key  # book imports the registry, as this module

    try:
        return 0, book_key(id)
    except UnknownReproductionError:
        return 1, (0, 0, id)


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
#: States of a paper item (:meth:`~fdi_lib.reproduce.ledger.Ledger.mission`), from its rows: every
#: compared row agrees; the least explained difference among them; nothing compared.
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
