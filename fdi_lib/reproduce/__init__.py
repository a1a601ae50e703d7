"""Reproductions of the papers' figures and tables (one module per paper).

Use :func:`reproduce` from Python or ``python -m fdi_lib reproduce ID --json``
from the shell; ``python -m fdi_lib reproduce --list`` lists the identifiers.
"""

from fdi_lib.reproduce.registry import (
    Reproduction,
    ReproductionResult,
    get,
    list_reproductions,
    register,
    reproduce,
)

__all__ = [
    "Reproduction",
    "ReproductionResult",
    "get",
    "list_reproductions",
    "register",
    "reproduce",
]
