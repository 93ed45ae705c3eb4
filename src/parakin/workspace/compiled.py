"""The compiled workspace classifier: the loops of :mod:`parakin.workspace._loops` bound to one
mechanism's kernels and compiled by numba (blocks of poses on threads: every core), cached on disk
beside the kernels (:mod:`parakin.kernels.store`) under a hash of the kernel's sources and of the
loops'. Used by :func:`parakin.workspace.classify` for batches of at least :data:`MIN_ROWS` poses
where the compiled path is on (:func:`parakin.kernels.enabled`) and the mechanism runs its kernel
(:meth:`Mechanism.kernel`); the numpy path gives the same classes (cond(J) to ~1e-9 relative: the
joint Jacobian by central differences here, the mechanism's own there).
"""

from __future__ import annotations

import sys
import types
from collections.abc import Callable
from functools import cache

import numpy as np

from parakin import kernels
from parakin.workspace.region import Region

__all__ = ["MIN_ROWS", "classifier", "loops_of"]

#: batches below this run on numpy (loading the compiled loop costs ~0.1-0.5 s per process)
MIN_ROWS = 20_000
#: rows per call of the compiled loop (bounds the memory of one call)
CHUNK = 1 << 18
_FUNCTIONS = ("joint_jacobian", "solve_in_place", "svd_cond", "row", "rows_serial")


def _sources(module: types.ModuleType) -> list[types.ModuleType]:
    """The kernel module and every kernel module it takes functions from."""
    out = {module} | {
        sys.modules[f.__module__]
        for f in vars(module).values()
        if getattr(f, "__parakin_kernel__", False)
    }
    return sorted(out, key=lambda m: m.__name__)


@cache
def loops_of(module: types.ModuleType) -> types.SimpleNamespace:
    """The loops of :mod:`parakin.workspace._loops` compiled over kernel ``module``, numba-cached
    in ``<kernel cache>/<module>.workspace-<hash>``."""
    import parakin.workspace._loops as _loops
    from parakin.kernels import _math, store

    numba = kernels._numba()
    kern = kernels.compiled(module)
    hash_ = store.digest(*_sources(module), _math, _loops)
    path = store.kernel_dir(f"{module.__name__}.workspace", hash_)
    glob = dict(vars(_loops))
    glob.update(IK=kern.ik, JAC=kern.jacobian, RES=kern.residual)
    out = {}
    with store.numba_cache(path):
        for name in _FUNCTIONS:
            fn = getattr(_loops, name)
            copy = types.FunctionType(fn.__code__, glob, fn.__name__, fn.__defaults__)
            # a name per kernel: numba names a cached function by its qualified name
            copy.__qualname__ = f"{fn.__qualname__}__{module.__name__.replace('.', '_')}"
            copy.__module__ = fn.__module__
            glob[name] = numba.njit(cache=True, error_model="numpy", nogil=True)(copy)
            out[name] = glob[name]
    # the batch loop, loaded (or compiled) on its first call through the cache's checks
    out["rows"] = kernels._Entry(out["rows_serial"], path)
    return types.SimpleNamespace(path=path, **out)


def classifier(region: Region, n: int, compiled: bool | None) -> Callable | None:
    """``classify(x, want_cond) -> (q, domain, limits, cond)`` on the compiled loop, or None where
    the numpy path runs: ``compiled=False``, a batch below :data:`MIN_ROWS` (``compiled=None``),
    the compiled path off, or a mechanism without its kernel."""
    if compiled is False or (compiled is None and n < MIN_ROWS):
        return None
    kern = kernels.kernel_of(region.mech)
    if kern is None:
        return None
    loops = loops_of(kern.module)
    params = np.ascontiguousarray(kern.params, dtype=float)
    jlo = np.ascontiguousarray(region.joint_lo, dtype=float)
    jhi = np.ascontiguousarray(region.joint_hi, dtype=float)
    m = region.mech.n_joints

    def run(x: np.ndarray, want_cond: bool):
        x = np.ascontiguousarray(x, dtype=float)
        q = np.empty((len(x), m))
        flags = np.zeros((len(x), 2), dtype=np.int8)
        cond = np.empty(len(x))
        for s in range(0, len(x), CHUNK):
            sl = slice(s, s + CHUNK)
            args = (params, x[sl], jlo, jhi, bool(want_cond), q[sl], flags[sl], cond[sl])
            kernels.threads.rows(loops.rows, args, (1, 5, 6, 7))
        domain = flags[:, 0] == 1
        q[~domain] = np.nan
        return q, domain, flags[:, 1] == 1, cond

    return run
