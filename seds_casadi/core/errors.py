"""Project exceptions.

Errors a user can cause are ``ValueError``/``TypeError`` (or subclasses of them, below) with a
message saying what was wrong and what to do. Solver and certification failures have their own
classes so callers can catch them precisely.
"""

from __future__ import annotations


class SEDSError(Exception):
    """Base class of the errors raised by seds_casadi."""


class SolverError(SEDSError):
    """The optimiser failed (IPOPT returned an error status or non-finite values).

    Attributes
    ----------
    status : str
        The solver's return status (IPOPT's ``return_status``).
    """

    def __init__(self, message: str, status: str = "unknown") -> None:
        super().__init__(f"{message} (solver status: {status})")
        self.status = status


class StabilityError(SEDSError):
    """A model failed the stability certificate of Eq. 10 and is not returned.

    Attributes
    ----------
    constraint : str
        Which part of Eq. 10 failed, e.g. ``"(b) A_k + A_k^T < 0"``.
    status : str
        The solver status of the solve that produced the model (or ``"loaded"``).
    """

    def __init__(self, message: str, constraint: str, status: str = "unknown") -> None:
        super().__init__(f"{message} [constraint {constraint}; solver status: {status}]")
        self.constraint = constraint
        self.status = status


class ModelFileError(SEDSError, ValueError):
    """A saved model file is unreadable, incomplete, corrupt or tampered with."""


class ConvergenceWarning(UserWarning):
    """IPOPT stopped before converging, but the model it returned is certified stable."""
