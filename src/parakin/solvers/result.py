"""The result of a forward-kinematics solve, and the batched loop every iterative solver shares.

:class:`FKResult` plays the part of ``scipy.optimize.OptimizeResult``: one object, the same fields
for every method, per-pose arrays when the call was batched.

:func:`iterate` is the one loop behind every iterative solver. A solver only supplies ``init``
(extra per-pose state at the start, e.g. Broyden's first Jacobian) and ``step`` (one iteration on
the poses still running; both in a :class:`Plan`, and :func:`iterative` turns the declaration of
a solver's options into the registered method that runs it); the loop keeps the ``active`` set,
the per-pose counters, the convergence tests, the finiteness guard and the status codes, so that
every solver stops, counts and fails in the same way:

* a pose is *active* until it converges or fails; only active poses are stepped, and only their
  residuals and Jacobians are evaluated (an :class:`Evaluator` counts them per pose);
* a pose converges when the inf-norm of its residual is ``<= tol`` (or, where the caller asks for
  it, its step is ``<= xtol`` or its gradient ``<= gtol``);
* a pose whose new iterate or residual is not finite stops with ``success = False`` and keeps its
  last finite iterate: no NaN ever leaves a solver.

:func:`conditioning` measures how well the joints pin an answer down (``FKResult.conditioning``,
computed on first use): near a singularity another solution of the same joints comes close and the
start decides which one is returned; such an answer is flagged ``near_singular``
(``docs/near_singular.md``).
"""

from __future__ import annotations

import dataclasses
import functools
import inspect
import time
from collections.abc import Callable
from enum import IntEnum
from typing import Any, NamedTuple

import numpy as np
from numpy.typing import NDArray

from parakin.errors import ParakinError
from parakin.mechanisms.base import Array, Mechanism

__all__ = [
    "Conditioning",
    "Evaluator",
    "FKResult",
    "NEAR_SINGULAR",
    "ROW_ERRORS",
    "Status",
    "Plan",
    "StepInfo",
    "inf_norm",
    "conditioning",
    "iterate",
    "iterative",
    "rowwise",
    "summarize",
]

#: what a mechanism raises for one pose or joint row it cannot handle (outside its domain, singular)
ROW_ERRORS = (ParakinError, ArithmeticError)


def rowwise(
    f: Callable[..., Any], *rows: Array, tail: tuple[int, ...], fill: float = np.nan
) -> Array:
    """``f(*rows)`` on the whole batch; where it raises one of :data:`ROW_ERRORS`, on halves of the
    batch, so that a bad row gives ``fill`` (shape ``tail``) and never costs its neighbours.
    One vectorised call when every row is fine, ``O(k log N)`` calls for ``k`` bad rows."""
    n = len(rows[0])
    if n == 0:
        return np.full((0, *tail), fill)
    try:
        with np.errstate(all="ignore"):
            return np.asarray(f(*rows), dtype=float).reshape(n, *tail)
    except ROW_ERRORS:
        if n == 1:
            return np.full((1, *tail), fill)
    half = n // 2
    return np.concatenate(
        [
            rowwise(f, *(r[:half] for r in rows), tail=tail, fill=fill),
            rowwise(f, *(r[half:] for r in rows), tail=tail, fill=fill),
        ]
    )


class Status(IntEnum):
    """Why a pose stopped; ``>= 0`` is success, ``< 0`` failure (as ``FKResult.status``)."""

    CONVERGED = 0  #: inf-norm of the residual <= tol
    SMALL_STEP = 1  #: step inf-norm <= xtol (only where the caller set xtol > 0)
    SMALL_GRADIENT = 2  #: gradient inf-norm <= gtol (only where the caller set gtol > 0)
    MAXITER = -1  #: still running after maxiter iterations
    NONFINITE = -2  #: the next iterate or its residual was not finite (x is the last finite one)
    STALLED = -3  #: no acceptable step (line search exhausted its trials)
    NO_SOLUTION = -4  #: the closed form has no (accurate enough) solution for these joints
    LOCAL_MINIMUM = -5  #: the step became small at a large residual (unreachable joints?)
    WRONG_ASSEMBLY = -6  #: converged, but on another assembly mode / branch than the one asked for
    OUT_OF_DOMAIN = (
        -7
    )  #: converged, but the pose lies outside the mechanism's domain (its IK rejects it)
    WRONG_ANSWER = -8  #: residual within tol, but ik(x) misses the joints by more than joint_tol
    BAD_INPUT = -9  #: the row's joints or start are not finite (x is the mechanism's home)
    UNREACHABLE = -10  #: the mechanism's check_joints rejects the row's joints (no solve attempted)


_RUNNING = 127  # internal status of a pose still iterating

_WHY = {
    Status.MAXITER: "reached maxiter={maxiter}",
    Status.NONFINITE: "became non-finite",
    Status.STALLED: "stalled (line search found no decrease)",
    Status.NO_SOLUTION: "had no closed-form solution within tol",
    Status.LOCAL_MINIMUM: "stopped at a small step with a large residual",
    Status.WRONG_ASSEMBLY: "converged on another assembly",
    Status.OUT_OF_DOMAIN: "converged outside the mechanism's domain",
    Status.WRONG_ANSWER: "had a small residual but ik(x) missed the joints by more than joint_tol",
    Status.BAD_INPUT: "had non-finite joints or start",
    Status.UNREACHABLE: "had joints that cannot be assembled",
}


def inf_norm(r: Array) -> Array:
    """Inf-norm over the last axis (NaN where any entry is NaN)."""
    return np.max(np.abs(r), axis=-1, initial=0.0)


def summarize(status: NDArray[np.integer], maxiter: int | None = None) -> str:
    """``"converged"``, or how many poses failed and why, e.g.
    ``"3 of 1000 poses did not converge within maxiter=50"``."""
    failed = status[status < 0]
    if failed.size == 0:
        return "converged"
    head = f"{failed.size} of {status.size} pose{'s' if status.size != 1 else ''} did not converge"
    codes, counts = np.unique(failed, return_counts=True)
    if codes.tolist() == [Status.MAXITER]:
        return f"{head} within maxiter={maxiter}"
    why = [f"{c} {_WHY[Status(s)]}" for s, c in zip(codes, counts, strict=True)]
    return f"{head}: " + ", ".join(why).format(maxiter=maxiter)


def _to_json(a: Any) -> Any:
    """Python lists/scalars; non-finite floats become None (JSON ``null``)."""
    if a is None:
        return None
    a = np.asarray(a)
    if a.dtype.kind == "f":
        a = np.where(np.isfinite(a), a, None)
    return a.tolist()


@dataclasses.dataclass(frozen=True, eq=False)
class Conditioning:
    """How well the joints pin down an FK answer, per pose (the batch shape of the result).

    Computed at the answer ``x`` from the IK alone (:func:`conditioning`, method and threshold
    in ``docs/near_singular.md``): near a forward singularity two solutions of
    the same joints come together, and the answer returned depends on the start.
    """

    #: 2-norm condition number of ``d ik / d pose`` at ``x``, pose coordinates in box widths
    condition: Array
    #: estimated offset ``(..., n_pose)`` from ``x`` to the nearest other solution of the same
    #: joints, across the nearest fold (pose units); NaN where no fold is predicted
    neighbour: Array
    #: how far that is: the smaller of the offset as a fraction of the pose box (``max_k
    #: |neighbour_k| / width_k``) and the largest displacement of the mechanism's drawn points as
    #: a fraction of the extent of the points that move (computed where the box fraction is
    #: 1-10 %); inf where no fold is predicted
    distance: Array
    #: True where ``distance <= threshold``: near a singularity, another solution close by
    near_singular: NDArray[np.bool_]
    #: the threshold on ``distance`` (:data:`NEAR_SINGULAR`)
    threshold: float

    @property
    def message(self) -> str:
        """``""``, or one line: how many answers are near a singularity, the closest neighbour."""
        near = np.asarray(self.near_singular)
        if not near.any():
            return ""
        closest = float(np.min(np.asarray(self.distance)[near]))
        count = f"{int(near.sum())} of {near.size} poses" if near.size > 1 else "the pose"
        return (
            f"near a singularity ({count}): another solution of the same joints within "
            f"{closest:.2g} of the pose box (threshold {self.threshold:g}); the start decides "
            "which one is returned"
        )


@dataclasses.dataclass(frozen=True, eq=False)
class FKResult:
    """Forward-kinematics solution of a (batch of) joint vector(s).

    Per-pose fields have the batch shape ``(...)`` of the call (0-d arrays for a single joint
    vector); ``x`` has shape ``(..., n_pose)``.
    """

    x: Array  #: solution (the last finite iterate where a pose failed)
    success: NDArray[np.bool_]  #: True where the pose met its stopping criterion
    status: NDArray[np.int64]  #: :class:`Status` code per pose
    nit: NDArray[np.int64]  #: iterations per pose (0 for a pose that starts converged)
    nfev: NDArray[np.int64]  #: residual evaluations per pose (including the one at x0)
    njev: NDArray[np.int64]  #: Jacobian evaluations per pose
    residual: Array  #: inf-norm of the final residual per pose
    wall_time: float  #: seconds for the whole call
    method: str  #: the method's registered name
    message: str  #: "converged" or a summary of the failures
    #: ``max_k |ik(x)_k - joints_k|`` per pose (inf where x is outside the IK's domain); set by
    #: :func:`parakin.solvers.solve_fk` (None from a method called directly)
    joint_error: Array | None = None
    #: seconds of ``wall_time`` spent loading or compiling compiled code (the first call of a
    #: compiled solver in a process: seconds to a minute on an empty kernel cache); the rest is
    #: the solve. Set by :func:`parakin.solvers.solve_fk`
    startup: float = 0.0

    @property
    def shape(self) -> tuple[int, ...]:
        """The batch shape (``()`` for a single joint vector)."""
        return self.success.shape

    def reshape(self, shape: tuple[int, ...]) -> FKResult:
        """The same result with per-pose fields reshaped to batch shape ``shape``."""
        per_pose = {
            f: getattr(self, f).reshape(shape)
            for f in ("success", "status", "nit", "nfev", "njev", "residual")
        }
        if self.joint_error is not None:
            per_pose["joint_error"] = self.joint_error.reshape(shape)
        out = dataclasses.replace(self, x=self.x.reshape(*shape, self.x.shape[-1]), **per_pose)
        mech = self.__dict__.get("_mech")
        return out if mech is None else out.bind(mech)

    def bind(self, mech: Mechanism) -> FKResult:
        """This result, with the mechanism it solved remembered for :attr:`conditioning` (what
        :func:`parakin.solvers.solve_fk` does; nothing is computed until it is asked for, and the
        frozen fields are untouched)."""
        self.__dict__["_mech"] = mech
        return self

    @functools.cached_property
    def conditioning(self) -> Conditioning | None:
        """The :class:`Conditioning` at the answer (:func:`conditioning`), computed on first use (a
        few IK evaluations per pose, so a solve never pays for it unasked); None for a result
        that :func:`~parakin.solvers.solve_fk` did not make."""
        mech = self.__dict__.get("_mech")
        return None if mech is None else conditioning(mech, self.x)

    @property
    def near_singular(self) -> NDArray[np.bool_] | None:
        """Per pose: near a singularity, another solution of the same joints close by (see
        :attr:`conditioning`); None where the conditioning is unknown."""
        c = self.conditioning
        return None if c is None else c.near_singular

    def to_dict(self) -> dict[str, Any]:
        """Every field as JSON-serialisable python lists/scalars (non-finite floats -> None)."""
        return {
            f.name: _to_json(getattr(self, f.name))
            if isinstance(getattr(self, f.name), np.ndarray) or getattr(self, f.name) is None
            else getattr(self, f.name)
            for f in dataclasses.fields(self)
        }

    def __repr__(self) -> str:
        n = self.success.size
        if self.shape == ():
            x = np.array2string(self.x, precision=6)
            what = f"x={x}, success={bool(self.success)}, nit={int(self.nit)}"
        else:
            nit = int(self.nit.max(initial=0))
            what = f"shape={self.shape}, success={int(self.success.sum())}/{n}, nit<={nit}"
        res = float(self.residual.max(initial=0.0)) if n else 0.0
        return (
            f"FKResult(method={self.method!r}, {what}, residual<={res:.2e}, "
            f"wall_time={self.wall_time:.3g} s, message={self.message!r})"
        )


# ---------------------------------------------------------------------------- the shared loop
class StepInfo(NamedTuple):
    """What one solver step reports besides the new state, per stepped pose."""

    step: Array  #: inf-norm of the step taken (or attempted), tested against xtol
    grad: Array | None = None  #: inf-norm of the gradient at the new iterate, tested against gtol
    stalled: NDArray[np.bool_] | None = None  #: True where no acceptable step was found


class Evaluator:
    """``mech.residual`` and ``mech.jacobian_pose`` on a subset ``rows`` of a flat batch.

    Counts evaluations per pose in ``nfev`` / ``njev``. Rows whose pose is not finite are not
    evaluated (the mechanism would reject them) and come back as NaN.
    """

    def __init__(self, mech: Mechanism, joints: Array) -> None:
        self.mech, self.joints = mech, joints
        self.nfev = np.zeros(len(joints), dtype=np.int64)
        self.njev = np.zeros(len(joints), dtype=np.int64)

    def residual(self, x: Array, rows: NDArray[np.intp]) -> Array:
        """Residuals ``(len(rows), m)`` of poses ``x`` against the joints of ``rows``."""
        return self._call(self.mech.residual, self.nfev, x, rows, (self.joints.shape[-1],))

    def jacobian(self, x: Array, rows: NDArray[np.intp]) -> Array:
        """``d residual / d pose`` ``(len(rows), m, n)`` at ``x``."""
        return self._call(
            self.mech.jacobian_pose, self.njev, x, rows, (self.joints.shape[-1], x.shape[-1])
        )

    def _call(
        self,
        f: Callable,
        counter: NDArray[np.int64],
        x: Array,
        rows: NDArray[np.intp],
        tail: tuple[int, ...],
    ) -> Array:
        ok = np.all(np.isfinite(x), axis=-1)
        if ok.all() and ok.size:
            counter[rows] += 1
            # every row running (rows = 0..N-1): the joints as they are, no gather
            q = self.joints if len(rows) == len(self.joints) else self.joints[rows]
            try:
                return np.asarray(f(x, q), dtype=float)
            except ROW_ERRORS:  # one row left the mechanism's domain: isolate it, NaN there
                return rowwise(f, x, q, tail=tail)
        out = np.full((len(rows), *tail), np.nan)
        if ok.any():
            counter[rows[ok]] += 1
            out[ok] = rowwise(f, x[ok], self.joints[rows[ok]], tail=tail)
        return out


State = dict[str, Array]
Init = Callable[[Evaluator, NDArray[np.intp], State], State]
Step = Callable[[Evaluator, NDArray[np.intp], State], tuple[State, StepInfo]]


def _take(state: State, rows: NDArray[Any]) -> State:
    return {k: v[rows] for k, v in state.items()}


def _put(state: State, rows: NDArray[np.intp], sub: State) -> None:
    """Write ``sub`` into rows ``rows`` of ``state``, allocating keys it does not have yet."""
    size = len(state["x"])
    for k, v in sub.items():
        if k not in state:
            state[k] = np.zeros((size, *v.shape[1:]), dtype=v.dtype)
        state[k][rows] = v


def iterate(
    mech: Mechanism,
    joints: Array,
    x0: Array,
    *,
    step: Step,
    init: Init | None = None,
    tol: float,
    maxiter: int,
    xtol: float = 0.0,
    gtol: float = 0.0,
    callback: Callable[[int, Array, Array], Any] | None = None,
    method: str = "",
) -> FKResult:
    """Run ``step`` on the flat batch (``joints (N, m)``, ``x0 (N, n)``) until every pose stops.

    ``state`` is a dict of per-pose arrays with at least ``"x"`` (iterate) and ``"r"`` (its
    residual); ``init(ev, rows, state_rows)`` returns extra keys for the poses that do not start
    converged, ``step(ev, rows, state_rows)`` returns the next state of ``rows`` and a
    :class:`StepInfo`. One call of ``step`` is one iteration of each pose in ``rows``.
    ``callback(k, x, residual_norm)``, if given, sees the whole batch after iteration ``k``
    (``k = 0``: the start).
    """
    start = time.perf_counter()
    ev = Evaluator(mech, joints)
    nit = np.zeros(len(x0), dtype=np.int64)
    with np.errstate(all="ignore"):  # non-finite values are detected below, never warned about
        state: State = {"x": np.array(x0, dtype=float), "r": ev.residual(x0, np.arange(len(x0)))}
        res = inf_norm(state["r"])
        status = np.where(res <= tol, Status.CONVERGED, _RUNNING).astype(np.int64)
        status[~np.isfinite(res)] = Status.NONFINITE
        rows = np.flatnonzero(status == _RUNNING)
        if init is not None and rows.size:
            _put(state, rows, init(ev, rows, _take(state, rows)))
        if callback is not None:
            callback(0, state["x"].copy(), res.copy())
        for k in range(1, maxiter + 1):
            rows = np.flatnonzero(status == _RUNNING)
            if rows.size == 0:
                break
            new, info = step(ev, rows, _take(state, rows))
            nit[rows] += 1
            new_res = inf_norm(new["r"])
            finite = np.all(np.isfinite(new["x"]), axis=-1) & np.isfinite(new_res)
            code = np.full(rows.size, _RUNNING, dtype=np.int64)
            if xtol > 0:
                code[info.step <= xtol] = Status.SMALL_STEP
            if gtol > 0 and info.grad is not None:
                code[info.grad <= gtol] = Status.SMALL_GRADIENT
            if info.stalled is not None:
                code[info.stalled] = Status.STALLED
            code[new_res <= tol] = Status.CONVERGED
            code[~finite] = Status.NONFINITE  # keeps its last finite iterate: not written back
            if finite.all():  # the usual case: write the whole step back, no masking
                _put(state, rows, new)
                res[rows] = new_res
            else:
                _put(state, rows[finite], _take(new, finite))
                res[rows[finite]] = new_res[finite]
            status[rows] = code
            if callback is not None:
                callback(k, state["x"].copy(), res.copy())
    status[status == _RUNNING] = Status.MAXITER
    return FKResult(
        x=state["x"],
        success=status >= 0,
        status=status,
        nit=nit,
        nfev=ev.nfev,
        njev=ev.njev,
        residual=res,
        wall_time=time.perf_counter() - start,
        method=method,
        message=summarize(status, maxiter),
    )


Callback = Callable[[int, Array, Array], Any]


class Plan(NamedTuple):
    """An iterative method's own part of :func:`iterate`: its ``step`` and, if any, its ``init``."""

    step: Step
    init: Init | None = None


def iterative(method: str) -> Callable[[Callable[..., Plan]], Callable[..., FKResult]]:
    """Decorator: the FK method named ``method`` (``FKResult.method``) from the declaration of its
    options, ``plan(*, <options>) -> Plan``.

    ``plan`` declares the options (keyword-only names, defaults and order, and the docstring),
    checks their values and returns the method's ``init`` and ``step``. The method is
    ``fn(mech, joints, x0, *, tol, maxiter, <options>, callback=None) -> FKResult``, the
    registered-method protocol (:mod:`parakin.solvers.registry`), under ``plan``'s name: it runs
    the plan in :func:`iterate`, with the options ``xtol`` and ``gtol``, where declared, as the
    loop's stopping tests.
    """

    def make(plan: Callable[..., Plan]) -> Callable[..., FKResult]:
        options = inspect.signature(plan).parameters
        stops = {k: options[k].default for k in ("xtol", "gtol") if k in options}

        def solver(
            mech: Mechanism,
            joints: Array,
            x0: Array,
            *,
            tol: float,
            maxiter: int,
            callback: Callback | None = None,
            **chosen: Any,
        ) -> FKResult:
            step, init = plan(**chosen)
            loop = {k: chosen.get(k, default) for k, default in stops.items()}
            return iterate(
                mech,
                joints,
                x0,
                step=step,
                init=init,
                tol=tol,
                maxiter=maxiter,
                callback=callback,
                method=method,
                **loop,
            )

        own = inspect.signature(solver)
        functools.update_wrapper(solver, plan)  # name (also in argument errors), docstring
        # its annotations are names of this module (typing.get_type_hints reads the globals of
        # the function __wrapped__ points to; the signature is set below)
        del solver.__wrapped__
        head, tail = list(own.parameters.values())[:5], own.parameters["callback"]
        signature = own.replace(parameters=[*head, *options.values(), tail])
        solver.__signature__ = signature  # type: ignore[attr-defined]
        solver.__annotations__ = {
            **{k: p.annotation for k, p in signature.parameters.items()},
            "return": signature.return_annotation,
        }
        return solver

    return make


# ------------------------------------------------------------ conditioning at the answer
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

    How near is near, relative to the mechanism and not to one set of coordinates: ``distance``
    is the smaller of (1) the offset as a fraction of the pose box, ``max_k |offset_k| /
    width_k``, and (2) how far the mechanism's drawn points (:meth:`Mechanism.skeleton`) move from
    ``x`` to ``x + offset``, as a fraction of the extent of the points that move (the platform
    and the legs, in metres: no coordinate chart, no box). Both are scale-free, and
    ``near_singular`` is ``distance <= NEAR_SINGULAR`` (1%) on either. (2) is what sees a
    neighbour across a chart's own singularity: at Z-Y-X Euler angles near gimbal lock (beta near
    pi/2) a rotation of 0.012 rad is an offset of 0.07 rad in alpha and gamma, 1.1% of their box,
    which (1) alone let pass. (2) is computed where (1) is between 1% and 10% (a few skeleton
    drawings per such answer, none elsewhere), so what (1) flags is flagged as before.
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
    look = np.flatnonzero((distance > NEAR_SINGULAR) & (distance <= 10 * NEAR_SINGULAR))
    distance = np.minimum(distance, _points_moved(mech, flat, offset, look))
    return Conditioning(
        condition=condition.reshape(shape),
        neighbour=offset.reshape(*shape, n),
        distance=distance.reshape(shape),
        near_singular=(distance <= NEAR_SINGULAR).reshape(shape),
        threshold=NEAR_SINGULAR,
    )


def _points_moved(mech: Mechanism, x: Array, offset: Array, rows: Array) -> Array:
    """Per row of ``x (N, n)``: the largest displacement of the mechanism's drawn points from
    ``x`` to ``x + offset``, as a fraction of the extent (bounding-box diagonal) of the points
    that move; inf where not computed (rows not in ``rows``, a mechanism that draws nothing, a
    pose it cannot draw, fewer than two moving points)."""
    out = np.full(len(x), np.inf)
    for i in rows:
        try:
            with np.errstate(all="ignore"):
                a, b = (
                    np.array(list(mech.skeleton(p).points.values()), dtype=float).reshape(-1, 3)
                    for p in (x[i], x[i] + offset[i])
                )
        except (NotImplementedError, ParakinError, ArithmeticError, ValueError, TypeError):
            continue
        step = np.linalg.norm(b - a, axis=-1)
        moving = step > 1e-12 * (1.0 + np.max(np.abs(a), initial=0.0))
        if moving.sum() >= 2 and np.all(np.isfinite(step)):
            extent = float(np.linalg.norm(np.ptp(a[moving], axis=0)))
            if extent > 0:
                out[i] = float(np.max(step)) / extent
    return out


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
