"""One source per mechanism: its kernels, run by numba (one pose), numpy and torch (batches).

A mechanism opts in by returning a :class:`Kernel` from ``Mechanism.kernel()``: the name of a
module of five functions for **one** pose (``residual(p, x, q, out)``, ``jacobian(p, x, q, out)``,
``ik(p, x, out) -> ok``, ``in_domain(p, x) -> ok``, ``on_assembly(p, x, q) -> ok``), written once,
elementwise and branch-free in the names of :mod:`parakin.kernels._math`, and the parameter
vector ``p`` they read. The same functions serve three paths (docs/kernels.md):

* :func:`evaluate`: the batched numpy API (the module as imported; the batch on the trailing
  axis), what the mechanisms' ``residual``, ``jacobian_pose``, ``ik``, ... methods call;
* :func:`compiled` / :func:`build`: the functions under ``numba.njit``, and compiled Newton,
  Levenberg-Marquardt, Broyden and BFGS loops over them (the template ``_loops.py``, written with
  the kernel module's name into the kernel cache and compiled with ``cache=True``, so the compile
  cost is paid once per machine, not per process), each in a serial and a ``prange``-parallel
  driver that run the same per-row code (identical results);
* :func:`torch_kernel`: the functions on torch tensors (CPU or CUDA), the residual and analytic
  Jacobian of :mod:`parakin.solvers.torch_newton`.

:func:`solve` is what :func:`parakin.solvers.solve_fk` calls first: it returns ``None`` (use the
generic numpy path) for a mechanism without a kernel, a method without a compiled loop, an
option the loop does not take, a callback, or where numba is not installed. Numba (and torch)
are imported only here, lazily: the kernel modules import without them.

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

from parakin.kernels import _math

__all__ = [
    "Kernel",
    "build",
    "cache_dir",
    "compiled",
    "enabled",
    "evaluate",
    "solve",
    "torch_kernel",
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
    #: False: the numpy and torch paths only (``solve_fk`` keeps the generic numpy solvers)
    compiled: bool = True


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


#: the kernels' own numba options: no on-disk cache of their own (numba would key it on the kernel
#: file alone and serve a stale build after a change to ``_math.py``); the cached loops hold them
_NJIT = dict(cache=False, error_model="numpy", nogil=True)


@cache
def compiled(module: str) -> ModuleType:
    """The kernel functions of ``module`` under ``numba.njit`` (one pose, scalar math): a module
    registered in ``sys.modules`` as ``_parakin_numba_<module>``, which the generated loops
    import. The generated loops (``cache=True``, keyed on the hash of every source) keep them
    compiled on disk. A module not written with :func:`parakin.kernels._math.kernel` (its own
    ``numba.njit`` functions, compiled path only) is returned as it is."""
    import numba

    source = importlib.import_module(module)
    if not one_source(module):  # a module of numba.njit functions of its own: used as it is
        return source
    ns = _math.rebind(source, _math.numba_names(numba.njit), numba.njit(**_NJIT))
    name = "_parakin_numba_" + module.replace(".", "_")
    mod = ModuleType(name, f"numba kernels of {module}")
    mod.__dict__.update(vars(ns))
    sys.modules[name] = mod
    return mod


#: batches up to this size run row by row on Python floats (:func:`_scalar_namespace`): a
#: vectorised call costs ~1 us per numpy operation whatever the size, a scalar row ~50 ns
SCALAR_MAX_ROWS = 4


@cache
def one_source(module: str) -> bool:
    """Whether kernel ``module`` is written once for numba, numpy and torch (its functions marked
    with :func:`parakin.kernels._math.kernel`), not as ``numba.njit`` functions only."""
    mod = importlib.import_module(module)
    return any(getattr(f, "__parakin_kernel__", False) for f in vars(mod).values())


@cache
def _numpy_module(module: str) -> ModuleType:
    return importlib.import_module(module)


@cache
def _scalar_namespace(module: str) -> Any:
    """The kernels on Python floats (``math`` functions, the scalar ``where`` / ``maximum`` that
    numba compiles, uncompiled): the same IEEE operations as the numpy and numba runs."""
    return _math.rebind(importlib.import_module(module), _math.scalar_names())


def evaluate(kernel: Kernel, name: str, pose: np.ndarray, joints: np.ndarray | None = None):
    """Kernel function ``name`` of ``kernel`` on a numpy batch: ``pose (..., n)`` (and ``joints
    (..., m)``, broadcast against it) in, the batch moved to the trailing axis, one vectorised
    call of the very function numba compiles, and back. Returns ``(..., m)`` for ``residual``,
    ``(..., m, n)`` for ``jacobian``, ``(values (..., m), ok (...))`` for ``ik`` and the mask
    ``(...)`` for ``in_domain`` / ``on_assembly``. Floating-point warnings are silenced: NaN
    marks a pose outside the domain, as in the compiled path."""
    fn = getattr(_numpy_module(kernel.module), name)
    x = np.asarray(pose, dtype=float)
    batch = x.shape[:-1]
    if joints is not None:
        q = np.asarray(joints, dtype=float)
        batch = np.broadcast_shapes(batch, q.shape[:-1])
        qt = np.ascontiguousarray(
            np.broadcast_to(q, batch + q.shape[-1:]).reshape(-1, q.shape[-1]).T
        )
    xt = np.ascontiguousarray(np.broadcast_to(x, batch + x.shape[-1:]).reshape(-1, x.shape[-1]).T)
    size = xt.shape[1]
    p = kernel.params.tolist()
    m, n = kernel.n_joints, kernel.n_pose
    if size <= SCALAR_MAX_ROWS:
        try:
            return _evaluate_rows(kernel, name, xt, qt if joints is not None else None, p, batch)
        except (ArithmeticError, ValueError):  # x / 0, sin(inf): numpy's inf / NaN instead
            pass
    with np.errstate(all="ignore"):
        if name == "residual":
            out = np.empty((m, size))
            fn(p, xt, qt, out)
            return np.ascontiguousarray(out.T).reshape(batch + (m,))
        if name == "jacobian":
            out = np.empty((m, n, size))
            fn(p, xt, qt, out)
            return np.ascontiguousarray(np.moveaxis(out, -1, 0)).reshape(batch + (m, n))
        if name == "ik":
            out = np.empty((m, size))
            ok = fn(p, xt, out)
            values = np.ascontiguousarray(out.T).reshape(batch + (m,))
            return values, np.array(np.broadcast_to(ok, (size,)), dtype=bool).reshape(batch)
        ok = fn(p, xt, qt) if name == "on_assembly" else fn(p, xt)
        return np.array(np.broadcast_to(ok, (size,)), dtype=bool).reshape(batch)


def _evaluate_rows(kernel: Kernel, name: str, xt: np.ndarray, qt: Any, p: list, batch: tuple):
    """:func:`evaluate` of a few rows, one at a time on Python floats."""
    fn = getattr(_scalar_namespace(kernel.module), name)
    m, n = kernel.n_joints, kernel.n_pose
    size = xt.shape[1]
    xs = xt.T.tolist()
    qs = qt.T.tolist() if qt is not None else None
    shape = {"residual": (m,), "jacobian": (m, n), "ik": (m,)}.get(name, ())
    out = np.empty((size, *shape))
    ok = np.ones(size, dtype=bool)
    for r in range(size):
        if name in ("residual", "jacobian"):
            fn(p, xs[r], qs[r], out[r])
        elif name == "ik":
            ok[r] = fn(p, xs[r], out[r])
        elif name == "on_assembly":
            ok[r] = fn(p, xs[r], qs[r])
        else:
            ok[r] = fn(p, xs[r])
    if shape:
        out = out.reshape(batch + shape)
    if name == "ik":
        return out, ok.reshape(batch)
    return out if shape else ok.reshape(batch)


class _Slots:
    """Where a torch kernel writes ``out[i]`` / ``out[i, j]``: kept, then stacked (no in-place
    writes, so ``torch.func`` transforms compose with the kernel)."""

    def __init__(self) -> None:
        self.values: dict[Any, Any] = {}

    def __setitem__(self, key: Any, value: Any) -> None:
        self.values[key] = value

    def stack(self, shape: tuple[int, ...], like: Any) -> Any:
        import torch

        keys = list(np.ndindex(*shape)) if len(shape) > 1 else list(range(shape[0]))
        vals = [self.values[k] for k in keys]
        vals = [
            v
            if isinstance(v, torch.Tensor)
            else torch.tensor(v, dtype=like.dtype, device=like.device)
            for v in vals
        ]
        out = torch.stack(torch.broadcast_tensors(*vals), dim=-1)
        return out.reshape(*out.shape[:-1], *shape)


def torch_kernel(kernel: Kernel) -> tuple[Any, Any]:
    """``(residual, jacobian)`` of ``kernel`` on torch tensors: ``residual(pose (..., n), joints
    (..., m)) -> (..., m)``, ``jacobian(pose, joints) -> (..., m, n)`` (the analytic
    ``jacobian_pose``), on the device and in the dtype of ``pose``, from the same source as the
    numpy and numba paths. Compose with ``torch.func`` (vmap, jacrev, jacfwd). Needs torch.
    NotImplementedError for a kernel module that is not :func:`one_source`."""
    if not one_source(kernel.module):
        raise NotImplementedError(
            f"kernel module {kernel.module} is numba-only (not written in the names of "
            "parakin.kernels._math): no torch version"
        )
    ns = _torch_namespace(kernel.module)
    p = tuple(float(v) for v in kernel.params)
    m, n = kernel.n_joints, kernel.n_pose

    def residual(pose: Any, joints: Any) -> Any:
        out = _Slots()
        ns.residual(p, pose.movedim(-1, 0), joints.movedim(-1, 0), out)
        return out.stack((m,), pose)

    def jacobian(pose: Any, joints: Any) -> Any:
        out = _Slots()
        ns.jacobian(p, pose.movedim(-1, 0), joints.movedim(-1, 0), out)
        return out.stack((m, n), pose)

    return residual, jacobian


@cache
def _torch_namespace(module: str) -> Any:
    import torch

    return _math.rebind(importlib.import_module(module), _math.torch_names(torch))


def compiled_name(module: str) -> str:
    """The module the generated loops import the numba kernels of ``module`` from (registered
    by :func:`compiled`, which :func:`build` calls first)."""
    return compiled(module).__name__


def _source_of(module: str) -> str:
    mod = importlib.import_module(module)
    return inspect.getsource(mod)


@cache
def build(module: str, n_joints: int, n_pose: int) -> ModuleType:
    """The compiled solver loops over the kernels of ``module`` (generated once, then imported).

    The generated file's name carries a hash of the template, the kernel module's source (and
    :mod:`parakin.kernels._math`'s) and the numba version, so numba's on-disk cache never serves
    loops compiled against an older kernel (numba itself only watches the file a function is
    defined in). The loops import the kernels from :func:`compiled`'s module."""
    import numba

    name, text = _generated(module, n_joints, n_pose, numba.__version__)
    if (
        "NUMBA_THREADING_LAYER" not in os.environ
    ):  # fork-safe (the pipeline forks worker processes);
        numba.config.THREADING_LAYER = (
            "workqueue"  # GNU OpenMP is not. No effect once a layer is running.
        )
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


def _generated(module: str, n_joints: int, n_pose: int, numba_version: str) -> tuple[str, str]:
    """The name and text of the loops module generated for ``module``: the name ends in a hash of
    the text, the kernel sources and the numba version."""
    template = (Path(__file__).parent / "_loops.py").read_text()
    # name -> (driver arguments, body for row i): a serial and a prange-parallel driver each
    pso = "p, Q, X, V, PB, PF, GB, GF, RND, W, k0, lo, hi, vmax, coef, STATE, HIST"
    drivers = {
        **{
            name: (
                "p, Q, X0, opts, X, info, res",
                f"res[i] = {name}_row(p, Q[i], X0[i], opts, X[i], info[i])",
            )
            for name in METHODS
        },
        "verify": ("p, Q, X, flags, err", "err[i] = verify_row(p, Q[i], X[i], flags[i])"),
        "pso": (
            pso,
            "pso_row(" + ", ".join(a + "[i]" if a.isupper() else a for a in pso.split(", ")) + ")",
        ),
    }
    batch = []
    for name, (args, body) in drivers.items():
        if name in METHODS:  # one pose, solved and checked in one call (the single-call path)
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
        template.replace("__KERNEL_MODULE__", compiled_name(module))
        .replace("__M__", str(int(n_joints)))
        .replace("__N__", str(int(n_pose)))
        + "\n\n"
        + "\n\n".join(batch)
    )
    kernel_source = _source_of(module) + _source_of(_math.__name__)
    digest = hashlib.sha256((text + kernel_source + numba_version).encode()).hexdigest()[:16]
    return f"parakin_loops_{module.replace('.', '_')}_{int(n_joints)}x{int(n_pose)}_{digest}", text


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
    if k is not None and not k.compiled:
        return None
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
