"""Interactive explorations for the book (ipywidgets).

Each chapter has a module here with a *tested, pure* callback
``explore_*(..., fig=None) -> Figure`` that the notebook wires to sliders via
:func:`interactive_figure`. The callback is what the book also calls once at
the default values to show a static figure, so the HTML is never empty.
"""

from __future__ import annotations

from typing import Any, Callable

__all__ = ["interactive_figure", "keep_artists", "reusable_artists"]

_ARTISTS = "_fdi_widget_artists"


def keep_artists(fig: Any, key: str, artists: dict[str, Any]) -> None:
    """Remember on ``fig`` the artists a callback ``key`` drew, for :func:`reusable_artists`."""
    setattr(fig, _ARTISTS, (key, artists))
    fig.set_layout_engine("constrained")  # a new figure is laid out at its next draw


def reusable_artists(fig: Any, key: str) -> dict[str, Any] | None:
    """The artists that callback ``key`` kept on ``fig`` (``None``: draw the figure anew).

    A callback that finds its own artists on the figure it is given updates their data instead
    of clearing and rebuilding the figure: a slider move then costs the computation and one
    render without a new layout (issue 10, redraw <= 100 ms). Any other figure (or ``None``)
    is rebuilt and laid out anew by :func:`keep_artists`.
    """
    kept = getattr(fig, _ARTISTS, None) if fig is not None else None
    if kept is None or kept[0] != key or not kept[1]:
        return None
    # Moving artists keeps the layout the figure was last drawn with: the constrained layout,
    # half of a render, is not redone (the panels also stay put between slider values).
    fig.set_layout_engine("none")
    return kept[1]


def interactive_figure(callback: Callable[..., Any], **sliders: Any):
    """Wire ``callback(**values, fig=fig)`` to ipywidgets sliders (``continuous_update=False``).

    Parameters
    ----------
    callback : callable
        Pure function drawing into ``fig`` and returning it.
    **sliders : ipywidgets.ValueWidget
        One widget per keyword argument of ``callback``.

    Returns
    -------
    ipywidgets.VBox
        The sliders above an output area holding the figure.
    """
    import ipywidgets as widgets
    import matplotlib.pyplot as plt
    from IPython.display import display

    out = widgets.Output()
    for w in sliders.values():
        if hasattr(w, "continuous_update"):
            w.continuous_update = False
    state: dict[str, Any] = {"fig": None}

    def redraw(_change: Any = None) -> None:
        with out:
            out.clear_output(wait=True)
            state["fig"] = callback(**{k: w.value for k, w in sliders.items()}, fig=state["fig"])
            display(state["fig"])
            # Shown in the output area only: keep pyplot from showing it again at the end of the
            # cell. A closed figure can still be cleared and redrawn by the next callback.
            plt.close(state["fig"])

    for w in sliders.values():
        w.observe(redraw, names="value")
    redraw()
    return widgets.VBox([widgets.HBox(list(sliders.values())[:3]),
                         widgets.HBox(list(sliders.values())[3:]), out])
