"""Constants and helpers shared by the sections of the Ye et al. reproduction (12-leg cube)."""

from __future__ import annotations

import time
from dataclasses import dataclass

import numpy as np

from parakin import registry
from parakin.mechanisms.stewart12 import NESTED_PASSIVE, DriveMode, Stewart12
from parakin.solvers import solve_fk

#: the methods, key -> (generic solver, its options). "nr": the paper's N-R (eq. 30) in
#: least-squares form (Gauss-Newton; Newton on the square R = 0 system). "broyden": the paper's
#: inverse rank-one update (eqs 31-32, docs/ye_stewart12.md#s2.4) with H0 = pinv(J(X0)) for every
#: mode. "broyden_direct" (beyond the paper): the direct rank-one update of a rectangular B with
#: least-squares steps; the two Broyden forms coincide, to rounding, only for R = 0
#: (docs/ye_stewart12.md#s5.6)
METHODS_USED: dict[str, tuple[str, dict]] = {
    "nr": ("gauss-newton", {}),
    "broyden": ("broyden", {"update": "inverse"}),
    "broyden_direct": ("broyden-ls", {}),
}
#: the paper's two methods (what its numbers are judged against)
PAPER_METHODS = ("nr", "broyden")
#: how figures and tables name each method
METHOD_LABELS = {
    "nr": "N-R (Gauss-Newton)",
    "broyden": "Broyden, inverse update (the paper's)",
    "broyden_direct": "Broyden, direct update (beyond the paper)",
}

KEY = "ye_stewart12"

#: the registry's declarations with this paper's key filled in (:func:`registry.declarations`):
#: ``@artefact(name, outputs=...)``, ``@table(name, stem)``, ``@table_and_figure(name, stem, draw)``,
#: ``@drawn_figure(name, stem, draw)``
artefact, table, table_and_figure, drawn_figure = registry.declarations(KEY)
TITLE = (
    "Ye, You, Shen, Wu, Ru — Stewart-derived 12-leg cube mechanism: closed-form FK, "
    "compatibility equations, N-R vs Broyden, drive modes"
)

#: paper mode numbers (Table 6): I = R5 ... VI = R0
MODE_NAMES = {5: "I", 4: "II", 3: "III", 2: "IV", 1: "V", 0: "VI"}


@dataclass(frozen=True)
class Setup:
    """What every solver artefact reads from the ``ye_stewart12`` config section, read once."""

    c: dict  #: the config section itself (artefact-specific keys)
    mech: Stewart12  #: the configured structure (n, L, lambda convention)
    pose: np.ndarray  #: §3.3's test pose (SI)
    sets: dict[int, tuple[int, ...]]  #: passive legs per redundancy R
    tol_mm: float  #: stopping tolerance |dX|_2 < tol (mm)
    maxiter: int

    @property
    def tol_m(self) -> float:
        return self.tol_mm * 1e-3


def setup(config: dict) -> Setup:
    """The shared set-up of the solver artefacts (:class:`Setup`) from ``config``."""
    c = config[KEY]
    return Setup(
        c=c,
        mech=mech(config),
        pose=test_pose(config),
        sets=passive_sets(config),
        tol_mm=float(c["tol"]),
        maxiter=int(c["maxiter"]),
    )


def mech(config: dict, n_mm: float | None = None, L_mm: float | None = None) -> Stewart12:
    """The mechanism of the configured geometry (paper: n = 15, L = 25 mm) and lambda convention."""
    c = config[KEY]
    return Stewart12(
        n=(c["n_mm"] if n_mm is None else n_mm) * 1e-3,
        L=(c["L_mm"] if L_mm is None else L_mm) * 1e-3,
        convention=c["convention"],
    )


def test_pose(config: dict) -> np.ndarray:
    """§3.3's pose (x0 = 0.5 mm, lambda = (-0.05, 0.05, 0.05)) in SI."""
    p = np.asarray(config[KEY]["test_pose"], dtype=float)
    return np.concatenate([p[:3] * 1e-3, p[3:]])


def passive_sets(config: dict) -> dict[int, tuple[int, ...]]:
    """Passive legs per redundancy R (config ``passive_sets``; default the nested sets of docs/ye_stewart12.md#s5.5)."""
    sets = config[KEY].get("passive_sets") or {}
    return {r: tuple(sets.get(r, sets.get(str(r), NESTED_PASSIVE[r]))) for r in range(6)}


def passive_caption(config: dict) -> str:
    return caption_of(passive_sets(config))


def caption_of(sets: dict[int, tuple[int, ...]]) -> str:
    """ "passive legs R=5: {...}, ..., R=0: {...}" of passive sets per redundancy R."""
    return "passive legs " + ", ".join(
        f"R={r}: {{{','.join(map(str, sets[r]))}}}" for r in range(5, -1, -1)
    )


def run_mode(
    m: Stewart12,
    passive: tuple[int, ...],
    pose: np.ndarray,
    d: np.ndarray,
    method: str,
    maxiter: int,
    xtol_floor: float = 1e-13,
    options: dict | None = None,
) -> dict[str, np.ndarray]:
    """Solve the drive mode from ``X0 = (1 + d) X*`` for every d (batched, generic solver
    ``method`` with ``options``, e.g. ``METHODS_USED[key]``).

    The solver runs with ``tol = 0`` and a step floor ``xtol_floor`` (m) well below every
    tolerance used, recording the trajectory; the step count under a stopping rule
    ``|X_{k} - X_{k-1}| < tol`` is read from the trajectory afterwards (``steps(...)``).
    Returns X* (m), the trajectory (iterations+1, len(d), 6-R) and the FKResult fields.
    """
    dm = DriveMode(m, passive)
    xs, act = dm.split(m.ik(pose))
    traj: list[np.ndarray] = []
    res = solve_fk(
        dm,
        act,
        x0=(1.0 + np.asarray(d))[:, None] * xs,
        method=method,
        tol=0.0,
        maxiter=maxiter,
        xtol=xtol_floor,
        callback=lambda k, x, r: traj.append(x),
        **(options or {}),
    )
    return {"xstar": xs, "traj": np.array(traj), "status": res.status, "nit": res.nit, "x": res.x}


def steps(traj: np.ndarray, tol: float, norm: str = "2") -> np.ndarray:
    """Iterations until the first step with ``|dX| < tol`` (that step counted) per case; -1 never."""
    dx = np.diff(traj, axis=0)
    size = np.linalg.norm(dx, axis=-1) if norm == "2" else np.max(np.abs(dx), axis=-1)
    hit = size < tol
    first = np.argmax(hit, axis=0) + 1
    return np.where(hit.any(axis=0), first, -1)


def state_at(traj: np.ndarray, k: np.ndarray) -> np.ndarray:
    """Iterate number ``k`` (per case; the last one where k < 0) of a trajectory."""
    k = np.where(k < 0, len(traj) - 1, np.minimum(k, len(traj) - 1))
    return traj[k, np.arange(traj.shape[1])]


def time_solve(
    m: Stewart12,
    passive: tuple[int, ...],
    pose: np.ndarray,
    d: float,
    method: str,
    tol: float,
    repeats: int,
    options: dict | None = None,
) -> float:
    """Median wall time (s) of one single-case solve stopped by ``xtol = tol`` (inf-norm)."""
    dm = DriveMode(m, passive)
    xs, act = dm.split(m.ik(pose))
    times = []
    for _ in range(repeats):
        t = time.perf_counter()
        solve_fk(
            dm,
            act,
            x0=(1.0 + d) * xs,
            method=method,
            tol=0.0,
            maxiter=100,
            xtol=tol,
            **(options or {}),
        )
        times.append(time.perf_counter() - t)
    return float(np.median(times))
