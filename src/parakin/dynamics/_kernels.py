"""Compiled kernels of the dynamics (numba; imported when first needed, so that importing
:mod:`parakin.dynamics` compiles nothing).

* :func:`replay`: the interpreter of :class:`parakin.dynamics.program.Program`. One pass over the
  program per chunk of samples, the samples innermost: every instruction is a short loop over
  contiguous registers (structure of arrays), which the compiler vectorises; one sample is a
  chunk of one. Opcodes: :mod:`parakin.dynamics.program`.
* :func:`forces`: :func:`parakin.dynamics.inverse.solve_forces` sample by sample (a few dozen
  numbers each, where numpy's batched linear algebra spends its time in overhead);
* :func:`accelerations`: the forward dynamics' solve ``M xddot = rhs`` with the condition number of
  ``M``, sample by sample (LAPACK through numba).
"""

from __future__ import annotations

import numpy as np
from numba import njit

from parakin.kernels import (
    store,
)  # numba's cache directory (parakin.kernels.store), set before any @njit

__all__ = ["replay", "forces", "accelerations"]


@njit(cache=True, nogil=True)
def replay(code, constants, inputs, outputs, registers, chunk):  # noqa: C901 (one flat dispatch)
    """Run ``code`` (rows ``opcode, destination, operands...``) on every row of ``inputs``
    (n, columns in), writing ``outputs`` (n, columns out), ``chunk`` rows at a time."""
    n = inputs.shape[0]
    width = max(min(chunk, n), 1)
    reg = np.empty((registers, width))
    for start in range(0, n, width):
        m = min(width, n - start)
        for k in range(code.shape[0]):
            op, d, a, b = code[k, 0], code[k, 1], code[k, 2], code[k, 3]
            if op == 22:  # MUL2ADD: a*b + c*e
                c, e = code[k, 4], code[k, 5]
                for i in range(m):
                    reg[d, i] = reg[a, i] * reg[b, i] + reg[c, i] * reg[e, i]
            elif op == 19:  # MULADD: a*b + c
                c = code[k, 4]
                for i in range(m):
                    reg[d, i] = reg[a, i] * reg[b, i] + reg[c, i]
            elif op == 0:  # MUL
                for i in range(m):
                    reg[d, i] = reg[a, i] * reg[b, i]
            elif op == 3:  # MULC: a*k
                x = constants[b]
                for i in range(m):
                    reg[d, i] = reg[a, i] * x
            elif op == 24:  # MULCADD: a*k + c (b holds c)
                x = constants[code[k, 4]]
                for i in range(m):
                    reg[d, i] = reg[a, i] * x + reg[b, i]
            elif op == 1:  # ADD
                for i in range(m):
                    reg[d, i] = reg[a, i] + reg[b, i]
            elif op == 23:  # MUL2SUB: a*b - c*e
                c, e = code[k, 4], code[k, 5]
                for i in range(m):
                    reg[d, i] = reg[a, i] * reg[b, i] - reg[c, i] * reg[e, i]
            elif op == 20:  # MULSUB: a*b - c
                c = code[k, 4]
                for i in range(m):
                    reg[d, i] = reg[a, i] * reg[b, i] - reg[c, i]
            elif op == 21:  # SUBMUL: c - a*b
                c = code[k, 4]
                for i in range(m):
                    reg[d, i] = reg[c, i] - reg[a, i] * reg[b, i]
            elif op == 25:  # MULCSUB: a*k - c (b holds c)
                x = constants[code[k, 4]]
                for i in range(m):
                    reg[d, i] = reg[a, i] * x - reg[b, i]
            elif op == 26:  # SUBMULC: c - a*k (b holds c)
                x = constants[code[k, 4]]
                for i in range(m):
                    reg[d, i] = reg[b, i] - reg[a, i] * x
            elif op == 2:  # SUB
                for i in range(m):
                    reg[d, i] = reg[a, i] - reg[b, i]
            elif op == 4:  # ADDC: a + k
                x = constants[b]
                for i in range(m):
                    reg[d, i] = reg[a, i] + x
            elif op == 5:  # NEG
                for i in range(m):
                    reg[d, i] = -reg[a, i]
            elif op == 6:  # SUBC: a - k
                x = constants[b]
                for i in range(m):
                    reg[d, i] = reg[a, i] - x
            elif op == 7:  # CSUB: k - a
                x = constants[b]
                for i in range(m):
                    reg[d, i] = x - reg[a, i]
            elif op == 8:  # DIV
                for i in range(m):
                    reg[d, i] = reg[a, i] / reg[b, i]
            elif op == 9:  # DIVC: a / k
                x = constants[b]
                for i in range(m):
                    reg[d, i] = reg[a, i] / x
            elif op == 10:  # CDIV: k / a
                x = constants[b]
                for i in range(m):
                    reg[d, i] = x / reg[a, i]
            elif op == 11:  # SQRT
                for i in range(m):
                    reg[d, i] = np.sqrt(reg[a, i])
            elif op == 12:  # SIN
                for i in range(m):
                    reg[d, i] = np.sin(reg[a, i])
            elif op == 13:  # COS
                for i in range(m):
                    reg[d, i] = np.cos(reg[a, i])
            elif op == 14:  # POW
                for i in range(m):
                    reg[d, i] = reg[a, i] ** reg[b, i]
            elif op == 15:  # POWC: a ** k
                x = constants[b]
                for i in range(m):
                    reg[d, i] = reg[a, i] ** x
            else:
                _transfer(op, d, a, start, m, constants, inputs, outputs, reg)


@njit(inline="always")
def _transfer(op, d, a, start, m, constants, inputs, outputs, reg):
    """Opcodes 16-18: INPUT (register d <- input column a), OUTPUT (output column d <- register
    a), SET (output column d <- constant a)."""
    if op == 16:
        for i in range(m):
            reg[d, i] = inputs[start + i, a]
    elif op == 17:
        for i in range(m):
            outputs[start + i, d] = reg[a, i]
    else:
        x = constants[a]
        for i in range(m):
            outputs[start + i, d] = x


@njit(cache=True, nogil=True)
def _invert(g, inv):
    """``inv = g^-1`` by Gauss-Jordan elimination with partial pivoting; False when a pivot
    vanishes (the caller falls back to a pseudo-inverse)."""
    k = g.shape[0]
    a = g.copy()
    for i in range(k):
        for j in range(k):
            inv[i, j] = 1.0 if i == j else 0.0
    for col in range(k):
        p = col
        for r in range(col + 1, k):
            if abs(a[r, col]) > abs(a[p, col]):
                p = r
        if a[p, col] == 0.0:
            return False
        if p != col:
            for j in range(k):
                a[p, j], a[col, j] = a[col, j], a[p, j]
                inv[p, j], inv[col, j] = inv[col, j], inv[p, j]
        pivot = a[col, col]
        for j in range(k):
            a[col, j] /= pivot
            inv[col, j] /= pivot
        for r in range(k):
            if r != col:
                factor = a[r, col]
                if factor != 0.0:
                    for j in range(k):
                        a[r, j] -= factor * a[col, j]
                        inv[r, j] -= factor * inv[col, j]
    return True


@njit(cache=True)
def _norm1(a):
    """The 1-norm (largest column sum of magnitudes) of a square matrix."""
    best = 0.0
    for j in range(a.shape[1]):
        s = 0.0
        for i in range(a.shape[0]):
            s += abs(a[i, j])
        best = max(best, s)
    return best


@njit(cache=True)
def _matvec(a, x, out):
    """``out = a x``, each entry summed in the order of ``x``."""
    for i in range(out.shape[0]):
        acc = 0.0
        for r in range(x.shape[0]):
            acc += a[i, r] * x[r]
        out[i] = acc


@njit(cache=True, nogil=True)
def forces(jac, load, force, cond, residual, ok):
    """For each sample: ``f`` with ``J^T f = Q`` (minimum norm when ``m > n``, least squares when
    ``m < n``), the 1-norm condition number of ``J`` (of ``J^T J`` or ``J J^T``, square-rooted,
    when ``J`` is not square) and ``|J^T f - Q| / |Q|``; ``ok[s]`` False where a pivot vanished
    (``force`` is then left unset)."""
    samples, m, n = jac.shape
    k = min(m, n)
    g = np.empty((k, k))
    inv = np.empty((k, k))
    y = np.empty(k)
    for s in range(samples):
        j = jac[s]
        q = load[s]
        for a in range(k):  # g = J, J^T J or J J^T
            for b in range(k):
                if m == n:
                    g[a, b] = j[a, b]
                else:
                    acc = 0.0
                    for r in range(max(m, n)):
                        acc += j[r, a] * j[r, b] if m > n else j[a, r] * j[b, r]
                    g[a, b] = acc
        ok[s] = _invert(g, inv)
        if not ok[s]:
            continue
        c = _norm1(g) * _norm1(inv)
        c = c if np.isfinite(c) else np.inf
        cond[s] = c if m == n else np.sqrt(c)
        if m == n:  # f = J^-T Q
            _matvec(inv.T, q, force[s])
        elif m > n:  # f = J (J^T J)^-1 Q
            _matvec(inv, q, y)
            _matvec(j, y, force[s])
        else:  # f = (J J^T)^-1 J Q
            _matvec(j, q, y)
            _matvec(inv, y, force[s])
        worst, scale = 0.0, 0.0
        for r in range(n):
            acc = -q[r]
            for i in range(m):
                acc += j[i, r] * force[s, i]
            worst += acc * acc
            scale += q[r] * q[r]
        residual[s] = np.sqrt(worst) / max(np.sqrt(scale), 1e-300)


@njit(cache=True, nogil=True)
def accelerations(mass, jac, bias, force, extra, out, cond):
    """For each sample: ``rhs = J^T f - h + extra``, the 2-norm condition number of the
    symmetric mass matrix (its extreme eigenvalues' ratio; ``inf`` when one vanishes) and, where
    it is finite, ``out = M^-1 rhs`` (NaN elsewhere)."""
    samples, m, n = jac.shape
    rhs = np.empty(n)
    for s in range(samples):
        for r in range(n):
            acc = 0.0
            for i in range(m):
                acc += jac[s, i, r] * force[s, i]
            rhs[r] = acc - bias[s, r] + extra[s, r]
        e = np.abs(np.linalg.eigvalsh(mass[s]))
        low = e.min()
        cond[s] = e.max() / low if low > 0.0 else np.inf
        if np.isfinite(cond[s]):
            out[s] = np.linalg.solve(mass[s], rhs)
        else:
            out[s] = np.nan


# one process at a time compiles each of these functions; the others wait and load it
store.share_compiles(vars())
