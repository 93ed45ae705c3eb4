"""The mechanism protocol that every mechanism implements and every solver consumes.

A mechanism is an immutable description (a frozen dataclass of its parameters, SI units inside).
Its kinematics is written as a set of closure equations ``residual(pose, joints) = 0``, one per
actuated joint, that vanish exactly when the pose and the joint values belong to one assembly.
From that one function everything generic follows:

* inverse kinematics ``ik(pose) -> joints`` (closed form for every mechanism of the papers);
* the two Jacobians of the residual, ``A = d residual / d pose`` (``jacobian_pose``) and
  ``B = d residual / d joints`` (``jacobian_joints``), analytic where the mechanism provides them;
* the velocity Jacobian ``J = -B^-1 A`` with ``qdot = J xdot`` (the papers' "Jacobian");
* forward kinematics by any generic solver in :mod:`parakin.solvers` (they only call ``residual``
  and ``jacobian_pose``), or in closed form where the mechanism has one (``fk``).

Arrays are batched: a pose array has shape ``(..., n_pose)``, a joint array ``(..., n_joints)``;
one pose or a million, no Python loop over poses.

A mechanism is its geometry, declared once: a subclass names its kernel module (:attr:`kernels`,
the closure equations, Jacobian, IK, domain and assembly test of **one** pose, written once for
numpy, numba and torch; docs/kernels.md) and returns its parameters as one vector
(:meth:`kernel_params`); the numpy methods below, the compiled solvers and the torch solver then
all run those functions. A subclass that declares a ``name`` registers itself
(:data:`REGISTRY`): the command line, the tests, the solver atlas and the benchmarks read their
list of mechanisms from there.
"""

from __future__ import annotations

import dataclasses
from abc import ABC, abstractmethod
from collections.abc import Callable
from functools import cache, cached_property
from types import ModuleType
from typing import TYPE_CHECKING, Any, ClassVar

import numpy as np
from numpy.typing import ArrayLike, NDArray

from parakin.errors import ParakinError, ShapeError, SingularityError, UnreachableError
from parakin.kernels import Kernel, evaluate

if TYPE_CHECKING:  # the types of the optional dynamics hooks (parakin.dynamics imports this module)
    from parakin.dynamics.jet import Jet
    from parakin.dynamics.model import Bodies, MassModel

Array = NDArray[np.float64]
#: a torch residual ``f(pose (..., n), joints (..., m)) -> (..., m)`` on tensors
#: (:meth:`Mechanism.torch_residual`; ``Any``: torch is optional)
TorchResidual = Callable[[Any, Any], Any]

__all__ = [
    "REGISTRY",
    "Assemblies",
    "Assembly",
    "Mechanism",
    "Skeleton",
    "TorchResidual",
    "as_batch",
    "describe_first",
]

#: CLI name -> mechanism class, in the order the classes were defined; filled by
#: :meth:`Mechanism.__init_subclass__` (see :func:`parakin.mechanisms.get` for the lookup that
#: first imports every mechanism module of the package)
REGISTRY: dict[str, type[Mechanism]] = {}

#: the methods a kernel module provides; a subclass that overrides one of them below the class
#: that declared the kernels has no kernel (:meth:`Mechanism.kernel`): it may change the kinematics
KERNEL_METHODS = ("residual", "jacobian_pose", "ik", "in_domain", "on_assembly", "kernel_params")


def _register(cls: type[Mechanism]) -> None:
    """Add ``cls`` to :data:`REGISTRY` under ``cls.name`` (done for every subclass that declares a
    ``name``, unless it is defined with ``register=False``). A second class under a taken name is
    an error, unless it is the same class defined again (a reloaded module)."""
    old = REGISTRY.get(cls.name)
    if old is not None and old.__qualname__ != cls.__qualname__:
        raise ValueError(
            f"mechanism name {cls.name!r} is taken by {old.__module__}.{old.__qualname__}"
        )
    REGISTRY[cls.name] = cls


#: what a registered mechanism declares about itself besides its ``name``
_DESCRIBED = (
    "pose_names",
    "joint_names",
    "pose_units",
    "joint_units",
    "paper_pose_units",
    "paper_joint_units",
)


@cache
def _kernel_owner(cls: type) -> type | None:
    """The class whose :attr:`Mechanism.kernels` ``cls`` uses, or None: no kernels declared, or a
    class between ``cls`` and that one overrides a method of :data:`KERNEL_METHODS`."""
    for klass in cls.__mro__:
        if klass.__dict__.get("kernels") is not None:
            return klass
        if any(name in klass.__dict__ for name in KERNEL_METHODS):
            return None
    return None


@dataclasses.dataclass(frozen=True)
class Skeleton:
    """What a drawing of one assembly shows, in world coordinates (m); see :mod:`parakin.plot`.

    ``points``: labelled points, name -> (3,) (e.g. ``"u_1"``, ``"c_1"``);
    ``segments``: (kind, (2, 3) array) lines, kind in {"rail", "actuator", "passive", "equivalent",
    "base", "platform"}; ``polygons``: (kind, (k, 3)) closed outlines (base, platform);
    ``frames``: name -> (origin (3,), rotation (3, 3) whose columns are the frame axes).
    """

    points: dict[str, Array]
    segments: list[tuple[str, Array]]
    polygons: list[tuple[str, Array]]
    frames: dict[str, tuple[Array, Array]]


@dataclasses.dataclass(frozen=True)
class Assembly:
    """One real forward solution of a joint vector: the pose, what kind of assembly it is (the
    mechanism's words, :meth:`Mechanism.assembly_label`) and whether it is the working one (what
    the mechanism's ``fk`` returns)."""

    x: Array
    label: str
    working: bool


@dataclasses.dataclass(frozen=True)
class Assemblies:
    """Every real assembly of each input of a batch (:meth:`Mechanism.assemblies`).

    ``solutions[i]``: the assemblies of input ``i``; ``complete[i]``: True where the method
    guarantees that every real assembly was found (a certificate, or an exact closed form), False
    where it knows it may have missed some (a degenerate input, an uncertified path); ``None``
    (the whole field) where the method gives no guarantee either way."""

    solutions: list[list[Assembly]]
    complete: NDArray[np.bool_] | None

    @property
    def n_found(self) -> list[int]:
        """How many real assemblies each input has."""
        return [len(rows) for rows in self.solutions]


def wrap_angles(values: ArrayLike, units: tuple[str, ...]) -> Array:
    """``values (..., k)`` with every coordinate whose unit is ``rad`` wrapped into ``(-pi, pi]``
    (the same angle, counted in the first turn); entries already there, and every other
    coordinate, are returned bit for bit."""
    a = np.array(values, dtype=float)
    rad = [k for k, u in enumerate(units) if u == "rad"]
    if rad and a.size:
        v = a[..., rad]
        outside = (np.abs(v) > np.pi) | (v == -np.pi)
        if np.any(outside):
            turned = v - 2 * np.pi * np.ceil((v - np.pi) / (2 * np.pi))
            a[..., rad] = np.where(outside, turned, v)
    return a


def as_batch(values: ArrayLike, size: int, what: str) -> Array:
    """``values`` as a float array whose last axis has ``size`` entries, or a clear ShapeError."""
    a = np.asarray(values, dtype=float)
    if a.ndim == 0 or a.shape[-1] != size:
        raise ShapeError(f"{what} must have {size} values along its last axis, got shape {a.shape}")
    if not np.all(np.isfinite(a)):
        bad = np.argwhere(~np.isfinite(a))[0]
        raise ValueError(
            f"{what} contains a non-finite value {a[tuple(bad)]!r} at index {tuple(bad)}"
        )
    return a


def describe_first(mask: NDArray[np.bool_], batch_shape: tuple[int, ...]) -> str:
    """'at index (i, j)' of the first True entry of ``mask`` plus how many more, for messages."""
    idx = np.argwhere(mask)
    count = len(idx)
    where = f" at batch index {tuple(int(i) for i in idx[0])}" if batch_shape else ""
    more = f" ({count - 1} more in this batch)" if count > 1 else ""
    return where + more


def raise_first(
    mask: NDArray[np.bool_],
    batch_shape: tuple[int, ...],
    message: Callable[[tuple[int, ...]], str],
    error: type[Exception] = UnreachableError,
) -> None:
    """Raise ``error`` where ``mask`` has a True entry: ``message(idx)`` of the first one's index
    ``idx``, then :func:`describe_first`'s where and how many more. ``mask`` covers the batch
    (``batch_shape``) and may have trailing axes (a limb, a leg): ``idx`` then names the entry and
    the count is of the samples with any."""
    if not np.any(mask):
        return
    idx = tuple(np.argwhere(mask)[0])
    per_sample = mask if mask.shape == batch_shape else np.any(mask, axis=-1)
    raise error(message(idx) + describe_first(per_sample, batch_shape))


class Mechanism(ABC):
    """Base class of every mechanism: subclasses are frozen dataclasses of their parameters."""

    #: CLI name, e.g. ``"3p4s"``.
    name: ClassVar[str]
    #: Names of the pose coordinates, e.g. ``("x", "y", "z")``.
    pose_names: ClassVar[tuple[str, ...]]
    #: Names of the actuated joints, e.g. ``("l1", "l2", "l3")``.
    joint_names: ClassVar[tuple[str, ...]]
    #: SI unit of each pose coordinate (``"m"`` or ``"rad"``).
    pose_units: ClassVar[tuple[str, ...]]
    #: SI unit of each joint.
    joint_units: ClassVar[tuple[str, ...]]
    #: Units the paper prints poses and joints in (``--units paper`` in the CLI), e.g. mm and deg.
    paper_pose_units: ClassVar[tuple[str, ...]]
    paper_joint_units: ClassVar[tuple[str, ...]]
    #: The kernel module (:mod:`parakin.kernels`): ``residual``, ``jacobian``, ``ik``,
    #: ``in_domain`` and ``on_assembly`` of one pose, written once; with :meth:`kernel_params` it
    #: gives this class its numpy methods, the compiled solvers and the torch solver. ``None``: the
    #: mechanism writes :meth:`ik` and :meth:`residual` itself (the generic numpy solvers run).
    kernels: ClassVar[ModuleType | None] = None

    def __init_subclass__(cls, register: bool = True, **kwargs: Any) -> None:
        """Register a subclass that declares a ``name`` and the names and units of its pose and
        joints (:data:`REGISTRY`, what the CLI, tests, atlas and benchmarks list);
        ``register=False`` keeps a variant or a test's mechanism out of the lists."""
        super().__init_subclass__(**kwargs)
        if register and "name" in cls.__dict__ and all(hasattr(cls, a) for a in _DESCRIBED):
            _register(cls)

    # ------------------------------------------------------------------ what a mechanism defines
    def kernel_params(self) -> Array:
        """The parameter vector ``p`` every function of :attr:`kernels` reads (float64, 1-D)."""
        raise NotImplementedError(f"{type(self).__name__} declares no kernel parameters")

    def ik(self, pose: ArrayLike) -> Array:
        """Joint values ``(..., n_joints)`` of ``pose`` ``(..., n_pose)``; raises UnreachableError
        where the pose is outside the domain. Default: the kernel's ``ik``."""
        x = as_batch(pose, self.n_pose, "pose")
        q, ok = evaluate(self._declared_kernel, "ik", x)
        bad = ~ok & np.all(np.isfinite(x), axis=-1)  # a non-finite pose: NaN, named by callers
        raise_first(
            bad,
            x.shape[:-1],
            lambda idx: (
                f"pose {tuple(np.round(x[idx], 6).tolist())} is outside the domain of "
                f"{type(self).__name__}: no inverse kinematics"
            ),
        )
        return q

    def residual(self, pose: ArrayLike, joints: ArrayLike) -> Array:
        """Closure equations ``(..., n_joints)``: zero exactly where pose and joints assemble.
        Default: the kernel's ``residual``."""
        x = as_batch(pose, self.n_pose, "pose")
        return evaluate(
            self._declared_kernel, "residual", x, as_batch(joints, self.n_joints, "joints")
        )

    @abstractmethod
    def home(self) -> Array:
        """The default initial guess of numeric FK (the paper's initial pose), shape ``(n_pose,)``."""

    @abstractmethod
    def pose_bounds(self) -> tuple[Array, Array]:
        """Lower and upper bounds of the pose box used for sampling the workspace."""

    # ------------------------------------------------------------------ generic defaults
    @property
    def n_pose(self) -> int:
        return len(self.pose_names)

    @property
    def n_joints(self) -> int:
        return len(self.joint_names)

    def jacobian_pose(self, pose: ArrayLike, joints: ArrayLike | None = None) -> Array:
        """``d residual / d pose`` ``(..., n_joints, n_pose)``: the kernel's ``jacobian`` (``joints``
        default to the IK of ``pose``), else central differences of :meth:`residual`."""
        x = as_batch(pose, self.n_pose, "pose")
        if self.kernels is not None:
            if joints is None:
                q = evaluate(self._declared_kernel, "ik", x)[0]
            else:
                q = as_batch(joints, self.n_joints, "joints")
            return evaluate(self._declared_kernel, "jacobian", x, q)
        q = self.ik(x) if joints is None else as_batch(joints, self.n_joints, "joints")
        return _central_difference(lambda xx: self.residual(xx, q), x)

    def jacobian_joints(self, pose: ArrayLike, joints: ArrayLike) -> Array:
        """``d residual / d joints`` ``(..., n_joints, n_joints)``; central differences by default."""
        x = as_batch(pose, self.n_pose, "pose")
        q = as_batch(joints, self.n_joints, "joints")
        return _central_difference(lambda qq: self.residual(x, qq), q)

    def velocity_jacobian(self, pose: ArrayLike, joints: ArrayLike | None = None) -> Array:
        """``J`` with ``qdot = J @ xdot``, ``J = -B^-1 A`` (``(..., n_joints, n_pose)``).

        ``joints`` defaults to ``ik(pose)``. Raises SingularityError where ``B`` is singular
        (an actuator-singular configuration).
        """
        x = as_batch(pose, self.n_pose, "pose")
        q = self.ik(x) if joints is None else as_batch(joints, self.n_joints, "joints")
        a = self.jacobian_pose(x, q)
        b = self.jacobian_joints(x, q)
        cond = np.linalg.cond(b)
        bad = ~np.isfinite(cond) | (cond > 1e12)
        if np.any(bad):
            raise SingularityError(
                "joint Jacobian d(residual)/d(joints) is singular (condition number "
                f"{cond[bad].flat[0]:.3g} > 1e12){describe_first(bad, cond.shape)}"
            )
        return -np.linalg.solve(b, a)

    def pose_difference(self, pose: ArrayLike, reference: ArrayLike) -> Array:
        """``pose - reference`` (broadcast), angle coordinates (unit ``rad``) wrapped into
        ``[-pi, pi)``: how far apart two poses are, whatever turn an angle was counted in."""
        d = np.asarray(pose, dtype=float) - np.asarray(reference, dtype=float)
        rad = np.array([u == "rad" for u in self.pose_units])
        d[..., rad] = (d[..., rad] + np.pi) % (2 * np.pi) - np.pi
        return d

    def is_reachable(self, pose: ArrayLike) -> NDArray[np.bool_]:
        """Boolean mask ``(...)``: True where ``ik(pose)`` exists. Default: try the IK on the whole
        batch and, where it raises, on halves of it (``O(k log N)`` calls for ``k`` bad poses)."""
        x = as_batch(pose, self.n_pose, "pose")
        flat = x.reshape(-1, self.n_pose)
        out = np.zeros(len(flat), dtype=bool)

        def visit(idx: NDArray[np.intp]) -> None:
            try:
                self.ik(flat[idx])
            except UnreachableError:
                if len(idx) > 1:
                    half = len(idx) // 2
                    visit(idx[:half])
                    visit(idx[half:])
                return
            out[idx] = True

        if len(flat):
            visit(np.arange(len(flat)))
        return out.reshape(x.shape[:-1])

    # ------------------------------------------------------------------ is a pose a valid answer?
    def in_domain(self, pose: ArrayLike) -> NDArray[np.bool_]:
        """Boolean mask ``(...)``: True where ``pose`` lies in the mechanism's domain (finite, and
        where its IK is defined): the kernel's ``in_domain``, else :meth:`is_reachable`. A forward
        solve that converges outside it is not a success (:mod:`parakin.solvers.verify`)."""
        x = np.asarray(pose, dtype=float)
        fin = np.all(np.isfinite(x), axis=-1)
        if self.kernels is not None:
            return fin & evaluate(
                self._declared_kernel, "in_domain", np.where(fin[..., None], x, 0)
            )
        out = np.zeros(x.shape[:-1], dtype=bool)
        out[fin] = self.is_reachable(x[fin])
        return out

    def on_assembly(self, pose: ArrayLike, joints: ArrayLike) -> NDArray[np.bool_]:
        """Boolean mask ``(...)``: True where ``pose`` is on the assembly mode / branch this
        mechanism asks for (the papers' by default): the kernel's ``on_assembly``, else every pose
        (no assembly modes told apart beyond what :meth:`ik` reproduces)."""
        x = np.asarray(pose, dtype=float)
        if self.kernels is not None:
            return evaluate(
                self._declared_kernel, "on_assembly", x, np.asarray(joints, dtype=float)
            )
        return np.ones(np.broadcast_shapes(x.shape[:-1], np.shape(joints)[:-1]), dtype=bool)

    def joint_error(self, pose: ArrayLike, joints: ArrayLike) -> Array:
        """``max_k |ik(pose)_k - joints_k|`` per row (joint units): how far ``pose`` is from being an
        answer for ``joints``; a revolute joint's (unit ``rad``) error is taken modulo a turn, so
        3.56 rad and -2.72 rad are the same crank angle. Raises where :meth:`ik` does (callers
        isolate such rows)."""
        d = self.ik(pose) - np.asarray(joints, dtype=float)
        rad = np.array([u == "rad" for u in getattr(self, "joint_units", ())], dtype=bool)
        if rad.any():
            d = np.where(rad, (d + np.pi) % (2 * np.pi) - np.pi, d)
        return np.max(np.abs(d), axis=-1, initial=0.0)

    def check_joints(self, joints: ArrayLike) -> None:
        """Raise UnreachableError where ``joints`` cannot be assembled in the working mode.

        The default accepts everything (a generic mechanism cannot tell cheaply; a numeric FK
        solver then reports ``success=False``). Mechanisms with a closed-form test override it.
        """
        as_batch(joints, self.n_joints, "joints")

    def skeleton(self, pose: ArrayLike) -> Skeleton:
        """Points, links and frames of the assembly at one pose, for :func:`parakin.plot.draw_mechanism`."""
        raise NotImplementedError(f"{type(self).__name__} does not describe its drawing")

    #: Closed-form forward kinematics, where one exists (``None`` otherwise).
    fk: Any = None

    # ------------------------------------------------------------------ every assembly
    def real_solutions(self, joints: ArrayLike) -> tuple[Array, NDArray[np.bool_] | None]:
        """Every real forward solution of ``joints (N, m)`` as poses ``(N, k, n)``, NaN-padded, and
        per input whether the method guarantees that none is missing (``None``: no guarantee
        either way). Default: the mechanism's ``fk_all``, without a guarantee; a mechanism whose
        method certifies its answer (or solves exactly) overrides this. Raises ValueError for a
        mechanism without an all-solutions method."""
        fk_all = getattr(self, "fk_all", None)
        if fk_all is None:
            raise ValueError(f"{self.name} has no all-solutions method (fk_all)")
        return np.asarray(fk_all(joints), dtype=float), None

    @classmethod
    def lists_assemblies(cls) -> bool:
        """Whether :meth:`assemblies` can list every real assembly (the class has an all-solutions
        method: ``fk_all``, or its own :meth:`real_solutions`)."""
        return (
            getattr(cls, "fk_all", None) is not None
            or cls.real_solutions is not Mechanism.real_solutions
        )

    def assembly_label(self, pose: ArrayLike, joints: ArrayLike) -> str:
        """A few words that say which assembly ``pose`` is among the solutions of ``joints`` (e.g.
        "above the base"); "" by default (the mechanism tells its assemblies apart no further)."""
        return ""

    def solution_labels(self, solutions: Array, joints: Array) -> list[list[str]]:
        """The label of each solution ``(N, k, n)`` of :meth:`real_solutions` for joints ``(N, m)``
        (NaN rows get ""): :meth:`assembly_label` of each, unless the mechanism knows more from
        where in its answer a solution sits (the 2-UPS: which branch's polynomial gave it)."""
        return [
            [self.assembly_label(x, q) if np.all(np.isfinite(x)) else "" for x in rows]
            for rows, q in zip(solutions, joints)
        ]

    def assemblies(self, joints: ArrayLike) -> Assemblies:
        """Every real assembly of each joint vector ``(N, m)`` (SI), labelled
        (:meth:`solution_labels`), with the working one marked: the solution that ``fk`` returns
        (the mechanism's own assembly, nearest home) where ``fk`` has one for that input (one per
        input at most: the nearest, the first of equals)."""
        q = np.atleast_2d(as_batch(joints, self.n_joints, "joints"))
        with np.errstate(all="ignore"):
            sols, complete = self.real_solutions(q)
            labels = self.solution_labels(sols, q)
        working = np.full((len(q), self.n_pose), np.nan)
        if self.fk is not None:
            try:
                with np.errstate(all="ignore"):
                    working[:] = self.fk(q)
            except (
                ParakinError,
                ArithmeticError,
            ):  # an input without one: the others still have it
                for i in range(len(q)):
                    try:
                        with np.errstate(all="ignore"):
                            working[i] = self.fk(q[i])
                    except (ParakinError, ArithmeticError):
                        pass
        out = []
        for i in range(len(q)):
            finite = [j for j, x in enumerate(sols[i]) if np.all(np.isfinite(x))]
            best, best_gap = None, 1e-7
            if np.all(np.isfinite(working[i])):
                for j in finite:
                    gap = float(np.max(np.abs(self.pose_difference(sols[i, j], working[i]))))
                    if gap < best_gap and self._answers(sols[i, j], q[i]):
                        best, best_gap = j, gap
            rows = []
            for j in finite:
                label = labels[i][j]
                if j == best:
                    label = ", ".join(filter(None, [label, "working (what fk returns)"]))
                rows.append(Assembly(np.asarray(sols[i, j], dtype=float), label, j == best))
            out.append(rows)
        return Assemblies(out, None if complete is None else np.asarray(complete, dtype=bool))

    def _answers(self, pose: Array, joints: Array) -> bool:
        """Whether ``pose`` is an answer for ``joints`` on this instance's IK (within 1e-6)."""
        try:
            with np.errstate(all="ignore"):
                return float(self.joint_error(pose, joints)) < 1e-6
        except (ParakinError, ArithmeticError):
            return False

    def kernel(self) -> Kernel | None:
        """This mechanism's kernels (:mod:`parakin.kernels`): the module :attr:`kernels` with
        :meth:`kernel_params`, run by the compiled solvers and the torch solver; ``None`` without
        one, and for a subclass that overrides a method of :data:`KERNEL_METHODS` below the class
        that declared the kernels (it may change the kinematics; the generic numpy solvers then
        run its own methods)."""
        if _kernel_owner(type(self)) is None:
            return None
        return self._declared_kernel

    @cached_property
    def _declared_kernel(self) -> Kernel:
        """The :class:`Kernel` of :attr:`kernels` and :meth:`kernel_params` (built once)."""
        if self.kernels is None:
            raise NotImplementedError(
                f"{type(self).__name__} declares no kernels: it must define ik and residual"
            )
        params = np.ascontiguousarray(self.kernel_params(), dtype=float)
        layout = getattr(self.kernels, "PARAMS", None)
        if layout is not None:  # named parameters: the length is checked once, here
            layout.check(params)
        return Kernel(
            self.kernels, params, self.n_pose, self.n_joints, np.asarray(self.home(), float)
        )

    def torch_residual(self) -> TorchResidual | None:
        """A torch residual ``f(pose (..., n), joints (..., m)) -> (..., m)`` for a mechanism
        without a :meth:`kernel` (the torch solver differentiates it with ``torch.func``), or
        ``None`` (the default). Mechanisms with a kernel need none: the solver runs the kernel."""
        return None

    def replace(self, **changes: Any) -> Mechanism:
        """A copy with some parameters changed (``dataclasses.replace``)."""
        return dataclasses.replace(self, **changes)  # type: ignore[type-var]

    def parameters(self) -> dict[str, float]:
        """The mechanism's parameters as a plain dict (SI units)."""
        return {f.name: getattr(self, f.name) for f in dataclasses.fields(self)}  # type: ignore[arg-type]

    # ------------------------------------------------------------------ dynamics (optional)
    def mass_model(self) -> MassModel | None:
        """Default masses, centres of mass and inertias of the moving bodies and gravity
        (:class:`parakin.dynamics.model.MassModel`), or ``None`` (the default): the mechanism
        declares no dynamics. A mechanism that returns one also implements :meth:`bodies`."""
        return None

    def bodies(self, pose: Jet) -> Bodies:
        """Every moving body as a function of the pose, given as a jet
        (:mod:`parakin.dynamics.jet`): frame origins and rotations (or spin-free axes), each body's
        parent joint, the loop closures and the joints as jets
        (:class:`parakin.dynamics.model.Bodies`). :mod:`parakin.dynamics` derives inverse and
        forward dynamics and the physics-engine models from it; docs/dynamics.md."""
        raise NotImplementedError(
            f"{type(self).__name__} does not declare its bodies (no dynamics)"
        )


def _central_difference(f, x: Array, h: float = 1e-7) -> Array:
    """Jacobian of ``f`` at ``x`` (batched) by central differences, shape ``(..., m, n)``.

    The step of coordinate k is ``h * max(1, |x_k|)`` per row, so a row's Jacobian does not
    depend on the other rows of its batch."""
    n = x.shape[-1]
    cols = []
    for k in range(n):
        step = h * np.maximum(1.0, np.abs(x[..., k]))
        e = np.zeros_like(x)
        e[..., k] = step
        cols.append((f(x + e) - f(x - e)) / (2 * step[..., None]))
    return np.stack(cols, axis=-1)
