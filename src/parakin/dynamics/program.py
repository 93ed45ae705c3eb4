"""Record a batched numpy function of the pose once, as a straight-line program, and replay it compiled.

The dynamics of a mechanism (:mod:`parakin.dynamics.inverse`, :mod:`parakin.dynamics.forward`) is
a fixed sequence of arithmetic on a few hundred numbers per trajectory sample: the jets of
:mod:`parakin.dynamics.jet` evaluated through the mechanism's :meth:`Mechanism.bodies`. In numpy
every one of those operations runs on arrays whose inner axes are 3 long, so Python and numpy's
per-call overhead, not the arithmetic, set the cost: tens of microseconds per sample in a batch,
milliseconds for one sample. :func:`record` runs the *same* function once on symbols instead of
numbers (numpy object arrays of :class:`Symbol`, whose arithmetic appends to a tape), which
yields every scalar operation in order (a Wengert list; Griewank & Walther, *Evaluating
Derivatives*, 2nd ed., SIAM 2008, ch. 2): identical sub-expressions merged, operations on
constants folded, those that cannot change a value (``x * 1``, ``x + 0``, ``x * 0`` for finite
``x``) dropped, unused results removed, a product that only one sum reads computed inside it,
and the values given registers by liveness. A small compiled interpreter
(:func:`parakin.dynamics._kernels.replay`, numba) runs that program over a batch with the samples
innermost (structure of arrays), or over one sample with almost no overhead.

The program computes each output by the same operations in the same order as the numpy
function, so the two agree to rounding (sums over an axis may associate differently, and the
compiled ``sin``, ``cos`` and ``pow`` may differ from numpy's in the last bit). :func:`record`
checks that on a probe before it hands the program out, and returns ``None`` for a function it
cannot record (one that branches on values, calls a function the symbols do not have, or
converts a value to a float): the caller then runs the numpy function itself.
"""

from __future__ import annotations

import functools
import importlib.util
import math
import numbers
import warnings
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass

import numpy as np

Array = np.ndarray

__all__ = ["Symbol", "Program", "record", "NotRecordable", "available"]

# opcodes of the program (what parakin.dynamics._kernels.replay dispatches on)
MUL, ADD, SUB, MULC, ADDC, NEG, SUBC, CSUB, DIV, DIVC, CDIV = range(11)
SQRT, SIN, COS, POW, POWC, INPUT, OUTPUT, SET = range(11, 19)
# fused: a*b + c, a*b - c, c - a*b, a*b + c*e, a*b - c*e, a*k + c, a*k - c, c - a*k
MULADD, MULSUB, SUBMUL, MUL2ADD, MUL2SUB, MULCADD, MULCSUB, SUBMULC = range(19, 27)
#: operations on two registers whose operands commute (merged whatever their order)
_COMMUTATIVE = (MUL, ADD)
#: relative agreement with the numpy function that :func:`record` requires on its probe
PROBE_RTOL = 1e-9


def available() -> bool:
    """False where the compiled path is off (:func:`parakin.kernels.enabled`: numba missing,
    ``PARAKIN_KERNELS=0``, no cache of one's own, or inside :func:`parakin.kernels.interpreted`,
    as a command of a few samples runs): the dynamics then runs its numpy functions, with the
    same numbers."""
    from parakin import kernels

    return kernels.enabled() and _have_numba()


@functools.lru_cache(maxsize=1)
def _have_numba() -> bool:
    return importlib.util.find_spec("numba") is not None


class NotRecordable(TypeError):
    """The function did something with a recorded value that a program cannot do (a branch on
    it, a conversion to a float, a function the symbols do not implement)."""


class Symbol:
    """A scalar value being recorded: the index of the tape entry that computes it.

    Arithmetic with another symbol or a number records an operation (numbers are folded in as
    constants); ``np.sqrt``, ``np.sin``, ``np.cos`` of object arrays call the methods of the same
    name. Anything that would need the value itself (``bool``, ``float``, comparisons) raises
    :class:`NotRecordable`.
    """

    __slots__ = ("tape", "index")

    def __init__(self, tape: _Tape, index: int) -> None:
        self.tape = tape
        self.index = index

    # ------------------------------------------------------------------ arithmetic
    def _with(self, other, op: int, op_constant: int, identity: float):
        """``self op other``: one op of two symbols, or ``op_constant`` with a number (none where
        the number is the op's identity)."""
        if isinstance(other, Symbol):
            return self.tape.binary(op, self, other)
        c = _number(other)
        return self if c == identity else self.tape.with_constant(op_constant, self, c)

    def __add__(self, other):
        return self._with(other, ADD, ADDC, 0.0)

    __radd__ = __add__

    def __sub__(self, other):
        return self._with(other, SUB, SUBC, 0.0)

    def __rsub__(self, other):
        c = _number(other)
        return -self if c == 0.0 else self.tape.with_constant(CSUB, self, c)

    def __mul__(self, other):
        if isinstance(other, Symbol):
            return self.tape.binary(MUL, self, other)
        c = _number(other)
        if c == 0.0:  # exact for a finite value, which every recorded value is
            return 0.0
        if c == 1.0:
            return self
        return -self if c == -1.0 else self.tape.with_constant(MULC, self, c)

    __rmul__ = __mul__

    def __truediv__(self, other):
        return self._with(other, DIV, DIVC, 1.0)

    def __rtruediv__(self, other):
        c = _number(other)
        return 0.0 if c == 0.0 else self.tape.with_constant(CDIV, self, c)

    def __neg__(self):
        return self.tape.unary(NEG, self)

    def __pos__(self):
        return self

    def __pow__(self, other):
        if isinstance(other, Symbol):
            return self.tape.binary(POW, self, other)
        c = _number(other)
        # numpy's own shortcuts for these exponents (np.power): the same values
        if c == 2.0:
            return self * self
        if c == 1.0:
            return self
        if c == 0.5:
            return self.sqrt()
        if c == -1.0:
            return 1.0 / self
        return self.tape.with_constant(POWC, self, c)

    def sqrt(self):
        return self.tape.unary(SQRT, self)

    def sin(self):
        return self.tape.unary(SIN, self)

    def cos(self):
        return self.tape.unary(COS, self)

    # ------------------------------------------------------------------ what a program cannot do
    def _refuse(self, *_args):
        raise NotRecordable(
            "a recorded value was compared or converted (the function branches on values)"
        )

    __bool__ = __float__ = __int__ = __index__ = __complex__ = _refuse
    __lt__ = __le__ = __gt__ = __ge__ = __eq__ = __ne__ = _refuse
    __abs__ = __round__ = __floor__ = __ceil__ = __trunc__ = _refuse
    __hash__ = None  # type: ignore[assignment]


def _number(value) -> float:
    if isinstance(value, numbers.Real):
        return float(value)
    raise NotRecordable(f"cannot combine a recorded value with {type(value).__name__}")


class _Tape:
    """The operations recorded so far: ``(opcode, a, b)`` with register operands (tape indices)
    or, for the ``*C`` opcodes, a constant index ``b``; identical entries are merged."""

    def __init__(self) -> None:
        self.entries: list[tuple[int, int, int]] = []
        self.merged: dict[tuple[int, int, int], int] = {}
        self.constants: list[float] = []
        self.constant_index: dict[str, int] = {}

    def add(self, op: int, a: int, b: int = 0) -> Symbol:
        key = (op, a, b)
        index = self.merged.get(key)
        if index is None:
            index = self.merged[key] = len(self.entries)
            self.entries.append(key)
        return Symbol(self, index)

    def binary(self, op: int, x: Symbol, y: Symbol) -> Symbol:
        if x.tape is not self or y.tape is not self:
            raise NotRecordable("symbols of two recordings combined")
        a, b = x.index, y.index
        if op in _COMMUTATIVE and b < a:
            a, b = b, a
        return self.add(op, a, b)

    def unary(self, op: int, x: Symbol) -> Symbol:
        if op == NEG and self.entries[x.index][0] == NEG:
            return Symbol(self, self.entries[x.index][1])
        return self.add(op, x.index)

    def with_constant(self, op: int, x: Symbol, c: float) -> Symbol:
        return self.add(op, x.index, self.constant(c))

    def constant(self, c: float) -> int:
        """The index of constant ``c`` (finite) in :attr:`constants`."""
        if not math.isfinite(c):
            raise NotRecordable(f"non-finite constant {c!r}")
        key = c.hex()
        k = self.constant_index.get(key)
        if k is None:
            k = self.constant_index[key] = len(self.constants)
            self.constants.append(c)
        return k


# ---------------------------------------------------------------------------------------- program
@dataclass(frozen=True, eq=False)
class Program:
    """A recorded function: ``program(*arrays)`` returns what the function returns (a dict of
    arrays), for inputs ``arrays[i]`` (..., ``widths[i]``) with a common batch shape.

    ``code`` (k, 4) int32 rows ``(opcode, destination, a, b)``; ``constants``; ``registers`` the
    number of scalar registers; ``outputs``: name -> (first column, shape).
    """

    code: Array
    constants: Array
    registers: int
    widths: tuple[int, ...]
    outputs: Mapping[str, tuple[int, tuple[int, ...]]]
    columns: int

    #: samples per pass of the interpreter over the program (its registers fit in the caches)
    CHUNK = 256

    def __call__(self, *arrays: Array) -> dict[str, Array]:
        if len(arrays) != len(self.widths):
            raise ValueError(f"the program takes {len(self.widths)} arrays, got {len(arrays)}")
        arrays = [np.asarray(a, dtype=float) for a in arrays]
        batch = arrays[0].shape[:-1]
        if any(a.shape[:-1] != batch for a in arrays):
            batch = np.broadcast_shapes(*(a.shape[:-1] for a in arrays))
            arrays = [np.broadcast_to(a, batch + a.shape[-1:]) for a in arrays]
        return self.unpack(
            self.run(np.concatenate(arrays, axis=-1).reshape(-1, sum(self.widths))), batch
        )

    def unpack(self, out: Array, batch: tuple[int, ...]) -> dict[str, Array]:
        """The outputs by name, each (*batch, *shape), from :meth:`run`'s columns."""
        return {name: out[:, cols].reshape(batch + shape) for name, cols, shape in self._slices}

    @functools.cached_property
    def _slices(self) -> list[tuple[str, slice, tuple[int, ...]]]:
        return [
            (name, slice(start, start + math.prod(shape)), shape)
            for name, (start, shape) in self.outputs.items()
        ]

    def run(self, inputs: Array) -> Array:
        """The outputs (k, :attr:`columns`) of inputs (k, sum of :attr:`widths`), as columns."""
        from parakin.dynamics._kernels import replay

        # one array type for the compiled replay: a column slice (layout 'A') or a read-only
        # view would each compile it again
        inputs = np.require(inputs, np.float64, ["C", "W"])
        out = np.empty((inputs.shape[0], self.columns))
        replay(self.code, self.constants, inputs, out, self.registers, self.CHUNK)
        return out

    @property
    def size(self) -> int:
        """Number of instructions."""
        return len(self.code)


def _assemble(tape: _Tape, widths: Sequence[int], results: Mapping[str, object]) -> Program:
    """The program that computes ``results`` (name -> object array, batch axis first, of length
    1): dead entries dropped, products fused into the sums that alone read them, registers reused
    after their last use."""
    outputs, stores, column = {}, [], 0  # stores: (column, entry or None, constant)
    for name, value in results.items():
        arr = np.asarray(value, dtype=object)
        if arr.ndim == 0 or arr.shape[0] != 1:
            raise NotRecordable(f"output {name!r} lost the batch axis")
        outputs[name] = (column, arr.shape[1:])
        for item in arr.reshape(-1):
            if isinstance(item, Symbol) and item.tape is not tape:
                raise NotRecordable("an output from another recording")
            symbol = isinstance(item, Symbol)
            stores.append(
                (column, item.index if symbol else None, 0.0 if symbol else _number(item))
            )
            column += 1
    readers = np.zeros(len(tape.entries), dtype=int)  # reads by live entries, and stores
    for _, index, _ in stores:
        if index is not None:
            readers[index] += 1
    for i in range(len(tape.entries) - 1, -1, -1):  # operands precede their results
        if readers[i]:
            for operand in _operands(tape.entries[i]):
                readers[operand] += 1
    code = [(SET, col, tape.constant(value)) for col, index, value in stores if index is None]
    code += _allocate(_fuse(tape.entries, readers), stores)
    rows = np.zeros((len(code), 6), dtype=np.int32)
    for k, row in enumerate(code):
        rows[k, : len(row)] = row
    registers = 1 + max((int(r[1]) for r in code if r[0] not in (OUTPUT, SET)), default=0)
    return Program(
        rows, np.asarray(tape.constants, dtype=float), registers, tuple(widths), outputs, column
    )


def _operands(entry: tuple[int, int, int]) -> tuple[int, ...]:
    """The tape entries that ``entry`` reads."""
    op, a, b = entry
    if op == INPUT:
        return ()
    return (a, b) if op in (MUL, ADD, SUB, DIV, POW) else (a,)


#: fused forms of ``x + y`` and ``x - y`` by which operand is a product read by nothing else:
#: ``(x's kind, y's kind) -> opcode, operand order`` (``"p"``: a product of two registers, ``"c"``: of
#: a register and a constant, ``"r"``: any register; the order lists x's then y's operands)
_FUSED = {
    (ADD, "p", "p"): MUL2ADD,
    (ADD, "p", "r"): MULADD,
    (ADD, "r", "p"): MULADD,
    (ADD, "c", "r"): MULCADD,
    (ADD, "r", "c"): MULCADD,
    (SUB, "p", "p"): MUL2SUB,
    (SUB, "p", "r"): MULSUB,
    (SUB, "r", "p"): SUBMUL,
    (SUB, "c", "r"): MULCSUB,
    (SUB, "r", "c"): SUBMULC,
}


def _fuse(entries: list, readers: Array) -> list[tuple[int, int, tuple[int, ...], tuple[int, ...]]]:
    """The live entries as instructions ``(opcode, entry, register operands, other operands)``,
    in order; a product (of registers, or of a register and a constant) that only one sum or
    difference reads is computed inside it (the same two roundings, one instruction)."""
    fused, absorbed = _fusions(entries, readers)
    out = []
    for i in np.flatnonzero(readers):
        if i in absorbed:
            continue
        op, a, b = entries[i]
        if i in fused:
            out.append((fused[i][0], i, fused[i][1], fused[i][2]))
        elif op == INPUT:
            out.append((op, i, (), (a,)))
        elif op in (MUL, ADD, SUB, DIV, POW):
            out.append((op, i, (a, b), ()))
        elif op in (NEG, SQRT, SIN, COS):
            out.append((op, i, (a,), ()))
        else:  # an operation with a constant
            out.append((op, i, (a,), (b,)))
    return out


def _fusions(entries: list, readers: Array) -> tuple[dict[int, tuple], set[int]]:
    """Which sums and differences take in which products (:data:`_FUSED`): ``{entry: (opcode,
    register operands, constants)}``, and the products so absorbed."""

    def kind(i: int) -> str:
        op = entries[i][0]
        if readers[i] == 1 and op in (MUL, MULC):
            return "p" if op == MUL else "c"
        return "r"

    fused: dict[int, tuple] = {}
    absorbed: set[int] = set()
    for i in np.flatnonzero(readers):
        op, a, b = entries[i]
        if op not in (ADD, SUB):
            continue
        ka, kb = kind(a), kind(b)
        if ka == "c" and kb in "pc" or kb == "c" and ka == "p":  # a constant's product alone
            kb = "r"
        if (op, ka, kb) not in _FUSED:
            continue
        regs, extra = [], []
        # the products' operands first (the opcodes' order), then the other register
        for operand, k in ((a, ka), (b, kb)) if ka != "r" or kb == "r" else ((b, kb), (a, ka)):
            if k == "r":
                regs.append(operand)
                continue
            absorbed.add(operand)
            regs += entries[operand][1:] if k == "p" else entries[operand][1:2]
            extra += () if k == "p" else entries[operand][2:]
        fused[i] = (_FUSED[op, ka, kb], tuple(regs), tuple(extra))
    return fused, absorbed


def _allocate(instructions: list, stores: list) -> list[tuple[int, ...]]:
    """Code rows for ``instructions``: each result in the first free register, a register free
    again after the last instruction that reads it; outputs stored as soon as they are made."""
    columns: dict[int, list[int]] = {}
    for col, index, _ in stores:
        if index is not None:
            columns.setdefault(index, []).append(col)
    last: dict[int, int] = {}
    for k, (_, _, regs, _) in enumerate(instructions):
        for r in regs:
            last[r] = k
    register: dict[int, int] = {}
    free: list[int] = []
    count = 0
    code = []
    for k, (op, entry, regs, extra) in enumerate(instructions):
        operands = [register[r] for r in regs]
        for r in set(regs):
            if last[r] == k:
                free.append(register.pop(r))
        if free:
            dest = free.pop()
        else:
            dest, count = count, count + 1
        code.append((op, dest, *operands, *extra))
        code += [(OUTPUT, col, dest) for col in columns.get(entry, ())]
        if entry in last:
            register[entry] = dest
        else:  # read by no instruction: an output only
            free.append(dest)
    return code


# ---------------------------------------------------------------------------------------- record
def record(fn: Callable[..., Mapping[str, Array]], probe: Sequence[Array]) -> Program | None:
    """Record ``fn(*arrays) -> {name: array}`` (arrays (..., w_i), results (..., *shape),
    elementwise over the batch axes) as a :class:`Program`, or ``None`` when it cannot be
    recorded. ``probe``: one valid input (each (w_i,)); the program must reproduce ``fn`` there
    to :data:`PROBE_RTOL`, else a warning and ``None``."""
    probe = [np.asarray(p, dtype=float).reshape(-1) for p in probe]
    widths = [len(p) for p in probe]
    tape = _Tape()
    symbols, start = [], 0
    for w in widths:
        arr = np.empty((1, w), dtype=object)
        for k in range(w):
            arr[0, k] = tape.add(INPUT, start + k)
        symbols.append(arr)
        start += w
    try:
        with np.errstate(all="ignore"):
            program = _assemble(tape, widths, fn(*symbols))
    except (NotRecordable, TypeError, ValueError, AttributeError, IndexError):
        return None
    expected = fn(*(p[None] for p in probe))
    got = program(*(p[None] for p in probe))
    for name, want in expected.items():
        want = np.asarray(want, dtype=float)
        scale = max(float(np.max(np.abs(want), initial=0.0)), 1e-300)
        if not np.all(np.abs(got[name] - want) <= PROBE_RTOL * scale):
            warnings.warn(
                f"the recorded program differs from numpy on {name!r}; using numpy",
                RuntimeWarning,
                stacklevel=3,
            )
            return None
    return program
