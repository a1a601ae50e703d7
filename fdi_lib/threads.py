"""BLAS threading control for the many small-matrix computations of the library.

The filters, signatures and set-valued observers work on matrices of a few rows. On such sizes a
multi-threaded BLAS only adds synchronisation: on a busy 2-core machine one 4x4 matrix
exponential was measured at 10 ms with OpenBLAS threads against 20 us single-threaded. The
Monte Carlo engine parallelises over realisations instead (processes, :mod:`fdi_lib.montecarlo`).
threadpoolctl (a scikit-learn dependency) does the switching, for whichever BLAS numpy uses.
"""

from __future__ import annotations

import functools
from typing import Any, Callable, TypeVar

from threadpoolctl import threadpool_limits

__all__ = ["single_threaded_blas"]

F = TypeVar("F", bound=Callable[..., Any])


def single_threaded_blas(func: F) -> F:
    """Decorator: run ``func`` with the BLAS limited to one thread, restored afterwards."""

    @functools.wraps(func)
    def wrapper(*args: Any, **kwargs: Any) -> Any:
        with threadpool_limits(limits=1, user_api="blas"):
            return func(*args, **kwargs)

    return wrapper  # type: ignore[return-value]
