"""What "the workspace" of a mechanism means here: which pose coordinates span it, at which given
values the others are held, inside which box, under which joint limits, with which orientation
box, condition bound and leg clearance. One frozen :class:`Region` carries all of it; every
function of :mod:`parakin.workspace` takes one.

Generic: only the :class:`~parakin.mechanisms.base.Mechanism` protocol is used. Two optional
hooks a mechanism may offer are read when present (proposed additions to the protocol):

* ``joint_limits() -> (lo, hi)``: the actuated joints' limits (``-inf``/``inf`` where none);
  until a mechanism declares it, a described mechanism's legs' ``limits`` and a ``stroke_limits``
  field (symmetric ``|q_k| <= s_k``, the 2-UPS's eq 19) are read as one;
* ``leg_segments(pose) -> (..., n_legs, 2, 3)`` (see :mod:`parakin.workspace.legs`).
"""

from __future__ import annotations

import dataclasses
from collections.abc import Sequence

import numpy as np
from numpy.typing import ArrayLike

from parakin.mechanisms.base import Array, Mechanism

__all__ = [
    "DEFAULT_COND_MAX",
    "DEFAULT_STROKE",
    "Region",
    "declared_joint_limits",
    "default_axes",
    "make_region",
    "measure_unit",
]

#: the dexterous workspace's default bound on cond(J) (the velocity Jacobian's condition number)
DEFAULT_COND_MAX = 100.0
#: joint limits assumed where a mechanism declares none: home +- this fraction of the mean |home
#: joint value| (every actuator the same stroke); always reported as assumed
DEFAULT_STROKE = 0.25


def declared_joint_limits(mech: Mechanism) -> tuple[Array, Array] | None:
    """The mechanism's own joint limits ``(lo, hi)`` (``n_joints`` each), or None: its
    ``joint_limits()`` hook where it has one, else a ``stroke_limits`` field read as
    ``|q_k| <= s_k``."""
    hook = getattr(mech, "joint_limits", None)
    if callable(hook):
        lo, hi = (np.broadcast_to(np.asarray(v, dtype=float), (mech.n_joints,)) for v in hook())
        return lo.copy(), hi.copy()
    legs = getattr(mech, "legs", None)
    if isinstance(legs, (tuple, list)) and len(legs) == mech.n_joints:
        if all(hasattr(leg, "limits") for leg in legs):  # a described mechanism's legs
            lim = [leg.limits or (-np.inf, np.inf) for leg in legs]
            return np.array([a for a, _ in lim], float), np.array([b for _, b in lim], float)
    stroke = getattr(mech, "stroke_limits", None)
    if stroke is not None:
        s = np.broadcast_to(np.asarray(stroke, dtype=float), (mech.n_joints,))
        return -s.copy(), s.copy()
    return None


def default_axes(mech: Mechanism) -> tuple[int, ...]:
    """The pose coordinates that span the workspace by default: the lengths (unit ``m``) where there
    are at least two (a platform's position: 3-D for a spatial mechanism, 2-D for a planar one),
    else the coordinates that are not angles where there are at least two, else all of them."""
    units = mech.pose_units
    for keep in (lambda u: u == "m", lambda u: u != "rad", lambda u: True):
        axes = tuple(k for k, u in enumerate(units) if keep(u))
        if len(axes) >= 2:
            return axes
    return tuple(range(mech.n_pose))


def measure_unit(units: Sequence[str]) -> str:
    """The unit of a volume over coordinates of ``units``: ``m^3``, ``m^2 rad``, ``1`` ..."""
    counts: dict[str, int] = {}
    for u in units:
        if u != "1":
            counts[u] = counts.get(u, 0) + 1
    if not counts:
        return "1"
    return " ".join(u if n == 1 else f"{u}^{n}" for u, n in counts.items())


@dataclasses.dataclass(frozen=True, eq=False)
class Region:
    """A workspace question about one mechanism (build it with :func:`make_region`).

    ``axes``: the pose coordinates that span the workspace; ``pose``: a full pose whose other
    coordinates are the *given* values (the constant-orientation workspace holds them there);
    ``lo``/``hi``: the box over ``axes`` in which volumes are measured; ``joint_lo``/``joint_hi``:
    joint limits (``-inf``/``inf`` where none) and ``limits_source`` how they were obtained;
    ``orient_lo``/``orient_hi``: the box over the other coordinates within which the reachable
    workspace may choose them; ``cond_max``: the dexterous workspace's bound on cond(J);
    ``clearance``: the least distance between two legs (None: interference not checked).
    """

    mech: Mechanism
    axes: tuple[int, ...]
    pose: Array
    lo: Array
    hi: Array
    joint_lo: Array
    joint_hi: Array
    limits_source: str
    orient_lo: Array
    orient_hi: Array
    cond_max: float = DEFAULT_COND_MAX
    clearance: float | None = None

    @property
    def others(self) -> tuple[int, ...]:
        """The pose coordinates held at their given values (the 'orientation')."""
        return tuple(k for k in range(self.mech.n_pose) if k not in self.axes)

    @property
    def dim(self) -> int:
        return len(self.axes)

    @property
    def axis_names(self) -> tuple[str, ...]:
        return tuple(self.mech.pose_names[k] for k in self.axes)

    @property
    def axis_units(self) -> tuple[str, ...]:
        return tuple(self.mech.pose_units[k] for k in self.axes)

    @property
    def unit(self) -> str:
        """The unit of a volume of this workspace (``m^3``, ``m^2``, ...)."""
        return measure_unit(self.axis_units)

    @property
    def box_volume(self) -> float:
        return float(np.prod(self.hi - self.lo))

    @property
    def has_limits(self) -> bool:
        return bool(np.any(np.isfinite(self.joint_lo) | np.isfinite(self.joint_hi)))

    def poses(self, points: ArrayLike, orientation: ArrayLike | None = None) -> Array:
        """Full poses ``(..., n_pose)`` of workspace points ``(..., dim)``: the given pose with
        its ``axes`` replaced; ``orientation`` ``(..., n_others)`` replaces the other coordinates."""
        p = np.asarray(points, dtype=float)
        shape = p.shape[:-1]
        if orientation is not None:
            shape = np.broadcast_shapes(shape, np.shape(orientation)[:-1])
        x = np.empty(shape + (self.mech.n_pose,))
        x[...] = self.pose
        x[..., list(self.axes)] = p
        if orientation is not None and self.others:
            x[..., list(self.others)] = orientation
        return x

    def replace(self, **changes) -> Region:
        return dataclasses.replace(self, **changes)

    def describe(self) -> dict:
        """A JSON-ready description (SI units)."""
        names = self.mech.pose_names
        return {
            "axes": list(self.axis_names),
            "axis_units": list(self.axis_units),
            "given": {names[k]: float(self.pose[k]) for k in self.others},
            "box": {names[k]: [float(a), float(b)] for k, a, b in zip(self.axes, self.lo, self.hi)},
            "orientation_box": {
                names[k]: [float(a), float(b)]
                for k, a, b in zip(self.others, self.orient_lo, self.orient_hi)
            },
            "joint_limits": {
                "source": self.limits_source,
                "lo": [_json_float(v) for v in self.joint_lo],
                "hi": [_json_float(v) for v in self.joint_hi],
            },
            "cond_max": self.cond_max,
            "clearance": self.clearance,
        }


def _json_float(v: float) -> float | None:
    """A finite float, or None for an absent limit (strict JSON has no infinity)."""
    return float(v) if np.isfinite(v) else None


def _vector(values: ArrayLike, n: int, what: str) -> Array:
    a = np.asarray(values, dtype=float)
    if a.shape != (n,):
        raise ValueError(f"{what} must have {n} values, got shape {a.shape}")
    if not np.all(np.isfinite(a)):
        raise ValueError(f"{what} = {a.tolist()} must be finite")
    return a


def make_region(
    mech: Mechanism,
    *,
    axes: Sequence[int | str] | None = None,
    pose: ArrayLike | None = None,
    box: tuple[ArrayLike, ArrayLike] | None = None,
    joint_limits: tuple[ArrayLike, ArrayLike] | None = None,
    stroke: float | None = None,
    orientation_box: tuple[ArrayLike, ArrayLike] | None = None,
    orientation_fraction: float = 1.0,
    cond_max: float = DEFAULT_COND_MAX,
    clearance: float | None = None,
) -> Region:
    """A :class:`Region` of ``mech`` with defaults for everything not given.

    ``axes``: indices or names of pose coordinates (default :func:`default_axes`); ``pose``: the
    given pose (default ``mech.home()``); ``box``: over ``axes`` (default the mechanism's
    ``pose_bounds()`` there; :func:`parakin.workspace.fit_box` grows it to hold the workspace);
    ``joint_limits``: ``(lo, hi)`` (scalars or ``n_joints`` values; default the mechanism's,
    :func:`declared_joint_limits`); without either, ``stroke`` (default :data:`DEFAULT_STROKE`,
    0 for none) assumes home +- ``stroke`` x the mean |home joint value| for the length joints
    (a revolute joint keeps its full turn); ``orientation_box``:
    over the other coordinates (default: the given values +- ``orientation_fraction`` x half the
    width of their ``pose_bounds()``, within those bounds); ``cond_max`` >= 1;
    ``clearance`` >= 0 or None. Bad values raise a ValueError that names the value and the limit.
    """
    n = mech.n_pose
    names = mech.pose_names
    if axes is None:
        ax = default_axes(mech)
    else:
        ax = tuple(_axis_index(a, names) for a in axes)
        if not ax or len(set(ax)) != len(ax):
            raise ValueError(f"axes {list(axes)} must name distinct pose coordinates of {names}")
        ax = tuple(sorted(ax))
    given = np.asarray(mech.home(), dtype=float) if pose is None else _vector(pose, n, "pose")
    blo, bhi = (np.asarray(b, dtype=float) for b in mech.pose_bounds())
    if box is None:
        lo, hi = blo[list(ax)].copy(), bhi[list(ax)].copy()
    else:
        lo, hi = (_vector(np.broadcast_to(b, (len(ax),)), len(ax), "box") for b in box)
    bad = ~(hi > lo)
    if np.any(bad):
        k = int(np.argmax(bad))
        raise ValueError(f"box of {names[ax[k]]}: [{lo[k]:g}, {hi[k]:g}] must have low < high")
    others = [k for k in range(n) if k not in ax]
    if orientation_box is None:
        if not (np.isfinite(orientation_fraction) and 0 <= orientation_fraction <= 1):
            raise ValueError(f"orientation_fraction = {orientation_fraction!r} must lie in [0, 1]")
        half = orientation_fraction * 0.5 * (bhi[others] - blo[others])
        olo = np.maximum(given[others] - half, blo[others])
        ohi = np.minimum(given[others] + half, bhi[others])
    else:
        olo, ohi = (
            np.broadcast_to(np.asarray(b, dtype=float), (len(others),)) for b in orientation_box
        )
        olo, ohi = olo.copy(), ohi.copy()
        if not np.all(np.isfinite(olo) & np.isfinite(ohi) & (olo <= ohi)):
            raise ValueError(
                f"orientation box {olo.tolist()}..{ohi.tolist()} must be finite with low <= high"
            )
    if not (np.isfinite(cond_max) and cond_max >= 1):
        raise ValueError(f"cond_max = {cond_max!r} must be a finite number >= 1")
    if clearance is not None and not (np.isfinite(clearance) and clearance >= 0):
        raise ValueError(f"clearance = {clearance!r} must be a finite length >= 0")
    jlo, jhi, source = _joint_limits(mech, joint_limits, stroke)
    return Region(mech, ax, given, lo, hi, jlo, jhi, source, olo, ohi, float(cond_max), clearance)


def _axis_index(a: int | str, names: Sequence[str]) -> int:
    if isinstance(a, (int, np.integer)):
        if not 0 <= int(a) < len(names):
            raise ValueError(f"axis {a} must lie in 0..{len(names) - 1}")
        return int(a)
    if a not in names:
        raise ValueError(f"axis {a!r} is not a pose coordinate; known: {', '.join(names)}")
    return list(names).index(a)


def _joint_limits(
    mech: Mechanism, given: tuple[ArrayLike, ArrayLike] | None, stroke: float | None
) -> tuple[Array, Array, str]:
    m = mech.n_joints
    if given is not None:
        lo, hi = (np.broadcast_to(np.asarray(v, dtype=float), (m,)).copy() for v in given)
        bad = np.isnan(lo) | np.isnan(hi) | ~(lo < hi)
        if np.any(bad):
            k = int(np.argmax(bad))
            raise ValueError(
                f"joint limits of {mech.joint_names[k]}: [{lo[k]:g}, {hi[k]:g}] must have low < high"
            )
        return lo, hi, "given"
    declared = declared_joint_limits(mech)
    if declared is not None and not np.any(np.isfinite(declared[0]) | np.isfinite(declared[1])):
        declared = None  # declared as "no limits" (a described mechanism's legs without any)
    if declared is not None:
        return declared[0], declared[1], "declared by the mechanism"
    f = DEFAULT_STROKE if stroke is None else float(stroke)
    if not (np.isfinite(f) and 0 <= f <= 10):
        raise ValueError(f"stroke = {stroke!r} must be a fraction in [0, 10]")
    # a stroke is a length's: a revolute joint (unit rad) keeps its full turn
    linear = np.array([u != "rad" for u in mech.joint_units])
    if f == 0 or not linear.any():
        why = "none" if f == 0 else "none (revolute joints turn freely)"
        return np.full(m, -np.inf), np.full(m, np.inf), why
    q0 = np.asarray(mech.ik(mech.home()), dtype=float)
    scale = float(np.mean(np.abs(q0[linear])))
    if not scale > 0:
        raise ValueError(
            f"{mech.name}: the home joint values are all 0, so a stroke relative to them means "
            "nothing: give the joint limits"
        )
    half = f * scale
    units = {u for u, lin in zip(mech.joint_units, linear) if lin}
    unit = f" {units.pop()}" if len(units) == 1 and "1" not in units else ""
    lo = np.where(linear, q0 - half, -np.inf)
    hi = np.where(linear, q0 + half, np.inf)
    return lo, hi, f"assumed: home +- {f:g} x mean |home joint| = +- {half:.4g}{unit}"
