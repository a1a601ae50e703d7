"""Typed errors of :mod:`fdi_lib`.

Every error subclasses a builtin (mostly ``ValueError`` or ``TypeError``; ``ConnectionError``
for a cluster that cannot be reached) so that generic handlers keep working, and every message names the offending argument
together with what was expected and what was received. Warnings subclass
:class:`FDIWarning` (a ``UserWarning``: shown by default, once per place).
"""

from __future__ import annotations

__all__ = [
    "FDIError",
    "ShapeError",
    "NonFiniteError",
    "CovarianceError",
    "ModelError",
    "PersistentExcitationError",
    "RankConditionError",
    "UnknownReproductionError",
    "EmptySetError",
    "UnboundedSetError",
    "NumericalError",
    "ResourceError",
    "ClusterError",
    "UnknownExerciseError",
    "AnswerError",
    "ReferenceNotShippedError",
    "FDIWarning",
    "UnsoundOptionWarning",
    "EnvelopeWarning",
    "JobsCappedWarning",
    "CacheWarning",
]


class FDIError(Exception):
    """Base class of all errors raised by :mod:`fdi_lib`."""


class ShapeError(FDIError, ValueError):
    """An array has the wrong number of dimensions or the wrong shape."""


class NonFiniteError(FDIError, ValueError):
    """An array contains NaN or infinite values (the message gives the first index)."""


class CovarianceError(FDIError, ValueError):
    """A covariance matrix is not symmetric, not positive semi-definite, or not definite."""


class ModelError(FDIError, ValueError):
    """A model, profile or option is inconsistent (wrong keyword, bad horizon, ...)."""


class PersistentExcitationError(FDIError, ValueError):
    """The information matrix of a GLR or isolation test is singular.

    Zhang & Basseville (2014), condition (22): the fault signature must be
    persistently exciting over the samples used by the test.
    """


class RankConditionError(FDIError, ValueError):
    """A rank assumption (e.g. full column rank of :math:`C_{k+1} E_k` for the Kitanidis filter) fails."""


class UnknownReproductionError(FDIError, KeyError):
    """No reproduction is registered under the requested identifier."""

    def __str__(self) -> str:  # KeyError quotes its message otherwise
        return str(self.args[0]) if self.args else ""


class EmptySetError(FDIError, ValueError):
    """A polytope that must be non-empty (e.g. an SVO's initial set) is empty."""


class UnboundedSetError(FDIError, ValueError):
    """A polytope that must be bounded (e.g. an SVO's initial set) is unbounded."""


class NumericalError(FDIError, ArithmeticError):
    """A floating-point geometric computation (e.g. vertex enumeration of a very thin polytope) failed."""


class ResourceError(FDIError, ValueError):
    """A request would exceed a resource limit (memory, frames, page weight); the message gives
    the estimate and the limit."""


class ClusterError(FDIError, ConnectionError):
    """A compute cluster (e.g. the Dask scheduler of ``--cluster tcp://HOST:PORT``) cannot be reached or
    started; the message names the address and the time waited."""


class UnknownExerciseError(FDIError, KeyError):
    """No exercise is registered under the requested identifier (:mod:`fdi_lib.exercises`)."""

    def __str__(self) -> str:  # KeyError quotes its message otherwise
        return str(self.args[0]) if self.args else ""


class AnswerError(FDIError, ValueError):
    """An answer cannot be compared with anything: not a real number or array, or not finite."""


class ReferenceNotShippedError(FDIError, LookupError):
    """The reference answers (and the code computing them) are not part of this package.

    Raised by :func:`~fdi_lib.exercises.reference_answer` in the student package, and by
    :func:`~fdi_lib.exercises.check` there for a student whose reference digests it does not hold.
    """


class FDIWarning(UserWarning):
    """Base class of all warnings issued by :mod:`fdi_lib`."""


class UnsoundOptionWarning(FDIWarning):
    """An option was used that can lose the true state (e.g. a set-valued observer's ``joint=True``
    or ``strip_before_hull=True`` with an uncertain A): an empty set is then no proof of a fault."""


class EnvelopeWarning(FDIWarning):
    """A record leaves the range in which a model's stated margins were measured to hold (e.g. the
    UAV's manoeuvre envelope): the model's guarantees, such as containment of the true state, may fail."""


class JobsCappedWarning(FDIWarning):
    """More parallel jobs were requested than can run (CPU cores, chunks of work): fewer are used."""


class CacheWarning(FDIWarning):
    """The results cache cannot be read or written (corrupt entry, not a directory): treated as a miss."""
