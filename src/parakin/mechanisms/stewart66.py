"""The general 6-6 Gough-Stewart platform: any six base and six platform anchor points, and all 40
forward-kinematics solutions, batched and certified.

Geometry: ``base`` B (6, 3) in the fixed frame, ``platform`` P (6, 3) in the moving frame; leg i is
the S-P-S chain joining ``B[i]`` and ``P[i]``. Joints: the six leg lengths ``L_1 .. L_6`` (m).

Pose ``(alpha, beta, gamma, X, Y, Z)`` (rad, rad, rad, m, m, m), the convention of
:class:`parakin.mechanisms.stewart36.Stewart36`: the platform point ``p`` sits at
``T p + O`` in the fixed frame with ``T = Rz(alpha) Ry(beta) Rx(gamma)`` (Z-Y-X Euler) and
``O = (X, Y, Z)`` the origin of the moving frame. Residual (squared form, as for the 3-6):
``f_i = |T P_i + O - B_i|^2 - L_i^2``.

Default geometry: Dietmaier's platform (Dietmaier 1998, "The Stewart-Gough platform of general
geometry can have 40 real postures", Advances in Robot Kinematics, pp. 7-16), whose leg lengths
:data:`DIETMAIER_LENGTHS` have all 40 forward solutions real. Numbers as printed (6 decimals;
transcribed from the CuikSuite documentation of its ``Dietmeier`` example, which cites the paper),
read as metres.

:meth:`Stewart66.fk_all`: parameter homotopy in Study (soma) coordinates from one generic complex
start system whose 40 solutions are stored in ``data/stewart66_start.npz`` (made by monodromy,
:func:`parakin.mechanisms.stewart66_homotopy.generate_start`), every path tracked in one batched
numpy predictor-corrector, each endpoint refined by Newton and certified by Smale's alpha test
(approximate zero of a distinct, nonsingular solution); real ones checked by the IK. See
``docs/stewart66.md``.
"""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass
from functools import cached_property, lru_cache
from importlib import resources
from types import ModuleType
from typing import Any, ClassVar

import numpy as np
from numpy.typing import ArrayLike

import parakin.mechanisms.stewart66_homotopy as hc
from parakin.dynamics.model import MassModel, hexapod_masses
from parakin.errors import UnreachableError
from parakin.geometry import euler_zyx, euler_zyx_from_matrix
from parakin.kernels import stewart66 as stewart66_kernels
from parakin.mechanisms.base import (
    Array,
    as_batch,
    describe_first,
)
from parakin.mechanisms.stewart66_legs import SixLegs

__all__ = [
    "Stewart66",
    "fk_all_geometries",
    "random_platform",
    "random_pose",
    "DIETMAIER_BASE",
    "DIETMAIER_PLATFORM",
    "DIETMAIER_LENGTHS",
    "FKAll",
    "load_start",
]

#: Dietmaier (1998) base points A1..A6 (rows), as printed
DIETMAIER_BASE = (
    (0.0, 0.0, 0.0),
    (1.107915, 0.0, 0.0),
    (0.549094, 0.756063, 0.0),
    (0.735077, -0.223935, 0.525991),
    (0.514188, -0.526063, -0.368418),
    (0.590473, 0.094733, -0.205018),
)
#: Dietmaier (1998) platform points B1..B6 (rows), as printed
DIETMAIER_PLATFORM = (
    (0.0, 0.0, 0.0),
    (0.542805, 0.0, 0.0),
    (0.956919, -0.528915, 0.0),
    (0.665885, -0.353482, 1.402538),
    (0.478359, 1.158742, 0.107672),
    (-0.137087, -0.235121, 0.353913),
)
#: Dietmaier (1998) leg lengths with 40 real forward solutions
DIETMAIER_LENGTHS = (1.0, 0.645275, 1.086284, 1.503439, 1.281933, 0.771071)

#: seed of the random complex leg constants of each geometry's own start system (a module constant)
FIBER_SEED = 66
#: height of :meth:`Stewart66.home`'s platform centroid above the base's, in units of ``size``
HOME_HEIGHT = 1.5
#: retries (with a fresh random bend of the parameter path) of inputs not complete after the first pass
RETRIES = 3
#: :meth:`Stewart66.fk_all` takes the new-geometry path (no start system of the geometry's own) for
#: at most this many inputs on a geometry whose start system is not built yet, and only in its first
#: call: a second call on the same geometry builds the start system (the cost of one input) and
#: takes the fibre, about a third of the new-geometry path's cost per input from then on
NEW_GEOMETRY_MAX = 1
#: step control of the once-per-geometry tracking from the stored generic start (cautious)
START_TRACK: dict[str, float] = {"h0": 0.02, "tau": 5e-4, "hmin": 1e-13, "max_steps": 3000}
#: attempts at a geometry's start system: the direct segment, then detours through random problems
START_ATTEMPTS = 6
#: step control of the per-input tracking (see :func:`parakin.mechanisms.stewart66_homotopy.track`)
TRACK_OPTIONS: dict[str, float] = {
    "h0": 0.2,
    "hmax": 1.0,
    "tau": 0.1,
    "hmin": 1e-13,
    "max_steps": 1500,
}


def _compiled_kernel(q0: np.ndarray | None = None):
    """:mod:`parakin.kernels.stewart66_track` where the compiled path is on and the geometry's
    quadrics ``q0`` (where given) are real; None otherwise (the numpy path). Imported here, on the
    first ``fk_all``: importing the mechanism compiles nothing."""
    from parakin import kernels

    if not kernels.enabled() or (q0 is not None and np.any(np.imag(q0) != 0)):
        return None
    from parakin.kernels import stewart66_track

    return stewart66_track


def load_start() -> dict[str, np.ndarray]:
    """The stored generic start system (``base``, ``platform``, ``c``, ``patch``, ``solutions``),
    a copy the caller may change."""
    return {k: v.copy() for k, v in _stored_start().items()}


@lru_cache(maxsize=1)
def _stored_start() -> dict[str, np.ndarray]:
    """:func:`load_start`, read once per process (every new-geometry call sets out from it)."""
    with (
        resources.files("parakin.mechanisms").joinpath("data/stewart66_start.npz").open("rb") as fh
    ):
        with np.load(fh) as z:
            return {k: z[k] for k in z.files}


def _central_c(b: np.ndarray) -> np.ndarray:
    """Mean leg constants ``c_i = |p_i|^2 + |b_i|^2 - L_i^2`` (centred anchors, units of
    ``size``) over poses with a uniformly random orientation and the platform centroid normal
    around :meth:`Stewart66.home`'s with unit variance per axis: ``E|t|^2 = h^2 + 3`` and
    ``E[t] = (0, 0, h)`` give ``2 h b_iz - h^2 - 3``. The start system sits there (plus a random
    imaginary part): the paths to typical inputs are short."""
    h = HOME_HEIGHT
    return 2 * h * b[:, 2] - (h * h + 3.0)


def _as_points(value: Any, what: str) -> tuple[tuple[float, float, float], ...]:
    a = np.asarray(value, dtype=float)
    if a.shape != (6, 3):
        raise ValueError(f"{what} must be six 3-D points, shape (6, 3), got shape {a.shape}")
    if not np.all(np.isfinite(a)):
        bad = tuple(int(i) for i in np.argwhere(~np.isfinite(a))[0])
        raise ValueError(f"{what}[{bad[0]}] has a non-finite coordinate {a[bad]!r}")
    return tuple(tuple(float(v) for v in row) for row in a)


def _cross(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """``a x b`` over the last axis: numpy's ``cross`` formula without its axis handling, which
    costs more than the products for the few poses a geometry's check takes (same values)."""
    a0, a1, a2 = a[..., 0], a[..., 1], a[..., 2]
    b0, b1, b2 = b[..., 0], b[..., 1], b[..., 2]
    return np.stack([a1 * b2 - a2 * b1, a2 * b0 - a0 * b2, a0 * b1 - a1 * b0], -1)


def _coincident(a: np.ndarray, tol: float) -> list[tuple[int, int]]:
    d = np.linalg.norm(a[:, None] - a[None], axis=-1)
    return [(i, j) for i in range(6) for j in range(i + 1, 6) if d[i, j] <= tol]


@dataclass(frozen=True)
class FKAll:
    """Everything :meth:`Stewart66.fk_all` finds for a batch of inputs (batch shape ``S``).

    ``poses`` (S, 40, 6): the real solutions as poses, NaN-padded, sorted by Z descending;
    ``study`` (S, 40, 8) complex: every solution found, Study parameters ``(e, g)`` scaled to
    ``e . e = 1`` (NaN-padded); ``rotation`` (S, 40, 3, 3) and ``translation`` (S, 40, 3): the same
    solutions as (complex) rotation and origin ``O`` of the moving frame; ``is_real`` (S, 40);
    ``alpha`` (S, 40): Smale's alpha of each solution (certified where ``< ALPHA0``);
    ``n_found`` (S,): certified distinct solutions; ``n_expected``: the root count of this geometry
    (40 unless it is special); ``complete`` (S,): ``n_found == n_expected``; ``n_real`` (S,): solutions
    certified real (:func:`parakin.mechanisms.stewart66_homotopy.real_decision`) whose pose reproduces the legs;
    ``n_undecided`` (S,): certified solutions whose reality the certificate left undecided (or real
    ones whose pose misses the IK tolerance), counted neither real nor complex;
    ``ik_error`` (S,): max ``|IK(pose) - L|`` over the real solutions; ``steps`` (S,): predictor-
    corrector steps over all paths; ``retries`` (S,): extra passes the input needed."""

    poses: Array
    study: np.ndarray
    rotation: np.ndarray
    translation: np.ndarray
    is_real: np.ndarray
    alpha: Array
    n_found: np.ndarray
    n_expected: int
    complete: np.ndarray
    n_real: np.ndarray
    n_undecided: np.ndarray
    ik_error: Array
    steps: np.ndarray
    retries: np.ndarray


@lru_cache(maxsize=START_ATTEMPTS)
def _start_leg(attempt: int) -> tuple[np.ndarray, tuple, np.ndarray, np.ndarray]:
    """Where attempt ``attempt`` at a geometry's start system (:attr:`Stewart66.fk_start`) sets
    out from: ``(patch, (B, P, c), x, ok)``, the chart, the problem and its 40 solutions with the
    flags of those reached. Attempt 0 sets out from the stored generic start; a retry first takes
    the stored solutions, on a new random chart, to a random complex problem (a detour, so the
    second leg follows other paths). That first leg is the same for every geometry, so it is
    tracked once per process (a retry took two tracks before)."""
    st = load_start()
    start = (st["base"], st["platform"], st["c"])
    if attempt == 0:
        return st["patch"], start, st["solutions"], np.ones(len(st["solutions"]), dtype=bool)
    rng = np.random.default_rng(FIBER_SEED + attempt)
    patch = (rng.normal(size=8) + 1j * rng.normal(size=8)) / 4
    x0 = st["solutions"] / (st["solutions"] @ patch)[:, None]
    mid = hc.random_problem(rng)
    x, ok, _ = _start_track(patch, start, mid, x0)
    return patch, mid, x, ok


def _start_track(patch: np.ndarray, source: tuple, target: tuple, x0: np.ndarray):
    """A start system's paths from the problem ``source`` to ``target`` (each ``(B, P, c)``, all
    parameters on one straight complex segment) in the affine ``patch``: ``(x, reached, steps)``.
    Compiled where the kernels are on: the lane tracker of every 6-6 homotopy
    (:mod:`parakin.kernels.stewart66_lanes`, the Taylor/Padé predictor of the per-input paths, at
    the cost of a new geometry's input); else the cautious numpy tracker
    (:func:`parakin.mechanisms.stewart66_homotopy.track` with :data:`START_TRACK`)."""
    from parakin import kernels

    if kernels.enabled():
        from parakin.kernels import stewart66_lanes as lanes

        par = np.zeros((1, 3, 6, 7), dtype=complex)
        for q, (u, v) in enumerate(zip(source, target)):
            cols = slice(6, 7) if q == 2 else slice(3 * q, 3 * q + 3)
            u = np.asarray(u, dtype=complex).reshape(6, -1)
            v = np.asarray(v, dtype=complex).reshape(6, -1)
            par[0, 0, :, cols] = u
            par[0, 1, :, cols] = v - u
        m = len(x0)
        x = np.empty((m, 8), dtype=complex)
        ok = np.zeros(m, dtype=bool)
        steps = np.zeros(m, dtype=np.int64)
        lanes.track_queue(
            par,
            np.ascontiguousarray(x0, dtype=complex),
            np.zeros(m, dtype=np.int64),
            np.arange(m),
            lanes.options_vector(),
            True,
            np.ascontiguousarray(patch, dtype=complex),
            x,
            ok,
            steps,
        )
        return x, ok, steps
    return hc.track(hc.GeneralHomotopy(patch, source, target), x0, **START_TRACK)


@dataclass(frozen=True)
class Stewart66(SixLegs):
    """General 6-6 Gough-Stewart platform (SI units): ``base`` and ``platform`` are (6, 3) point sets
    (stored as tuples, so the mechanism stays hashable and its parameters print as JSON).

    Raises ValueError for non-finite or malformed anchors, coincident anchors (a 3-6, 6-3 or 3-3
    layout: pass ``allow_coincident=True`` to study it anyway; :class:`Stewart36` is the dedicated
    solver of the 3-6) and architecturally singular layouts (the Jacobian singular at every pose,
    e.g. six collinear anchors)."""

    base: Any = DIETMAIER_BASE
    platform: Any = DIETMAIER_PLATFORM
    allow_coincident: bool = False

    name: ClassVar[str] = "stewart66"
    pose_units: ClassVar[tuple[str, ...]] = ("rad", "rad", "rad", "m", "m", "m")
    joint_units: ClassVar[tuple[str, ...]] = ("m",) * 6
    paper_pose_units: ClassVar[tuple[str, ...]] = ("deg", "deg", "deg", "m", "m", "m")
    paper_joint_units: ClassVar[tuple[str, ...]] = ("m",) * 6
    #: the compiled single solves and the torch solver (the numpy methods below are the same)
    kernels: ClassVar[ModuleType] = stewart66_kernels

    def kernel_params(self) -> Array:
        """The six platform points (moving frame), then the six base points."""
        return np.concatenate([self.platform_points.ravel(), self.base_points.ravel()])

    def __post_init__(self) -> None:
        b = _as_points(self.base, "base")
        p = _as_points(self.platform, "platform")
        object.__setattr__(self, "base", b)
        object.__setattr__(self, "platform", p)
        ba, pa = np.array(b), np.array(p)
        size = max(np.ptp(ba, axis=0).max(), np.ptp(pa, axis=0).max())
        if not size > 0:
            raise ValueError("base and platform anchors are all one point: no mechanism")
        tol = 1e-9 * size
        cb, cp = _coincident(ba, tol), _coincident(pa, tol)
        if (cb or cp) and not self.allow_coincident:
            kind = {(3, 0): "3-6", (0, 3): "6-3", (3, 3): "3-3"}.get(
                (len(cp), len(cb)), "degenerate"
            )
            where = "; ".join(
                f"{what} points {', '.join(f'{i + 1}={j + 1}' for i, j in pairs)}"
                for what, pairs in (("platform", cp), ("base", cb))
                if pairs
            )
            raise ValueError(
                f"coincident anchors ({where}): a {kind} layout, not a general 6-6 platform; "
                "use Stewart36 for the 3-6, or pass allow_coincident=True (fk_all then finds "
                "the fewer solutions of that layout)"
            )
        # architecture singularity: the 6x6 Jacobian singular at random poses
        rng = np.random.default_rng(0)
        poses = np.concatenate([rng.uniform(-1, 1, (3, 3)), rng.normal(size=(3, 3)) * size], -1)
        with np.errstate(all="ignore"):
            cond = np.linalg.cond(self.jacobian_pose(poses))
        if np.all(~np.isfinite(cond) | (cond > 1e11)):
            raise ValueError(
                f"architecturally singular layout: the Jacobian is singular at every pose tried "
                f"(condition numbers {np.round(cond, 1).tolist()}), e.g. collinear or "
                "similar planar anchor sets"
            )

    # ------------------------------------------------------------------ geometry
    @cached_property
    def base_points(self) -> Array:
        """B (6, 3), fixed frame."""
        return np.array(self.base, dtype=float)

    @cached_property
    def platform_points(self) -> Array:
        """P (6, 3), moving frame."""
        return np.array(self.platform, dtype=float)

    @cached_property
    def size(self) -> float:
        """Characteristic length: RMS distance of the anchors from their centroids (the FK's unit)."""
        b = self.base_points - self.base_points.mean(0)
        p = self.platform_points - self.platform_points.mean(0)
        return float(np.sqrt((np.sum(b * b) + np.sum(p * p)) / 12))

    def home(self) -> Array:
        """Platform parallel to the base frame, its anchor centroid one ``size`` above the base's."""
        o = (
            self.base_points.mean(0)
            - self.platform_points.mean(0)
            + np.array([0.0, 0.0, HOME_HEIGHT * self.size])
        )
        return np.concatenate([np.zeros(3), o])

    def pose_bounds(self) -> tuple[Array, Array]:
        """Angles ``[-pi, pi] x [-pi/2, pi/2] x [-pi, pi]``; origin within ``3 size`` of :meth:`home`'s."""
        o = self.home()[3:]
        s = 3 * self.size
        return (
            np.concatenate([[-np.pi, -np.pi / 2, -np.pi], o - s]),
            np.concatenate([[np.pi, np.pi / 2, np.pi], o + s]),
        )

    # ------------------------------------------------------------------ kinematics
    def platform_world(self, pose: ArrayLike) -> Array:
        """Platform anchors in the fixed frame, (..., 6, 3)."""
        x = as_batch(pose, 6, "pose")
        return x[..., None, 3:] + self.platform_points @ np.swapaxes(self.rotation(x), -1, -2)

    def leg_vectors(self, pose: ArrayLike) -> Array:
        return self.platform_world(pose) - self.base_points

    def ik(self, pose: ArrayLike) -> Array:
        """Leg lengths ``|T P_i + O - B_i|`` (..., 6); every pose has an IK."""
        v = self.leg_vectors(pose)
        return np.sqrt(np.einsum("...ij,...ij->...i", v, v))

    def residual(self, pose: ArrayLike, joints: ArrayLike) -> Array:
        """``f_i = |T P_i + O - B_i|^2 - L_i^2``."""
        q = as_batch(joints, 6, "joints")
        v = self.leg_vectors(pose)
        return np.einsum("...ij,...ij->...i", v, v) - q * q

    def jacobian_pose(self, pose: ArrayLike, joints: ArrayLike | None = None) -> Array:
        """Analytic ``d f / d pose`` (..., 6, 6): ``2 v_i`` for X, Y, Z; for angle q,
        ``2 v_i . (u_q x w_i) = 2 u_q . (w_i x v_i)`` with ``w_i = T P_i``, ``v_i`` the leg vector and
        ``u_alpha = z``, ``u_beta = Rz(alpha) y``, ``u_gamma = T x`` (the z-y'-x'' joint axes)."""
        x = as_batch(pose, 6, "pose")
        r = euler_zyx(x[..., 0], x[..., 1], x[..., 2])
        w = self.platform_points @ np.swapaxes(r, -1, -2)
        v = x[..., None, 3:] + w - self.base_points
        c = _cross(w, v)
        ca, sa = np.cos(x[..., 0])[..., None], np.sin(x[..., 0])[..., None]
        tx = r[..., :, 0]
        cols = (c[..., 2], ca * c[..., 1] - sa * c[..., 0], np.einsum("...j,...ij->...i", tx, c))
        return 2 * np.concatenate([np.stack(cols, axis=-1), v], axis=-1)

    def check_joints(self, joints: ArrayLike) -> None:
        """Raise UnreachableError where a leg length is not > 0 (no cheap exact test of assembly
        exists for the 6-6; :meth:`fk_all` reports inputs without a real solution)."""
        self._check_positive(as_batch(joints, 6, "joints"))

    # ------------------------------------------------------------------ all forward solutions
    @cached_property
    def _scaled(self) -> tuple[Array, Array, Array, Array, float]:
        """Centred, scaled anchors (b, p), the centroids and the scale: the FK works in units of
        :attr:`size` with both anchor sets centred (translation ``t = O + T Pc - Bc``)."""
        bc, pc = self.base_points.mean(0), self.platform_points.mean(0)
        s = self.size
        return (self.base_points - bc) / s, (self.platform_points - pc) / s, bc, pc, s

    @cached_property
    def fk_start(self) -> dict[str, Any]:
        """This geometry's own start system: the stored generic start moved (general parameter
        homotopy, 40 paths) to this geometry with random complex leg constants ``c``. Its certified
        distinct finite endpoints are the root count of the geometry (40 unless special)."""
        b, p, *_ = self._scaled
        rng = np.random.default_rng(FIBER_SEED)
        c1 = _central_c(b) + 1j * rng.normal(size=6)
        m = len(load_start()["solutions"])
        q1 = hc.quadrics(b, p, c1)
        best = np.zeros((0, 8), dtype=complex)
        for attempt in range(START_ATTEMPTS):
            patch, source, x0, ok0 = _start_leg(attempt)
            best = best / (best @ patch)[:, None]
            x, ok, _ = _start_track(patch, source, (b, p, c1), x0)
            x = np.concatenate([best, x[ok & ok0]])
            q = np.broadcast_to(q1, (len(x), 7, 8, 8))
            x, beta, jn = hc.newton_refine(q, patch, x, iters=4)
            alpha = hc.certify(q, beta, jn)
            finite = np.abs(np.sum(x[:, :4] ** 2, -1)) > 1e-10 * np.sum(np.abs(x[:, :4]) ** 2, -1)
            ok = ((alpha < hc.ALPHA0) & finite)[None]
            keep = hc.distinct(x[None], beta[None], ok, alpha[None])[0]
            best = x[keep]
            if len(best) == m:
                break
        return {"c": c1, "patch": patch, "solutions": best, "q0": hc.quadrics(b, p, np.zeros(6))}

    @cached_property
    def _kernel(self):
        """The compiled kernel module and this geometry prepared for it, or None (numpy path)."""
        kernel = _compiled_kernel(self.fk_start["q0"])
        if kernel is None:
            return None
        st = self.fk_start
        bs, ps, bc, pc, s = self._scaled
        prepared = kernel.geometry(
            bs,
            ps,
            st["c"],
            st["solutions"],
            st["patch"],
            bc,
            pc,
            s,
            self.base_points,
            self.platform_points,
        )
        return kernel, prepared

    @property
    def root_count(self) -> int:
        """Number of isolated complex forward solutions found for this geometry (40 for a general one)."""
        return len(self.fk_start["solutions"])

    @cached_property
    def expected_count(self) -> int:
        """What a complete answer has: 40 (the generic count) unless coincident anchors were allowed,
        then the count of that layout found by :attr:`fk_start` (16 for the 3-6). A general geometry
        whose start system found fewer than 40 reports every input incomplete rather than hide it."""
        return self.root_count if self._special_layout else 40

    def _target_c(self, q: Array) -> Array:
        """The leg constants ``c_i = |p_i|^2 + |b_i|^2 - (L_i / size)^2`` of leg lengths ``q``."""
        return self._anchor_norms - (q / self._scaled[4]) ** 2

    @cached_property
    def _anchor_norms(self) -> Array:
        """``|b_i|^2 + |p_i|^2`` of the centred, scaled anchors: the constant part of
        :meth:`_target_c`, computed once per geometry."""
        b, p, *_ = self._scaled
        return np.sum(b * b, -1) + np.sum(p * p, -1)

    def _solve_fiber(self, c1: Array, bend_seed: int | None):
        """Track all start solutions to every target ``c1`` (n, 6); refine, certify; per-input
        arrays (the numpy path)."""
        st = self.fk_start
        m = len(st["solutions"])
        n = len(c1)
        x0 = np.broadcast_to(st["solutions"], (n, m, 8)).reshape(-1, 8)
        c0 = np.broadcast_to(st["c"], (n * m, 6))
        cc = np.repeat(c1, m, axis=0).astype(complex)
        bend = None
        patch = st["patch"]
        if bend_seed is not None:  # a bent path, in another random patch
            rng = np.random.default_rng(bend_seed)
            d = rng.normal(size=(n, 1, 6)) + 1j * rng.normal(size=(n, 1, 6))
            bend = np.broadcast_to(d * (1 + np.abs(c1 - st["c"]))[:, None, :], (n, m, 6)).reshape(
                -1, 6
            )
            patch = (rng.normal(size=8) + 1j * rng.normal(size=8)) / 4
            x0 = x0 / (x0 @ patch)[:, None]
        hom = hc.FiberHomotopy(st["q0"], patch, c0, cc, bend)
        x, ok, steps = hc.track(hom, x0, **TRACK_OPTIONS)
        if bend_seed is not None:
            with np.errstate(all="ignore"):
                x = x / (x @ st["patch"])[:, None]  # back to the common patch
            x = np.where(np.isfinite(x), x, 0)
        q = np.broadcast_to(self._quadrics_for(c1)[:, None], (n, m, 7, 8, 8))
        q = q.reshape(-1, 7, 8, 8)
        x, beta, jn = hc.newton_refine(q, st["patch"], x, iters=3)
        alpha = hc.certify(q, beta, jn)
        return (
            x.reshape(n, m, 8),
            beta.reshape(n, m),
            alpha.reshape(n, m),
            ok.reshape(n, m),
            steps.reshape(n, m).sum(-1),
        )

    def _quadrics_for(self, c1: Array) -> np.ndarray:
        q = np.broadcast_to(self.fk_start["q0"], (len(c1), 7, 8, 8)).copy()
        q[:, 1:, :4, :4] += c1[:, :, None, None] * np.eye(4)
        return q

    def real_solutions(self, joints: ArrayLike) -> tuple[Array, np.ndarray]:
        """Every certified real solution (N, 40, 6) and, per input, the homotopy's certificate that
        none is missing (:attr:`FKAll.complete`)."""
        info = self.fk_all(joints, return_info=True)
        return info.poses, np.asarray(info.complete)

    def fk_all(self, joints: ArrayLike, *, return_info: bool = False, retries: int = RETRIES):
        """Every forward solution of leg lengths ``joints`` (..., 6).

        Returns the real ones as poses, (..., 40, 6) NaN-padded, sorted by Z descending (the shape
        the generic ``"all-solutions"`` solver expects); with ``return_info=True`` an :class:`FKAll`
        with every complex solution, the certificates and the per-input counts instead.

        Method: each input's leg constants ``c_i = |p_i|^2 + |b_i|^2 - L_i^2`` are reached from this
        geometry's start system (:attr:`fk_start`) by a straight complex segment; all (inputs x 40)
        paths are tracked at once (:func:`parakin.mechanisms.stewart66_homotopy.track`), refined by
        Newton and certified (alpha < ALPHA0 and pairwise disjoint 2 beta balls). Inputs with fewer
        than :attr:`root_count` certified distinct solutions are tracked again along a randomly bent
        path (up to ``retries`` times) and the new certified solutions merged in. Solutions with
        ``e . e`` numerically 0 are not assemblies and are dropped (and counted as not found).
        Real solutions (real up to the patch scale) are turned into poses and kept where
        ``max |IK(pose) - L| <= 1e-8 size``."""
        q = as_batch(joints, 6, "joints")
        self._check_positive(q)  # :meth:`check_joints` of a batch already checked by as_batch
        batch = q.shape[:-1]
        qf = q.reshape(-1, 6)
        compiled = _compiled_kernel()
        if compiled is not None and self._new_geometry_path(len(qf)):
            fields = self._fk_all_new(compiled, qf, retries)
        elif compiled is not None:  # the geometry's own start system, then every input's fibre
            kernel, prepared = self._kernel
            fields = kernel.fk_all(prepared, self._target_c(qf), qf, retries=retries, alpha0=hc.ALPHA0)  # fmt: skip
            fields.update(n_expected=self.expected_count)
        else:
            info = self._fk_all_numpy(qf, retries)
            # the fields (not dataclasses.asdict: it deep-copies every array)
            fields = {f.name: getattr(info, f.name) for f in dataclasses.fields(info)}
        if not return_info:
            return fields["poses"].reshape(batch + fields["poses"].shape[1:])
        fields["complete"] = fields["n_found"] == fields["n_expected"]
        if len(batch) != 1:  # the arrays in the batch's shape
            fields = {
                k: (v.reshape(batch + v.shape[1:]) if isinstance(v, np.ndarray) else v)
                for k, v in fields.items()
            }
        return FKAll(**fields)

    def _new_geometry_path(self, n: int) -> bool:
        """Whether :meth:`fk_all` takes the new-geometry path for ``n`` inputs: a general layout
        whose start system is not built yet, at most :data:`NEW_GEOMETRY_MAX` inputs, and this
        geometry's first call. A path from the stored generic start takes about five times the
        steps of one from the geometry's own start system, which costs as much as one input to
        build: a geometry called once pays one input, a geometry called again (a loop of single
        inputs on one platform) builds its start system on the second call and takes the fibre
        from then on (1.3 against 4.5 ms per input, docs/stewart66.md)."""
        if n > NEW_GEOMETRY_MAX or "fk_start" in self.__dict__ or self._special_layout:
            return False
        first = "_new_geometry_used" not in self.__dict__
        self.__dict__["_new_geometry_used"] = True  # frozen dataclass: as cached_property writes
        return first

    @cached_property
    def _special_layout(self) -> bool:
        """Coincident anchors allowed and present: the root count is the layout's, found by
        :attr:`fk_start`, not 40."""
        b, p = self.base_points, self.platform_points
        tol = 1e-9 * max(np.ptp(b, axis=0).max(), np.ptp(p, axis=0).max())
        return self.allow_coincident and bool(_coincident(b, tol) or _coincident(p, tol))

    def _fk_all_new(self, kernel, qf: Array, retries: int) -> dict[str, Any]:
        """:meth:`fk_all` on the new-geometry path: one homotopy per input from the stored
        generic start (:func:`parakin.kernels.stewart66_track.fk_all_new`); an input still
        incomplete after its retries is solved again from this geometry's own start system.
        Returns :class:`FKAll`'s fields but ``complete``."""
        bs, ps, bc, pc, s = self._scaled
        n = len(qf)
        geo = (
            np.broadcast_to(bc, (n, 3)),
            np.broadcast_to(pc, (n, 3)),
            np.full(n, s),
            np.broadcast_to(self.base_points, (n, 6, 3)),
            np.broadcast_to(self.platform_points, (n, 6, 3)),
        )
        res = kernel.fk_all_new(
            _stored_start(),
            np.broadcast_to(bs, (n, 6, 3)),
            np.broadcast_to(ps, (n, 6, 3)),
            self._target_c(qf),
            qf,
            geo,
            retries=retries,
            alpha0=hc.ALPHA0,
        )
        bad = np.flatnonzero(res["n_found"] < 40)
        if bad.size:  # the geometry's own start system, then its fibre (rare)
            k, prepared = self._kernel
            again = k.fk_all(prepared, self._target_c(qf[bad]), qf[bad], retries=retries, alpha0=hc.ALPHA0)  # fmt: skip
            for key, value in again.items():
                res[key][bad] = value
        res["n_expected"] = 40
        return res

    def _fk_all_numpy(self, qf: Array, retries: int) -> FKAll:
        """:meth:`fk_all` on flat inputs with the numpy tracker (kernels off or unavailable)."""
        n = len(qf)
        m = self.root_count
        c1 = self._target_c(qf)
        x, beta, alpha, ok, steps = self._solve_fiber(c1, None)
        keep = self._keep(x, beta, alpha)
        retried = np.zeros(n, dtype=np.int64)
        for r in range(retries):
            bad = np.flatnonzero(keep.sum(-1) < m)
            if not bad.size:
                break
            retried[bad] += 1
            x2, b2, a2, _, s2 = self._solve_fiber(c1[bad], bend_seed=1000 + r)
            steps[bad] += s2
            xx = np.concatenate([np.where(keep[bad, :, None], x[bad], np.nan), x2], 1)
            bb = np.concatenate([np.where(keep[bad], beta[bad], np.inf), b2], 1)
            aa = np.concatenate([np.where(keep[bad], alpha[bad], np.inf), a2], 1)
            kk = self._keep(xx, bb, aa)
            order = np.argsort(~kk, axis=1, kind="stable")[:, :m]
            x[bad] = np.take_along_axis(xx, order[..., None], 1)
            beta[bad] = np.take_along_axis(bb, order, 1)
            alpha[bad] = np.take_along_axis(aa, order, 1)
            keep[bad] = np.take_along_axis(kk, order, 1)
        return self._package(qf, x, alpha, keep, steps, retried)

    @staticmethod
    def _keep(x, beta, alpha):
        e = x[..., :4]
        with np.errstate(invalid="ignore"):
            finite = np.abs(np.sum(e * e, -1)) > 1e-10 * np.sum(np.abs(e) ** 2, -1)
        return hc.distinct(x, beta, (alpha < hc.ALPHA0) & finite, alpha)

    def _package(self, qf, x, alpha, keep, steps, retried) -> FKAll:
        n, m, _ = x.shape
        b, p, bc, pc, s = self._scaled
        big = 40
        xs = np.where(keep[..., None], x, np.nan)
        with np.errstate(all="ignore"):
            xs = xs / np.sqrt(np.sum(xs[..., :4] ** 2, -1))[..., None]  # e . e = 1
        # real or not: decided by the certificate (hc.real_decision), not by a threshold
        q = self._quadrics_for(self._target_c(qf))
        y = np.full((n, m, 8), np.nan + 0j)
        decision = np.zeros((n, m), dtype=int)
        y[keep], decision[keep] = hc.real_decision(q[np.nonzero(keep)[0]], x[keep])
        real = keep & (decision == 1)
        with np.errstate(all="ignore"):
            rot, trn = hc.study_to_rt(np.nan_to_num(xs))
            # moving-frame origin O = t + Bc - T Pc, in metres
            origin = trn * s + bc - np.einsum("...ij,j->...i", rot, pc)
        rot = np.where(keep[..., None, None], rot, np.nan)
        origin = np.where(keep[..., None], origin, np.nan)
        yr = np.where(real[..., None], y.real, 1.0)
        with np.errstate(all="ignore"):
            rr, tr = hc.study_to_rt(yr)
            angles = euler_zyx_from_matrix(rr)
            o = tr * s + bc - np.einsum("...ij,j->...i", rr, pc)
        poses = np.concatenate([angles, o], -1)
        poses = np.where(real[..., None], poses, np.nan)
        with np.errstate(invalid="ignore"):
            err = np.abs(self.ik(np.nan_to_num(poses)) - qf[:, None, :]).max(-1)
        good = real & (err <= 1e-8 * max(1.0, s))
        # undecided: the certificate decides neither way, or a real solution's pose misses the IK
        undecided = keep & ((decision == 0) | (real & ~good))
        poses = np.where(good[..., None], poses, np.nan)
        key = np.where(good, -np.nan_to_num(poses[..., 5]), np.inf)
        order = np.argsort(key, axis=-1, kind="stable")
        poses = np.take_along_axis(poses, order[..., None], 1)
        out = np.full((n, big, 6), np.nan)
        out[:, :m] = poses

        def pad(a, fill):
            o_ = np.full((n, big) + a.shape[2:], fill, dtype=a.dtype)
            o_[:, :m] = a
            return o_

        nf = keep.sum(-1)
        ik_err = np.where(good.any(-1), np.where(good, err, -np.inf).max(-1), np.nan)
        return FKAll(
            poses=out,
            study=pad(xs, np.nan),
            rotation=pad(rot, np.nan),
            translation=pad(origin, np.nan),
            is_real=pad(good, False),
            alpha=pad(np.where(keep, alpha, np.nan), np.nan),
            n_found=nf,
            n_expected=self.expected_count,
            complete=nf == self.expected_count,
            n_real=good.sum(-1),
            n_undecided=undecided.sum(-1),
            ik_error=ik_err,
            steps=steps,
            retries=retried,
        )

    def fk(self, joints: ArrayLike, near: ArrayLike | None = None) -> Array:
        """One forward solution: the certified real solution nearest ``near`` (default :meth:`home`;
        distance in units of the :meth:`pose_bounds` box, angles modulo 2 pi), (..., 6). Raises
        UnreachableError where an input has no real solution."""
        sols = self.fk_all(joints)
        ref = self.home() if near is None else as_batch(near, 6, "near")
        lo, hi = self.pose_bounds()
        with np.errstate(invalid="ignore"):
            d = self.pose_difference(sols, np.asarray(ref)[..., None, :]) / (hi - lo)
            dist = np.sqrt(np.sum(d * d, -1))
        ok = np.isfinite(dist)
        none = ~np.any(ok, -1)
        if np.any(none):
            raise UnreachableError(
                f"leg lengths have no real forward solution{describe_first(none, none.shape)}"
            )
        best = np.argmin(np.where(ok, dist, np.inf), -1)
        return np.take_along_axis(sols, best[..., None, None], -2)[..., 0, :]

    # ------------------------------------------------------------------ dynamics (issue 27)
    def mass_model(self) -> MassModel:
        """Illustrative defaults (no source gives masses for a general 6-6): a 10 kg platform and
        legs of a 1.5 kg cylinder and a 1 kg piston, shaped by
        :func:`parakin.dynamics.model.hexapod_masses` to the mean leg length at :meth:`home`."""
        leg = float(np.mean(self.ik(self.home())))
        return hexapod_masses(
            self.platform_points, leg, 10.0, 1.5, 1.0, note="stewart66 illustrative defaults"
        )


# ---------------------------------------------------------------------- sampling, many geometries
def random_platform(rng: np.random.Generator) -> Stewart66:
    """A random general 6-6 platform: base and platform anchors standard normal in 3-D."""
    return Stewart66(base=rng.normal(size=(6, 3)), platform=rng.normal(size=(6, 3)))


def random_pose(rng: np.random.Generator, n: int, mech: Stewart66) -> Array:
    """``n`` random poses: uniformly random orientation (ZYX angles of a random unit quaternion),
    origin normal around :meth:`Stewart66.home` with standard deviation ``size``."""
    q = rng.normal(size=(n, 4))
    q /= np.linalg.norm(q, axis=-1, keepdims=True)
    ang = euler_zyx_from_matrix(hc.quat_rotation(q))
    o = mech.home()[3:] + rng.normal(size=(n, 3)) * mech.size
    return np.concatenate([ang, o], -1)


def fk_all_geometries(
    base: ArrayLike, platform: ArrayLike, joints: ArrayLike, *, retries: int = RETRIES
) -> FKAll:
    """Every forward solution of ``n`` inputs, each on its own geometry: ``base``, ``platform``
    (n, 6, 3) and leg lengths ``joints`` (n, 6). The new-geometry path batched: every input
    tracked from the stored generic start system in one homotopy (no start system of its own),
    all inputs' paths side by side in the compiled lanes; an input still incomplete after its
    retries is solved again from its geometry's own start system. Anchors are validated as
    :class:`Stewart66` does (a general layout: coincident anchors are refused). Returns an
    :class:`FKAll` with batch shape ``(n,)`` (``n_expected`` 40). Needs the compiled kernels;
    without them each geometry's :meth:`Stewart66.fk_all` runs in turn."""
    b = np.asarray(base, dtype=float)
    p = np.asarray(platform, dtype=float)
    q = np.asarray(joints, dtype=float)
    if b.ndim != 3 or b.shape[1:] != (6, 3) or p.shape != b.shape or q.shape != (len(b), 6):
        raise ValueError(
            f"base and platform must be (n, 6, 3) and joints (n, 6), got {b.shape}, {p.shape}, "
            f"{q.shape}"
        )
    mechs = [Stewart66(base=bi, platform=pi) for bi, pi in zip(b, p)]
    for m, qi in zip(mechs, q):
        m.check_joints(qi)
    kernel = _compiled_kernel()
    if kernel is None:
        infos = [m.fk_all(qi, return_info=True, retries=retries) for m, qi in zip(mechs, q)]
        return _stack(infos)
    scaled = [m._scaled for m in mechs]
    bs = np.stack([sc[0] for sc in scaled])
    ps = np.stack([sc[1] for sc in scaled])
    geo = (
        np.stack([sc[2] for sc in scaled]),
        np.stack([sc[3] for sc in scaled]),
        np.array([sc[4] for sc in scaled]),
        b,
        p,
    )
    c1 = np.stack([m._target_c(qi[None])[0] for m, qi in zip(mechs, q)])
    res = kernel.fk_all_new(_stored_start(), bs, ps, c1, q, geo, retries=retries, alpha0=hc.ALPHA0)
    for i in np.flatnonzero(res["n_found"] < 40):  # its own start system, then its fibre (rare)
        k, prepared = mechs[i]._kernel
        again = k.fk_all(prepared, c1[i : i + 1], q[i : i + 1], retries=retries, alpha0=hc.ALPHA0)
        for key, value in again.items():
            res[key][i] = value[0]
    n_found = res.pop("n_found")
    return FKAll(**res, n_found=n_found, n_expected=40, complete=n_found == 40)


def _stack(infos: list[FKAll]) -> FKAll:
    """One :class:`FKAll` of single-input results (each with batch shape ``()``)."""
    fields = [f.name for f in dataclasses.fields(FKAll)]
    out = {}
    for name in fields:
        values = [getattr(r, name) for r in infos]
        out[name] = values[0] if name == "n_expected" else np.stack([np.asarray(v) for v in values])
    return FKAll(**out)
