"""The hybrid forward kinematics of Zhao et al. 2017 (§1.1, Fig. 3): a trained network's guess,
refined by a quasi-Newton iteration.

The network maps joints to an approximate pose (accuracy ~1e-4 m for the paper's BP network);
the quasi-Newton method (Broyden's, the classic quasi-Newton method for nonlinear equations, by
default; BFGS on the squared residual or Newton on request) then iterates from that
guess until its step falls below the paper's "iteration error" ``eps`` (1e-7) or the residual
below ``tol``. Any object with ``predict(joints) -> pose`` serves as the network (see
:class:`parakin.nn.BPNetwork`), so the method works on every mechanism that has one.
"""

from __future__ import annotations

import dataclasses
from typing import Any, Protocol

import numpy as np

from parakin.mechanisms.base import Array, Mechanism
from parakin.solvers.registry import METHODS
from parakin.solvers.result import FKResult, Status, rowwise, summarize

__all__ = ["hybrid", "Network"]


class Network(Protocol):
    def predict(self, inputs: Array) -> Array: ...


def hybrid(
    mech: Mechanism,
    joints: Array,
    x0: Array,
    *,
    tol: float,
    maxiter: int,
    network: Network | None = None,
    refine: str = "broyden",
    eps: float = 1e-7,
    check: bool = True,
    **options: Any,
) -> FKResult:
    """Network guess + quasi-Newton refinement (Zhao 2017, Fig. 3).

    ``network``: required, an object with ``predict``; ``x0`` is ignored (the network gives the
    start). ``refine``: the registered method that refines the guess: ``"broyden"`` (default;
    the paper does not say which quasi-Newton method it used, its ref. [13] solves the FK
    equations directly), ``"bfgs"`` (minimising |r|^2), or ``"newton"``. From a guess ~1 mm off,
    Broyden needs 3 iterations where BFGS needs 4 (``fk_benchmark`` has both). ``eps``: the paper's iteration error, used as the
    step tolerance ``xtol`` of the refinement. A pose converges when its residual is ``<= tol``,
    or when the step is ``<= eps`` *and* the residual is ``<= 10 eps`` (a small step at a large
    residual is a local minimum of unreachable joints, not a solution). ``nit`` counts the
    quasi-Newton iterations (the network evaluation is not an iteration).

    ``check``: first call ``mech.check_joints`` so that joints outside the reachable set are not
    refined from a network that would silently extrapolate: those rows stop with
    :attr:`Status.UNREACHABLE` (``x = x0``), the others are solved.
    """
    if network is None:
        raise ValueError(
            "the hybrid method needs network=... (e.g. parakin.nn.BPNetwork.load(path))"
        )
    if refine == "hybrid" or refine not in METHODS:
        raise ValueError(f"refine = {refine!r} must be one of {sorted(set(METHODS) - {'hybrid'})}")
    reachable = np.ones(len(joints), dtype=bool)
    if check:  # row by row where it raises: one unreachable input never costs the batch
        reachable = rowwise(lambda q: _passes(mech, q), joints, tail=(), fill=0.0) > 0.5
    with np.errstate(all="ignore"):
        guess = np.broadcast_to(np.asarray(network.predict(joints), dtype=float), x0.shape).copy()
    guess = np.where(
        reachable[:, None] & np.all(np.isfinite(guess), axis=-1, keepdims=True), guess, x0
    )
    res = METHODS[refine](mech, joints, guess, tol=tol, maxiter=maxiter, xtol=eps, **options)
    # a step below eps counts only where the residual is at the level of eps too
    ok = (res.residual <= tol) | ((res.status == Status.SMALL_STEP) & (res.residual <= 10 * eps))
    status = np.where(ok | (res.status < 0), res.status, Status.LOCAL_MINIMUM).astype(np.int64)
    status[~reachable] = Status.UNREACHABLE
    x = np.where(reachable[:, None], res.x, x0)
    return dataclasses.replace(
        res,
        x=x,
        success=status >= 0,
        status=status,
        method="hybrid",
        message=summarize(status, maxiter),
    )


def _passes(mech: Mechanism, joints: Array) -> Array:
    """Ones where ``mech.check_joints`` accepts the batch (it raises otherwise)."""
    mech.check_joints(joints)
    return np.ones(len(joints))
