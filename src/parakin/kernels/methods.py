"""The solvers' options, declared once: what the numpy solvers default to and what the compiled
loops (:mod:`parakin.kernels.drivers`) read, by position, from one options vector.

Plain Python (no numba): the numpy solvers take their defaults from :data:`DEFAULTS`, the compiled
path packs a call's options with :func:`pack`, and the drivers index the vector with the positions
of :data:`VECTOR`. A method the table does not list, or an option its row does not name, runs on
the numpy solver.
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np

__all__ = ["BAD_INPUT", "BOUNDS", "COMPILED", "DEFAULTS", "VECTOR", "pack"]

#: option -> default of the iterative solvers (:mod:`parakin.solvers`), numpy and compiled alike:
#: ``xtol``/``gtol`` off at 0; Levenberg-Marquardt's initial damping factor ``tau``; BFGS's
#: sufficient-decrease constant ``c1``, backtracking factor ``shrink``, at most ``maxls`` trials
#: per line search and the relative regularisation ``reg`` of its initial Gauss-Newton Hessian;
#: the dog leg's initial trust radius ``factor * |D x0|`` (MINPACK's ``factor``, its default 100)
#: and its acceptance threshold ``eta`` on the ratio of actual to predicted reduction (MINPACK's
#: 1e-4; Nocedal & Wright's Alg. 4.1 asks for ``0 <= eta < 1/4``)
DEFAULTS: dict[str, float] = {
    "xtol": 0.0,
    "gtol": 0.0,
    "tau": 1e-9,
    "c1": 1e-4,
    "shrink": 0.5,
    "maxls": 30,
    "reg": 1e-10,
    "factor": 100.0,
    "eta": 1e-4,
}

#: the options vector of a compiled call, in order: its position is what the drivers read
VECTOR: tuple[str, ...] = ("tol", "maxiter", *DEFAULTS)

#: method -> the options (besides ``tol`` and ``maxiter``) its compiled loop takes
COMPILED: dict[str, tuple[str, ...]] = {
    "newton": ("xtol",),
    "lm": ("xtol", "gtol", "tau"),
    "broyden": ("xtol",),
    "bfgs": ("xtol", "gtol", "c1", "shrink", "maxls", "reg"),
    "dogleg": ("xtol", "factor", "eta"),
}

#: option -> ``(lo, hi)``: a solver takes ``lo <= value < hi``; a value outside leaves the call to
#: the numpy solver, which names the value and the limit
BOUNDS: dict[str, tuple[float, float]] = {"factor": (math.ulp(0.0), math.inf), "eta": (0.0, 0.25)}

#: the status a compiled single call reports for joints or a start that are not finite (the caller
#: then marks the row itself)
BAD_INPUT = 999

#: options that must be whole numbers (a float of an integral value is fine)
_INTEGRAL = ("maxiter", "maxls")


def pack(method: str, tol: float, maxiter: int, options: dict[str, Any]) -> np.ndarray | None:
    """The options vector of a compiled ``method`` call (:data:`VECTOR` order), or ``None`` where
    the compiled loop does not apply: a method without one, an option it does not take, or a
    value that is not a number (the numpy solver then reports it)."""
    taken = COMPILED.get(method)
    if taken is None or any(k not in taken for k in options):
        return None
    values = {**DEFAULTS, **options, "tol": tol, "maxiter": maxiter}
    try:
        vector = np.array([float(values[k]) for k in VECTOR])
    except (TypeError, ValueError, OverflowError):
        return None
    if not all(math.isfinite(vector[VECTOR.index(k)]) for k in _INTEGRAL) or not all(
        float(vector[VECTOR.index(k)]).is_integer() for k in _INTEGRAL
    ):
        return None
    if not all(lo <= vector[VECTOR.index(k)] < hi for k, (lo, hi) in BOUNDS.items()):
        return None
    return vector
