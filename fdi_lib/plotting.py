"""One central matplotlib style for the book and the CLI, and small shared helpers.

Plot functions of the reproductions live next to them (``plot_<figure>(result, fig=None)``)
and use :func:`figure` so that every figure of the book looks the same.
"""

from __future__ import annotations

from typing import Any

import matplotlib as mpl
import matplotlib.pyplot as plt

__all__ = ["STYLE", "use_style", "figure", "PAPER_COLOR", "OURS_COLOR", "THRESHOLD_COLOR"]

OURS_COLOR = "#1f77b4"
PAPER_COLOR = "#d62728"
THRESHOLD_COLOR = "#d62728"

STYLE: dict[str, Any] = {
    "figure.figsize": (7.0, 3.6),
    "figure.dpi": 110,
    "savefig.dpi": 110,
    "axes.grid": True,
    "grid.alpha": 0.3,
    "axes.spines.top": False,
    "axes.spines.right": False,
    "axes.titlesize": 11,
    "axes.labelsize": 10,
    "legend.fontsize": 9,
    "legend.frameon": False,
    "lines.linewidth": 1.2,
}


def use_style() -> None:
    """Apply the book's matplotlib style (idempotent)."""
    mpl.rcParams.update(STYLE)


def figure(nrows: int = 1, ncols: int = 1, *, fig: Any = None, sharex: bool = False,
           figsize: tuple[float, float] | None = None, **kwargs: Any):
    """A figure with the book's style: ``(fig, axes)``; ``fig`` reuses an existing figure (widgets)."""
    use_style()
    if fig is None:
        fig = plt.figure(figsize=figsize or STYLE["figure.figsize"], layout="constrained")
    else:
        fig.clear()
    axes = fig.subplots(nrows, ncols, sharex=sharex, squeeze=False, **kwargs)
    return fig, axes
