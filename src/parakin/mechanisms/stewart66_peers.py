"""The peers of :meth:`parakin.mechanisms.stewart66.Stewart66.fk_all`, timed fairly against it on the
same inputs in one process, and their solution sets compared (``parakin bench --peers``,
``docs/peers.md``).

* **Bertini 2** (the ``bertini2`` wheel, import name ``bertini``; optional extra
  ``parakin[peers]``): the same coefficient-parameter homotopy as ours, tracked by Bertini: the
  Study-coordinate system of ``docs/stewart66.md`` in the same affine patch, the six leg rows moving
  on the straight segment from the geometry's start leg constants to each input's (``gamma = 1``),
  the Study quadric and the patch held, from our 40 start solutions; adaptive precision (Bates et
  al. 2013) and double precision. Its records are switched off (``bertini.recording(False)``):
  every solve is computed, none replayed.
* **Martyushev's elimination-template solver** (Mech. Mach. Theory 2025, public repository
  ``martyushev/fkSGP``, MIT; its Python ``solver66``), where the user points at a local copy of that
  repository; its code stays there, loaded from that path, and so does its input generator
  ``genSGP``, which draws half of the inputs here.

**How they are timed** (:func:`bench_peers`): per input, ours and the peer one after the other,
the order alternating from input to input (A B, B A, ...), each call timed by the CPU time of the
process (``time.process_time``: Bertini computes in worker threads of its own; for the
single-threaded solvers it is the calling thread's, ``time.thread_time``, recorded beside) and by
the wall clock; ours on one numba thread, every BLAS on one thread (:func:`blas_threads`). The figure of a row is the median and interquartile range of
the per-input ratio of the peer's CPU time to ours, never a ratio of totals timed apart. Two cases
are kept apart: *same geometry* (the geometry's start system built before the clock starts, as
when a platform is reused) and *new geometry per call* (everything timed: the mechanism built from
its anchors, then its first call, which takes the new-geometry path). Inputs come from each side's
generator: ours (Dietmaier's platform, random platforms) and fkSGP's ``genSGP``.

Agreement: Bertini's finite solutions against ours (both scaled to the common patch, within
``1e-6``); the elimination template's real postures that reproduce the legs to ``1e-6`` against our
real poses (rotation and origin within ``1e-6``).
"""

from __future__ import annotations

import contextlib
import ctypes
import importlib
import importlib.util
import os
import sys
import time
import types
from collections.abc import Callable, Iterator
from pathlib import Path

import numpy as np
import pandas as pd

from parakin.geometry import euler_zyx, euler_zyx_from_matrix
from parakin.mechanisms.stewart66 import (
    DIETMAIER_LENGTHS,
    Stewart66,
    fk_all_geometries,
    random_platform,
    random_pose,
)
from parakin.timing import machine, one_thread

__all__ = [
    "bertini_available",
    "bertini_solver",
    "martyushev_solver",
    "martyushev_inputs",
    "blas_threads",
    "bench_peers",
    "format_peers",
    "interleaved",
]

#: agreement tolerance of two solutions (Study coordinates in the common patch, or pose parts)
AGREE_TOL = 1e-6


def bertini_available() -> bool:
    """Whether the optional ``bertini2`` wheel is installed."""
    return importlib.util.find_spec("bertini") is not None


# ------------------------------------------------------------------------------ BLAS threads
_BLAS_SETTERS = (
    ("openblas_set_num_threads", "openblas_get_num_threads"),
    ("openblas_set_num_threads64_", "openblas_get_num_threads64_"),
    ("scipy_openblas_set_num_threads", "scipy_openblas_get_num_threads"),
    ("scipy_openblas_set_num_threads64_", "scipy_openblas_get_num_threads64_"),
    ("MKL_Set_Num_Threads", "MKL_Get_Max_Threads"),
)


def _blas_libraries() -> list[tuple[Callable, Callable]]:
    """The ``(set, get)`` thread-count functions of every BLAS this process has loaded (OpenBLAS,
    the OpenBLAS builds that numpy and scipy ship, MKL), found in ``/proc/self/maps`` (Linux)."""
    try:
        with open("/proc/self/maps") as fh:
            paths = {line.split()[-1] for line in fh if ".so" in line}
    except OSError:
        return []
    found = []
    for path in sorted(p for p in paths if "blas" in p.lower() or "mkl" in p.lower()):
        try:
            lib = ctypes.CDLL(path)
        except OSError:
            continue
        for set_name, get_name in _BLAS_SETTERS:
            if hasattr(lib, set_name) and hasattr(lib, get_name):
                found.append((getattr(lib, set_name), getattr(lib, get_name)))
                break
    return found


@contextlib.contextmanager
def blas_threads(n: int) -> Iterator[int]:
    """Every loaded BLAS on ``n`` threads inside the block (what threadpoolctl does, without the
    dependency), the counts restored after; yields how many libraries it set. The elimination
    template's LAPACK calls are then timed on one thread, as ours are."""
    import scipy.linalg  # noqa: F401  (load scipy's BLAS too, so that it is found and set)

    libs = _blas_libraries()
    before = [get() for _, get in libs]
    for set_, _ in libs:
        set_(n)
    try:
        yield len(libs)
    finally:
        for (set_, _), count in zip(libs, before):
            set_(count)


# ------------------------------------------------------------------------------ Bertini 2
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


# ------------------------------------------------------------------------------ fkSGP
def _fksgp_package(path: str | Path) -> str:
    """The local copy of ``martyushev/fkSGP`` at ``path`` loaded as a package of its own (its
    ``python/`` folder; its ``__init__`` not run): the package name."""
    folder = Path(path).expanduser() / "python"
    if not (folder / "solver66.py").is_file():
        raise FileNotFoundError(
            f"{folder / 'solver66.py'} not found: --peers takes a local copy of the "
            "martyushev/fkSGP repository"
        )
    name = "_parakin_peer_fksgp"
    pkg = sys.modules.get(name)
    if pkg is None or list(pkg.__path__) != [str(folder)]:
        pkg = types.ModuleType(name)
        pkg.__path__ = [str(folder)]
        sys.modules[name] = pkg
        for sub in [k for k in sys.modules if k.startswith(name + ".")]:
            del sys.modules[sub]
    return name


def martyushev_solver(path: str | Path) -> Callable[..., np.ndarray]:
    """A function ``(mech, lengths (6,), seed=0) -> poses (k, 6)``: the real postures of
    Martyushev's ``solver66`` from the local copy of ``martyushev/fkSGP`` at ``path``. Its random
    rotations are drawn from numpy's global generator, seeded per call here so that a run
    repeats."""
    solver66 = importlib.import_module(f"{_fksgp_package(path)}.solver66").solver66

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
        return np.concatenate([euler_zyx_from_matrix(rt[:, :, :3]), origin], -1)

    return solve


def martyushev_inputs(path: str | Path, n: int, seed: int) -> list[tuple]:
    """``n`` inputs from the peer's own generator ``genSGP`` (a general 6-6, generic motion:
    anchors uniform in ``[-2, 2]^3`` less the first, a Cayley rotation of a normal vector, a normal
    translation), numpy's global generator seeded with ``seed + i`` for input ``i``: a list of
    ``(base, platform, lengths)``."""
    gen = importlib.import_module(f"{_fksgp_package(path)}.genSGP").genSGP
    out = []
    for i in range(n):
        np.random.seed(seed + i)  # noqa: NPY002  (the peer's generator draws from it)
        sgp = gen(1, 1)
        out.append((np.array(sgp["X"]), np.array(sgp["x"]), np.sqrt(np.asarray(sgp["L"]))))
    return out


# ------------------------------------------------------------------------------ agreement
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


def _pose_key(poses: np.ndarray) -> np.ndarray:
    """Rotation matrix entries and origin: a pose comparable without angle wrapping."""
    if not len(poses):
        return np.zeros((0, 12))
    r = euler_zyx(poses[:, 0], poses[:, 1], poses[:, 2]).reshape(-1, 9)
    return np.concatenate([r, poses[:, 3:]], -1)


def _real_agree(mech: Stewart66, lengths: np.ndarray, theirs: np.ndarray, ours) -> tuple:
    """``(agree, worst leg error of their real postures)``: their postures that reproduce the legs
    to :data:`AGREE_TOL` are exactly our real poses."""
    err = np.abs(mech.ik(theirs) - lengths).max(-1) if len(theirs) else np.zeros(0)
    mine = ours.poses[np.isfinite(ours.poses[:, 0])]
    same = _same_set(_pose_key(theirs[err <= AGREE_TOL]), _pose_key(mine))
    return bool(ours.complete) and same, float(err.max(initial=0.0))


# ------------------------------------------------------------------------------ timing
def _clock(f: Callable[[], object]) -> tuple[float, float, float, object]:
    """``(CPU seconds of the process, wall seconds, CPU seconds of this thread, result)`` of one
    call. The process's CPU time is the figure: Bertini 2 computes in worker threads of its own
    (one adaptive-precision solve: 0.06 s of the calling thread, 6.8 s of the process), and it
    equals the calling thread's for the single-threaded solvers."""
    c0, w0, t0 = time.process_time(), time.perf_counter(), time.thread_time()
    out = f()
    return time.process_time() - c0, time.perf_counter() - w0, time.thread_time() - t0, out


def interleaved(
    ours: Callable[[int], object], theirs: Callable[[int], object], n: int
) -> tuple[np.ndarray, list, list]:
    """Per input ``i < n``: ``ours(i)`` and ``theirs(i)`` one after the other, the order
    alternating (A B, B A, ...), so that neither side always runs first (caches, clock boosts).
    Returns ``times`` (n, 2, 3): [input, ours/theirs, process CPU/wall/thread CPU] seconds, and
    both results."""
    times = np.empty((n, 2, 3))
    mine, peer = [], []
    for i in range(n):
        order = (0, 1) if i % 2 == 0 else (1, 0)
        for side in order:
            cpu, wall, thread, out = _clock(
                (lambda i=i: ours(i)) if side == 0 else (lambda i=i: theirs(i))
            )
            times[i, side] = cpu, wall, thread
            (mine if side == 0 else peer).append((i, out))
    return (
        times,
        [o for _, o in sorted(mine, key=lambda t: t[0])],
        [o for _, o in sorted(peer, key=lambda t: t[0])],
    )


def _ratio_row(case, inputs_from, solver, times, agree, note) -> dict:
    """A row of the per-input comparison: medians of both sides (the process's CPU time, wall,
    the calling thread's CPU time) and the median and interquartile range of the per-input CPU
    ratio (theirs / ours)."""
    ratio = times[:, 1, 0] / times[:, 0, 0]
    q1, med, q3 = np.percentile(ratio, [25, 50, 75])
    return {
        "case": case,
        "inputs_from": inputs_from,
        "peer": solver,
        "inputs": len(times),
        "ours_cpu_ms": 1e3 * float(np.median(times[:, 0, 0])),
        "peer_cpu_ms": 1e3 * float(np.median(times[:, 1, 0])),
        "ratio_median": float(med),
        "ratio_q1": float(q1),
        "ratio_q3": float(q3),
        "ours_wall_ms": 1e3 * float(np.median(times[:, 0, 1])),
        "peer_wall_ms": 1e3 * float(np.median(times[:, 1, 1])),
        "ours_thread_ms": 1e3 * float(np.median(times[:, 0, 2])),
        "peer_thread_ms": 1e3 * float(np.median(times[:, 1, 2])),
        "agree": int(agree),
        "note": note,
    }


# ------------------------------------------------------------------------------ the benchmark
def _our_inputs(n: int, seed: int) -> tuple[list, list]:
    """Our inputs: on Dietmaier's platform, his leg lengths and ``n - 1`` random poses (the same
    geometry); and ``n`` random platforms with one random pose each (new geometries)."""
    rng = np.random.default_rng(seed)
    d = Stewart66()
    q = d.ik(random_pose(rng, max(n - 1, 0), d))
    same = [(d.base_points, d.platform_points, np.asarray(DIETMAIER_LENGTHS))]
    same += [(d.base_points, d.platform_points, qi) for qi in q]
    new = []
    for _ in range(n):
        m = random_platform(rng)
        new.append((m.base_points, m.platform_points, m.ik(random_pose(rng, 1, m))[0]))
    return same[:n], new


def bench_peers(
    *,
    n_inputs: int = 31,
    n_bertini: int | None = None,
    fksgp: str | Path | None = None,
    seed: int = 2029,
    double: bool = True,
    progress: Callable[[str], None] | None = None,
) -> pd.DataFrame:
    """``fk_all`` against its peers, input by input (module docstring): ``n_inputs`` inputs from
    each generator and case, Bertini on ``n_bertini`` of ours (default 20, 3 where
    ``n_inputs < 20``: seconds each), skipped where the wheel is missing; the elimination template
    where ``fksgp`` (a local copy of ``martyushev/fkSGP``) is given. One row per case, inputs'
    origin and peer: ``ours_cpu_ms``, ``peer_cpu_ms`` (medians), ``ratio_median``, ``ratio_q1``,
    ``ratio_q3`` (the per-input ratio of the peer's CPU time to ours), the wall-clock medians,
    ``agree`` (inputs whose solution sets agree) and ``note``; then our batched throughput (all
    threads) on the same inputs. ``attrs``: the machine, the load average before and after, the
    BLAS libraries set to one thread."""
    say = progress or (lambda s: None)
    n_bertini = (20 if n_inputs >= 20 else 3) if n_bertini is None else n_bertini
    load0 = os.getloadavg() if hasattr(os, "getloadavg") else (np.nan,) * 3
    same_in, new_in = _our_inputs(n_inputs, seed)
    peer_in = martyushev_inputs(fksgp, n_inputs, seed) if fksgp is not None else []
    dietmaier = Stewart66()
    dietmaier.fk_all(np.stack([q for *_, q in same_in[:2]]))  # its start system, the kernels
    Stewart66(base=new_in[0][0], platform=new_in[0][1]).fk_all(new_in[0][2])  # the new path
    rows = []
    with one_thread(), blas_threads(1) as blas:
        if fksgp is not None:
            solve = martyushev_solver(fksgp)
            solve(dietmaier, same_in[0][2])  # warm-up: scipy's first calls
            say("same geometry: parakin and the elimination template, input by input")
            for label, inputs in (("parakin: Dietmaier's platform", same_in), ("fkSGP genSGP", peer_in)):  # fmt: skip
                if inputs is same_in:
                    mechs = [dietmaier] * len(inputs)
                else:
                    mechs = [Stewart66(base=b, platform=p) for b, p, _ in inputs]
                    for m in mechs:
                        m.fk_start  # noqa: B018  (the start system, before the clock)
                times, ours, theirs = interleaved(
                    lambda i, m=mechs, x=inputs: m[i].fk_all(x[i][2], return_info=True),
                    lambda i, m=mechs, x=inputs: solve(m[i], x[i][2], seed=i),
                    len(inputs),
                )
                agree, worst = zip(*(_real_agree(m, x[2], t, o) for m, x, t, o in zip(mechs, inputs, theirs, ours)))  # fmt: skip
                rows.append(_ratio_row("same geometry, one input per call", label, "Martyushev elimination template (solver66)", times, sum(agree), f"worst leg error of its real postures {max(worst):.1e}"))  # fmt: skip
            say("new geometry per call: parakin and the elimination template, input by input")
            for label, inputs in (("parakin: random platforms", new_in), ("fkSGP genSGP", peer_in)):
                # the peer reads the anchors alone: its mechanisms are built before the clock
                mechs = [Stewart66(base=b, platform=p) for b, p, _ in inputs]
                times, ours, theirs = interleaved(
                    lambda i, x=inputs: Stewart66(base=x[i][0], platform=x[i][1]).fk_all(
                        x[i][2], return_info=True
                    ),
                    lambda i, m=mechs, x=inputs: solve(m[i], x[i][2], seed=i),
                    len(inputs),
                )
                agree, worst = zip(*(_real_agree(m, x[2], t, o) for m, x, t, o in zip(mechs, inputs, theirs, ours)))  # fmt: skip
                rows.append(_ratio_row("new geometry per call (everything timed)", label, "Martyushev elimination template (solver66)", times, sum(agree), f"worst leg error of its real postures {max(worst):.1e}"))  # fmt: skip
        if bertini_available() and n_bertini > 0:
            for mptype in ("adaptive", "double") if double else ("adaptive",):
                say(f"same geometry: parakin and Bertini 2 ({mptype} precision), input by input")
                rows.append(_bertini_row(dietmaier, same_in[:n_bertini], mptype))
    say("batched: parakin on every thread")
    rows += _batch_rows(dietmaier, same_in, new_in, peer_in)
    df = pd.DataFrame(rows)
    df.attrs.update(
        machine=machine(),
        load_before=tuple(round(v, 2) for v in load0),
        load_after=tuple(round(v, 2) for v in os.getloadavg()) if hasattr(os, "getloadavg") else (),
        blas_set_to_one_thread=blas,
        bertini="installed" if bertini_available() else "not installed (pip install bertini2)",
        fksgp=str(fksgp) if fksgp is not None else "not given",
    )
    return df


def _bertini_row(mech: Stewart66, inputs: list, mptype: str) -> dict:
    """Bertini 2 against ours, input by input, on one geometry: its finite solutions against our
    certified ones."""
    solve = bertini_solver(mech, mptype)
    if mptype == "double":  # warm-up: building the system, first evaluations (an adaptive
        solve(inputs[0][2])  # solve takes seconds: its first call is one of the median's inputs
    times, ours, theirs = interleaved(
        lambda i: mech.fk_all(inputs[i][2], return_info=True),
        lambda i: solve(inputs[i][2]),
        len(inputs),
    )
    patch = mech.fk_start["patch"]
    agree, found = 0, []
    for sol, r in zip(theirs, ours):
        mine = _in_patch(r.study[np.isfinite(r.study[:, 0])], patch)
        t = _in_patch(sol, patch)
        t = t[np.all(np.isfinite(t), -1)]
        found.append(len(t))
        agree += bool(r.complete) and _same_set(t, mine)
    counts = np.bincount(found)
    note = "finite solutions per input: " + ", ".join(
        f"{k} ({c}x)" for k, c in enumerate(counts) if c
    )
    return _ratio_row("same geometry, one input per call", "parakin: Dietmaier's platform", f"Bertini 2 parameter homotopy, {mptype} precision", times, agree, note)  # fmt: skip


#: runs of each batch; the rows give the median wall and CPU time
BATCH_RUNS = 7


def _batch_rows(dietmaier: Stewart66, same_in: list, new_in: list, peer_in: list) -> list[dict]:
    """Our throughput on every thread (numba's count): the same inputs in one call, on one
    geometry and each on its own (:func:`parakin.mechanisms.stewart66.fk_all_geometries`), CPU
    time of the whole process per input beside (medians of :data:`BATCH_RUNS` runs)."""
    import numba

    rows = []
    q = np.stack([x[2] for x in same_in])
    cases = [("batched, same geometry", "parakin: Dietmaier's platform", lambda: dietmaier.fk_all(q, return_info=True))]  # fmt: skip
    for label, inputs in (("parakin: random platforms", new_in), ("fkSGP genSGP", peer_in)):
        if inputs:
            b, p, legs = (np.stack(a) for a in zip(*inputs))
            cases.append(("batched, new geometry per input", label, lambda b=b, p=p, legs=legs: fk_all_geometries(b, p, legs)))  # fmt: skip
    for case, label, run in cases:
        run()  # warm-up
        walls, cpus = [], []
        for _ in range(BATCH_RUNS):  # one batch takes milliseconds: one run is mostly jitter
            c0, w0 = time.process_time(), time.perf_counter()
            r = run()
            walls.append(time.perf_counter() - w0)
            cpus.append(time.process_time() - c0)
        wall, cpu = float(np.median(walls)), float(np.median(cpus))
        n = len(r.complete)
        rows.append(
            {
                "case": case,
                "inputs_from": label,
                "peer": f"parakin fk_all, {numba.get_num_threads()} threads",
                "inputs": n,
                "ours_cpu_ms": 1e3 * cpu / n,
                "ours_wall_ms": 1e3 * wall / n,
                "inputs_per_s": n / wall,
                "agree": int(np.sum(r.complete)),
                "note": f"median of {BATCH_RUNS} runs; agree: complete inputs (40 certified distinct solutions)",
            }
        )
    return rows


def format_peers(df: pd.DataFrame) -> str:
    """The rows of :func:`bench_peers` as Markdown: the machine and load, the per-input comparison
    (ratios: the peer's CPU time over ours, median and interquartile range), then our batches."""
    a = df.attrs
    lines = [
        f"machine: {a.get('machine', '?')}; load average before {a.get('load_before', '?')}, "
        f"after {a.get('load_after', '?')}; BLAS libraries set to one thread: "
        f"{a.get('blas_set_to_one_thread', '?')}; Bertini 2: {a.get('bertini', '?')}; "
        f"fkSGP: {a.get('fksgp', '?')}",
        "",
        "| case | inputs from | peer | inputs | parakin CPU ms (median) | peer CPU ms (median) | "
        "peer / parakin, per input: median [IQR] | wall ms: parakin, peer | agreeing | note |",
        "|---|---|---|---|---|---|---|---|---|---|",
    ]
    per_input = df[df["case"].str.startswith(("same", "new"))] if len(df) else df
    for r in per_input.itertuples():
        lines.append(
            f"| {r.case} | {r.inputs_from} | {r.peer} | {r.inputs} | {r.ours_cpu_ms:.3g} | "
            f"{r.peer_cpu_ms:.3g} | **{r.ratio_median:.3g}** [{r.ratio_q1:.3g}, {r.ratio_q3:.3g}] | "
            f"{r.ours_wall_ms:.3g}, {r.peer_wall_ms:.3g} | {r.agree} of {r.inputs} | {r.note} |"
        )
    batch = df[df["case"].str.startswith("batched")] if len(df) else df
    if len(batch):
        lines += [
            "",
            "| case | inputs from | solver | inputs | inputs/s (wall) | CPU ms per input "
            "(all threads) | complete |",
            "|---|---|---|---|---|---|---|",
        ]
        for r in batch.itertuples():
            lines.append(
                f"| {r.case} | {r.inputs_from} | {r.peer} | {r.inputs} | {r.inputs_per_s:.4g} | "
                f"{r.ours_cpu_ms:.3g} | {r.agree} of {r.inputs} |"
            )
    return "\n".join(lines)
