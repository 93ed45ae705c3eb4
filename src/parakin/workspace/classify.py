"""Which poses belong to which workspace: batched tests over the Mechanism protocol.

A pose is in the *constant-orientation* workspace (of a :class:`~parakin.workspace.Region`) when
its inverse kinematics exists, every joint lies within its limits and (where a clearance is asked
for and the mechanism declares legs) no two legs come closer than the clearance; in the
*dexterous* workspace when, besides, the velocity Jacobian ``J = -B^-1 A`` has ``cond(J) <=
cond_max``. The IK and the Jacobians are the mechanism's kernels (:mod:`parakin.kernels`) where it
has them, on numpy or, for large batches with the compiled path on, under numba on every core
(:mod:`parakin.workspace.compiled`); else its numpy methods.
"""

from __future__ import annotations

import dataclasses

import numpy as np

from parakin.kernels import evaluate
from parakin.mechanisms.base import Array, Mechanism
from parakin.workspace.legs import min_leg_distance
from parakin.workspace.region import Region

__all__ = [
    "Classes",
    "classify",
    "condition_numbers",
    "jacobian_dets",
    "joints_of",
    "within_limits",
]

#: the joint Jacobian B counts as singular above this condition number (as
#: Mechanism.velocity_jacobian): cond(J) is then reported as inf
_B_SINGULAR = 1e12


@dataclasses.dataclass(frozen=True)
class Classes:
    """The classification of a batch of poses ``(N,)`` (boolean arrays unless said otherwise).

    ``domain``: the IK exists; ``limits``: and every joint is within its limits; ``clear``: the
    legs keep the clearance (True where not checked); ``member``: in the constant-orientation
    workspace (``limits & clear``); ``cond``: cond(J) (float, NaN where not computed);
    ``dexterous``: ``member & (cond <= cond_max)``; ``joints``: the IK ``(N, n_joints)``."""

    domain: np.ndarray
    limits: np.ndarray
    clear: np.ndarray
    member: np.ndarray
    cond: np.ndarray
    dexterous: np.ndarray
    joints: np.ndarray


def joints_of(mech: Mechanism, poses: Array) -> tuple[Array, np.ndarray]:
    """The IK ``(N, n_joints)`` (NaN where none) and where it exists ``(N,)``, batched: the kernel's
    ``ik`` where the mechanism has a kernel, else ``is_reachable`` and ``ik`` of the reachable."""
    x = np.asarray(poses, dtype=float)
    finite = np.all(np.isfinite(x), axis=-1)
    kern = mech.kernel()
    if kern is not None:
        q, ok = evaluate(kern, "ik", np.where(finite[..., None], x, 0.0))
        ok = ok & finite & np.all(np.isfinite(q), axis=-1)
        return np.where(ok[..., None], q, np.nan), ok
    ok = np.zeros(x.shape[:-1], dtype=bool)
    ok[finite] = mech.is_reachable(x[finite])
    q = np.full(x.shape[:-1] + (mech.n_joints,), np.nan)
    if np.any(ok):
        q[ok] = mech.ik(x[ok])
    ok &= np.all(np.isfinite(q), axis=-1)
    return q, ok


def within_limits(region: Region, q: Array) -> np.ndarray:
    """Every joint within ``[joint_lo, joint_hi]`` (False where a joint is NaN)."""
    return np.all((q >= region.joint_lo) & (q <= region.joint_hi), axis=-1)


def condition_numbers(mech: Mechanism, poses: Array, joints: Array) -> Array:
    """cond(J) = sigma_max / sigma_min of ``J = -B^-1 A`` per pose ``(N,)`` (inf where B or A is
    singular), from the mechanism's ``jacobian_pose`` and ``jacobian_joints``."""
    x = np.asarray(poses, dtype=float)
    q = np.asarray(joints, dtype=float)
    out = np.full(len(x), np.nan)
    if len(x) == 0:
        return out
    a = mech.jacobian_pose(x, q)
    b = mech.jacobian_joints(x, q)
    with np.errstate(all="ignore"):
        bad = ~np.all(np.isfinite(a), axis=(-2, -1)) | ~np.all(np.isfinite(b), axis=(-2, -1))
        sb = np.linalg.svd(np.where(bad[:, None, None], 1.0, b), compute_uv=False)
        bad |= ~(sb[:, -1] > sb[:, 0] / _B_SINGULAR)
        good = ~bad
        out[bad] = np.inf
        if np.any(good):
            j = -np.linalg.solve(b[good], a[good])
            s = np.linalg.svd(j, compute_uv=False)
            out[good] = np.where(
                s[:, -1] > 0, s[:, 0] / np.where(s[:, -1] > 0, s[:, -1], 1), np.inf
            )
    return out


def jacobian_dets(mech: Mechanism, poses: Array, joints: Array) -> dict[str, Array]:
    """Per pose: ``det_A``, ``det_B`` (NaN where the matrix is not square: a redundant mechanism)
    and ``smin_A``, ``smin_B``, ``smax_A``, ``smax_B`` (their extreme singular values), of
    ``A = d residual / d pose`` (direct kinematics) and ``B = d residual / d joints`` (inverse
    kinematics; Gosselin & Angeles 1990)."""
    x = np.asarray(poses, dtype=float)
    q = np.asarray(joints, dtype=float)
    out: dict[str, Array] = {}
    n = len(x)
    with np.errstate(all="ignore"):
        for name, mat in (("A", mech.jacobian_pose(x, q)), ("B", mech.jacobian_joints(x, q))):
            fin = np.all(np.isfinite(mat), axis=(-2, -1))
            safe = np.where(fin[:, None, None], mat, 0.0)
            if mat.shape[-1] == mat.shape[-2]:
                det = np.linalg.det(safe) if n else np.zeros(0)
            else:
                det = np.full(n, np.nan)
            s = np.linalg.svd(safe, compute_uv=False) if n else np.zeros((0, 1))
            out[f"det_{name}"] = np.where(fin, det, np.nan)
            out[f"smin_{name}"] = np.where(fin, s[:, -1], np.nan)
            out[f"smax_{name}"] = np.where(fin, s[:, 0], np.nan)
    return out


def classify(
    region: Region,
    points: Array,
    *,
    orientation: Array | None = None,
    cond: bool = True,
    interference: bool = True,
    compiled: bool | None = None,
) -> Classes:
    """Classify workspace points ``(N, dim)`` (over ``region.axes``; the other coordinates at their
    given values, or at ``orientation`` ``(N or 1, n_others)``): see :class:`Classes`. ``cond``:
    compute cond(J) (the dexterous test); ``interference``: test the legs' clearance where the
    region asks for one; ``compiled``: None = the compiled path for large batches where it is on."""
    x = region.poses(points, orientation).reshape(-1, region.mech.n_pose)
    import parakin.workspace.compiled as cc

    fast = cc.classifier(region, len(x), compiled)
    if fast is not None:
        q, domain, limits, cnd = fast(x, cond)
    else:
        q, domain = joints_of(region.mech, x)
        limits = domain & within_limits(region, q)
        cnd = np.full(len(x), np.nan)
        if cond and np.any(limits):
            cnd[limits] = condition_numbers(region.mech, x[limits], q[limits])
    clear = np.ones(len(x), dtype=bool)
    if interference and region.clearance is not None and np.any(limits):
        d = min_leg_distance(region.mech, x[limits])
        if d is not None:
            clear[limits] = d >= region.clearance
    member = limits & clear
    with np.errstate(invalid="ignore"):
        dexterous = member & (cnd <= region.cond_max)
    return Classes(domain, limits, clear, member, np.where(member, cnd, np.nan), dexterous, q)
