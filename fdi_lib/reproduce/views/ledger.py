"""The claims ledger in the figure captions: what a caption may say about its paper figure
(:func:`figure_claim`) and the glue of its words (:func:`glue_caption`), from the ledger rows
of :func:`fdi_lib.reproduce.ledger.build_ledger`.
"""

from __future__ import annotations

import re
from dataclasses import dataclass

from fdi_lib.report import fmt_count
from fdi_lib.reproduce.ledger import (
    _UNSCALED,
    _fmt,
    _is_rate_claim,
    build_ledger,
)
from fdi_lib.reproduce.ledger_claims import (
    AGREES,
    DIFFERING,
    SET_BY_BOOK,
    LedgerRow,
)
from fdi_lib.reproduce.registry import ReproductionResult

__all__ = [
    "FigureClaim",
    "figure_claim",
    "glue_caption",
    "REPRODUCES",
    "COMPARE",
    "REDRAWS",
    "CAPTION_ITEMS",
]

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
        :data:`~fdi_lib.reproduce.ledger_claims.AGREES` (the rows of
        :data:`~fdi_lib.reproduce.ledger_claims.SET_BY_BOOK`, inputs, our estimates of them and
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
