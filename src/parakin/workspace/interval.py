"""Certified inner and outer bounds on a workspace's volume by interval analysis (Merlet's approach).

A mechanism's kernel ``ik`` (:mod:`parakin.kernels`) is written once in a handful of math names
(``sqrt``, ``sin``, ``cos``, ``where``, ``maximum``, operators, comparisons); here it is run a
fourth way, on *intervals*: each pose coordinate is a box side ``[lo, hi]`` (the held ones a
point), every operation returns an interval that holds every value the operation can take over its
arguments' intervals (rounded outwards by a few ulp, so round-off cannot shrink it), and every
comparison a three-valued answer (certainly true, certainly false, either). The kernel's result is
an enclosure of every joint over the box and whether the IK certainly exists, certainly does not,
or either. A box is then

* **in** when the IK certainly exists and every joint enclosure lies within its limits;
* **out** when the IK certainly does not exist, or a joint's enclosure lies beyond a limit;
* **undecided** otherwise: it is halved along every axis and its children classified in turn.

The volume of the boxes found in is an inner bound of the constant-orientation workspace
(IK existence and joint limits; the clearance and the condition bound are not certified); adding the
undecided boxes left at the last level gives an outer bound. Every box carries all its
coordinates as intervals, so this works for any kernel mechanism whose constant-orientation
workspace is asked for (translational, planar, or a spatial one at a fixed orientation), as long as
its ``ik`` branches on values only through ``where`` (the kernels' rule).
"""

from __future__ import annotations

import dataclasses
import math
from collections.abc import Iterator

import numpy as np

from parakin.kernels import _math
from parakin.workspace.region import Region

__all__ = ["Bounds", "Interval", "Tri", "certify", "interval_ik"]

_EPS = np.finfo(float).eps
_TINY = 1e-300


def _down(x):
    """``x`` moved down by a few ulp (round-off of one operation, with a margin); infinite and
    NaN ends stay."""
    with np.errstate(invalid="ignore"):
        return np.where(np.isfinite(x), x - (4 * _EPS * np.abs(x) + _TINY), x)


def _up(x):
    with np.errstate(invalid="ignore"):
        return np.where(np.isfinite(x), x + (4 * _EPS * np.abs(x) + _TINY), x)


class Tri:
    """A three-valued boolean per box: ``yes`` certainly true, ``maybe`` possibly true."""

    __slots__ = ("yes", "maybe", "centre")

    def __init__(self, yes, maybe) -> None:
        self.yes = np.asarray(yes, dtype=bool)
        self.maybe = np.asarray(maybe, dtype=bool)

    @staticmethod
    def of(v) -> Tri:
        if isinstance(v, Tri):
            return v
        b = np.asarray(v, dtype=bool)
        return Tri(b, b)

    def _with_centre(self, out: Tri, other, op) -> Tri:
        """``out`` with the centre's answer (:meth:`Node._compare`) combined alike."""
        if hasattr(self, "centre") or hasattr(other, "centre"):
            out.centre = op(
                Tri.of(getattr(self, "centre", self)), Tri.of(getattr(other, "centre", other))
            )
        return out

    def __and__(self, other) -> Tri:
        o = Tri.of(other)
        return self._with_centre(Tri(self.yes & o.yes, self.maybe & o.maybe), other, Tri.__and__)

    __rand__ = __and__

    def __or__(self, other) -> Tri:
        o = Tri.of(other)
        return self._with_centre(Tri(self.yes | o.yes, self.maybe | o.maybe), other, Tri.__or__)

    __ror__ = __or__

    def __invert__(self) -> Tri:
        out = Tri(~self.maybe, ~self.yes)
        if hasattr(self, "centre"):
            out.centre = ~self.centre
        return out

    def __bool__(self) -> bool:
        raise TypeError("the kernel branches on a value outside where(): not interval-evaluable")


class Interval:
    """Intervals ``[lo, hi]`` (arrays of one shape, one interval per box); NaN ends: no value."""

    __slots__ = ("lo", "hi")

    def __init__(self, lo, hi=None) -> None:
        self.lo = np.asarray(lo, dtype=float)
        self.hi = self.lo if hi is None else np.asarray(hi, dtype=float)

    @staticmethod
    def of(v) -> Interval:
        return v if isinstance(v, Interval) else Interval(float(v))

    # -------------------------------------------------------------- arithmetic
    def __add__(self, other) -> Interval:
        o = Interval.of(other)
        return Interval(_down(self.lo + o.lo), _up(self.hi + o.hi))

    __radd__ = __add__

    def __sub__(self, other) -> Interval:
        o = Interval.of(other)
        return Interval(_down(self.lo - o.hi), _up(self.hi - o.lo))

    def __rsub__(self, other) -> Interval:
        return Interval.of(other) - self

    def __neg__(self) -> Interval:
        return Interval(-self.hi, -self.lo)

    def __pos__(self) -> Interval:
        return self

    def __mul__(self, other) -> Interval:
        if other is self:  # x * x: a square, never negative (no dependency overestimate)
            return self.square()
        o = Interval.of(other)
        with np.errstate(invalid="ignore"):
            prods = np.stack([self.lo * o.lo, self.lo * o.hi, self.hi * o.lo, self.hi * o.hi])
        nan = np.isnan(prods)
        # 0 x inf is 0 in interval arithmetic; a NaN end (no value) stays NaN
        none = np.isnan(self.lo) | np.isnan(o.lo)
        prods = np.where(nan, 0.0, prods)
        lo = np.where(none, np.nan, _down(prods.min(axis=0)))
        hi = np.where(none, np.nan, _up(prods.max(axis=0)))
        return Interval(lo, hi)

    __rmul__ = __mul__

    def square(self) -> Interval:
        a, b = self.lo * self.lo, self.hi * self.hi
        straddle = (self.lo <= 0) & (self.hi >= 0)
        lo = np.where(straddle, 0.0, _down(np.minimum(a, b)))
        return Interval(np.where(np.isnan(self.lo), np.nan, lo), _up(np.maximum(a, b)))

    def __truediv__(self, other) -> Interval:
        o = Interval.of(other)
        zero = (o.lo <= 0) & (o.hi >= 0)
        with np.errstate(divide="ignore", invalid="ignore"):
            inv = Interval(_down(1.0 / o.hi), _up(1.0 / o.lo))
        out = self * inv
        none = np.isnan(out.lo)
        return Interval(
            np.where(zero & ~none, -np.inf, out.lo), np.where(zero & ~none, np.inf, out.hi)
        )

    def __rtruediv__(self, other) -> Interval:
        return Interval.of(other) / self

    def __pow__(self, k) -> Interval:
        if k == 2:
            return self.square()
        raise TypeError(f"interval power {k!r}: only squares are supported")

    def __abs__(self) -> Interval:
        a, b = np.abs(self.lo), np.abs(self.hi)
        straddle = (self.lo <= 0) & (self.hi >= 0)
        return Interval(np.where(straddle, 0.0, np.minimum(a, b)), np.maximum(a, b))

    # -------------------------------------------------------------- comparisons
    def __lt__(self, other) -> Tri:
        o = Interval.of(other)
        return Tri(self.hi < o.lo, self.lo < o.hi)

    def __le__(self, other) -> Tri:
        o = Interval.of(other)
        return Tri(self.hi <= o.lo, self.lo <= o.hi)

    def __gt__(self, other) -> Tri:
        return Interval.of(other) < self

    def __ge__(self, other) -> Tri:
        return Interval.of(other) <= self

    def __eq__(self, other) -> Tri:  # type: ignore[override]
        if other is self:  # x == x: the kernels' test for a number (not NaN)
            fin = ~np.isnan(self.lo)
            return Tri(fin, fin)
        o = Interval.of(other)
        point = (self.lo == self.hi) & (o.lo == o.hi) & (self.lo == o.lo)
        return Tri(point, (self.lo <= o.hi) & (o.lo <= self.hi))

    __hash__ = None  # type: ignore[assignment]


# ---------------------------------------------------------------------------- interval functions
def _isqrt(a: Interval) -> Interval:
    with np.errstate(invalid="ignore"):
        lo = np.sqrt(np.maximum(a.lo, 0.0))
        hi = np.sqrt(a.hi)  # NaN where hi < 0: no value
    return Interval(np.where(np.isnan(hi), np.nan, np.maximum(_down(lo), 0.0)), _up(hi))


def _trig(a: Interval, fn, peak: float) -> Interval:
    """sin (``peak`` = pi/2) or cos (0) over intervals: the ends, and +-1 where a peak or a
    trough lies inside."""
    two_pi = 2 * math.pi
    ya, yb = fn(a.lo), fn(a.hi)
    wide = (a.hi - a.lo) >= two_pi
    with np.errstate(invalid="ignore"):
        has_max = np.ceil((a.lo - peak) / two_pi) <= np.floor((a.hi - peak) / two_pi)
        trough = peak + math.pi
        has_min = np.ceil((a.lo - trough) / two_pi) <= np.floor((a.hi - trough) / two_pi)
    lo = np.where(wide | has_min, -1.0, np.maximum(_down(np.minimum(ya, yb)), -1.0))
    hi = np.where(wide | has_max, 1.0, np.minimum(_up(np.maximum(ya, yb)), 1.0))
    # the peaks are located by a division that rounds: near one, widen to the extreme value
    near = 8 * _EPS * (np.abs(a.lo) + np.abs(a.hi) + 1)
    lo = np.where(np.abs(np.minimum(ya, yb) + 1) < near, -1.0, lo)
    hi = np.where(np.abs(np.maximum(ya, yb) - 1) < near, 1.0, hi)
    none = np.isnan(a.lo)
    return Interval(np.where(none, np.nan, lo), np.where(none, np.nan, hi))


def _hull(a: Interval, b: Interval) -> Interval:
    """The smallest interval holding both (a NaN side: the other)."""
    return Interval(np.fmin(a.lo, b.lo), np.fmax(a.hi, b.hi))


def _pick(c: Tri, a: Interval, b: Interval) -> Interval:
    """``a`` where ``c`` certainly holds, ``b`` where it certainly does not, else their hull."""
    h = _hull(a, b)
    return Interval(
        np.where(c.yes, a.lo, np.where(~c.maybe, b.lo, h.lo)),
        np.where(c.yes, a.hi, np.where(~c.maybe, b.hi, h.hi)),
    )


def _intersect(a: Interval, b: Interval) -> Interval:
    """``a`` narrowed to ``b`` where ``b`` is a finite, non-empty enclosure too."""
    use = np.isfinite(b.lo) & np.isfinite(b.hi) & ~np.isnan(a.lo)
    lo = np.where(use, np.maximum(a.lo, b.lo), a.lo)
    hi = np.where(use, np.minimum(a.hi, b.hi), a.hi)
    return Interval(lo, np.maximum(hi, lo))  # rounding could cross them: keep a point


_WHOLE = Interval(-np.inf, np.inf)


class Node:
    """A value of the kernel over a box, in three enclosures: ``val`` over the whole box, ``cv`` at
    the box's centre, and ``d`` the gradient over the box (one interval per free coordinate, None
    for a constant). Every operation narrows ``val`` by the mean-value form ``cv + sum_k d_k (X_k -
    c_k)`` (valid where the value is Lipschitz on the box; where a ``where`` switches branch inside
    the box the gradient is unbounded and the natural enclosure alone is kept), which shrinks like
    the box's width squared where the natural one shrinks like its width."""

    __slots__ = ("val", "cv", "d", "ctx")

    def __init__(self, val: Interval, cv: Interval, d, ctx) -> None:
        self.val, self.cv, self.d, self.ctx = val, cv, d, ctx
        if d is not None:  # the mean-value form
            mvf = cv
            for dk, hk in zip(d, ctx.half):
                mvf = mvf + dk * hk
            self.val = _intersect(val, mvf)

    def _of(self, v) -> Node:
        return v if isinstance(v, Node) else Node(Interval.of(v), Interval.of(v), None, self.ctx)

    @staticmethod
    def _grad(f, a: Node, b: Node):
        """``f(da_k, db_k)`` per coordinate (a None gradient is zero)."""
        if a.d is None and b.d is None:
            return None
        zero = Interval(0.0)
        return [f(a.d[k] if a.d else zero, b.d[k] if b.d else zero) for k in range(len(a.ctx.half))]

    def __add__(self, other) -> Node:
        o = self._of(other)
        return Node(
            self.val + o.val, self.cv + o.cv, self._grad(lambda x, y: x + y, self, o), self.ctx
        )

    __radd__ = __add__

    def __sub__(self, other) -> Node:
        o = self._of(other)
        return Node(
            self.val - o.val, self.cv - o.cv, self._grad(lambda x, y: x - y, self, o), self.ctx
        )

    def __rsub__(self, other) -> Node:
        return self._of(other) - self

    def __neg__(self) -> Node:
        return Node(-self.val, -self.cv, None if self.d is None else [-g for g in self.d], self.ctx)

    def __mul__(self, other) -> Node:
        o = self._of(other)
        val = self.val.square() if o is self else self.val * o.val
        cv = self.cv.square() if o is self else self.cv * o.cv
        a, b = self.val, o.val
        return Node(val, cv, self._grad(lambda x, y: x * b + a * y, self, o), self.ctx)

    __rmul__ = __mul__

    def __truediv__(self, other) -> Node:
        o = self._of(other)
        val = self.val / o.val
        b = o.val
        grad = self._grad(lambda x, y: (x - val * y) / b, self, o)
        return Node(val, self.cv / o.cv, grad, self.ctx)

    def __rtruediv__(self, other) -> Node:
        return self._of(other) / self

    def __abs__(self) -> Node:
        v = self.val
        sign = Interval(np.where(v.lo >= 0, 1.0, -1.0), np.where(v.hi <= 0, -1.0, 1.0))
        grad = None if self.d is None else [g * sign for g in self.d]
        return Node(abs(self.val), abs(self.cv), grad, self.ctx)

    def _compare(self, other, op) -> Tri:
        o = self._of(other)
        whole = op(self.val, o.val)
        centre = op(self.cv, o.cv)
        whole.centre = centre  # where() picks its centre value by it
        return whole

    def __lt__(self, other) -> Tri:
        return self._compare(other, lambda a, b: a < b)

    def __le__(self, other) -> Tri:
        return self._compare(other, lambda a, b: a <= b)

    def __gt__(self, other) -> Tri:
        return self._compare(other, lambda a, b: a > b)

    def __ge__(self, other) -> Tri:
        return self._compare(other, lambda a, b: a >= b)

    def __eq__(self, other) -> Tri:  # type: ignore[override]
        if other is self:
            return self._compare(self, lambda a, b: a == a)
        return self._compare(other, lambda a, b: a == b)

    __hash__ = None  # type: ignore[assignment]


def _node(ctx, v) -> Node:
    return v if isinstance(v, Node) else Node(Interval.of(v), Interval.of(v), None, ctx)


def _chain(a: Node, val: Interval, cv: Interval, slope: Interval) -> Node:
    """``f(a)`` with ``f'(a) in slope``."""
    grad = None if a.d is None else [g * slope for g in a.d]
    return Node(val, cv, grad, a.ctx)


def _sqrt(a) -> Node:
    if not isinstance(a, Node):
        return math.sqrt(a) if a >= 0 else math.nan
    val = _isqrt(a.val)
    return _chain(a, val, _isqrt(a.cv), Interval(0.5) / val)


def _sin(a) -> Node:
    if not isinstance(a, Node):
        return math.sin(a)
    return _chain(a, _trig(a.val, np.sin, math.pi / 2), _trig(a.cv, np.sin, math.pi / 2),
                  _trig(a.val, np.cos, 0.0))  # fmt: skip


def _cos(a) -> Node:
    if not isinstance(a, Node):
        return math.cos(a)
    return _chain(a, _trig(a.val, np.cos, 0.0), _trig(a.cv, np.cos, 0.0),
                  -_trig(a.val, np.sin, math.pi / 2))  # fmt: skip


def _tri_centre(c: Tri) -> Tri:
    return getattr(c, "centre", c)


def _gradients(ctx, a: Node, b: Node) -> Iterator[tuple[Interval, Interval]]:
    """Per coordinate of the box, the gradient bounds of ``a`` and ``b`` (0 for a node without)."""
    zero = Interval(0.0)
    for k in range(len(ctx.half)):
        yield (a.d[k] if a.d else zero), (b.d[k] if b.d else zero)


def _where(cond, a, b) -> Node:
    nodes = [v for v in (a, b) if isinstance(v, Node)]
    if not nodes:
        return a if cond else b
    ctx = nodes[0].ctx
    c = Tri.of(cond)
    a, b = _node(ctx, a), _node(ctx, b)
    val = _pick(c, a.val, b.val)
    cv = _pick(Tri.of(_tri_centre(cond)), a.cv, b.cv)
    if a.d is None and b.d is None:
        return Node(val, cv, None, ctx)
    grad = []
    for da, db in _gradients(ctx, a, b):
        g = _pick(c, da, db)
        # a branch switch inside the box: no gradient bound (a jump, or a NaN side)
        switch = c.maybe & ~c.yes
        grad.append(Interval(np.where(switch, -np.inf, g.lo), np.where(switch, np.inf, g.hi)))
    return Node(val, cv, grad, ctx)


def _maximum(a, b) -> Node:
    nodes = [v for v in (a, b) if isinstance(v, Node)]
    if not nodes:
        return a if (a >= b or a != a) else b
    ctx = nodes[0].ctx
    a, b = _node(ctx, a), _node(ctx, b)
    first = a.val >= b.val  # a certainly the larger: its gradient; else the hull (Lipschitz)
    second = b.val >= a.val
    val = Interval(np.maximum(a.val.lo, b.val.lo), np.maximum(a.val.hi, b.val.hi))
    cv = Interval(np.maximum(a.cv.lo, b.cv.lo), np.maximum(a.cv.hi, b.cv.hi))
    if a.d is None and b.d is None:
        return Node(val, cv, None, ctx)
    grad = []
    for da, db in _gradients(ctx, a, b):
        h = _hull(da, db)
        grad.append(Interval(np.where(first.yes, da.lo, np.where(second.yes, db.lo, h.lo)),
                             np.where(first.yes, da.hi, np.where(second.yes, db.hi, h.hi))))  # fmt: skip
    return Node(val, cv, grad, ctx)


def _iatan2(y: Interval, x: Interval) -> Interval:
    """atan2 over boxes: the corners' extreme angles where the box misses the origin and the
    branch cut (x < 0, y = 0); else ``[-pi, pi]``."""
    ang = np.stack([np.arctan2(y.lo, x.lo), np.arctan2(y.lo, x.hi),
                    np.arctan2(y.hi, x.lo), np.arctan2(y.hi, x.hi)])  # fmt: skip
    cut = (x.lo <= 0) & (y.lo <= 0) & (y.hi >= 0)
    lo = np.where(cut, -math.pi, _down(ang.min(axis=0)))
    hi = np.where(cut, math.pi, _up(ang.max(axis=0)))
    none = np.isnan(x.lo) | np.isnan(y.lo)
    return Interval(np.where(none, np.nan, np.maximum(lo, -math.pi)),
                    np.where(none, np.nan, np.minimum(hi, math.pi)))  # fmt: skip


def _atan2(y, x) -> Node:
    nodes = [v for v in (y, x) if isinstance(v, Node)]
    if not nodes:
        return math.atan2(y, x)
    ctx = nodes[0].ctx
    y, x = _node(ctx, y), _node(ctx, x)
    val = _iatan2(y.val, x.val)
    cv = _iatan2(y.cv, x.cv)
    if y.d is None and x.d is None:
        return Node(val, cv, None, ctx)
    r2 = x.val * x.val + y.val * y.val
    dy, dx = x.val / r2, -y.val / r2  # d atan2 / dy, d atan2 / dx (unbounded at the origin)
    zero = Interval(0.0)
    grad = []
    # across the branch cut the angle jumps by 2 pi: no gradient bound there
    cut = (x.val.lo <= 0) & (y.val.lo <= 0) & (y.val.hi >= 0)
    for k in range(len(ctx.half)):
        g = (y.d[k] if y.d else zero) * dy + (x.d[k] if x.d else zero) * dx
        grad.append(Interval(np.where(cut, -np.inf, g.lo), np.where(cut, np.inf, g.hi)))
    return Node(val, cv, grad, ctx)


def _floor(a) -> Node:
    if not isinstance(a, Node):
        return float(math.floor(a)) if math.isfinite(a) else a
    val = Interval(np.floor(a.val.lo), np.floor(a.val.hi))
    cv = Interval(np.floor(a.cv.lo), np.floor(a.cv.hi))
    if a.d is None:
        return Node(val, cv, None, a.ctx)
    jump = val.lo != val.hi  # a step inside the box: no gradient bound; else flat
    grad = [Interval(np.where(jump, -np.inf, 0.0), np.where(jump, np.inf, 0.0)) for _ in a.d]
    return Node(val, cv, grad, a.ctx)


def _unsupported(name: str):
    def fail(*_args):
        raise TypeError(
            f"{name} has no interval version here: the kernel is not interval-evaluable"
        )

    return fail


_NAMES = {
    "sqrt": _sqrt,
    "sin": _sin,
    "cos": _cos,
    "atan2": _atan2,
    "floor": _floor,
    "where": _where,
    "maximum": _maximum,
    "acos": _unsupported("acos"),
    "asin": _unsupported("asin"),
}


class _Context:
    """The boxes' half-widths (one interval ``[-h_k, h_k]`` per free coordinate)."""

    def __init__(self, half: list[Interval]) -> None:
        self.half = half


class _Out:
    """Where a kernel writes ``out[i]``."""

    def __init__(self, n: int) -> None:
        self.values: list = [None] * n

    def __setitem__(self, i, v) -> None:
        self.values[i] = v


_BOUND: dict = {}


def interval_ik(kernel, lo: np.ndarray, hi: np.ndarray) -> tuple[Interval, Tri]:
    """The kernel's ``ik`` over the boxes ``[lo, hi]`` ``(B, n_pose)`` (a coordinate with ``lo ==
    hi`` everywhere is held): joint enclosures (an ``Interval`` of ``(B, n_joints)`` arrays) and
    whether the IK exists (a ``Tri``)."""
    ns = _BOUND.get(kernel.module)
    if ns is None:
        ns = _BOUND[kernel.module] = _math.rebind(kernel.module, _NAMES)
    b = len(lo)
    free = [k for k in range(lo.shape[1]) if np.any(lo[:, k] != hi[:, k])]
    with np.errstate(all="ignore"):
        mid = 0.5 * (lo + hi)
        half = [Interval(_down(-(hi[:, k] - mid[:, k])), _up(hi[:, k] - mid[:, k])) for k in free]
        ctx = _Context(half)
        x = []
        for k in range(lo.shape[1]):
            if k in free:
                unit = [Interval(float(k == f)) for f in free]
                x.append(Node(Interval(lo[:, k], hi[:, k]), Interval(mid[:, k]), unit, ctx))
            else:
                x.append(Node(Interval(lo[:, k]), Interval(lo[:, k]), None, ctx))
        out = _Out(kernel.n_joints)
        ok = Tri.of(ns.ik(kernel.params.tolist(), x, out))
    vals = [v.val if isinstance(v, Node) else Interval.of(v) for v in out.values]
    qlo = np.stack([np.broadcast_to(v.lo, (b,)) for v in vals], axis=-1)
    qhi = np.stack([np.broadcast_to(v.hi, (b,)) for v in vals], axis=-1)
    yes = np.broadcast_to(ok.yes, (b,))
    maybe = np.broadcast_to(ok.maybe, (b,))
    return Interval(qlo, qhi), Tri(yes, maybe)


@dataclasses.dataclass(frozen=True)
class Bounds:
    """Certified ``inner`` <= volume <= ``outer`` of the constant-orientation workspace (IK and
    joint limits), after ``levels`` halvings; ``boxes``: undecided boxes left."""

    inner: float
    outer: float
    levels: int
    boxes: int


def classify_boxes(region: Region, lo: np.ndarray, hi: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """``(inside, outside)`` masks of workspace boxes ``[lo, hi]`` ``(B, dim)`` (module docstring)."""
    kern = region.mech.kernel()
    xlo = region.poses(lo)
    xhi = region.poses(hi)
    q, ok = interval_ik(kern, xlo, xhi)
    jlo, jhi = region.joint_lo, region.joint_hi
    with np.errstate(invalid="ignore"):
        beyond = np.any((q.hi < jlo) | (q.lo > jhi), axis=-1)
        within = np.all((q.lo >= jlo) & (q.hi <= jhi), axis=-1)
    inside = ok.yes & within
    outside = ~ok.maybe | (beyond & ~np.any(np.isnan(q.lo), axis=-1))
    return inside, outside & ~inside


def certify(region: Region, *, levels: int = 8, max_boxes: int = 400_000) -> Bounds | None:
    """Inner and outer bounds on the constant-orientation workspace's volume (IK existence and
    joint limits) by bisecting the region's box ``levels`` times (fewer where the undecided boxes'
    children would pass ``max_boxes``); None for a mechanism without a kernel, or whose kernel's
    ``ik`` uses a function without an interval version here (``acos``, ``asin``)."""
    if region.mech.kernel() is None:
        return None
    try:
        classify_boxes(region, region.lo[None], region.hi[None])
    except TypeError:
        return None
    if not (isinstance(levels, (int, np.integer)) and 0 <= levels <= 30):
        raise ValueError(f"levels = {levels!r} must be an integer in [0, 30]")
    dim = region.dim
    lo, hi = region.lo[None, :].copy(), region.hi[None, :].copy()
    inner = 0.0
    level = 0
    corners = np.array(np.meshgrid(*[[0, 1]] * dim, indexing="ij")).reshape(dim, -1).T
    while True:
        inside, outside = classify_boxes(region, lo, hi)
        vol = np.prod(hi - lo, axis=-1)
        inner += float(np.sum(vol[inside]))
        keep = ~inside & ~outside
        lo, hi = lo[keep], hi[keep]
        if level >= levels or len(lo) == 0 or len(lo) * len(corners) > max_boxes:
            break
        mid = 0.5 * (lo + hi)
        # children: per corner bit k, the low half [lo, mid] or the high half [mid, hi] of axis k
        clo = np.where(corners[None, :, :] == 0, lo[:, None, :], mid[:, None, :])
        chi = np.where(corners[None, :, :] == 0, mid[:, None, :], hi[:, None, :])
        lo, hi = clo.reshape(-1, dim), chi.reshape(-1, dim)
        level += 1
    undecided = float(np.sum(np.prod(hi - lo, axis=-1)))
    return Bounds(inner, inner + undecided, level, len(lo))
