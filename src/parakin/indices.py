"""Kinematic performance indices of any mechanism and their workspace means.

From the velocity Jacobian ``J = -B^-1 A`` of any :class:`~parakin.mechanisms.base.Mechanism`:
the speed (condition number), stiffness and manipulability indices (Zhao et al. 2017, eqs 30-37,
generalised), and their means over a pose box by tensor Gauss-Legendre quadrature. The 3-P(4S)'s
own indices (its dynamic index needs its mass matrix) live beside it, in
:mod:`parakin.mechanisms.p3p4s_indices`.
"""

from __future__ import annotations

from typing import Literal

import numpy as np
from numpy.typing import ArrayLike

from parakin.errors import UnreachableError

__all__ = [
    "KINEMATIC_INDEX_NAMES",
    "Quadrature",
    "kinematic_indices",
    "box_nodes",
    "global_kinematic_indices",
]

Quadrature = Literal["gauss", "midpoint"]

#: the kinematic indices :func:`kinematic_indices` returns, for any mechanism
KINEMATIC_INDEX_NAMES = ("speed", "stiffness_lambda", "stiffness_sqrt", "manipulability")


def kinematic_indices(mech, poses: ArrayLike, *, k: float = 1.0) -> dict[str, np.ndarray]:
    """The kinematic indices of any mechanism from its velocity Jacobian ``J = -B^-1 A``
    (``qdot = J xdot``), batched over poses ``(..., n_pose)``:

    * ``speed``: ``sigma_max(J) / sigma_min(J)`` (eq 36's condition number; >= 1);
    * ``stiffness_lambda``: ``k sigma_min(J)^2 = lambda_min(J^T k J)`` (eq 30 with ``k_a = k``);
    * ``stiffness_sqrt``: its square root (eq 33 as printed);
    * ``manipulability``: ``prod sigma_i(J)`` (Yoshikawa's ``sqrt(det(J^T J))`` for square J).

    For the 3-P(4S) these equal :func:`parakin.mechanisms.p3p4s_indices.mech_indices`'s (a test checks it). Where pose
    coordinates mix units (m and rad) ``speed`` depends on that choice of units, as every
    condition number of a mixed Jacobian does. Unreachable poses raise UnreachableError and
    actuator-singular ones SingularityError (from :meth:`Mechanism.velocity_jacobian`).
    """
    if not (np.isfinite(k) and k > 0):
        raise ValueError(f"k = {k!r} must be finite and > 0")
    s = np.linalg.svd(
        mech.velocity_jacobian(poses), compute_uv=False
    )  # (..., min(m, n)), descending
    smin = s[..., -1]
    with np.errstate(divide="ignore"):
        speed = np.where(smin > 0, s[..., 0] / np.where(smin > 0, smin, 1.0), np.inf)
    return {
        "speed": speed,
        "stiffness_lambda": k * smin**2,
        "stiffness_sqrt": np.sqrt(k) * smin,
        "manipulability": np.prod(s, axis=-1),
    }


def box_nodes(
    lo: ArrayLike, hi: ArrayLike, n: int, rule: Quadrature = "gauss"
) -> tuple[np.ndarray, np.ndarray]:
    """Tensor quadrature over the pose box ``[lo, hi]`` (any dimension; an axis with ``lo == hi`` is
    held fixed): points ``(N, d)`` and weights ``(N,)`` summing to 1, ``n`` nodes per free axis,
    Gauss-Legendre or midpoint (as :meth:`parakin.mechanisms.p3p4s_indices.Workspace.nodes`)."""
    lo, hi = np.asarray(lo, dtype=float), np.asarray(hi, dtype=float)
    if lo.shape != hi.shape or lo.ndim != 1 or np.any(hi < lo):
        raise ValueError(f"box bounds must be two 1-D arrays with lo <= hi, got {lo} and {hi}")
    if not (isinstance(n, (int, np.integer)) and n >= 1):
        raise ValueError(f"n = {n!r} nodes per axis must be a positive integer")
    if rule == "gauss":
        t, w = np.polynomial.legendre.leggauss(int(n))
        t, w = 0.5 * (t + 1.0), 0.5 * w
    elif rule == "midpoint":
        t, w = (np.arange(n) + 0.5) / n, np.full(n, 1.0 / n)
    else:
        raise ValueError(f"rule = {rule!r} must be 'gauss' or 'midpoint'")
    axes = [np.array([a]) if a == b else a + (b - a) * t for a, b in zip(lo, hi)]
    weights = [np.array([1.0]) if a == b else w for a, b in zip(lo, hi)]
    grid = np.stack(np.meshgrid(*axes, indexing="ij"), axis=-1).reshape(-1, len(lo))
    wt = weights[0]
    for ww in weights[1:]:
        wt = np.multiply.outer(wt, ww)
    return grid, wt.reshape(-1)


def global_kinematic_indices(
    mech, lo: ArrayLike, hi: ArrayLike, n: int, *, k: float = 1.0, rule: Quadrature = "gauss"
) -> dict[str, float]:
    """Workspace means (eqs 29, 34, 37's ``int_W index dW / int_W dW``) of :func:`kinematic_indices`
    over the pose box ``[lo, hi]`` by :func:`box_nodes`. The box must lie inside the workspace: an
    unreachable node raises UnreachableError naming it (a mean over a partly unreachable box would
    depend on how the holes are treated)."""
    x, w = box_nodes(lo, hi, n, rule)
    bad = ~mech.is_reachable(x)
    if np.any(bad):
        raise UnreachableError(
            f"quadrature node {tuple(np.round(x[np.argmax(bad)], 9).tolist())} of the box "
            f"{np.asarray(lo).tolist()}..{np.asarray(hi).tolist()} is unreachable "
            f"({int(bad.sum())} of {len(x)} nodes)"
        )
    ind = kinematic_indices(mech, x, k=k)
    return {name: float(w @ v) for name, v in ind.items()}
