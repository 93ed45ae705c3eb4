"""The entry points of the compiled solvers: what Python calls, one set per kernel and method.

Each function below calls a loop of :mod:`parakin.kernels.drivers` with the kernel's functions
``RES``, ``JAC``, ``IK``, ``DOM``, ``ASM``, ``PER`` (the joints' periods) and the method's loop
``ROW``. Those names are
bound by :func:`parakin.kernels.entries_of` when it compiles a copy of these functions for one
kernel and one method (the way :func:`parakin.kernels._math.rebind` binds the math names of a
kernel), with numba's on-disk cache in a directory named by the hash of every source that went
into them (:mod:`parakin.kernels.store`): a changed kernel, driver or numba is a new directory,
never a stale build. Unbound here (``None``): this module is never compiled as it is.

Arguments: ``p`` the parameter vector, ``Q`` joints ``(N, m)``, ``X0`` starts, ``opts`` the
options vector (:mod:`parakin.kernels.methods`), ``X`` the solutions (written), ``info``
``(status, nit, nfev, njev, ...)`` per row, ``out`` the residual norms (and joint errors).

One entry per group, each a serial loop over rows with the loop it runs inlined (numba's IR
inlining of the drivers): a single pose is a batch of one row. A large batch runs on every core as
blocks of rows on threads (:func:`parakin.kernels.threads.rows`: the entries release the GIL).
"""

from __future__ import annotations

import numpy as np

from parakin.kernels.drivers import finite, pso_iterations, verify, work
from parakin.kernels.methods import BAD_INPUT

RES = JAC = IK = DOM = ASM = PER = ROW = None  # bound per kernel and method (parakin.kernels)
#: the name of the kernel module the entry is built for, bound with them: the known-answer probe
#: (parakin.kernels.store) asks that module's source, not the module that defines RES or ASM (the
#: 6-6 takes its leg equations from the 3-6 and has its own assembly test)
KERNEL = None


def serial(p, Q, X0, opts, X, info, out):
    """Every row of a batch by the method's loop, one after the other: ``info[i]`` = status, nit,
    nfev, njev; ``out[i, 0]`` = residual norm at ``X[i]``. Where ``info`` has six columns (the
    single call, :func:`parakin.solvers.compiled.solve_one`), each answer is checked as well:
    ``info[i, 4:]`` = in domain, on assembly, ``out[i, 1]`` = joint error, and a row whose joints
    or start are not finite is left unsolved as ``BAD_INPUT``. (One function for both: numba
    optimises a caller again over every compiled function it links, so a single-call entry and a
    batched entry beside a shared one-row loop compiled that loop three times.) The loop's work
    arrays are made once for all rows (:func:`parakin.kernels.drivers.work`)."""
    checked = info.shape[1] > 4
    ws = work(Q.shape[1], X0.shape[1])
    joints = np.empty(Q.shape[1])
    for i in range(Q.shape[0]):
        if checked and not (finite(Q[i]) and finite(X0[i])):
            info[i, 0] = BAD_INPUT
            continue
        out[i, 0] = ROW(RES, JAC, p, Q[i], X0[i], opts, X[i], info[i], ws)
        if checked:
            out[i, 1] = verify(IK, DOM, ASM, PER, p, Q[i], X[i], info[i, 4:], joints)


def verify_serial(p, Q, X, flags, err):
    """``err[i]`` = joint error of pose ``X[i]`` for joints ``Q[i]``; ``flags[i]`` = in domain, on
    assembly."""
    joints = np.empty(Q.shape[1])
    for i in range(Q.shape[0]):
        err[i] = verify(IK, DOM, ASM, PER, p, Q[i], X[i], flags[i], joints)


def pso_serial(p, Q, X, V, PB, PF, GB, GF, RND, W, k0, lo, hi, vmax, coef, STATE, HIST):
    """A block of particle-swarm iterations of every run (``parakin.solvers.pso``)."""
    for i in range(Q.shape[0]):
        pso_iterations(RES, p, Q[i], X[i], V[i], PB[i], PF[i], GB[i], GF[i], RND[i], W[i], k0, lo,
                       hi, vmax, coef, STATE[i], HIST[i])  # fmt: skip
