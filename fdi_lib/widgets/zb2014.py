"""Widget callback of the GLR chapter: fault size, onset, window and threshold on the unstable example."""

from __future__ import annotations

from typing import Any

from fdi_lib.errors import ModelError
from fdi_lib.reproduce.zb2014 import plot_detection, unstable_run

__all__ = ["explore_glr", "DEFAULTS"]

#: Default slider values (paper Fig. 3 setting, plus an illustrative threshold).
DEFAULTS = {"fault_size": 1.5, "onset": 201, "window": 100, "threshold": 20.0, "seed": 0}


def explore_glr(fault_size: float = DEFAULTS["fault_size"], onset: int = DEFAULTS["onset"],
                window: int = DEFAULTS["window"], threshold: float = DEFAULTS["threshold"],
                seed: int = DEFAULTS["seed"], fig: Any = None):
    """Redraw the innovation and the windowed GLR ``l_k`` for ``theta = [fault_size, 0]``.

    Parameters
    ----------
    fault_size : float
        First component of the impulsive fault ``theta`` (jump of the first state).
    onset : int
        Jump time ``r`` in ``[10, 490]``.
    window : int
        GLR search window ``w`` in ``[5, 200]``.
    threshold : float
        Alarm threshold on ``l_k`` (> 0).
    seed : int
        Noise seed.
    fig : matplotlib.figure.Figure, optional
        Figure to redraw into (the widget passes its own).

    Returns
    -------
    matplotlib.figure.Figure
    """
    if not 10 <= onset <= 490:
        raise ModelError(f"onset: expected an integer in [10, 490], got {onset!r}")
    if not 5 <= window <= 200:
        raise ModelError(f"window: expected an integer in [5, 200], got {window!r}")
    if not threshold > 0:
        raise ModelError(f"threshold: expected a positive number, got {threshold!r}")
    run = unstable_run(theta=(float(fault_size), 0.0), onset=int(onset), window=int(window),
                       threshold=float(threshold), seed=int(seed))
    delay = run.alarm - run.onset if run.alarm >= run.onset else None
    status = ("no alarm" if run.alarm < 0 else
              f"false alarm at k = {run.alarm}" if delay is None else f"alarm after {delay} samples")
    return plot_detection(run, fig=fig, title=f"theta = [{fault_size:g}, 0], onset {onset}, "
                                              f"w = {window}: {status}")
