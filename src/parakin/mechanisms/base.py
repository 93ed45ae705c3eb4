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
"""

from __future__ import annotations

import dataclasses
from abc import ABC, abstractmethod
from collections.abc import Callable
from typing import TYPE_CHECKING, Any, ClassVar

import numpy as np
from numpy.typing import ArrayLike, NDArray

from parakin.errors import ShapeError, SingularityError, UnreachableError
from parakin.kernels import Kernel

if TYPE_CHECKING:  # the types of the optional dynamics hooks (parakin.dynamics imports this module)
    from parakin.dynamics.jet import Jet
    from parakin.dynamics.model import Bodies, MassModel

Array = NDArray[np.float64]
#: a torch residual ``f(pose (..., n), joints (..., m)) -> (..., m)`` on tensors
#: (:meth:`Mechanism.torch_residual`; ``Any``: torch is optional)
TorchResidual = Callable[[Any, Any], Any]

__all__ = ["Mechanism", "Skeleton", "TorchResidual", "as_batch", "describe_first"]


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

    # ------------------------------------------------------------------ what a mechanism defines
    @abstractmethod
    def ik(self, pose: ArrayLike) -> Array:
        """Joint values ``(..., n_joints)`` of ``pose`` ``(..., n_pose)``; raises UnreachableError."""

    @abstractmethod
    def residual(self, pose: ArrayLike, joints: ArrayLike) -> Array:
        """Closure equations ``(..., n_joints)``: zero exactly where pose and joints assemble."""

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

    def jacobian_pose(self, pose: ArrayLike, joints: ArrayLike) -> Array:
        """``d residual / d pose`` ``(..., n_joints, n_pose)``; central differences by default."""
        x = as_batch(pose, self.n_pose, "pose")
        q = as_batch(joints, self.n_joints, "joints")
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
        where its IK is defined). Default: :meth:`is_reachable`. A forward solve that converges
        outside it is not a success (:mod:`parakin.solvers.verify`)."""
        x = np.asarray(pose, dtype=float)
        fin = np.all(np.isfinite(x), axis=-1)
        out = np.zeros(x.shape[:-1], dtype=bool)
        out[fin] = self.is_reachable(x[fin])
        return out

    def on_assembly(self, pose: ArrayLike, joints: ArrayLike) -> NDArray[np.bool_]:
        """Boolean mask ``(...)``: True where ``pose`` is on the assembly mode / branch this
        mechanism asks for (the papers' by default). Default: every pose (no assembly modes told
        apart beyond what :meth:`ik` reproduces)."""
        x = np.asarray(pose, dtype=float)
        return np.ones(np.broadcast_shapes(x.shape[:-1], np.shape(joints)[:-1]), dtype=bool)

    def joint_error(self, pose: ArrayLike, joints: ArrayLike) -> Array:
        """``max_k |ik(pose)_k - joints_k|`` per row (joint units): how far ``pose`` is from being an
        answer for ``joints``. Raises where :meth:`ik` does (callers isolate such rows)."""
        return np.max(np.abs(self.ik(pose) - np.asarray(joints, dtype=float)), axis=-1, initial=0.0)

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

    def kernel(self) -> Kernel | None:
        """This mechanism's kernels (:mod:`parakin.kernels`), or ``None`` (the default): numeric FK
        then runs the generic numpy solvers on the methods above, and the torch solver needs
        :meth:`torch_residual`. A kernel module writes ``residual``, ``jacobian_pose``, ``ik``,
        ``in_domain`` and ``on_assembly`` once, for numba (the compiled loops), numpy (the batched
        methods, which call it) and torch (:mod:`parakin.solvers.torch_newton`); see
        docs/kernels.md. Subclasses that override one of those methods return ``None`` unless
        they provide their own kernel."""
        return None

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
