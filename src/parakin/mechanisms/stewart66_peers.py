"""The peers of :meth:`parakin.mechanisms.stewart66.Stewart66.fk_all`, run on the same inputs in one
process: timings side by side and the solution sets compared (``parakin bench --peers``,
``docs/peers.md``).

* **Bertini 2** (the ``bertini2`` wheel, import name ``bertini``; optional extra
  ``parakin[peers]``): the same coefficient-parameter homotopy as ours, tracked by Bertini: the
  Study-coordinate system of ``docs/stewart66.md`` in the same affine patch, the six leg rows moving
  on the straight segment from this geometry's start leg constants to each input's
  (``gamma = 1``), the Study quadric and the patch held, from our 40 start solutions; adaptive
  precision (Bates et al. 2013) and double precision. Its records are switched off
  (``bertini.recording(False)``): every solve is computed, none replayed.
* **Martyushev's elimination-template solver** (Mech. Mach. Theory 2025, public repository
  ``martyushev/fkSGP``, MIT; its Python ``solver66``), where the user points at a local copy of that
  repository; its code stays there, loaded from that path.

Agreement: Bertini's finite solutions against ours (both scaled to the common patch, within
``1e-6``); the elimination template's real postures that reproduce the legs to ``1e-6`` against our
real poses (rotation and origin within ``1e-6``). Timings are single calls, one input each; ours
also batched; each timing comes from this run only (ratios, never absolute claims).
"""

from __future__ import annotations

import importlib
import importlib.util
import sys
import time
import types
from collections.abc import Callable
from pathlib import Path

import numpy as np
import pandas as pd

from parakin.geometry import euler_zyx
from parakin.mechanisms.stewart66 import DIETMAIER_LENGTHS, Stewart66, random_pose
from parakin.timing import one_thread

__all__ = [
    "bertini_available",
    "bertini_solver",
    "martyushev_solver",
    "bench_peers",
    "format_peers",
]

#: agreement tolerance of two solutions (Study coordinates in the common patch, or pose parts)
AGREE_TOL = 1e-6


def bertini_available() -> bool:
    """Whether the optional ``bertini2`` wheel is installed."""
    return importlib.util.find_spec("bertini") is not None


def _bertini_rows(b, q0: np.ndarray, c, variables) -> list:
    """The six leg quadrics ``x^T (Q0_m + c_{m-1} E) x`` (m = 1..6) as Bertini expressions."""

    def coef(z) -> object:
        z = complex(z)
        node = b.coefficient(repr(z.real))
        return node + b.coefficient(repr(z.imag)) * b.I if z.imag else node

    rows = []
    for m in range(1, 7):
        f = None
        for i in range(8):
            for j in range(i, 8):
                h = q0[m, i, j] * (1 if i == j else 2) + (c[m - 1] if i == j and i < 4 else 0)
                if h != 0:
                    term = coef(h) * variables[i] * variables[j]
                    f = term if f is None else f + term
        rows.append(f)
    return rows


def bertini_solver(mech: Stewart66, mptype: str = "adaptive") -> Callable[[np.ndarray], np.ndarray]:
    """A function ``lengths (6,) -> solutions (k, 8)`` (complex, ``NaN`` rows for failed paths):
    Bertini 2 tracking our parameter homotopy (module docstring) with precision model
    ``mptype`` (``"adaptive"`` or ``"double"``)."""
    import bertini as b
    from bertini import nag_algorithm as na

    b.recording(False)
    st = mech.fk_start
    q0 = st["q0"].real
    v = [b.Variable(n) for n in ("e0", "e1", "e2", "e3", "g0", "g1", "g2", "g3")]
    fixed = b.System()
    fixed.add_variable_group(v)
    study = v[0] * v[4] + v[1] * v[5] + v[2] * v[6] + v[3] * v[7]
    patch = st["patch"]
    lin = None
    for i in range(8):
        z = complex(patch[i])
        term = (b.coefficient(repr(z.real)) + b.coefficient(repr(z.imag)) * b.I) * v[i]
        lin = term if lin is None else lin + term
    fixed.add_function(study)
    fixed.add_function(lin - b.coefficient("1"))
    start_rows = _bertini_rows(b, q0, st["c"], v)
    starts = [list(x) for x in st["solutions"]]

    def solve(lengths: np.ndarray) -> np.ndarray:
        c1 = mech._target_c(np.asarray(lengths, dtype=float)[None])[0]
        rows = _bertini_rows(b, q0, c1, v)
        hom = na.straight_line_homotopy(rows, start_rows, fixed=fixed, gamma=1)
        solver = na.HomotopySolver(hom.homotopy, starts, hom.target, mptype=mptype)
        solver.solve()
        out = [
            [complex(z) for z in p] if len(list(p)) == 8 else [np.nan] * 8
            for p in solver.all_solutions()
        ]
        return np.array(out, dtype=complex).reshape(-1, 8)

    return solve


def martyushev_solver(path: str | Path) -> Callable[[Stewart66, np.ndarray], np.ndarray]:
    """A function ``(mech, lengths (6,)) -> poses (k, 6)``: the real postures of Martyushev's
    ``solver66`` from the local copy of ``martyushev/fkSGP`` at ``path`` (its ``python/`` folder is
    loaded as a package of its own, its ``__init__`` not run). Its random rotations are drawn from
    numpy's global generator, seeded per call here so that a run repeats."""
    folder = Path(path).expanduser() / "python"
    if not (folder / "solver66.py").is_file():
        raise FileNotFoundError(
            f"{folder / 'solver66.py'} not found: --peers takes a local copy of the "
            "martyushev/fkSGP repository"
        )
    name = "_parakin_peer_fksgp"
    if name not in sys.modules:
        pkg = types.ModuleType(name)
        pkg.__path__ = [str(folder)]
        sys.modules[name] = pkg
    solver66 = importlib.import_module(f"{name}.solver66").solver66

    def solve(mech: Stewart66, lengths: np.ndarray, seed: int = 0) -> np.ndarray:
        b0, p0 = mech.base_points[0], mech.platform_points[0]
        np.random.seed(seed)  # noqa: NPY002  (the peer draws from numpy's legacy global generator)
        rt, _ = solver66(
            mech.base_points - b0,
            mech.platform_points - p0,
            np.asarray(lengths, dtype=float) ** 2,
            1,
        )
        rt = np.asarray(rt, dtype=float).reshape(-1, 3, 4)
        # X = R x + t with X, x the anchors less their first ones: O = t - R P_0 + B_0
        origin = rt[:, :, 3] - rt[:, :, :3] @ p0 + b0
        from parakin.geometry import euler_zyx_from_matrix

        return np.concatenate([euler_zyx_from_matrix(rt[:, :, :3]), origin], -1)

    return solve


def _in_patch(x: np.ndarray, patch: np.ndarray) -> np.ndarray:
    with np.errstate(all="ignore"):
        return x / (x @ patch)[:, None]


def _same_set(a: np.ndarray, b: np.ndarray, tol: float = AGREE_TOL) -> bool:
    """Every row of ``a`` within ``tol`` of a row of ``b`` and back (max norm)."""
    if len(a) != len(b):
        return False
    if not len(a):
        return True
    d = np.abs(a[:, None] - b[None]).max(-1)
    return bool(np.all(d.min(0) <= tol) and np.all(d.min(1) <= tol))


def _pose_key(mech: Stewart66, poses: np.ndarray) -> np.ndarray:
    """Rotation matrix entries and origin: a pose comparable without angle wrapping."""
    if not len(poses):
        return np.zeros((0, 12))
    r = euler_zyx(poses[:, 0], poses[:, 1], poses[:, 2]).reshape(-1, 9)
    return np.concatenate([r, poses[:, 3:]], -1)


def _inputs(mech: Stewart66, n: int, seed: int) -> np.ndarray:
    """Dietmaier's leg lengths and ``n - 1`` inputs from random poses (``studies.stewart66``)."""
    rng = np.random.default_rng(seed)
    q = mech.ik(random_pose(rng, max(n - 1, 0), mech))
    return np.concatenate([np.asarray(DIETMAIER_LENGTHS)[None], q])[:n]


def _time_each(f: Callable[[int], object], n: int) -> tuple[float, list]:
    out = []
    t0 = time.perf_counter()
    for i in range(n):
        out.append(f(i))
    return (time.perf_counter() - t0) / max(n, 1), out


def bench_peers(
    *,
    n_inputs: int = 31,
    n_bertini: int = 3,
    fksgp: str | Path | None = None,
    seed: int = 2029,
    double: bool = True,
    progress: Callable[[str], None] | None = None,
) -> pd.DataFrame:
    """Time ``fk_all`` and its peers on the same inputs (Dietmaier's and random poses of his
    platform) in this process and compare the solution sets. One row per solver: ``ms_per_input``
    (single calls, one input each), ``inputs_per_s``, ``x_parakin`` (its time over ours, one
    thread), ``inputs``, ``agree`` (inputs whose solution set equals ours: all certified complex
    ones for Bertini, the real ones for the elimination template; for ours: complete inputs) and
    ``note``. Bertini runs on the first ``n_bertini`` inputs (seconds each); it is skipped where
    the wheel is missing, the elimination template where ``fksgp`` is None."""
    import numba

    mech = Stewart66()
    q = _inputs(mech, n_inputs, seed)
    say = progress or (lambda s: None)
    mech.fk_all(q[:2])  # the start system, the compiled kernels
    threads = numba.get_num_threads()
    with one_thread():
        t_one, infos = _time_each(lambda i: mech.fk_all(q[i], return_info=True), len(q))
    t0 = time.perf_counter()
    batch = mech.fk_all(q, return_info=True)
    t_batch = (time.perf_counter() - t0) / len(q)
    done = "complete: 40 certified solutions"
    rows = [
        _row(
            "parakin fk_all, one input per call (1 thread)",
            t_one,
            t_one,
            len(q),
            sum(bool(r.complete) for r in infos),
            done,
        ),
        _row(
            f"parakin fk_all, batched ({threads} threads)",
            t_batch,
            t_one,
            len(q),
            int(batch.complete.sum()),
            done,
        ),
    ]
    if bertini_available():
        for mptype in ("adaptive", "double") if double else ("adaptive",):
            say(f"Bertini 2, {mptype} precision")
            rows.append(_bertini_row(mech, q[:n_bertini], infos, mptype, t_one))
    if fksgp is not None:
        say("Martyushev's elimination template")
        rows.append(_martyushev_row(mech, q, infos, fksgp, t_one))
    return pd.DataFrame(rows)


def _bertini_row(mech: Stewart66, q: np.ndarray, infos: list, mptype: str, t_one: float) -> dict:
    """Bertini 2 on inputs ``q`` (timed) against our solutions ``infos`` (FKAll per input)."""
    solve = bertini_solver(mech, mptype)
    if mptype == "double":
        solve(q[0])  # warm-up: building the system, first evaluations
    t, sols = _time_each(lambda i: solve(q[i]), len(q))
    patch = mech.fk_start["patch"]
    agree, found = 0, []
    for i in range(len(q)):
        theirs = _in_patch(sols[i], patch)
        theirs = theirs[np.all(np.isfinite(theirs), -1)]
        found.append(len(theirs))
        ours = _in_patch(infos[i].study[np.isfinite(infos[i].study[:, 0])], patch)
        agree += _same_set(theirs, ours)
    note = f"finite solutions per input: {found}"
    return _row(f"Bertini 2 parameter homotopy, {mptype} precision", t, t_one, len(q), agree, note)


def _martyushev_row(mech: Stewart66, q: np.ndarray, infos: list, fksgp, t_one: float) -> dict:
    """The elimination template on inputs ``q`` (timed): its real postures that reproduce the legs
    to ``AGREE_TOL`` against our real poses."""
    solve = martyushev_solver(fksgp)
    solve(mech, q[0])  # warm-up: scipy's first calls
    t, poses = _time_each(lambda i: solve(mech, q[i], seed=i), len(q))
    agree, worst = 0, 0.0
    for i, p in enumerate(poses):
        err = np.abs(mech.ik(p) - q[i]).max(-1) if len(p) else np.zeros(0)
        worst = max(worst, float(err.max(initial=0.0)))
        ours = infos[i].poses[np.isfinite(infos[i].poses[:, 0])]
        agree += _same_set(_pose_key(mech, p[err <= AGREE_TOL]), _pose_key(mech, ours))
    note = f"worst leg error of its real postures {worst:.1e}"
    return _row("Martyushev elimination template (solver66)", t, t_one, len(q), agree, note)


def _row(solver: str, t: float, t_ref: float, inputs: int, agree: int, note: str) -> dict:
    return {
        "solver": solver,
        "ms_per_input": 1e3 * t,
        "inputs_per_s": 1.0 / t,
        "x_parakin": t / t_ref,
        "inputs": inputs,
        "agree": agree,
        "note": note,
    }


def format_peers(df: pd.DataFrame) -> str:
    """The rows of :func:`bench_peers` as a Markdown table."""
    lines = [
        "| solver | ms per input | inputs/s | time / parakin's (1 thread) | inputs agreeing "
        "(peers: same solution set as parakin; parakin: complete) | note |",
        "|---|---|---|---|---|---|",
    ]
    for r in df.itertuples():
        lines.append(
            f"| {r.solver} | {r.ms_per_input:.3g} | {r.inputs_per_s:.3g} | {r.x_parakin:.3g} | "
            f"{r.agree} of {r.inputs} | {r.note} |"
        )
    return "\n".join(lines)
