"""The math names the mechanisms' one-source kernels are written in, and their three bindings.

A kernel module (:mod:`parakin.kernels.p3p4s`, ...) writes each equation once, elementwise and
branch-free, with the names below (``sqrt``, ``sin``, ``cos``, ``where``, ``maximum``, ``pi``,
``nan``, plain operators and ``abs``), indexing ``x[k]``, ``q[k]``, ``p[k]`` and writing
``out[i]`` / ``out[i, j]``. The same function then runs three ways (see docs/kernels.md):

* **numpy, batched** (the module as imported, the names bound here to numpy's ufuncs): ``x`` has
  shape ``(n_pose, N)``, ``out`` ``(m, N)`` or ``(m, n, N)``, the batch on the trailing axis;
  this is what the mechanisms' numpy methods call;
* **numba, one pose** (:func:`rebind` with :func:`numba_names` and ``njit``): ``x[k]`` a float,
  the compiled solver loops' kernels;
* **torch** (:func:`rebind` with :func:`torch_names`), batched like numpy, on CPU or CUDA: the
  GPU solver's residual and Jacobian.

Branches on values do not vectorise: a kernel writes them as masks (``ok & (d >= 0)``) and
``where(ok, value, nan)``, which numba compiles on scalars as well.
"""

from __future__ import annotations

import math
import types
from collections.abc import Callable
from typing import Any

import numpy as np

__all__ = [
    "cos",
    "kernel",
    "maximum",
    "nan",
    "numba_names",
    "pi",
    "rebind",
    "scalar_names",
    "sin",
    "sqrt",
    "torch_names",
    "where",
]

pi = math.pi
nan = math.nan
# the numpy binding: a kernel module called directly computes on (..., N) arrays
sqrt = np.sqrt
sin = np.sin
cos = np.cos
where = np.where
maximum = np.maximum

#: the names a backend rebinds (every other global of a kernel module is shared)
NAMES = ("sqrt", "sin", "cos", "where", "maximum")


def kernel(fn: Callable[..., Any]) -> Callable[..., Any]:
    """Mark ``fn`` as a kernel function (no other effect): :func:`rebind` re-creates every
    marked function of a module, private helpers included, in the backend's namespace."""
    fn.__parakin_kernel__ = True  # type: ignore[attr-defined]
    return fn


def _scalar_where(c, a, b):
    return a if c else b


def _scalar_maximum(a, b):
    return a if (a >= b or a != a) else b  # NaN propagates, as np.maximum


def scalar_names() -> dict[str, Any]:
    """The names on Python floats (what numba compiles, uncompiled): a few rows, one at a time."""
    return {
        "sqrt": _scalar_sqrt,
        "sin": math.sin,
        "cos": math.cos,
        "where": _scalar_where,
        "maximum": _scalar_maximum,
    }


def _scalar_sqrt(a):
    return math.sqrt(a) if a >= 0 else nan  # NaN, as numpy's, not ValueError


def numba_names(njit: Callable[..., Any]) -> dict[str, Any]:
    """Scalar versions of :data:`NAMES` that numba compiles (``where`` and ``maximum`` as small
    ``njit`` functions, which LLVM inlines)."""
    return {
        "sqrt": math.sqrt,
        "sin": math.sin,
        "cos": math.cos,
        "where": njit(inline="always")(_scalar_where),
        "maximum": njit(inline="always")(_scalar_maximum),
    }


def torch_names(torch: Any) -> dict[str, Any]:
    """torch versions of :data:`NAMES` (``maximum(a, b)`` with a number ``b``: ``clamp``)."""
    return {
        "sqrt": torch.sqrt,
        "sin": torch.sin,
        "cos": torch.cos,
        "where": torch.where,
        "maximum": lambda a, b: torch.clamp(a, min=b),
    }


def rebind(
    module: types.ModuleType,
    names: dict[str, Any],
    wrap: Callable[[Callable[..., Any]], Any] = lambda f: f,
) -> types.SimpleNamespace:
    """Every :func:`kernel` function of ``module`` re-created over a copy of its globals with
    ``names`` bound in, each passed through ``wrap`` (e.g. ``numba.njit(...)``). The copies call
    each other through that namespace, so helpers follow their callers onto the backend."""
    glob = dict(vars(module))
    glob.update(names)
    out = {}
    for key, fn in vars(module).items():
        if not getattr(fn, "__parakin_kernel__", False):
            continue
        new = types.FunctionType(fn.__code__, glob, fn.__name__, fn.__defaults__, fn.__closure__)
        new.__qualname__, new.__module__, new.__doc__ = fn.__qualname__, fn.__module__, fn.__doc__
        glob[key] = out[key] = wrap(new)
    return types.SimpleNamespace(**out)
