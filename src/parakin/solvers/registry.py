"""The registry of forward-kinematics methods: name -> solver.

Kept apart from :mod:`parakin.solvers` (which fills it) so that a solver module can look up
another method (the hybrid refines with one) without importing the package that imports it.
A registered method is called as ``fn(mech, joints, x0, *, tol, maxiter, **options)`` with flat
2-D ``joints (N, m)`` and ``x0 (N, n)`` and returns an :class:`~parakin.solvers.result.FKResult`.
"""

from __future__ import annotations

from collections.abc import Callable

from parakin.solvers.result import FKResult

__all__ = ["METHODS", "Method", "register"]

Method = Callable[..., FKResult]

#: method name -> solver; extend with :func:`register`.
METHODS: dict[str, Method] = {}


def register(name: str, *, override: bool = False) -> Callable[[Method], Method]:
    """Decorator adding a solver to :data:`METHODS` under ``name``.

    Registering a different function under a taken name raises ValueError unless ``override``.
    """

    def add(fn: Method) -> Method:
        if not override and METHODS.get(name, fn) is not fn:
            raise ValueError(
                f"FK method {name!r} is already registered ({METHODS[name].__module__})"
            )
        METHODS[name] = fn
        return fn

    return add
