"""Performance indices of the 3-P(4S) and their workspace means (the generic kinematic indices of
any mechanism are :mod:`parakin.indices`) (Zhao et al. 2017, §3, eqs 24-37).

Three local indices, each a function of the pose ``p`` (and of the design):

* **dynamic** ``sigma = sqrt(lambda_max(M^T M))`` = largest singular value of the mass matrix
  ``M`` of eq (24) (``tau = M a`` with ``v = 0`` and no gravity), eqs (24)-(28); kg; smaller is
  better;
* **stiffness** from ``K = J^T k J`` (eq 30) with ``k = k_a I`` (the actuator stiffness, not given
  in the paper): eq (33) prints ``sigma* = sqrt(lambda_min(K))`` (= ``sqrt(k_a) sigma_min(J)``);
  the paper's numbers fit ``lambda_min(K)`` itself (docs/zhao2017_3p4s.md#s4.6, #g17). Both are returned
  (``stiffness_sqrt``, ``stiffness_lambda``); larger is better;
* **speed** ``sigma_hat = sigma_max(J) / sigma_min(J)`` = 2-norm condition number of ``J``,
  eqs (35)-(36); >= 1, 1 is isotropic.

Global values (eqs 29, 34, 37) are means over the workspace ``W``:
``sigma_i = int_W index dW / int_W dW``. ``W`` is not defined in the paper (docs/zhao2017_3p4s.md#g15); a
:class:`Workspace` is an axis-aligned box (a plane when its z range is a point) and the mean is
taken by tensor Gauss-Legendre quadrature (:meth:`Workspace.nodes`), or by the midpoint rule for
comparison. The integrands are smooth on a feasible design, so Gauss-Legendre converges
spectrally (:func:`convergence`).

Everything is batched: :func:`local_indices` takes designs ``(D,)`` (arrays of ``delta``, ``L``,
``phi``) and poses ``(N, 3)`` and returns ``(D, N)`` arrays without a Python loop. The kinematics
sees the radial dimensions ``(r_a, r_b, d)`` only through ``delta = r_b - sqrt(r_a^2 - d^2/4)``
(docs/zhao2017_3p4s.md#s0), so a design is ``(delta, L, phi)``; :func:`design_arrays` converts Table 3's five
variables. The mass matrix of the batched path (:func:`mass_matrix_batched`) is the closed form of
:func:`parakin.mechanisms.p3p4s_dynamics.force_terms` at ``v = 0``; :func:`mass_matrix` builds it column by column
from the dynamics module itself and the tests check that the two agree.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike

from parakin.errors import SingularityError, UnreachableError
from parakin.indices import Quadrature, box_nodes, kinematic_indices  # noqa: F401 (re-exported)
from parakin.mechanisms import p3p4s_dynamics as dyn
from parakin.mechanisms.base import as_batch
from parakin.mechanisms.p3p4s import P3P4S

__all__ = [
    "Workspace",
    "Indices",
    "GlobalIndices",
    "INDEX_NAMES",
    "design_arrays",
    "mass_matrix",
    "mass_matrix_batched",
    "local_indices",
    "local_indices_loop",
    "global_indices",
    "convergence",
    "mech_indices",
    "design_objectives",
]


#: names of the local indices returned by :func:`local_indices`
INDEX_NAMES = ("dynamic", "stiffness_lambda", "stiffness_sqrt", "speed")

_GAMMAS = np.deg2rad([0.0, 120.0, 240.0])
_E = np.stack([np.cos(_GAMMAS), np.sin(_GAMMAS), np.zeros(3)], axis=-1)  # (3 limbs, 3)
_EZ = np.array([0.0, 0.0, 1.0])
_NM_MIN = 1e-9  # n_i . m_i below this: rod perpendicular to its rail, J infinite


# ---------------------------------------------------------------------------------------- workspace
@dataclass(frozen=True)
class Workspace:
    """An axis-aligned box ``x in [x0, x1], y in [y0, y1], z in [z0, z1]`` (m) of platform centres.

    A zero-width z range (``z0 == z1``) is the plane the paper's atlases show (docs/zhao2017_3p4s.md#g15); the
    mean over ``W`` is then the area mean. Build one with :meth:`square`.
    """

    x: tuple[float, float]
    y: tuple[float, float]
    z: tuple[float, float]

    def __post_init__(self) -> None:
        for name in ("x", "y", "z"):
            lo, hi = (float(v) for v in getattr(self, name))
            if not (np.isfinite(lo) and np.isfinite(hi) and lo <= hi):
                raise ValueError(
                    f"workspace {name} range = ({lo}, {hi}) m must be finite with low <= high"
                )
            object.__setattr__(self, name, (lo, hi))
        if self.x[0] == self.x[1] or self.y[0] == self.y[1]:
            raise ValueError(
                f"workspace x range {self.x} and y range {self.y} must have non-zero width"
            )

    @classmethod
    def square(cls, z0: float, half_width: float, z_half_height: float = 0.0) -> Workspace:
        """``|x|, |y| <= half_width`` at height ``z0`` (+- ``z_half_height``), metres."""
        if not half_width > 0:
            raise ValueError(f"half_width = {half_width!r} m must be > 0")
        if not z_half_height >= 0:
            raise ValueError(f"z_half_height = {z_half_height!r} m must be >= 0")
        return cls(
            (-half_width, half_width),
            (-half_width, half_width),
            (z0 - z_half_height, z0 + z_half_height),
        )

    @property
    def planar(self) -> bool:
        return self.z[0] == self.z[1]

    def nodes(self, n: int, rule: Quadrature = "gauss") -> tuple[np.ndarray, np.ndarray]:
        """Quadrature points ``(N, 3)`` and weights ``(N,)`` summing to 1 (so ``w @ f`` is the mean).

        ``rule="gauss"``: tensor Gauss-Legendre with ``n`` nodes per axis (exact for polynomials of
        degree ``2n - 1`` in each coordinate); ``"midpoint"``: ``n`` equal cells per axis. A planar
        workspace has one z node.
        """
        if not (isinstance(n, (int, np.integer)) and n >= 1):
            raise ValueError(f"n = {n!r} nodes per axis must be a positive integer")
        if rule == "gauss":
            t, w = np.polynomial.legendre.leggauss(int(n))
            t, w = 0.5 * (t + 1.0), 0.5 * w  # on [0, 1], weights sum to 1
        elif rule == "midpoint":
            t, w = (np.arange(n) + 0.5) / n, np.full(n, 1.0 / n)
        else:
            raise ValueError(f"rule = {rule!r} must be 'gauss' or 'midpoint'")
        axes, weights = [], []
        for lo, hi in (self.x, self.y, self.z):
            if lo == hi:
                axes.append(np.array([lo]))
                weights.append(np.array([1.0]))
            else:
                axes.append(lo + (hi - lo) * t)
                weights.append(w)
        grid = np.stack(np.meshgrid(*axes, indexing="ij"), axis=-1).reshape(-1, 3)
        wt = np.einsum("i,j,k->ijk", *weights).reshape(-1)
        return grid, wt

    def grid(self, n: int, z: float | None = None) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """A uniform ``n x n`` grid over the x-y rectangle, edges included, at height ``z`` (default:
        the middle of the z range): ``(X, Y, poses)`` with ``poses`` of shape ``(n, n, 3)``."""
        if not (isinstance(n, (int, np.integer)) and n >= 2):
            raise ValueError(f"n = {n!r} must be an integer >= 2")
        zz = 0.5 * (self.z[0] + self.z[1]) if z is None else float(z)
        X, Y = np.meshgrid(np.linspace(*self.x, n), np.linspace(*self.y, n), indexing="xy")
        return X, Y, np.stack([X, Y, np.full_like(X, zz)], axis=-1)

    def describe(self) -> str:
        z = f"z = {self.z[0]:g} m" if self.planar else f"z in [{self.z[0]:g}, {self.z[1]:g}] m"
        return f"x in [{self.x[0]:g}, {self.x[1]:g}] m, y in [{self.y[0]:g}, {self.y[1]:g}] m, {z}"


# ---------------------------------------------------------------------------------------- designs
def design_arrays(
    r_a: ArrayLike, r_b: ArrayLike, L: ArrayLike, d: ArrayLike, phi: ArrayLike
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Table 3's variables (m, m, m, m, rad; any broadcastable shapes) -> ``(delta, L, phi)``.

    ``delta = r_b - sqrt(r_a^2 - d^2/4)`` (eq 1 with ``theta = arcsin(d / 2 r_a)``). Raises
    ValueError where ``d >= 2 r_a``.
    """
    r_a, r_b, L, d, phi = np.broadcast_arrays(
        *(np.asarray(v, dtype=float) for v in (r_a, r_b, L, d, phi))
    )
    bad = d >= 2 * r_a
    if np.any(bad):
        i = np.argwhere(np.atleast_1d(bad))[0]
        raise ValueError(
            f"d = {np.atleast_1d(d)[tuple(i)]} m must be < 2 r_a = {2 * np.atleast_1d(r_a)[tuple(i)]} m"
        )
    return r_b - np.sqrt(r_a**2 - d**2 / 4), L.copy(), phi.copy()


def _check_designs(delta, L, phi) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    delta, L, phi = np.broadcast_arrays(
        *(np.atleast_1d(np.asarray(v, dtype=float)) for v in (delta, L, phi))
    )
    if delta.ndim != 1:
        raise ValueError(f"designs must be 1-D arrays (D,), got shape {delta.shape}")
    if not np.all(np.isfinite(delta) & np.isfinite(L) & np.isfinite(phi)):
        raise ValueError("design parameters (delta, L, phi) must be finite")
    if np.any(L <= 0):
        raise ValueError(f"L = {L[L <= 0][0]} m must be > 0")
    if np.any((phi <= 0) | (phi >= np.pi / 2)):
        raise ValueError(
            f"phi = {phi[(phi <= 0) | (phi >= np.pi / 2)][0]} rad must lie in (0, pi/2)"
        )
    return delta, L, phi


# ---------------------------------------------------------------------------------------- mass matrix
def mass_matrix(mech: P3P4S, params: dyn.InertialParams, pose: ArrayLike) -> np.ndarray:
    """Eq (24)'s ``M`` (..., 3, 3) (kg) from :func:`parakin.mechanisms.p3p4s_dynamics.force_terms`: column ``k`` is the
    motor-force vector for a unit platform acceleration ``e_k`` at ``v = 0`` without gravity.

    The reference implementation (one mechanism, batched over poses); see
    :func:`mass_matrix_batched` for the design-batched closed form.
    """
    x = as_batch(pose, 3, "pose")
    acc = np.eye(3).reshape(
        (3,) + (1,) * (x.ndim - 1) + (3,)
    )  # (3, ..., 3): one unit acceleration each
    terms = dyn.force_terms(mech, params, x[None], np.zeros(3), acc)
    f = sum(v for k, v in terms.items() if k not in ("gravity", "gravity_moment"))  # (3, ..., 3)
    return np.moveaxis(f, 0, -1)  # (..., 3 forces, 3 accelerations)


def _kinematics(delta, L, phi, poses):
    """IK and rods for designs (D,) x poses (N, 3): ``n (D, N, 3, 3)``, ``nm (D, N, 3)``, ``m (D, 3, 3)``.

    Unreachable poses get NaN (the caller decides); eq (5) minus root.
    """
    m = -np.cos(phi)[:, None, None] * _E + np.sin(phi)[:, None, None] * _EZ  # (D, 3, 3)
    w = poses[None, :, None, :] - delta[:, None, None, None] * _E  # (D, N, 3, 3)
    b = np.einsum("dnij,dij->dni", w, m)
    disc = L[:, None, None] ** 2 - (np.einsum("dnij,dnij->dni", w, w) - b**2)
    with np.errstate(invalid="ignore"):
        q = b - np.sqrt(disc)  # NaN where unreachable
    n = (w - q[..., None] * m[:, None]) / L[:, None, None, None]
    nm = np.einsum("dnij,dij->dni", n, m)
    return n, nm, m, disc


def mass_matrix_batched(
    delta: ArrayLike,
    L: ArrayLike,
    phi: ArrayLike,
    poses: ArrayLike,
    params: dyn.InertialParams | None = None,
) -> np.ndarray:
    """Eq (24)'s ``M`` for designs (D,) x poses (N, 3) -> (D, N, 3, 3) (kg).

    With ``v = 0`` (so ``omega_i = 0``, ``vHv = 0``) eqs (16)-(20) give
    ``M = J^-T [m I + k m_d sum_i J_vi^T J_vi + k sum_i J_wi^T I_di J_wi] + m_e J``
    with ``J_vi = (I + m_i n_i^T / nm_i)/2`` (eq 11), ``J_wi = [hat(n_i) + (m_i x n_i) n_i^T/nm_i]/L``
    (eq 9), ``I_di = I_xx (I - n_i n_i^T) + I_zz n_i n_i^T`` and ``k = 2`` rods per limb (eq 20).
    NaN where a pose is unreachable.
    """
    params = dyn.InertialParams.zhao2017() if params is None else params
    delta, L, phi = _check_designs(delta, L, phi)
    x = as_batch(poses, 3, "poses").reshape(-1, 3)
    n, nm, m, _ = _kinematics(delta, L, phi, x)
    return _mass_from_rods(n, nm, m, L, params)


def _mass_from_rods(n, nm, m, L, params):
    J = n / nm[..., None]  # (D, N, 3, 3), eq 8
    mb = np.broadcast_to(m[:, None], n.shape)
    outer = mb[..., :, None] * J[..., None, :]  # m_i n_i^T / nm_i  (D, N, 3 limbs, 3, 3)
    Jv = 0.5 * (np.eye(3) + outer)
    mxn = np.cross(mb, n)
    hat = np.zeros(n.shape + (3,))
    hat[..., 0, 1], hat[..., 0, 2] = -n[..., 2], n[..., 1]
    hat[..., 1, 0], hat[..., 1, 2] = n[..., 2], -n[..., 0]
    hat[..., 2, 0], hat[..., 2, 1] = -n[..., 1], n[..., 0]
    Jw = (hat + mxn[..., :, None] * J[..., None, :]) / L[:, None, None, None, None]
    Ixx, _, Izz = params.I_rod
    nn = n[..., :, None] * n[..., None, :]
    Id = Ixx * (np.eye(3) - nn) + Izz * nn
    k = float(params.rods_per_limb)
    A = (
        params.m_platform * np.eye(3)
        + k * params.m_rod * np.einsum("...kji,...kjl->...il", Jv, Jv)
        + k * np.einsum("...kji,...kjm,...kml->...il", Jw, Id, Jw)
    )
    return np.linalg.solve(np.swapaxes(J, -1, -2), A) + params.m_slider * J


# ---------------------------------------------------------------------------------------- indices
@dataclass(frozen=True)
class Indices:
    """Local indices, arrays of shape (D, N) (or the batch shape of the poses for one mechanism).

    ``feasible`` is False where a pose is unreachable or singular (``n_i . m_i ~ 0``); the
    indices are NaN there.
    """

    dynamic: np.ndarray  #: sigma, eq 28 (kg)
    stiffness_lambda: np.ndarray  #: lambda_min(J^T k J), the paper's plotted index (N/m)
    stiffness_sqrt: np.ndarray  #: sqrt(lambda_min), eq 33 as printed (sqrt(N/m))
    speed: np.ndarray  #: cond(J), eq 36
    feasible: np.ndarray

    def __getitem__(self, name: str) -> np.ndarray:
        if name not in INDEX_NAMES:
            raise KeyError(f"unknown index {name!r}; one of {INDEX_NAMES}")
        return getattr(self, name)


def local_indices(
    delta: ArrayLike,
    L: ArrayLike,
    phi: ArrayLike,
    poses: ArrayLike,
    *,
    k: float = 1.0,
    params: dyn.InertialParams | None = None,
) -> Indices:
    """The three local indices of eqs (28), (33), (36) for designs (D,) x poses (N, 3) -> (D, N).

    ``k`` is the actuator stiffness ``k_a`` of ``K = J^T (k_a I) J`` (eq 30; N/m). Unreachable or
    singular poses are marked ``feasible = False`` and get NaN (no exception: the optimiser needs
    to see infeasible designs).
    """
    if not (np.isfinite(k) and k > 0):
        raise ValueError(f"k = {k!r} N/m must be finite and > 0")
    params = dyn.InertialParams.zhao2017() if params is None else params
    delta, L, phi = _check_designs(delta, L, phi)
    x = as_batch(poses, 3, "poses").reshape(-1, 3)
    n, nm, m, disc = _kinematics(delta, L, phi, x)
    ok = np.all((disc >= 0) & (nm > _NM_MIN), axis=-1)  # nm <= 0: the other assembly mode's side
    nm_safe = np.where(ok[..., None], nm, 1.0)
    n_safe = np.where(
        ok[..., None, None], n, np.eye(3)
    )  # placeholder rows (J = I) where infeasible
    with np.errstate(all="ignore"):
        J = n_safe / nm_safe[..., None]
        sj = np.linalg.svd(J, compute_uv=False)  # (D, N, 3), descending
        M = _mass_from_rods(n_safe, nm_safe, m, L, params)
        sm = np.linalg.svd(M, compute_uv=False)[..., 0]
    smin = sj[..., -1]
    singular = smin <= 1e-12 * sj[..., 0]
    ok = ok & ~singular & np.isfinite(sm)
    nan = np.where(ok, 1.0, np.nan)
    return Indices(
        dynamic=sm * nan,
        stiffness_lambda=k * smin**2 * nan,
        stiffness_sqrt=np.sqrt(k) * smin * nan,
        speed=sj[..., 0] / np.where(singular, 1.0, smin) * nan,
        feasible=ok,
    )


def mech_indices(
    mech: P3P4S,
    poses: ArrayLike,
    *,
    k: float = 1.0,
    params: dyn.InertialParams | None = None,
    strict: bool = True,
) -> Indices:
    """:func:`local_indices` for one :class:`P3P4S`, poses of any batch shape ``(..., 3)``.

    With ``strict`` (default) an unreachable or singular pose raises UnreachableError /
    SingularityError naming it.
    """
    x = as_batch(poses, 3, "poses")
    flat = x.reshape(-1, 3)
    if strict:
        bad = ~mech.is_reachable(flat)
        if np.any(bad):
            raise UnreachableError(
                f"pose {tuple(np.round(flat[np.argmax(bad)], 6).tolist())} m is unreachable for "
                f"delta = {mech.delta:.6g} m, L = {mech.L} m, phi = {np.rad2deg(mech.phi):.4g} deg"
            )
    ind = local_indices(mech.delta, mech.L, mech.phi, flat, k=k, params=params)
    if strict and not np.all(ind.feasible):
        i = int(np.argmin(ind.feasible[0]))
        raise SingularityError(
            f"J of eq (8) is singular at pose {tuple(np.round(flat[i], 6).tolist())} m"
        )
    shape = x.shape[:-1]
    return Indices(*(getattr(ind, f)[0].reshape(shape) for f in (*INDEX_NAMES, "feasible")))


def local_indices_loop(
    mech: P3P4S, poses: ArrayLike, *, k: float = 1.0, params: dyn.InertialParams | None = None
) -> np.ndarray:
    """The straightforward per-pose loop (the benchmark's baseline): ``(N, 4)`` array of
    (dynamic, stiffness_lambda, stiffness_sqrt, speed), one pose at a time through the
    mechanism's Jacobian and :func:`mass_matrix` from the dynamics module."""
    params = dyn.InertialParams.zhao2017() if params is None else params
    out = []
    for p in np.asarray(poses, dtype=float).reshape(-1, 3):
        J = mech.velocity_jacobian(p)
        sj = np.linalg.svd(J, compute_uv=False)
        M = mass_matrix(mech, params, p)
        lam = np.linalg.eigvalsh(J.T @ (k * np.eye(3)) @ J)[0]
        out.append((np.linalg.svd(M, compute_uv=False)[0], lam, np.sqrt(lam), sj[0] / sj[-1]))
    return np.array(out)


# ---------------------------------------------------------------------------------------- global
@dataclass(frozen=True)
class GlobalIndices:
    """Workspace means (eqs 29, 34, 37) per design, arrays (D,); NaN where a design is infeasible."""

    sigma1: np.ndarray  #: mean dynamic index (kg), eq 29
    sigma2_lambda: np.ndarray  #: mean lambda_min(K), the paper's plotted stiffness (N/m), eq 34
    sigma2_sqrt: np.ndarray  #: mean sqrt(lambda_min(K)), eq 33-34 as printed
    sigma3: np.ndarray  #: mean cond(J), eq 37
    feasible: np.ndarray  #: every quadrature node reachable and non-singular
    max_speed: np.ndarray  #: max cond(J) over the nodes (the feasibility limit's argument)

    def sigma2(self, form: str = "lambda") -> np.ndarray:
        if form not in ("lambda", "sqrt"):
            raise ValueError(f"stiffness form = {form!r} must be 'lambda' or 'sqrt'")
        return self.sigma2_lambda if form == "lambda" else self.sigma2_sqrt


def global_indices(
    delta: ArrayLike,
    L: ArrayLike,
    phi: ArrayLike,
    workspace: Workspace,
    n: int,
    *,
    rule: Quadrature = "gauss",
    k: float = 1.0,
    params: dyn.InertialParams | None = None,
    chunk: int = 200_000,
) -> GlobalIndices:
    """Eqs (29), (34), (37): the means of the local indices over ``workspace`` for designs (D,),
    by ``rule`` with ``n`` nodes per axis. Designs are processed in chunks of about ``chunk``
    (design, node) pairs to bound memory."""
    delta, L, phi = _check_designs(delta, L, phi)
    x, w = workspace.nodes(n, rule)
    step = max(1, chunk // len(x))
    parts = []
    for s in range(0, len(delta), step):
        ind = local_indices(
            delta[s : s + step], L[s : s + step], phi[s : s + step], x, k=k, params=params
        )
        feas = np.all(ind.feasible, axis=-1)
        parts.append(
            (
                *(np.where(feas, ind[name] @ w, np.nan) for name in INDEX_NAMES),
                feas,
                np.where(
                    feas, np.nanmax(np.where(ind.feasible, ind.speed, -np.inf), axis=-1), np.inf
                ),
            )
        )
    cols = [np.concatenate(c) for c in zip(*parts)]
    return GlobalIndices(
        sigma1=cols[0],
        sigma2_lambda=cols[1],
        sigma2_sqrt=cols[2],
        sigma3=cols[3],
        feasible=cols[4],
        max_speed=cols[5],
    )


def convergence(
    delta: ArrayLike,
    L: ArrayLike,
    phi: ArrayLike,
    workspace: Workspace,
    ns=(2, 4, 8, 16, 32, 64),
    rules: tuple[Quadrature, ...] = ("gauss", "midpoint"),
    **kw,
) -> list[dict]:
    """Global indices for each rule and node count (grid doubling): a list of rows
    ``{rule, n, nodes, design, sigma1, sigma2_lambda, sigma2_sqrt, sigma3}``."""
    delta, L, phi = _check_designs(delta, L, phi)
    rows = []
    for rule in rules:
        for n in ns:
            g = global_indices(delta, L, phi, workspace, int(n), rule=rule, **kw)
            for i in range(len(delta)):
                rows.append(
                    {
                        "rule": rule,
                        "n": int(n),
                        "nodes": int(n) ** (2 if workspace.planar else 3),
                        "design": i,
                        "sigma1": g.sigma1[i],
                        "sigma2_lambda": g.sigma2_lambda[i],
                        "sigma2_sqrt": g.sigma2_sqrt[i],
                        "sigma3": g.sigma3[i],
                    }
                )
    return rows


def design_objectives(
    designs: ArrayLike,
    workspace: Workspace,
    n: int,
    *,
    rule: Quadrature = "gauss",
    k: float = 1.0,
    stiffness: str = "lambda",
    max_speed: float = np.inf,
    params: dyn.InertialParams | None = None,
) -> np.ndarray:
    """``(sigma1, sigma2, sigma3)`` (P, 3) of Table 3's design vectors ``(r_a, r_b, L, d, phi)``
    (P, 5) (m, rad), NaN rows for infeasible designs: a node of ``W`` unreachable or singular, or
    ``cond(J) > max_speed`` somewhere on the nodes (the "end poses satisfying the workspace
    requirement" of §3.4, docs/zhao2017_3p4s.md#g15, #g19). ``stiffness`` picks lambda_min (``"lambda"``) or its
    square root (``"sqrt"``, eq 33 as printed) for sigma2."""
    X = np.atleast_2d(np.asarray(designs, dtype=float))
    if X.ndim != 2 or X.shape[1] != 5:
        raise ValueError(f"designs must have shape (P, 5) = (r_a, r_b, L, d, phi), got {X.shape}")
    delta, L, phi = design_arrays(*X.T)
    g = global_indices(delta, L, phi, workspace, n, rule=rule, k=k, params=params)
    ok = g.feasible & (g.max_speed <= max_speed)
    out = np.stack([g.sigma1, g.sigma2(stiffness), g.sigma3], axis=-1)
    return np.where(ok[:, None], out, np.nan)
