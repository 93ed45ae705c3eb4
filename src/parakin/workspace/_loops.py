"""The compiled workspace classifier's loops (numba; bound per kernel by
:mod:`parakin.workspace.compiled`, as :func:`parakin.kernels.entries_of` binds the solvers').

``IK``, ``JAC`` and ``RES`` are the kernel's one-pose ``ik``, ``jacobian`` and ``residual``; they
are unbound here (this module is never compiled as it is). Per pose: the IK, the joint limits and,
where asked, cond(J) of ``J = -B^-1 A`` with ``A`` the kernel's Jacobian, ``B = d residual / d
joints`` by central differences (exact up to rounding for residuals linear or quadratic in the
joints, as every registered mechanism's), ``B`` solved by Gaussian elimination with partial
pivoting and the singular values by one-sided Jacobi rotations.
"""

from __future__ import annotations

import math

import numpy as np

IK = JAC = RES = None  # bound per kernel (parakin.workspace.compiled)

#: the joint Jacobian counts as singular where a pivot falls below this times its largest entry
B_SINGULAR = 1e-12


def joint_jacobian(p, x, q, b, r0, r1, qq):
    """``B = d residual / d q`` (m, m) by central differences of step ``1e-5 max(1, |q_k|)``."""
    m = q.shape[0]
    for k in range(m):
        h = 1e-5 * max(1.0, abs(q[k]))
        for c in range(m):
            qq[c] = q[c]
        qq[k] = q[k] + h
        RES(p, x, qq, r1)
        qq[k] = q[k] - h
        RES(p, x, qq, r0)
        for r in range(m):
            b[r, k] = (r1[r] - r0[r]) / (2 * h)


def solve_in_place(b, a):
    """``a <- -b^-1 a`` (b (m, m), a (m, n)) by elimination with partial pivoting; False where a
    pivot is below :data:`B_SINGULAR` times the largest entry of ``b`` (or not finite)."""
    m = b.shape[0]
    n = a.shape[1]
    big = 0.0
    for i in range(m):
        for j in range(m):
            big = max(big, abs(b[i, j]))
    if not (big > 0 and big < math.inf):
        return False
    for col in range(m):
        piv = col
        for r in range(col + 1, m):
            if abs(b[r, col]) > abs(b[piv, col]):
                piv = r
        if not abs(b[piv, col]) > B_SINGULAR * big:
            return False
        if piv != col:
            for c in range(m):
                b[col, c], b[piv, c] = b[piv, c], b[col, c]
            for c in range(n):
                a[col, c], a[piv, c] = a[piv, c], a[col, c]
        for r in range(col + 1, m):
            f = b[r, col] / b[col, col]
            for c in range(col, m):
                b[r, c] -= f * b[col, c]
            for c in range(n):
                a[r, c] -= f * a[col, c]
    for col in range(m - 1, -1, -1):
        for c in range(n):
            s = a[col, c]
            for k in range(col + 1, m):
                s -= b[col, k] * a[k, c]
            a[col, c] = -s / b[col, col]
    return True


def svd_cond(j):
    """cond(J) = sigma_max / sigma_min of ``J`` (m, n), m >= n, overwritten: one-sided Jacobi
    (Hestenes) rotations until the columns are orthogonal, the singular values their norms (high
    relative accuracy, unlike the eigenvalues of J^T J); inf where sigma_min = 0."""
    m, n = j.shape
    for _sweep in range(60):
        rotated = False
        for a in range(n - 1):
            for b in range(a + 1, n):
                alpha = 0.0
                beta = 0.0
                gamma = 0.0
                for k in range(m):
                    alpha += j[k, a] * j[k, a]
                    beta += j[k, b] * j[k, b]
                    gamma += j[k, a] * j[k, b]
                if not abs(gamma) > 1e-15 * math.sqrt(alpha * beta):
                    continue
                rotated = True
                zeta = (beta - alpha) / (2 * gamma)
                t = (1.0 if zeta >= 0 else -1.0) / (abs(zeta) + math.sqrt(1 + zeta * zeta))
                c = 1 / math.sqrt(1 + t * t)
                s = c * t
                for k in range(m):
                    ja, jb = j[k, a], j[k, b]
                    j[k, a] = c * ja - s * jb
                    j[k, b] = s * ja + c * jb
        if not rotated:
            break
    lo = math.inf
    hi = 0.0
    for c in range(n):
        s2 = 0.0
        for k in range(m):
            s2 += j[k, c] * j[k, c]
        lo = min(lo, s2)
        hi = max(hi, s2)
    if not lo > 0:
        return math.inf
    return math.sqrt(hi / lo)


def row(p, x, jlo, jhi, want_cond, q, flags):
    """One pose: ``flags`` = IK exists, joints within limits; returns cond(J) (NaN if not asked or
    outside the limits)."""
    m = q.shape[0]
    n = x.shape[0]
    ok = IK(p, x, q)
    for k in range(m):
        ok = ok and (q[k] == q[k]) and abs(q[k]) < math.inf
    flags[0] = 1 if ok else 0
    inside = ok
    for k in range(m):
        inside = inside and q[k] >= jlo[k] and q[k] <= jhi[k]
    flags[1] = 1 if inside else 0
    if not (want_cond and inside):
        return math.nan
    a = np.empty((m, n))
    JAC(p, x, q, a)
    b = np.empty((m, m))
    r0 = np.empty(m)
    r1 = np.empty(m)
    qq = np.empty(m)
    joint_jacobian(p, x, q, b, r0, r1, qq)
    if not solve_in_place(b, a):
        return math.inf
    return svd_cond(a)


def rows_serial(p, X, jlo, jhi, want_cond, Q, F, C):
    """Every pose of a batch, one after the other (blocks of a batch run side by side:
    :func:`parakin.kernels.threads.rows`)."""
    for i in range(X.shape[0]):
        C[i] = row(p, X[i], jlo, jhi, want_cond, Q[i], F[i])
