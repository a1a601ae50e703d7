"""BLAS threading control for the many small-matrix computations of the library.

The filters, signatures and set-valued observers work on matrices of a few rows. On such sizes a
multi-threaded BLAS only adds synchronisation: on a busy 2-core machine one 4x4 matrix
exponential was measured at 10 ms with OpenBLAS threads against 20 us single-threaded. The
Monte Carlo engine parallelises over realisations instead (processes, :mod:`fdi_lib.montecarlo`).
threadpoolctl (a scikit-learn dependency) does the switching, for whichever BLAS numpy and scipy
use. Finding those libraries (a scan of the loaded shared objects) costs about 2 ms, so it is
done once per process, as threadpoolctl's documentation recommends (one
``ThreadpoolController``, then ``controller.limit(...)``, about 15 us per switch).
"""

from __future__ import annotations

import contextlib
import functools
from typing import Any, Callable, Iterator, TypeVar

__all__ = ["single_threaded_blas", "blas_single_thread"]

F = TypeVar("F", bound=Callable[..., Any])


@functools.lru_cache(maxsize=1)
def _controller() -> Any:
    """The process's ``ThreadpoolController``, created at first use.

    numpy's and scipy's BLAS (two distinct OpenBLAS builds in the wheels) are both loaded first,
    so that the controller sees them; a BLAS loaded later by another package is not limited.
    """
    import numpy  # noqa: F401  (loads numpy's BLAS)
    import scipy.linalg  # noqa: F401  (loads scipy's BLAS)
    from threadpoolctl import ThreadpoolController

    return ThreadpoolController()


@contextlib.contextmanager
def blas_single_thread() -> Iterator[None]:
    """Context manager: the BLAS limited to one thread inside, restored afterwards."""
    with _controller().limit(limits=1, user_api="blas"):
        yield


def single_threaded_blas(func: F) -> F:
    """Decorator: run ``func`` with the BLAS limited to one thread (:func:`blas_single_thread`)."""

    @functools.wraps(func)
    def wrapper(*args: Any, **kwargs: Any) -> Any:
        with blas_single_thread():
            return func(*args, **kwargs)

    return wrapper  # type: ignore[return-value]
