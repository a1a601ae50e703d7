"""Set-membership tools: convex polytopes and set-valued observers (Rosa & Silvestre 2013).

:mod:`fdi_lib.sets.polytope` holds the polytope algebra (eq. (2)), :mod:`fdi_lib.sets.svo`
the set-valued observer of §2 and the fault detection / isolation logic of §§3-4.
"""

from fdi_lib.sets.polytope import Polytope, box_corners, convex_hull, plot_polytope
from fdi_lib.sets.svo import (
    FDIResult,
    SetValuedObserver,
    SVOModel,
    SVORun,
    run_architecture_i,
    run_architecture_ii,
    run_svo,
)

__all__ = [
    "Polytope",
    "box_corners",
    "convex_hull",
    "plot_polytope",
    "SVOModel",
    "SetValuedObserver",
    "SVORun",
    "run_svo",
    "FDIResult",
    "run_architecture_i",
    "run_architecture_ii",
]
