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
:func:`conditioning` measures that at the answer (``FKResult.conditioning``, computed on first
use): the condition number of ``d ik / d pose`` and, from the fold normal form, the offset to the
nearest other solution; an answer whose neighbour lies within :data:`NEAR_SINGULAR` of the pose
box is flagged ``near_singular`` (still a success: it is a right answer). See
``docs/near_singular.md``.
"""

from __future__ import annotations

import dataclasses
from typing import Any

import numpy as np

from parakin import kernels
from parakin.mechanisms.base import Array, Mechanism
from parakin.solvers.result import Conditioning, FKResult, Status, rowwise, summarize

__all__ = [
    "JOINT_TOL_FLOOR",
    "NEAR_SINGULAR",
    "conditioning",
    "default_joint_tol",
    "judge_one",
    "verify",
]

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


#: an answer is *near a singularity* when another solution of the same joints is estimated within
#: this fraction of the pose box (largest |offset_k| / box width_k): a scale fixed beforehand, not
#: fitted to any case (docs/near_singular.md: derivation, and how often it fires per mechanism)
NEAR_SINGULAR = 0.01
#: central-difference step of ``d ik / d pose`` and the second-difference step along the fold
#: direction, in box widths (truncation ~h^2 and rounding ~eps/h of each stay below 1e-8)
_H_JACOBIAN, _H_CURVATURE = 1e-6, 1e-4


def conditioning(mech: Mechanism, x: Array) -> Conditioning:
    """The :class:`~parakin.solvers.result.Conditioning` of the FK answers ``x (..., n_pose)``.

    With ``F(x) = ik(x)`` in pose coordinates scaled by the box widths, ``J = dF/dx = U S V^T``:
    along the weakest direction ``v`` (smallest singular value ``s``, left vector ``u``) the
    joints change as ``s t + a t^2 / 2`` with ``a = u . F''[v, v]``, so (fold normal form) another
    solution of the same joints lies near ``t = -2 s / a``; its offset is ``t v`` (box widths).
    Square systems only (a redundant system, more joints than pose coordinates, has no such fold
    in general: offset NaN, never flagged). Rows that are not finite, or whose IK fails near
    ``x``, give NaN and are not flagged.
    """
    x = np.asarray(x, dtype=float)
    shape, n = x.shape[:-1], x.shape[-1]
    flat = x.reshape(-1, n)
    width = np.subtract(*(np.asarray(b, dtype=float) for b in mech.pose_bounds()[::-1]))
    condition, offset = np.full(len(flat), np.nan), np.full(flat.shape, np.nan)
    fin = np.all(np.isfinite(flat), axis=-1)
    if fin.any():
        condition[fin], offset[fin] = _fold(mech, flat[fin], width)
    with np.errstate(invalid="ignore"):
        distance = np.max(np.abs(offset) / width, axis=-1, initial=0.0)
    distance = np.where(np.isfinite(distance), distance, np.inf)
    return Conditioning(
        condition=condition.reshape(shape),
        neighbour=offset.reshape(*shape, n),
        distance=distance.reshape(shape),
        near_singular=(distance <= NEAR_SINGULAR).reshape(shape),
        threshold=NEAR_SINGULAR,
    )


def _fold(mech: Mechanism, x: Array, width: Array) -> tuple[Array, Array]:
    """Condition number and fold offset (see :func:`conditioning`) of finite poses ``x (N, n)``."""
    n = x.shape[-1]
    steps = np.concatenate([np.eye(n), -np.eye(n), np.zeros((1, n))]) * (_H_JACOBIAN * width)
    f = _ik_at(mech, x[:, None, :] + steps[None])  # (N, 2n + 1, m): x +- h e_k, then x
    jac = np.swapaxes(f[:, :n] - f[:, n : 2 * n], 1, 2) / (2 * _H_JACOBIAN)  # (N, m, n)
    with np.errstate(all="ignore"):
        ok = np.all(np.isfinite(jac), axis=(1, 2))
        u, sv, vt = np.linalg.svd(np.where(ok[:, None, None], jac, 0.0), full_matrices=False)
        condition = np.where(ok, sv[:, 0] / sv[:, -1], np.nan)
        weak, left = vt[:, -1, :], u[:, :, -1]  # (N, n), (N, m)
        g = _ik_at(mech, x[:, None, :] + np.stack([weak, -weak], 1) * (_H_CURVATURE * width))
        second = (g[:, 0] - 2 * f[:, -1] + g[:, 1]) / _H_CURVATURE**2
        t = -2 * sv[:, -1] / np.einsum("nm,nm->n", left, second)
        offset = t[:, None] * weak * width
    if f.shape[-1] != n:  # redundant: no fold normal form
        offset[:] = np.nan
    return condition, np.where(ok[:, None], offset, np.nan)


def _ik_at(mech: Mechanism, points: Array) -> Array:
    """``mech.ik`` of ``points (N, k, n)`` in one call, ``(N, k, m)``; NaN where the IK fails."""
    n_rows, k, n = points.shape
    flat = points.reshape(-1, n)
    return rowwise(mech.ik, flat, tail=(mech.n_joints,)).reshape(n_rows, k, mech.n_joints)
