"""One source per mechanism: its kernels, run by numba (one pose), numpy and torch (batches).

A mechanism declares its kernel module (``Mechanism.kernels``) and its parameter vector
(``Mechanism.kernel_params()``); :meth:`~parakin.mechanisms.base.Mechanism.kernel` returns the
:class:`Kernel` of an instance. The module holds five functions for **one** pose
(``residual(p, x, q, out)``, ``jacobian(p, x, q, out)``, ``ik(p, x, out) -> ok``,
``in_domain(p, x) -> ok``, ``on_assembly(p, x, q) -> ok``, and optionally
``joint_period(p, k)``: 2 pi for a revolute joint, whose errors are then taken modulo a turn),
written once, elementwise and branch-free in the names of :mod:`parakin.kernels._math`; its
parameter vector may be named (``PARAMS``, a :class:`parakin.kernels._math.Layout`). The same functions serve three paths
(docs/kernels.md):

* :func:`evaluate`: the batched numpy API (the module as imported, the batch on the trailing
  axis), what the mechanisms' ``residual``, ``jacobian_pose``, ``ik``, ... methods call;
* :func:`compiled` / :func:`entries_of`: the functions under ``numba.njit``, and the solver loops
  of :mod:`parakin.kernels.drivers` (Newton, Levenberg-Marquardt, Broyden, BFGS, verification,
  particle swarm; written once for every mechanism, the kernel passed as their first arguments)
  compiled over them, serial loops over a batch's rows that run on every core as blocks on
  threads (:mod:`parakin.kernels.threads`: identical results whatever the thread count), cached
  on disk under a hash of every source that went in (:mod:`parakin.kernels.store`);
* :func:`torch_kernel`: the functions on torch tensors (CPU or CUDA), the residual and analytic
  Jacobian of :mod:`parakin.solvers.torch_newton`.

Nothing compiled is imported with this package: numba is imported, and a loop loaded or compiled,
on the first solve that asks for it. :func:`enabled` says whether the compiled path is on: numba
installed, ``PARAKIN_KERNELS`` not ``0``, a writable cache (:func:`parakin.kernels.store.root`),
and not inside :func:`interpreted` (a short command whose solve costs less than loading compiled
code, e.g. ``parakin fk`` of a few inputs, runs the same kernels on numpy).
"""

from __future__ import annotations

import contextvars
import dataclasses
import importlib.util
import os
import sys
import time
import types
from collections.abc import Iterator
from contextlib import contextmanager
from functools import cache, lru_cache
from typing import Any

import numpy as np

from parakin.kernels import _math, methods, threads
from parakin.kernels import store as _store

__all__ = [
    "SCALAR_MAX_ROWS",
    "Kernel",
    "compiled",
    "enabled",
    "entries_of",
    "evaluate",
    "interpreted",
    "kernel_of",
    "load_seconds",
    "torch_kernel",
    "use_interpreted",
    "verify_hooks",
]

#: batches up to this size run row by row on Python floats (:func:`_scalar_namespace`): a
#: vectorised call costs ~1 us per numpy operation whatever the size, a scalar row ~50 ns
SCALAR_MAX_ROWS = 4
#: the kernel functions of a module, in the order the entries bind them (RES, JAC, IK, DOM, ASM)
FUNCTIONS = ("residual", "jacobian", "ik", "in_domain", "on_assembly")


@dataclasses.dataclass(frozen=True, eq=False)
class Kernel:
    """A mechanism's kernels: the module of its one-source functions and its parameters."""

    module: types.ModuleType  #: residual, jacobian, ik, in_domain, on_assembly (one pose)
    params: np.ndarray  #: float64 parameter vector passed as ``p`` to every kernel
    n_pose: int
    n_joints: int
    home: np.ndarray | None = None  #: the mechanism's home pose (the default start), if given

    def __reduce__(self):
        # a module does not pickle: by its import name (a mechanism, and with it a solver's result
        # that holds one, goes to worker processes and into caches)
        fields = (self.params, self.n_pose, self.n_joints, self.home)
        return (_kernel_of_module, (self.module.__name__, *fields))


def _kernel_of_module(module: str, *fields) -> Kernel:
    """A :class:`Kernel` of the kernel module imported by ``module`` name (unpickling)."""
    import importlib

    return Kernel(importlib.import_module(module), *fields)


# ---------------------------------------------------------------------------- is it on?
_INTERPRETED: contextvars.ContextVar[bool] = contextvars.ContextVar("interpreted", default=False)


def enabled() -> bool:
    """Whether the compiled path runs: numba installed, ``PARAKIN_KERNELS`` not ``0``, a writable
    cache directory, and not inside :func:`interpreted`."""
    if os.environ.get("PARAKIN_KERNELS", "1") == "0" or _INTERPRETED.get():
        return False
    return _have_numba() and _store.root() is not None


@contextmanager
def interpreted(on: bool = True) -> Iterator[None]:
    """Inside this block (``on``) the compiled path is off: the same kernels run on numpy. For
    work too small to pay for loading compiled code (0.5-1 s per process, more on a cold cache)."""
    token = _INTERPRETED.set(on or _INTERPRETED.get())
    try:
        yield
    finally:
        _INTERPRETED.reset(token)


def use_interpreted() -> None:
    """Turn the compiled path off for the rest of the current context (``contextvars``: a thread,
    or a command run in its own context, as the CLI does)."""
    _INTERPRETED.set(True)


@lru_cache(maxsize=1)
def _have_numba() -> bool:
    return importlib.util.find_spec("numba") is not None


@cache
def _numba() -> types.ModuleType:
    """numba, with the fork-safe ``workqueue`` threading layer (the pipeline forks worker
    processes; GNU OpenMP is not fork-safe) unless ``NUMBA_THREADING_LAYER`` says otherwise."""
    import numba

    if "NUMBA_THREADING_LAYER" not in os.environ:
        numba.config.THREADING_LAYER = "workqueue"  # no effect once a layer is running
    return numba


def kernel_of(mech: Any) -> Kernel | None:
    """``mech.kernel()`` (with its home filled in) where the compiled path is enabled, else None."""
    get = getattr(mech, "kernel", None)
    if get is None or not enabled():
        return None
    k = get()
    if k is not None and k.home is None:
        k = dataclasses.replace(k, home=np.asarray(mech.home(), dtype=float))
    return k


# ---------------------------------------------------------------------------- numpy and scalars
@cache
def _scalar_namespace(module: types.ModuleType) -> Any:
    """The kernels on Python floats (``math`` functions, the scalar ``where`` / ``maximum`` that
    numba compiles, uncompiled): the same IEEE operations as the numpy and numba runs."""
    return _math.rebind(module, _math.scalar_names())


def _flat(values: Any, batch: tuple[int, ...]) -> np.ndarray:
    """``values (..., k)`` broadcast to ``batch`` and transposed to ``(k, N)`` (contiguous)."""
    a = np.asarray(values, dtype=float)
    return np.ascontiguousarray(np.broadcast_to(a, batch + a.shape[-1:]).reshape(-1, a.shape[-1]).T)


def evaluate(kernel: Kernel, name: str, pose: np.ndarray, joints: np.ndarray | None = None):
    """Kernel function ``name`` of ``kernel`` on a numpy batch: ``pose (..., n)`` (and ``joints
    (..., m)``, broadcast against it) in, the batch moved to the trailing axis, one vectorised
    call of the very function numba compiles, and back. Returns ``(..., m)`` for ``residual``,
    ``(..., m, n)`` for ``jacobian``, ``(values (..., m), ok (...))`` for ``ik`` and the mask
    ``(...)`` for ``in_domain`` / ``on_assembly``. Floating-point warnings are silenced: NaN
    marks a pose outside the domain, as in the compiled path."""
    fn = getattr(kernel.module, name)
    x = np.asarray(pose, dtype=float)
    batch = x.shape[:-1]
    if joints is not None:
        batch = np.broadcast_shapes(batch, np.shape(joints)[:-1])
    qt = None if joints is None else _flat(joints, batch)
    xt = _flat(x, batch)
    size = xt.shape[1]
    p = kernel.params.tolist()
    m, n = kernel.n_joints, kernel.n_pose
    if size <= SCALAR_MAX_ROWS:
        try:
            return _evaluate_rows(kernel, name, xt, qt, p, batch)
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


# ---------------------------------------------------------------------------- torch
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
    numpy and numba paths. Compose with ``torch.func`` (vmap, jacrev, jacfwd). Needs torch."""
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
def _torch_namespace(module: types.ModuleType) -> Any:
    import torch

    return _math.rebind(module, _math.torch_names(torch))


# ---------------------------------------------------------------------------- compiled
#: numba options of the kernels and of the entries (``cache=True``: in the kernel's directory)
_NJIT = dict(cache=True, error_model="numpy", nogil=True)


@cache
def _drivers() -> types.ModuleType:
    """:mod:`parakin.kernels.drivers`, its shared linear algebra cached once per process
    (:data:`parakin.kernels.drivers.SHARED`, :func:`parakin.kernels.store.share_compiled`)."""
    from parakin.kernels import drivers

    _store.share_compiled(drivers.SHARED)
    return drivers


@cache
def _build(module: types.ModuleType) -> tuple[Any, Any]:
    """``(path, hash)`` of the compiled code of kernel ``module``: the directory named by the hash
    of the kernel (and of any kernel module it takes functions from), ``_math``, the drivers, the
    entries and the options table (:func:`parakin.kernels.store.digest`)."""
    from parakin.kernels import entries

    drivers = _drivers()
    sources = {module} | {  # a kernel may take functions from another kernel module
        sys.modules[f.__module__]
        for f in vars(module).values()
        if getattr(f, "__parakin_kernel__", False)
    }
    hash_ = _store.digest(
        *sorted(sources, key=lambda m: m.__name__), _math, drivers, entries, methods
    )
    return _store.kernel_dir(module.__name__, hash_), hash_


@cache
def compiled(module: types.ModuleType) -> Any:
    """The kernel functions of ``module`` under ``numba.njit`` (one pose, scalar math), as a
    namespace; cached on disk in the kernel's directory, tagged as the entries expect
    (:func:`parakin.kernels.store.guard`) whoever compiles them first."""
    numba = _numba()
    path, _ = _build(module)
    with _store.numba_cache(path / "kernel"):
        out = _math.rebind(module, _math.numba_names(numba.njit), numba.njit(**_NJIT))
    for fn in vars(out).values():
        _store.guard(fn, path)
    return out


#: entry groups: name -> (the entries of parakin.kernels.entries compiled in it, its ROW loop)
_GROUPS = {
    **{m: (("serial",), m) for m in methods.COMPILED},
    "verify": (("verify_serial",), None),
    "pso": (("pso_serial",), None),
}


#: seconds this process spent in first calls of compiled entries (loading them from the cache or
#: compiling them), what :func:`load_seconds` reports
_LOAD_SECONDS = [0.0]


def load_seconds() -> float:
    """Seconds this process has spent loading or compiling compiled entries (each entry's first
    call): a solve's share of its wall time is the difference before and after it."""
    return _LOAD_SECONDS[0]


class _Entry:
    """A compiled entry that loads (or compiles) itself on its first call, through
    :func:`parakin.kernels.store.first_call` (an unreadable cache entry is rebuilt); after that
    :attr:`fn` is the numba function itself."""

    def __init__(self, fn: Any, where: Any) -> None:
        self.fn, self.where, self.ready = fn, where, False

    def __call__(self, *args: Any) -> Any:
        if self.ready:
            return self.fn(*args)
        start = time.perf_counter()
        try:
            out = _store.first_call(self.fn, self.where, *args)
        finally:
            _LOAD_SECONDS[0] += time.perf_counter() - start
        self.ready = True
        return out


@cache
def entries_of(module: types.ModuleType, group: str) -> types.SimpleNamespace:
    """The entries of ``group`` (a method of :data:`parakin.kernels.methods.COMPILED`,
    ``"verify"`` or ``"pso"``) compiled over the kernels of ``module``: copies of the functions
    of :mod:`parakin.kernels.entries` with the kernel's functions and the method's loop bound
    (as :func:`parakin.kernels._math.rebind` binds math names), numba-cached in
    ``<kernel dir>/<group>``. Each compiles (or loads) on its first call."""
    from parakin.kernels import entries

    drivers = _drivers()
    numba = _numba()
    names, row = _GROUPS[group]
    kern = compiled(module)
    glob = dict(vars(entries))
    glob.update(zip(("RES", "JAC", "IK", "DOM", "ASM"), (getattr(kern, f) for f in FUNCTIONS)))
    # the joints' periods: a kernel with angle joints declares joint_period(p, k)
    glob["PER"] = getattr(kern, "joint_period", drivers.no_period)
    glob["ROW"] = getattr(drivers, row) if row else None
    glob["KERNEL"] = module.__name__
    path = _build(module)[0]
    where = path / group
    out = {}
    with _store.numba_cache(where):
        for name in names:
            fn = getattr(entries, name)
            copy = types.FunctionType(fn.__code__, glob, fn.__name__, fn.__defaults__)
            # a name of its own per kernel and group: numba names a compiled function by its
            # qualified name and a per-process counter, so two cached copies of one entry built by
            # different processes can carry the same symbol, and a process that loads both links
            # one's calls to the other's (the 3-6's single solves verified by the 6-6's assembly
            # test; the dog leg's single call running Newton's loop, loaded after Newton's)
            kernel_name = module.__name__.replace(".", "_")
            copy.__qualname__ = f"{fn.__qualname__}__{kernel_name}__{group}"
            copy.__module__ = fn.__module__
            glob[name] = numba.njit(**_NJIT)(copy)
            # tagged now, not at its first call: a bare call of the numba function (``.fn``)
            # before that would write untagged files, which every later process refuses
            _store.guard(glob[name], path)
            out[name] = _Entry(glob[name], path)  # an unreadable file: the whole build is rebuilt
    return types.SimpleNamespace(**out)


def verify_hooks(mech: Any, joints: np.ndarray, x: np.ndarray, *, parallel: bool | None = None):
    """``(in_domain, joint_error, on_assembly)`` of the flat rows by the compiled kernels, or
    ``None`` without a kernel: what :func:`parakin.solvers.verify.verify` otherwise asks the
    mechanism's numpy methods. ``joint_error`` is inf outside the domain, ``on_assembly`` False."""
    kernel = kernel_of(mech)
    if kernel is None:
        return None
    group = entries_of(kernel.module, "verify")
    n = len(joints)
    flags = np.zeros((n, 2), dtype=np.int64)
    err = np.empty(n)
    q = np.ascontiguousarray(joints, dtype=float)
    x = np.ascontiguousarray(x, dtype=float)
    threads.rows(
        group.verify_serial, (kernel.params, q, x, flags, err), (1, 2, 3, 4), parallel=parallel
    )
    return flags[:, 0] == 1, err, flags[:, 1] == 1
