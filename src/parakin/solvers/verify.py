"""What makes a solve a success: the pose is a valid answer for the joints, not only a small residual.

A method reports success where its own stopping rule holds (residual inf-norm ``<= tol``, or a
small step / gradient where the caller asked for one). :func:`verify` then checks, on the rows that
claim success, that the pose is an answer of the mechanism for those joints:

* the pose lies in the mechanism's domain (``mech.in_domain``: where its IK is defined), else
  :attr:`Status.OUT_OF_DOMAIN`;
* it is on the assembly mode / branch the mechanism instance asks for (``mech.on_assembly``, the
  papers' by default), else :attr:`Status.WRONG_ASSEMBLY`;
* the IK of the pose reproduces the joints: ``max_k |ik(x)_k - q_k| <= joint_tol``
  (``mech.joint_error``), else :attr:`Status.WRONG_ANSWER`. A residual tolerance alone does not
  bound this near a singularity, where the joints are very sensitive to the pose.

The joint error of every row is reported in ``FKResult.joint_error``. Where the mechanism has
compiled kernels (``mech.kernel()``, :mod:`parakin.kernels`) the three hooks are evaluated by them
(the same equations, one pose at a time); the rules above are the same for every result.

A valid answer can still sit near a forward singularity, where another solution of the same
joints (on the same assembly) comes close and the start decides which one a solver returns.
:func:`parakin.solvers.result.conditioning` measures that at the answer
(``FKResult.conditioning``, computed on first use): the condition number of ``d ik / d pose`` and,
from the fold normal form, the offset to the nearest other solution; an answer whose neighbour
lies within ``NEAR_SINGULAR`` of the pose box is flagged ``near_singular`` (still a success: it is
a right answer). See ``docs/near_singular.md``.
"""

from __future__ import annotations

import dataclasses
from typing import Any

import numpy as np

from parakin import kernels
from parakin.mechanisms.base import Array, Mechanism
from parakin.solvers.result import FKResult, Status, rowwise, summarize

__all__ = ["JOINT_TOL_FLOOR", "default_joint_tol", "judge_one", "verify"]

#: smallest default joint tolerance (joint units: m, or the dimensionless lengths of the 3-6 Stewart)
JOINT_TOL_FLOOR = 1e-8


def default_joint_tol(tol: float, options: dict[str, Any]) -> float:
    """100 x the accuracy the call asked for (``tol``, or the step / fitness tolerance ``xtol``,
    ``eps``, ``ftol`` of a method that stops on it), at least :data:`JOINT_TOL_FLOOR`."""
    if not options:  # the common single call: tol alone
        return max(JOINT_TOL_FLOOR, 100.0 * tol)
    asked = [tol] + [
        float(options[k]) for k in ("xtol", "eps", "ftol") if options.get(k) is not None
    ]
    return max(JOINT_TOL_FLOOR, 100.0 * max(asked))


def _mask(f, *rows: Array) -> Array:
    """A boolean hook evaluated row-safely (a row that raises counts as False)."""
    return rowwise(f, *rows, tail=(), fill=0.0) > 0.5


def judge_one(status: int, dom: bool, asm: bool, err: float, joint_tol: float) -> int:
    """:func:`verify`'s rules for one pose (the compiled single-call path): a claimed success
    outside the domain is OUT_OF_DOMAIN, off the assembly WRONG_ASSEMBLY, with ``ik(x)`` farther
    than ``joint_tol`` from the joints WRONG_ANSWER; anything else keeps its status."""
    if status < 0:
        return status
    if not dom:
        return int(Status.OUT_OF_DOMAIN)
    if not asm:
        return int(Status.WRONG_ASSEMBLY)
    if not err <= joint_tol:
        return int(Status.WRONG_ANSWER)
    return status


def verify(
    mech: Mechanism, joints: Array, result: FKResult, joint_tol: float, maxiter: int | None = None
) -> FKResult:
    """``result`` (flat, ``(N,)``) with ``joint_error`` filled in and every claimed success that is
    not a valid answer turned into its failure status (see the module docstring)."""
    x, n = result.x, len(joints)
    hooks = kernels.verify_hooks(
        mech, joints, x
    )  # the same three hooks, compiled, where the mechanism has a kernel
    if hooks is not None:
        dom, err, asm = hooks
    else:
        fin = np.all(np.isfinite(x), axis=-1)
        dom = np.zeros(n, dtype=bool)
        dom[fin] = _mask(mech.in_domain, x[fin])
        err = np.full(n, np.inf)
        asm = np.zeros(n, dtype=bool)
        if dom.any():
            err[dom] = rowwise(mech.joint_error, x[dom], joints[dom], tail=(), fill=np.inf)
            asm[dom] = _mask(mech.on_assembly, x[dom], joints[dom])
        err = np.where(np.isnan(err), np.inf, err)
    claimed = result.status >= 0
    status = result.status.copy()
    # the rules (judge_one is the same for one pose): the first failing check names the status
    status[claimed & ~(err <= joint_tol)] = Status.WRONG_ANSWER
    status[claimed & dom & ~asm] = Status.WRONG_ASSEMBLY
    status[claimed & ~dom] = Status.OUT_OF_DOMAIN
    if np.array_equal(status, result.status):
        return dataclasses.replace(result, joint_error=err)
    message = summarize(status, maxiter)
    return dataclasses.replace(
        result, success=status >= 0, status=status, joint_error=err, message=message
    )
