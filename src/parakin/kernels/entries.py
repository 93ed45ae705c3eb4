"""The entry points of the compiled solvers: what Python calls, one set per kernel and method.

Each function below calls a loop of :mod:`parakin.kernels.drivers` with the kernel's functions
``RES``, ``JAC``, ``IK``, ``DOM``, ``ASM``, ``PER`` (the joints' periods) and the method's loop
``ROW``. Those names are
bound by :func:`parakin.kernels.entries_of` when it compiles a copy of these functions for one
kernel and one method (the way :func:`parakin.kernels._math.rebind` binds the math names of a
kernel), with numba's on-disk cache in a directory named by the hash of every source that went
into them (:mod:`parakin.kernels.store`): a changed kernel, driver or numba is a new directory,
never a stale build. Unbound here (``None``): this module is never compiled as it is.

Arguments: ``p`` the parameter vector, ``q``/``Q`` joints (one row / ``(N, m)``), ``x0``/``X0``
starts, ``opts`` the options vector (:mod:`parakin.kernels.methods`), ``x``/``X`` the solutions
(written), ``info`` ``(status, nit, nfev, njev, ...)`` per row, ``out`` the residual norms.

The batched entries are serial loops over rows; a large batch runs on every core as blocks of rows
on threads (:func:`parakin.kernels.threads.rows`: the entries release the GIL).
"""

from __future__ import annotations

from parakin.kernels.drivers import finite, pso_iterations, verify
from parakin.kernels.methods import BAD_INPUT

RES = JAC = IK = DOM = ASM = PER = ROW = None  # bound per kernel and method (parakin.kernels)
#: the name of the kernel module the entry is built for, bound with them: the known-answer probe
#: (parakin.kernels.store) asks that module's source, not the module that defines RES or ASM (the
#: 6-6 takes its leg equations from the 3-6 and has its own assembly test)
KERNEL = None


def row(p, q, x0, opts, x, info):
    """One pose by the method's loop (compiled once per kernel and method; the entries below call
    it). Returns the residual norm at ``x``."""
    return ROW(RES, JAC, p, q, x0, opts, x, info)


def check(p, q, x, flags):
    """The verification of one pose: ``flags`` = in domain, on assembly; returns the joint error."""
    return verify(IK, DOM, ASM, PER, p, q, x, flags)


def one(p, q, x0, opts, x, info, out):
    """One pose solved and checked in one call: ``info`` (6,) = status, nit, nfev, njev, in domain,
    on assembly; ``out`` (2,) = residual norm, joint error."""
    if not (finite(q) and finite(x0)):
        info[0] = BAD_INPUT
        return
    out[0] = row(p, q, x0, opts, x, info)
    out[1] = check(p, q, x, info[4:])


def serial(p, Q, X0, opts, X, info, out):
    """Every row of a batch, one after the other."""
    for i in range(Q.shape[0]):
        out[i] = row(p, Q[i], X0[i], opts, X[i], info[i])


def verify_serial(p, Q, X, flags, err):
    """``err[i]`` = joint error of pose ``X[i]`` for joints ``Q[i]``; ``flags[i]`` = in domain, on
    assembly."""
    for i in range(Q.shape[0]):
        err[i] = check(p, Q[i], X[i], flags[i])


def swarm(p, q, x, v, pb, pf, gb, gf, rnd, w, k0, lo, hi, vmax, coef, state, hist):
    """A block of particle-swarm iterations of one run (``parakin.solvers.pso``)."""
    pso_iterations(RES, p, q, x, v, pb, pf, gb, gf, rnd, w, k0, lo, hi, vmax, coef, state, hist)


def pso_serial(p, Q, X, V, PB, PF, GB, GF, RND, W, k0, lo, hi, vmax, coef, STATE, HIST):
    """A block of iterations of every run."""
    for i in range(Q.shape[0]):
        swarm(p, Q[i], X[i], V[i], PB[i], PF[i], GB[i], GF[i], RND[i], W[i], k0, lo, hi, vmax,
              coef, STATE[i], HIST[i])  # fmt: skip
