"""Particle swarm optimisation (Kennedy & Eberhart 1995; inertia weight of Shi & Eberhart 1998) as a
forward-kinematics solver for any mechanism.

One swarm per pose of the flat batch: all swarms advance together, vectorised over the particles
*and* over the independent runs (rows), so 20 seeds x 5 inputs is one array computation. Each row
draws its random numbers from its own ``numpy.random.Generator`` seeded by ``seed[row]``, in
fixed-size blocks, so that a run gives the same result alone or inside any batch (reproducible per
seed).

Update per particle (standard global-best PSO)::

    v <- w_k v + c1 r1 (pbest - x) + c2 r2 (gbest - x),   r1, r2 ~ U(0, 1) per component
    v <- clip(v, -vmax, vmax)            (only if ``vclamp`` is given: vmax = vclamp * box range)
    x <- clip(x + v, lower, upper)       (positions are kept inside the search box)

Fitness: by default Li 2020's eq. (20), ``F = sum_j |f_j|`` with ``f = mech.residual`` (in the
residual's units, metres for the papers' mechanisms, so the paper's ``F < 1e-6 mm`` is
``ftol = 1e-9``); any ``fitness(x, joints) -> (runs, particles)`` replaces it.

Inertia weight ``w_k``: ``"constant"`` (``w``; Table 1 of Li 2020 read as printed), ``"linear"``
(``w`` -> ``w_end`` linearly over ``maxiter`` iterations: Shi & Eberhart's "improved" PSO), or any
callable ``schedule(k, maxiter, rows) -> float | array (len(rows),)`` (``k = 1 .. maxiter``,
``rows`` the indices of the runs still going), e.g. :class:`ChaoticLogistic` for a chaotic
logistic-map weight.

Registered as FK method ``"pso"``; :func:`pso` returns a :class:`PSOResult`, an
:class:`~parakin.solvers.result.FKResult` with the best-fitness history per iteration.
"""

from __future__ import annotations

import dataclasses
import time
from collections.abc import Callable
from typing import Any

import numpy as np
from numpy.typing import ArrayLike, NDArray

from parakin.mechanisms.base import Array, Mechanism
from parakin.solvers.result import FKResult, Status, inf_norm, rowwise, summarize

__all__ = [
    "pso",
    "PSOResult",
    "ChaoticLogistic",
    "linear_inertia",
    "inertia_schedule",
    "check_size",
    "MEMORY_LIMIT",
]

Schedule = Callable[[int, int, NDArray[np.intp]], "float | Array"]
Fitness = Callable[[Array, Array], Array]

_BLOCK = (
    64  # iterations of random numbers drawn per generator call (fixed: part of reproducibility)
)
#: most bytes the swarms of one call may hold (positions, velocities, bests, random block, history)
MEMORY_LIMIT = 2 * 1024**3


def _positive_integer(value: Any) -> bool:
    try:
        return not isinstance(value, bool) and float(value).is_integer() and value >= 1
    except (TypeError, ValueError, OverflowError):
        return False


def memory_needed(runs: int, swarm: int, maxiter: int, n: int) -> int:
    """Bytes :func:`pso` allocates for ``runs`` swarms of ``swarm`` particles in ``n`` dimensions."""
    return 8 * (runs * swarm * n * (4 + 2 * _BLOCK) + runs * (maxiter + 1) + (maxiter + 1))


def check_size(runs: int, swarm: int, maxiter: int, n: int) -> None:
    """ValueError naming the values and the limit where one call would need more than
    :data:`MEMORY_LIMIT` bytes."""
    need = memory_needed(runs, swarm, maxiter, n)
    if need > MEMORY_LIMIT:
        raise ValueError(
            f"pso with {runs} run(s) x swarm = {swarm} particles x maxiter = {maxiter} needs "
            f"{need / 1024**3:.3g} GiB, more than the limit of {MEMORY_LIMIT / 1024**3:g} GiB: "
            "use fewer particles, iterations or rows per call"
        )


@dataclasses.dataclass(frozen=True, eq=False)
class PSOResult(FKResult):
    """:class:`FKResult` plus the swarm's record."""

    fitness: Array = dataclasses.field(default_factory=lambda: np.zeros(0))  #: best fitness per run
    history: Array = dataclasses.field(
        default_factory=lambda: np.zeros((0, 1))
    )  #: (..., maxiter + 1)
    inertia: Array = dataclasses.field(
        default_factory=lambda: np.zeros(0)
    )  #: w_k used, (maxiter + 1,) (k = 0: NaN)

    def reshape(self, shape: tuple[int, ...]) -> PSOResult:
        base = super().reshape(shape)
        return dataclasses.replace(
            base,
            fitness=self.fitness.reshape(shape),
            history=self.history.reshape(*shape, self.history.shape[-1]),
        )


def linear_inertia(w_start: float, w_end: float) -> Schedule:
    """``w_k = w_start - (w_start - w_end) k / maxiter`` (Shi & Eberhart 1998)."""

    def schedule(k: int, maxiter: int, rows: NDArray[np.intp]) -> float:
        return w_start - (w_start - w_end) * k / max(maxiter, 1)

    return schedule


class ChaoticLogistic:
    """A chaotic inertia weight: the logistic map ``z <- mu z (1 - z)`` (one ``z`` per run) turned
    into ``w_k`` by ``combine(z, k, maxiter)``.

    Default ``combine`` (Feng et al.'s chaotic descending weight):
    ``w_k = (w_start - w_end) (maxiter - k) / maxiter + w_end * z_k``. Pass another
    ``combine(z, k, maxiter) -> w`` to plug in a paper's own formula. Stateful: use a new instance
    per solve (``z0`` may be a scalar or one value per run).
    """

    def __init__(
        self,
        w_start: float = 0.9,
        w_end: float = 0.4,
        z0: float | ArrayLike = 0.37,
        mu: float = 4.0,
        combine: Callable[[Array, int, int], Array] | None = None,
    ) -> None:
        self.w_start, self.w_end, self.mu = w_start, w_end, mu
        self.z0 = np.asarray(z0, dtype=float)
        if np.any((self.z0 <= 0) | (self.z0 >= 1)) or np.any(np.isin(self.z0, [0.25, 0.5, 0.75])):
            raise ValueError(
                f"z0 = {z0!r} must lie in (0, 1) and avoid the map's fixed/periodic points"
            )
        self.combine = combine or (
            lambda z, k, K: (self.w_start - self.w_end) * (K - k) / K + self.w_end * z
        )
        self._z: Array | None = None

    def __call__(self, k: int, maxiter: int, rows: NDArray[np.intp]) -> Array:
        if self._z is None or k == 1:
            n = int(rows.max(initial=-1)) + 1
            self._z = np.broadcast_to(self.z0, (max(n, self.z0.size),)).copy()
        self._z = self.mu * self._z * (1 - self._z)
        return np.asarray(self.combine(self._z, k, maxiter), dtype=float)[rows]


def inertia_schedule(inertia: str | Schedule, w: float, w_end: float) -> Schedule:
    """The schedule named by ``inertia`` ("constant", "linear") or ``inertia`` itself if callable."""
    if callable(inertia):
        return inertia
    if inertia == "constant":
        return lambda k, maxiter, rows: w
    if inertia == "linear":
        return linear_inertia(w, w_end)
    raise ValueError(
        f"inertia = {inertia!r} must be 'constant', 'linear' or a callable schedule(k, maxiter, rows)"
    )


def _eq20(mech: Mechanism) -> Fitness:
    def fitness(x: Array, joints: Array) -> Array:
        q = np.broadcast_to(joints[:, None, :], x.shape[:-1] + (joints.shape[-1],))
        return np.sum(np.abs(mech.residual(x, q)), axis=-1)

    return fitness


def pso(
    mech: Mechanism,
    joints: Array,
    x0: Array,
    *,
    tol: float,
    maxiter: int,
    swarm: int = 40,
    c1: float = 2.0,
    c2: float = 2.0,
    inertia: str | Schedule = "constant",
    w: float = 0.9,
    w_end: float = 0.4,
    bounds: tuple[ArrayLike, ArrayLike] | None = None,
    vclamp: float | None = None,
    fitness: Fitness | None = None,
    ftol: float | None = None,
    seed: int | ArrayLike = 0,
    include_x0: bool = False,
    callback: Callable[[int, Array, Array], Any] | None = None,
    **options: Any,
) -> PSOResult:
    """PSO forward kinematics of the flat batch ``joints (N, m)`` (one swarm per row).

    ``swarm`` particles per run, at most ``maxiter`` iterations; ``c1``, ``c2`` learning factors;
    ``inertia``/``w``/``w_end`` the inertia weight (see module docstring); ``bounds`` the search
    box (default ``mech.pose_bounds()``); initial positions uniform in the box, velocities zero
    (with ``include_x0`` particle 0 starts at ``x0``). ``vclamp``: velocity limit as a fraction of
    the box range per component (None: no clamp). A run stops when its best fitness is
    ``<= ftol`` (default ``tol``); ``success`` means exactly that. ``seed``: one int, or one per
    row (shape ``(N,)``): row ``i`` uses ``numpy.random.default_rng(seed[i])``.

    ``residual`` of the result is the inf-norm of the mechanism residual at the best position;
    ``nfev`` counts fitness evaluations (particles x iterations); ``nit`` the iterations run.
    """
    if options:
        raise TypeError(f"pso() got unexpected options {sorted(options)}")
    start = time.perf_counter()
    n_runs, n = x0.shape
    if not _positive_integer(swarm):
        raise ValueError(f"swarm = {swarm!r} must be a positive integer")
    swarm = int(swarm)
    check_size(n_runs, swarm, maxiter, n)
    lo, hi = _search_box(mech, bounds, n)
    flight = _Flight(
        schedule=inertia_schedule(inertia, w, w_end),
        maxiter=maxiter,
        lo=lo,
        hi=hi,
        vmax=None if vclamp is None else float(vclamp) * (hi - lo),
        c1=c1,
        c2=c2,
        ftol=tol if ftol is None else ftol,
    )
    fit = fitness or _eq20(mech)
    gens = _generators(seed, n_runs)
    sw = _initial_swarm(fit, joints, x0, gens, flight, swarm, include_x0)
    if callback is not None:
        callback(0, sw.gbest.copy(), sw.gf.copy())
    fast = (
        None
        if callback is not None or fitness is not None
        else _compiled(mech, inertia, sw.x, joints)
    )
    if fast is not None:  # the same iterations, compiled (parakin.kernels: pso_row)
        kernel, loops = fast
        _compiled_loop(kernel, loops, joints, sw, gens, flight)
    else:
        _numpy_loop(fit, joints, sw, gens, flight, callback)
    return _result(mech, joints, sw, flight, time.perf_counter() - start)


@dataclasses.dataclass(frozen=True)
class _Flight:
    """The fixed rules of one :func:`pso` call: inertia schedule, iteration cap, search box
    ``[lo, hi]``, velocity limit, learning factors and the fitness that stops a run."""

    schedule: Schedule
    maxiter: int
    lo: Array
    hi: Array
    vmax: Array | None
    c1: float
    c2: float
    ftol: float


@dataclasses.dataclass(eq=False)
class _Swarm:
    """The state of :func:`pso`'s runs, updated in place: positions ``x`` and velocities ``v``
    (R, P, n), personal bests ``pbest``/``pf``, global bests ``gbest``/``gf``, counters, the best
    fitness per iteration ``history``, the mean inertia weight per iteration ``weights`` and which
    runs are still ``running``."""

    x: Array
    v: Array
    pbest: Array
    pf: Array
    gbest: Array
    gf: Array
    nfev: NDArray[np.int64]
    nit: NDArray[np.int64]
    history: Array
    weights: Array
    running: NDArray[np.bool_]


def _search_box(
    mech: Mechanism, bounds: tuple[ArrayLike, ArrayLike] | None, n: int
) -> tuple[Array, Array]:
    """The search box ``(lo, hi)``: ``bounds``, default the mechanism's pose bounds; checked."""
    lo, hi = (
        np.asarray(b, dtype=float) for b in (bounds if bounds is not None else mech.pose_bounds())
    )
    if lo.shape != (n,) or hi.shape != (n,) or np.any(hi <= lo):
        raise ValueError(
            f"bounds must be two arrays of {n} values with lower < upper, got {lo}, {hi}"
        )
    return lo, hi


def _generators(seed: int | ArrayLike, n_runs: int) -> list[np.random.Generator]:
    """One ``numpy.random.default_rng`` per run from ``seed`` (one int, or one per run)."""
    seeds = np.asarray(seed)
    if seeds.ndim == 0:
        seeds = np.full(n_runs, int(seeds))
    seeds = seeds.reshape(-1)
    if seeds.size != n_runs:
        raise ValueError(f"seed must be one int or one per run ({n_runs}), got {seeds.size}")
    return [np.random.default_rng(int(s)) for s in seeds]


def _fitness_of(fit: Fitness, x: Array, joints: Array) -> Array:
    """The fitness of positions ``x`` (R, P, n) for the rows ``joints``; inf where not finite."""
    with np.errstate(all="ignore"):
        f = rowwise(fit, x, joints, tail=(len(x[0]),), fill=np.inf)
    return np.where(np.isfinite(f), f, np.inf)


def _initial_swarm(
    fit: Fitness,
    joints: Array,
    x0: Array,
    gens: list[np.random.Generator],
    flight: _Flight,
    swarm: int,
    include_x0: bool,
) -> _Swarm:
    """The swarm at iteration 0: positions from the first draw of each generator (particle 0 at
    ``x0`` with ``include_x0``), velocities zero, bests from the first fitness evaluation."""
    n_runs, n = x0.shape
    lo, hi = flight.lo, flight.hi
    x = np.stack([g.uniform(lo, hi, size=(swarm, n)) for g in gens])  # (R, P, n)
    if include_x0:
        x[:, 0, :] = np.clip(x0, lo, hi)
    f = _fitness_of(fit, x, joints)
    pbest, pf = x.copy(), f.copy()
    gi = np.argmin(pf, axis=1)
    gf = pf[np.arange(n_runs), gi].copy()
    history = np.empty((n_runs, flight.maxiter + 1))
    history[:, 0] = gf
    return _Swarm(
        x=x,
        v=np.zeros_like(x),
        pbest=pbest,
        pf=pf,
        gbest=pbest[np.arange(n_runs), gi].copy(),
        gf=gf,
        nfev=np.full(n_runs, swarm, dtype=np.int64),
        nit=np.zeros(n_runs, dtype=np.int64),
        history=history,
        weights=np.full(flight.maxiter + 1, np.nan),
        running=gf > flight.ftol,
    )


def _numpy_loop(
    fit: Fitness,
    joints: Array,
    sw: _Swarm,
    gens: list[np.random.Generator],
    fl: _Flight,
    callback: Callable[[int, Array, Array], Any] | None,
) -> None:
    """The iterations of :func:`pso` in numpy, on the runs still going; updates ``sw`` in place.
    Random numbers are drawn :data:`_BLOCK` iterations at a time per running run."""
    n_runs, swarm, n = sw.x.shape
    rand = np.empty((n_runs, _BLOCK, 2, swarm, n))
    for k in range(1, fl.maxiter + 1):
        rows = np.flatnonzero(sw.running)
        if rows.size == 0:
            sw.history[:, k:] = sw.gf[:, None]
            break
        slot = (k - 1) % _BLOCK
        if slot == 0:
            for i in rows:
                rand[i] = gens[i].random((_BLOCK, 2, swarm, n))
        wk = fl.schedule(k, fl.maxiter, rows)
        sw.weights[k] = float(np.mean(wk))
        wk = np.asarray(wk, dtype=float)
        wk = wk[:, None, None] if wk.ndim == 1 else wk
        idx = slice(None) if rows.size == n_runs else rows
        _move(fit, joints, sw, idx, rand[idx, slot], wk, fl)
        sw.nfev[idx] += swarm
        sw.nit[idx] += 1
        sw.history[:, k] = sw.gf
        sw.running[idx] = sw.gf[idx] > fl.ftol
        if callback is not None:
            callback(k, sw.gbest.copy(), sw.gf.copy())


def _move(
    fit: Fitness,
    joints: Array,
    sw: _Swarm,
    idx: slice | NDArray[np.intp],
    r: Array,
    wk: Array,
    fl: _Flight,
) -> None:
    """One PSO step of the runs ``idx`` with random numbers ``r`` and inertia ``wk``: new
    velocities and positions, then personal and global bests; updates ``sw`` in place."""
    x, v, pbest, pf, gbest = sw.x, sw.v, sw.pbest, sw.pf, sw.gbest
    xr, vr, pr = x[idx], v[idx], pbest[idx]
    vr = wk * vr + fl.c1 * r[:, 0] * (pr - xr) + fl.c2 * r[:, 1] * (gbest[idx][:, None, :] - xr)
    if fl.vmax is not None:
        vr = np.clip(vr, -fl.vmax, fl.vmax)
    xr = np.clip(xr + vr, fl.lo, fl.hi)
    fr = _fitness_of(fit, xr, joints[idx])
    better = fr < pf[idx]
    pr = np.where(better[..., None], xr, pr)
    pfr = np.where(better, fr, pf[idx])
    gi = np.argmin(pfr, axis=1)
    sel = np.arange(len(pfr))
    x[idx], v[idx], pbest[idx], pf[idx] = xr, vr, pr, pfr
    gbest[idx] = pr[sel, gi]
    sw.gf[idx] = pfr[sel, gi]


def _result(mech: Mechanism, joints: Array, sw: _Swarm, fl: _Flight, wall: float) -> PSOResult:
    """The :class:`PSOResult` of a finished swarm."""
    n_runs = len(sw.gbest)
    res = inf_norm(rowwise(mech.residual, sw.gbest, joints, tail=(joints.shape[-1],)))
    status = np.where(sw.gf <= fl.ftol, Status.CONVERGED, Status.MAXITER).astype(np.int64)
    return PSOResult(
        x=sw.gbest,
        success=status >= 0,
        status=status,
        nit=sw.nit,
        nfev=sw.nfev,
        njev=np.zeros(n_runs, dtype=np.int64),
        residual=res,
        wall_time=wall,
        method="pso",
        message=summarize(status, fl.maxiter),
        fitness=sw.gf,
        history=sw.history,
        inertia=sw.weights,
    )


def _compiled(mech: Mechanism, inertia: Any, x: Array, joints: Array):
    """``(kernel, entries)`` where the compiled PSO loop applies: a mechanism with kernels, the
    default fitness (eq. 20), no callback, and a schedule whose weights do not depend on which
    runs are still going ("constant", "linear", :class:`ChaoticLogistic`); else None."""
    if not (isinstance(inertia, ChaoticLogistic) or inertia in ("constant", "linear")):
        return None
    from parakin.kernels import entries_of, kernel_of

    kernel = kernel_of(mech)
    if kernel is None or kernel.n_pose != x.shape[-1] or kernel.n_joints != joints.shape[-1]:
        return None
    return kernel, entries_of(kernel.module, "pso")


#: the arguments of ``pso_serial`` that hold one row per run (the rest are shared)
_PSO_RUN_ARGS = (1, 2, 3, 4, 5, 6, 7, 8, 9, 15, 16)


def _compiled_loop(
    kernel, loops, joints: Array, sw: _Swarm, gens: list[np.random.Generator], fl: _Flight
) -> None:
    """The iterations of :func:`pso` by ``loops.pso_serial``, block by block of :data:`_BLOCK`
    iterations: the random numbers are drawn here exactly as in the numpy loop (one block per
    running run at iterations 1, 1 + _BLOCK, ...), the weights of a block asked of the schedule for
    every run, then every run advances independently (in parallel). Fills the arrays in place."""
    x, v, pbest, pf, gbest, gf = sw.x, sw.v, sw.pbest, sw.pf, sw.gbest, sw.gf
    history, weights, running = sw.history, sw.weights, sw.running
    schedule, maxiter, lo, hi, vmax = fl.schedule, fl.maxiter, fl.lo, fl.hi, fl.vmax
    c1, c2, ftol = fl.c1, fl.c2, fl.ftol
    n_runs, swarm, n = x.shape
    state = np.zeros((n_runs, 3), dtype=np.int64)  # running, fitness evaluations, iterations
    state[:, 0] = running
    q = np.ascontiguousarray(joints, dtype=float)
    best = np.ascontiguousarray(gf[:, None], dtype=float)
    rand = np.empty((n_runs, _BLOCK, 2, swarm, n))
    every = np.arange(n_runs)
    coef = np.array([c1, c2, ftol, 0.0 if vmax is None else 1.0], dtype=float)
    vm = np.zeros(n) if vmax is None else np.asarray(vmax, dtype=float)
    from parakin.kernels import threads

    k = 1
    while k <= maxiter:
        rows = np.flatnonzero(state[:, 0])
        if rows.size == 0:
            history[:, k:] = best
            break
        nk = min(_BLOCK, maxiter - k + 1)
        for i in rows:
            rand[i] = gens[i].random((_BLOCK, 2, swarm, n))
        w = np.empty((n_runs, nk))
        for s in range(nk):
            w[:, s] = np.broadcast_to(np.asarray(schedule(k + s, maxiter, every), float), n_runs)
        args = (kernel.params, q, x, v, pbest, pf, gbest, best, rand, w, k, lo, hi, vm, coef, state, history)  # fmt: skip
        # several runs: blocks of runs on every core; one run: no thread start-up
        threads.rows(loops.pso_serial, args, _PSO_RUN_ARGS, parallel=n_runs > 1)
        for s in range(nk):  # the mean weight over the runs going at each iteration
            going = history[:, k + s - 1] > ftol
            if going.any():
                weights[k + s] = float(np.mean(w[going, s]))
        k += nk
    gf[:] = best[:, 0]
    sw.nfev += state[:, 1]
    sw.nit += state[:, 2]
