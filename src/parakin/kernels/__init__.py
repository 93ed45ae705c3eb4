"""Compiled forward kinematics: numba kernels of one pose and solver loops over them.

A mechanism opts in by returning a :class:`Kernel` from ``Mechanism.kernel()``: the name of a
module of five ``numba.njit`` functions for **one** pose (``residual(p, x, q, out)``,
``jacobian(p, x, q, out)``, ``ik(p, x, out) -> bool``, ``in_domain(p, x) -> bool``,
``on_assembly(p, x, q) -> bool``) and the parameter vector ``p`` they read. :func:`build` turns
that module into compiled Newton, Levenberg-Marquardt, Broyden and BFGS loops (the template
``_loops.py``, written with the kernel module's name into the kernel cache and compiled with
``cache=True``, so the compile cost is paid once per machine, not per process), each in a serial
and a ``prange``-parallel driver that run the same per-row code (identical results).

:func:`solve` is what :func:`parakin.solvers.solve_fk` calls first: it returns ``None`` (use the
generic numpy path) for a mechanism without a kernel, a method without a compiled loop, an
option the loop does not take, a callback, or where numba is not installed. Numba is imported
only here, lazily.

Cache: ``$PARAKIN_KERNEL_CACHE`` or ``$XDG_CACHE_HOME/parakin/kernels`` (default
``~/.cache/parakin/kernels``). Set ``PARAKIN_KERNELS=0`` to switch the compiled path off.
"""

from __future__ import annotations

import dataclasses
import hashlib
import importlib
import importlib.util
import inspect
import os
import sys
import tempfile
import threading
from functools import cache, lru_cache
from pathlib import Path
from types import ModuleType
from typing import Any

import numpy as np

__all__ = [
    "Kernel",
    "build",
    "cache_dir",
    "enabled",
    "solve",
    "verify_hooks",
    "PARALLEL_MIN_ROWS",
    "METHODS",
]

#: rows from which a batch runs on every core (below: the serial driver, no thread start-up)
PARALLEL_MIN_ROWS = 64

#: method -> option names (and defaults) its compiled loop takes; others go to the numpy path
METHODS: dict[str, dict[str, float]] = {
    "newton": {"xtol": 0.0},
    "lm": {"xtol": 0.0, "gtol": 0.0, "tau": 1e-9},
    "broyden": {"xtol": 0.0},
    "bfgs": {"xtol": 0.0, "gtol": 0.0, "c1": 1e-4, "shrink": 0.5, "maxls": 30, "reg": 1e-10},
}
_OPTION_ORDER = ("tol", "maxiter", "xtol", "gtol", "tau", "c1", "shrink", "maxls", "reg")


@dataclasses.dataclass(frozen=True, eq=False)
class Kernel:
    """A mechanism's compiled kernels: the module of its ``njit`` functions, its parameters."""

    module: str  #: importable module with residual, jacobian, ik, in_domain, on_assembly
    params: np.ndarray  #: float64 parameter vector passed as ``p`` to every kernel
    n_pose: int
    n_joints: int
    home: np.ndarray | None = None  #: the mechanism's home pose (the default start), if given


def enabled() -> bool:
    """False where numba is missing or ``PARAKIN_KERNELS=0``."""
    if os.environ.get("PARAKIN_KERNELS", "1") == "0":
        return False
    return _have_numba()


@lru_cache(maxsize=1)
def _have_numba() -> bool:
    return importlib.util.find_spec("numba") is not None


def cache_dir() -> Path:
    """Where the generated solver modules (and numba's cache of them) live."""
    env = os.environ.get("PARAKIN_KERNEL_CACHE")
    if env:
        return Path(env)
    base = os.environ.get("XDG_CACHE_HOME") or os.path.join(os.path.expanduser("~"), ".cache")
    return Path(base) / "parakin" / "kernels"


def _source_of(module: str) -> str:
    mod = importlib.import_module(module)
    return inspect.getsource(mod)


@cache
def build(module: str, n_joints: int, n_pose: int) -> ModuleType:
    """The compiled solver loops over the kernels of ``module`` (generated once, then imported).

    The generated file's name carries a hash of the template, the kernel module's source and the
    numba version, so numba's on-disk cache never serves loops compiled against an older kernel
    (numba itself only watches the file a function is defined in)."""
    import numba

    if (
        "NUMBA_THREADING_LAYER" not in os.environ
    ):  # fork-safe (the pipeline forks worker processes);
        numba.config.THREADING_LAYER = (
            "workqueue"  # GNU OpenMP is not. No effect once a layer is running.
        )
    template = (Path(__file__).parent / "_loops.py").read_text()
    batch = []
    for name in (*METHODS, "verify"):
        args = "p, Q, X, flags, err" if name == "verify" else "p, Q, X0, opts, X, info, res"
        body = (
            "err[i] = verify_row(p, Q[i], X[i], flags[i])"
            if name == "verify"
            else f"res[i] = {name}_row(p, Q[i], X0[i], opts, X[i], info[i])"
        )
        if name != "verify":  # one pose, solved and checked in one call (the single-call path)
            batch.append(
                f"@njit(**_O)\ndef {name}_one(p, q, x0, opts, x, info, out):\n"
                "    if not (_finite(q) and _finite(x0)):\n        info[0] = 999\n        return\n"
                f"    out[0] = {name}_row(p, q, x0, opts, x, info)\n"
                "    out[1] = verify_row(p, q, x, info[4:])\n"
            )
        for kind, loop, extra in (
            ("serial", "range", ""),
            ("parallel", "prange", "parallel=True, "),
        ):
            batch.append(
                f"@njit({extra}**_O)\ndef {name}_{kind}({args}):\n"
                f"    for i in {loop}(Q.shape[0]):\n        {body}\n"
            )
    text = (
        template.replace("__KERNEL_MODULE__", module)
        .replace("__M__", str(int(n_joints)))
        .replace("__N__", str(int(n_pose)))
        + "\n\n"
        + "\n\n".join(batch)
    )
    digest = hashlib.sha256((text + _source_of(module) + numba.__version__).encode()).hexdigest()[
        :16
    ]
    name = f"parakin_loops_{module.replace('.', '_')}_{digest}"
    folder = cache_dir()
    folder.mkdir(parents=True, exist_ok=True)
    path = folder / f"{name}.py"
    if not path.exists():  # atomic: concurrent processes may build the same file
        _prune(folder, name.rsplit("_", 1)[0])
        fd, tmp = tempfile.mkstemp(dir=folder, suffix=".tmp")
        with os.fdopen(fd, "w") as fh:
            fh.write(f"# generated by parakin.kernels.build from {module}; do not edit\n" + text)
        os.replace(tmp, path)
    if name in sys.modules:
        return sys.modules[name]
    spec = importlib.util.spec_from_file_location(name, path)
    mod = importlib.util.module_from_spec(spec)
    sys.modules[name] = mod
    spec.loader.exec_module(mod)
    return mod


def _prune(folder: Path, prefix: str) -> None:
    """Remove the loops generated for an older version of a kernel module (and numba's cache of
    them): their hash no longer matches, they would only fill the cache."""
    for old in folder.glob(f"{prefix}_*.py"):
        digest = old.stem[len(prefix) + 1 :]
        if len(digest) != 16 or any(
            c not in "0123456789abcdef" for c in digest
        ):  # another module's
            continue
        for f in [old, *(folder / "__pycache__").glob(f"{old.stem}.*")]:
            try:
                f.unlink()
            except OSError:  # another process got there first, or no permission: harmless
                pass


def kernel_of(mech: Any) -> Kernel | None:
    """``mech.kernel()`` (with its home filled in) where the compiled path is enabled, else None."""
    get = getattr(mech, "kernel", None)
    if get is None or not enabled():
        return None
    k = get()
    if k is not None and k.home is None:
        k = dataclasses.replace(k, home=np.asarray(mech.home(), dtype=float))
    return k


def loops_of(kernel: Kernel) -> ModuleType:
    """The compiled solver loops over ``kernel``'s module (built once, cached on disk)."""
    return build(kernel.module, kernel.n_joints, kernel.n_pose)


def use_parallel(n: int, parallel: bool | None) -> bool:
    """Whether a batch of ``n`` rows runs on the prange driver: large batches, from the main thread
    only (numba's ``workqueue`` layer, chosen in :func:`build` because it is fork-safe, must not be
    entered from two threads at once; other threads get the serial driver, same results)."""
    if parallel is None:
        parallel = n >= PARALLEL_MIN_ROWS
    return parallel and threading.current_thread() is threading.main_thread()


def verify_hooks(mech: Any, joints: np.ndarray, x: np.ndarray, *, parallel: bool | None = None):
    """``(in_domain, joint_error, on_assembly)`` of the flat rows by the compiled kernels, or
    ``None`` without a kernel: what :func:`parakin.solvers.verify.verify` otherwise asks the
    mechanism's numpy methods. ``joint_error`` is inf outside the domain, ``on_assembly`` False."""
    kernel = kernel_of(mech)
    if kernel is None:
        return None
    loops = loops_of(kernel)
    n = len(joints)
    flags = np.zeros((n, 2), dtype=np.int64)
    err = np.empty(n)
    use_par = use_parallel(n, parallel)
    fn = loops.verify_parallel if use_par else loops.verify_serial
    fn(
        kernel.params,
        np.ascontiguousarray(joints, dtype=float),
        np.ascontiguousarray(x, dtype=float),
        flags,
        err,
    )
    return flags[:, 0] == 1, err, flags[:, 1] == 1
