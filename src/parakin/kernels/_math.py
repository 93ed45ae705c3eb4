"""The math names the mechanisms' one-source kernels are written in, their bindings, and the named
slots of a kernel's parameter vector.

A kernel module (:mod:`parakin.kernels.p3p4s`, ...) writes each equation once, elementwise and
branch-free, with the names of :data:`TABLE` (``sqrt``, ``sin``, ``cos``, ``atan2``, ``acos``,
``asin``, ``floor``, ``where``, ``maximum``), ``pi``, ``nan``, plain operators and ``abs``,
indexing ``x[k]``, ``q[k]``, ``p[k]`` and writing ``out[i]`` / ``out[i, j]``. The same function then
runs three ways (see docs/kernels.md):

* **numpy, batched** (the module as imported, the names bound here to numpy's ufuncs): ``x`` has
  shape ``(n_pose, N)``, ``out`` ``(m, N)`` or ``(m, n, N)``, the batch on the trailing axis;
  this is what the mechanisms' numpy methods call;
* **numba, one pose** (:func:`rebind` with :func:`numba_names` and ``njit``): ``x[k]`` a float,
  the compiled solver loops' kernels;
* **torch** (:func:`rebind` with :func:`torch_names`), batched like numpy, on CPU or CUDA: the
  GPU solver's residual and Jacobian.

Each name is one row of :data:`TABLE`: its numpy, Python-float, numba and torch binding side by
side, so a new function is one new row (nothing else here changes).

Branches on values do not vectorise: a kernel writes them as masks (``ok & (d >= 0)``) and
``where(ok, value, nan)``, which numba compiles on scalars as well. A branch on a *parameter*
(``if p[KIND] == 2.0:``) is fine on every backend: ``p`` holds plain floats.

:class:`Layout` names the slots of ``p``: a kernel module declares ``PARAMS = Layout(base=(3, 2),
...)`` and reads ``p[PARAMS.base + 2 * i]`` (module-level integer offsets, which numba freezes as
constants); its mechanism returns ``PARAMS.pack(base=..., ...)``, which checks every name and
shape once, where the vector is made.
"""

from __future__ import annotations

import math
import sys
import types
from collections.abc import Callable, Iterable, Mapping
from typing import Any, NamedTuple

import numpy as np

__all__ = [
    "Layout",
    "TABLE",
    "kernel",
    "nan",
    "numba_names",
    "pi",
    "rebind",
    "scalar_names",
    "torch_names",
]

pi = math.pi
nan = math.nan


def _scalar_where(c, a, b):
    return a if c else b


def _scalar_maximum(a, b):
    return a if (a >= b or a != a) else b  # NaN propagates, as np.maximum


def _scalar_sqrt(a):
    return math.sqrt(a) if a >= 0 else nan  # NaN, as numpy's, not ValueError


def _scalar_acos(a):
    return math.acos(a) if -1.0 <= a <= 1.0 else nan


def _scalar_asin(a):
    return math.asin(a) if -1.0 <= a <= 1.0 else nan


def _scalar_floor(a):
    return float(math.floor(a)) if math.isfinite(a) else a  # a float, as np.floor; inf, NaN kept


#: a binding compiled by numba as a small inline function of its own (not a ``math`` function)
_INLINE = "inline"


class Row(NamedTuple):
    """One math name on every backend: numpy's ufunc (batches), the same on Python floats (a few
    rows at a time), what numba compiles (``_INLINE``: the Python-float function, ``njit``-ed
    inline) and the torch function (a name of ``torch`` or a function of the torch module)."""

    numpy: Callable[..., Any]
    scalar: Callable[..., Any]
    numba: Any
    torch: str | Callable[[Any], Callable[..., Any]]


#: every math name a kernel may use, one row each
TABLE: dict[str, Row] = {
    "sqrt": Row(np.sqrt, _scalar_sqrt, math.sqrt, "sqrt"),
    "sin": Row(np.sin, math.sin, math.sin, "sin"),
    "cos": Row(np.cos, math.cos, math.cos, "cos"),
    "atan2": Row(np.arctan2, math.atan2, math.atan2, "atan2"),
    "acos": Row(np.arccos, _scalar_acos, math.acos, "acos"),
    "asin": Row(np.arcsin, _scalar_asin, math.asin, "asin"),
    "floor": Row(np.floor, _scalar_floor, np.floor, "floor"),
    "where": Row(np.where, _scalar_where, _INLINE, "where"),
    # torch.maximum wants two tensors; a kernel's bound is a number: clamp
    "maximum": Row(
        np.maximum, _scalar_maximum, _INLINE, lambda torch: lambda a, b: torch.clamp(a, min=b)
    ),
}

#: the names a backend rebinds (every other global of a kernel module is shared)
NAMES = tuple(TABLE)

# the numpy binding: a kernel module called directly computes on (..., N) arrays
globals().update({name: row.numpy for name, row in TABLE.items()})
__all__ += list(TABLE)


def kernel(fn: Callable[..., Any]) -> Callable[..., Any]:
    """Mark ``fn`` as a kernel function (no other effect): :func:`rebind` re-creates every
    marked function of a module, private helpers included, in the backend's namespace."""
    fn.__parakin_kernel__ = True  # type: ignore[attr-defined]
    return fn


def scalar_names() -> dict[str, Any]:
    """The names on Python floats (what numba compiles, uncompiled): a few rows, one at a time."""
    return {name: row.scalar for name, row in TABLE.items()}


def numba_names(njit: Callable[..., Any]) -> dict[str, Any]:
    """Scalar versions of :data:`NAMES` that numba compiles (``where`` and ``maximum`` as small
    ``njit`` functions, which LLVM inlines)."""
    return {
        name: njit(inline="always")(row.scalar) if row.numba == _INLINE else row.numba
        for name, row in TABLE.items()
    }


def torch_names(torch: Any) -> dict[str, Any]:
    """torch versions of :data:`NAMES`."""
    return {
        name: getattr(torch, row.torch) if isinstance(row.torch, str) else row.torch(torch)
        for name, row in TABLE.items()
    }


def rebind(
    module: types.ModuleType,
    names: dict[str, Any],
    wrap: Callable[[Callable[..., Any]], Any] = lambda f: f,
) -> types.SimpleNamespace:
    """Every :func:`kernel` function of ``module`` re-created over a copy of its globals with
    ``names`` bound in, each passed through ``wrap`` (e.g. ``numba.njit(...)``). The copies call
    each other through that namespace, so helpers follow their callers onto the backend. A
    function ``module`` takes from another kernel module (the 6-6's leg equations are the 3-6's)
    keeps that module's constants (its parameter offsets): their globals come first, ``module``'s
    own override them."""
    glob: dict[str, Any] = {}
    for fn in vars(module).values():
        if getattr(fn, "__parakin_kernel__", False) and fn.__module__ != module.__name__:
            source = sys.modules.get(fn.__module__)
            if source is not None:
                glob.update(vars(source))
    glob.update(vars(module))
    glob.update(names)
    out = {}
    for key, fn in vars(module).items():
        if not getattr(fn, "__parakin_kernel__", False):
            continue
        new = types.FunctionType(fn.__code__, glob, fn.__name__, fn.__defaults__, fn.__closure__)
        new.__qualname__, new.__module__, new.__doc__ = fn.__qualname__, fn.__module__, fn.__doc__
        glob[key] = out[key] = wrap(new)
    return types.SimpleNamespace(**out)


# ---------------------------------------------------------------------------- named parameters
class Layout:
    """The named slots of a kernel's parameter vector ``p``, in order: each a scalar (``1``) or a
    block of a given shape (``(3, 2)``: three points of two coordinates, row by row).

    ``Layout(base=(3, 2), platform=(3, 2), home_sign=1)``: ``layout.base`` is the offset of
    ``base`` in ``p`` (an ``int``; a kernel module binds it to a module constant, which numba
    freezes), ``layout.size`` the length of ``p``, and :meth:`pack` makes ``p`` from values given
    by name, checking each name and shape. A layout with a ``record`` (another :class:`Layout`) is
    followed by any number of such records (one per leg, say): record ``i`` starts at
    ``layout.size + i * record.size``.
    """

    def __init__(self, record: Layout | None = None, **fields: int | tuple[int, ...]) -> None:
        self.record = record
        self.fields: dict[str, tuple[int, tuple[int, ...]]] = {}
        offset = 0
        for name, shape in fields.items():
            dims = (shape,) if isinstance(shape, int) else tuple(shape)
            if not dims or any(not isinstance(d, int) or d < 1 for d in dims):
                raise ValueError(f"parameter {name!r}: shape {shape!r} must be positive integers")
            self.fields[name] = (offset, () if dims == (1,) else dims)
            offset += math.prod(dims)
        self.size = offset

    def __getattr__(self, name: str) -> int:
        fields = self.__dict__.get("fields", {})
        if name in fields:
            return fields[name][0]
        raise AttributeError(f"no kernel parameter {name!r}; declared: {', '.join(fields)}")

    def __repr__(self) -> str:
        parts = [f"{k}={s or 1}" for k, (_, s) in self.fields.items()]
        more = f", record={self.record!r}" if self.record is not None else ""
        return f"Layout({', '.join(parts)}{more})"

    def pack(self, records: Iterable[Mapping[str, Any]] | None = None, **values: Any) -> np.ndarray:
        """``p`` (float64, 1-D) from ``values`` by name (and, for a layout with a record, one
        mapping of the record's values per record). Every declared name must be given with its
        declared shape, and no other: a ValueError names the first that is not."""
        given, declared = set(values), set(self.fields)
        if given != declared:
            missing, extra = sorted(declared - given), sorted(given - declared)
            raise ValueError(
                "kernel parameters "
                + "; ".join(
                    part
                    for part in (
                        f"missing {missing}" if missing else "",
                        f"unknown {extra}" if extra else "",
                    )
                    if part
                )
                + f" (declared: {', '.join(self.fields)})"
            )
        parts = []
        for name, (_, shape) in self.fields.items():
            a = np.asarray(values[name], dtype=float)
            if a.shape != shape:
                raise ValueError(
                    f"kernel parameter {name!r} must have shape {shape or '()'}, got {a.shape}"
                )
            parts.append(a.ravel())
        if (records is None) != (self.record is None):
            raise ValueError("records are given exactly where the layout declares a record")
        if records is not None:
            parts += [self.record.pack(**r) for r in records]  # type: ignore[union-attr]
        return np.concatenate(parts) if parts else np.zeros(0)

    def check(self, p: np.ndarray) -> None:
        """A ValueError unless ``p`` has this layout's length (plus whole records)."""
        n = len(p)
        whole = n == self.size
        if self.record is not None and n >= self.size:
            whole = (n - self.size) % self.record.size == 0
        if not whole:
            per = f" + k x {self.record.size}" if self.record is not None else ""
            raise ValueError(f"kernel parameter vector has {n} values, its layout {self.size}{per}")
