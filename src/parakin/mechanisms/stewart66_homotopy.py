"""Study-parameter formulation and a batched parameter-homotopy tracker for the 6-6 Gough-Stewart FK.

Used by :mod:`parakin.mechanisms.stewart66`; see ``docs/stewart66.md`` for the method and references.

Unknowns: Study parameters ``x = (e, g)`` in C^8, a point of P^7 fixed by the affine patch
``a . x = 1`` (random complex ``a``). For a real pose ``(R, t)``: ``e`` is a quaternion of ``R``
and ``g = t e`` (quaternion product, ``t`` pure). Equations, all homogeneous quadrics
``f_k(x) = x^T Q_k x``:

* ``k = 0``: the Study quadric ``e . g = 0``;
* ``k = 1..6``: leg ``i = k - 1``, ``|R p_i + t - b_i|^2 - L_i^2`` times ``e . e``::

      c_i (e.e) + g.g + 2 e^T (A(p_i) - C(b_i)) g - 2 e^T S(b_i, p_i) e,   c_i = |p_i|^2 + |b_i|^2 - L_i^2

  with ``b^T R(e) p = e^T S(b, p) e`` (``R(e)`` the unnormalised rotation ``e p e'``),
  ``Re(e p g') = e^T A(p) g`` and ``b . vec(g e') = e^T C(b) g`` (Wampler 1996's "soma" form).

Generic root count: 40 (Raghavan 1993; Ronga & Vust; Lazard; Mourrain), all with ``e . e != 0``.
Everything here is batched over paths: ``x`` has shape ``(K, 8)``.
"""

from __future__ import annotations

import numpy as np

from parakin.geometry import skew

__all__ = [
    "GAMMA",
    "ALPHA0",
    "quadrics",
    "quat_rotation",
    "quat_from_matrix",
    "pose_to_study",
    "study_to_rt",
    "FiberHomotopy",
    "GeneralHomotopy",
    "track",
    "newton_refine",
    "certify",
    "real_decision",
    "ALPHA_ROBUST",
    "generate_start",
]

#: Smale's alpha-theory constant: alpha < ALPHA0 makes x an approximate zero (Blum et al. 1998, Ch. 8)
ALPHA0 = (13.0 - 3.0 * np.sqrt(17.0)) / 4.0


def quat_rotation(e: np.ndarray) -> np.ndarray:
    """Unnormalised rotation matrix ``R(e)`` (``e p e'`` as a matrix), (..., 3, 3); ``R(e)/(e.e)`` is a
    rotation for real ``e``. Works for complex ``e`` (no conjugation)."""
    w, x, y, z = (e[..., k] for k in range(4))
    return np.stack(
        [
            np.stack([w * w + x * x - y * y - z * z, 2 * (x * y - w * z), 2 * (x * z + w * y)], -1),
            np.stack([2 * (x * y + w * z), w * w - x * x + y * y - z * z, 2 * (y * z - w * x)], -1),
            np.stack([2 * (x * z - w * y), 2 * (y * z + w * x), w * w - x * x - y * y + z * z], -1),
        ],
        -2,
    )


def _gamma() -> np.ndarray:
    """``GAMMA[j, k]`` (3, 3, 4, 4) symmetric with ``R(e)[j, k] = e^T GAMMA[j, k] e`` (by polarisation)."""
    eye = np.eye(4)
    g = np.zeros((3, 3, 4, 4))
    for a in range(4):
        g[:, :, a, a] = quat_rotation(eye[a])
        for b in range(a + 1, 4):
            v = (quat_rotation(eye[a] + eye[b]) - quat_rotation(eye[a]) - quat_rotation(eye[b])) / 2
            g[:, :, a, b] = g[:, :, b, a] = v
    return g


GAMMA = _gamma()
_E = np.diag([1.0, 1, 1, 1, 0, 0, 0, 0])  # x^T E x = e.e


def quadrics(base: np.ndarray, platform: np.ndarray, c: np.ndarray) -> np.ndarray:
    """The seven symmetric matrices ``Q_k`` (..., 7, 8, 8) of the module docstring, complex.

    ``base``, ``platform`` (..., 6, 3) and ``c`` (..., 6) broadcast (complex allowed)."""
    b = np.asarray(base)
    p = np.asarray(platform)
    c = np.asarray(c)
    shape = np.broadcast_shapes(b.shape[:-2], p.shape[:-2], c.shape[:-1])
    q = np.zeros(shape + (7, 8, 8), dtype=complex)
    q[..., 0, :4, 4:] = np.eye(4) / 2
    q[..., 0, 4:, :4] = np.eye(4) / 2
    s = np.einsum("...ij,...ik,jkab->...iab", b, p, GAMMA)
    qee = c[..., :, None, None] * np.eye(4) - 2 * s
    d = p - b
    qeg = np.zeros(np.broadcast_shapes(b.shape, p.shape)[:-1] + (4, 4), dtype=np.result_type(b, p))
    qeg[..., 0, 1:] = d
    qeg[..., 1:, 0] = -d
    qeg[..., 1:, 1:] = skew(p) + skew(b)
    q[..., 1:, :4, :4] = qee
    q[..., 1:, :4, 4:] = qeg
    q[..., 1:, 4:, :4] = np.swapaxes(qeg, -1, -2)
    q[..., 1:, 4:, 4:] = np.eye(4)
    return q


def quat_from_matrix(r: np.ndarray) -> np.ndarray:
    """Unit quaternion (w, x, y, z) (..., 4) of rotation matrices (..., 3, 3) (Shepperd's method)."""
    r = np.asarray(r, dtype=float)
    tr = np.trace(r, axis1=-2, axis2=-1)
    cand = np.stack([tr, r[..., 0, 0], r[..., 1, 1], r[..., 2, 2]], -1)
    k = np.argmax(cand, axis=-1)
    out = np.empty(r.shape[:-2] + (4,))
    # four formulae; pick per row
    with np.errstate(all="ignore"):
        w0 = 0.5 * np.sqrt(np.maximum(1 + tr, 0))
        q0 = np.stack(
            [
                w0,
                (r[..., 2, 1] - r[..., 1, 2]) / (4 * w0),
                (r[..., 0, 2] - r[..., 2, 0]) / (4 * w0),
                (r[..., 1, 0] - r[..., 0, 1]) / (4 * w0),
            ],
            -1,
        )
        x1 = 0.5 * np.sqrt(np.maximum(1 + r[..., 0, 0] - r[..., 1, 1] - r[..., 2, 2], 0))
        q1 = np.stack(
            [
                (r[..., 2, 1] - r[..., 1, 2]) / (4 * x1),
                x1,
                (r[..., 0, 1] + r[..., 1, 0]) / (4 * x1),
                (r[..., 0, 2] + r[..., 2, 0]) / (4 * x1),
            ],
            -1,
        )
        y2 = 0.5 * np.sqrt(np.maximum(1 - r[..., 0, 0] + r[..., 1, 1] - r[..., 2, 2], 0))
        q2 = np.stack(
            [
                (r[..., 0, 2] - r[..., 2, 0]) / (4 * y2),
                (r[..., 0, 1] + r[..., 1, 0]) / (4 * y2),
                y2,
                (r[..., 1, 2] + r[..., 2, 1]) / (4 * y2),
            ],
            -1,
        )
        z3 = 0.5 * np.sqrt(np.maximum(1 - r[..., 0, 0] - r[..., 1, 1] + r[..., 2, 2], 0))
        q3 = np.stack(
            [
                (r[..., 1, 0] - r[..., 0, 1]) / (4 * z3),
                (r[..., 0, 2] + r[..., 2, 0]) / (4 * z3),
                (r[..., 1, 2] + r[..., 2, 1]) / (4 * z3),
                z3,
            ],
            -1,
        )
    for j, qj in enumerate((q0, q1, q2, q3)):
        sel = k == j
        out[sel] = qj[sel]
    return out


def pose_to_study(rot: np.ndarray, trans: np.ndarray) -> np.ndarray:
    """Study parameters ``(e, g)`` (..., 8) of rotations (..., 3, 3) and translations (..., 3): ``e`` the
    unit quaternion, ``g = t e``."""
    e = quat_from_matrix(rot)
    t = np.asarray(trans, dtype=float)
    return np.concatenate([e, _qmul_pure_left(t, e)], -1)


def _qmul_pure_left(t: np.ndarray, e: np.ndarray) -> np.ndarray:
    """Quaternion product ``(0, t) e`` (..., 4)."""
    e0, ev = e[..., :1], e[..., 1:]
    return np.concatenate([-np.sum(t * ev, -1, keepdims=True), e0 * t + np.cross(t, ev)], -1)


def study_to_rt(x: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Rotation ``R(e)/(e.e)`` (..., 3, 3) and translation ``vec(g e')/(e.e)`` (..., 3) of Study
    parameters (..., 8) (complex allowed; no conjugation)."""
    e, g = x[..., :4], x[..., 4:]
    n = np.sum(e * e, -1)
    vec = e[..., :1] * g[..., 1:] - g[..., :1] * e[..., 1:] + np.cross(e[..., 1:], g[..., 1:])
    return quat_rotation(e) / n[..., None, None], vec / n[..., None]


# ------------------------------------------------------------------------------------------ homotopies
def _inv(j: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Batched inverse and a mask of rows where it exists (singular rows get the identity, masked)."""
    try:
        return np.linalg.inv(j), np.ones(j.shape[0], dtype=bool)
    except np.linalg.LinAlgError:
        det = np.linalg.det(j)
        ok = np.isfinite(det) & (np.abs(det) > 0)
        jj = np.where(ok[:, None, None], j, np.eye(j.shape[-1]))
        try:
            return np.linalg.inv(jj), ok
        except np.linalg.LinAlgError:
            out = np.empty_like(jj)
            for i in range(len(jj)):
                try:
                    out[i] = np.linalg.inv(jj[i])
                except np.linalg.LinAlgError:
                    out[i] = np.eye(j.shape[-1])
                    ok[i] = False
            return out, ok


class FiberHomotopy:
    """``H(x, t) = F(x; c(t))`` for one geometry (shared ``Q0``, the leg quadrics without their ``c``
    term) with ``c(t) = c0 + t (c1 - c0) + t (1 - t) d`` per path (``d`` a complex bend, 0 for a
    straight segment). Evaluation is one (K, 8) x (8, 56) product plus the ``c_i e.e`` terms."""

    def __init__(
        self,
        q0: np.ndarray,
        patch: np.ndarray,
        c0: np.ndarray,
        c1: np.ndarray,
        bend=None,
        dtype=np.complex128,
    ):
        self.dtype = np.dtype(dtype)
        self.q0 = q0  # (7, 8, 8) with c = 0
        qf = q0.transpose(2, 0, 1).reshape(8, 56)
        self.qflat = np.ascontiguousarray(qf, dtype=self.dtype)  # x @ qflat = (Q_k x)_k
        self.patch = np.asarray(patch, dtype=self.dtype)
        self.c0 = np.asarray(c0, dtype=self.dtype)  # (K, 6)
        self.dc = np.asarray(c1 - c0, dtype=self.dtype)
        self.bend = None if bend is None else np.asarray(bend, dtype=self.dtype)

    def c(self, t, rows):
        tt = t[:, None].astype(np.float32 if self.dtype == np.complex64 else np.float64)
        c = self.c0[rows] + tt * self.dc[rows]
        if self.bend is not None:
            c += tt * (1 - tt) * self.bend[rows]
        return c

    def h(self, x, t, rows):
        y = (x @ self.qflat).reshape(-1, 7, 8)
        out = np.empty((len(x), 8), dtype=self.dtype)
        out[:, :7] = (y @ x[:, :, None])[..., 0]
        e = x[:, :4]
        ee = (e[:, None, :] @ e[:, :, None])[:, 0]
        out[:, 1:7] += self.c(t, rows) * ee
        out[:, 7] = x @ self.patch - 1
        return out

    def ht(self, x, t, rows):
        e = x[:, :4]
        ee = (e[:, None, :] @ e[:, :, None])[:, 0]
        d = (
            self.dc[rows]
            if self.bend is None
            else self.dc[rows] + (1 - 2 * t[:, None]) * self.bend[rows]
        )
        out = np.zeros((len(x), 8), dtype=self.dtype)
        out[:, 1:7] = d * ee
        return out

    def all(self, x, t, rows):
        """H (K, 8), J = dH/dx (K, 8, 8), dH/dt (K, 8)."""
        y = (x @ self.qflat).reshape(-1, 7, 8)
        c = self.c(t, rows)
        y[:, 1:, :4] += c[:, :, None] * x[:, None, :4]
        h = np.empty((len(x), 8), dtype=self.dtype)
        h[:, :7] = (y @ x[:, :, None])[..., 0]
        h[:, 7] = x @ self.patch - 1
        j = np.empty((len(x), 8, 8), dtype=self.dtype)
        j[:, :7] = 2 * y
        j[:, 7] = self.patch
        return h, j, self.ht(x, t, rows)

    def target_quadrics(self, rows):
        q = np.broadcast_to(self.q0, (len(rows), 7, 8, 8)).astype(complex)
        c = self.c0[rows] + self.dc[rows]
        q[:, 1:, :4, :4] += c[:, :, None, None] * np.eye(4)
        return q


class GeneralHomotopy:
    """``H(x, t) = F(x; B(t), P(t), c(t))`` with every parameter on one straight segment shared by all
    paths: for monodromy loops and for moving the generic start to a given geometry. ``Q(t)`` is
    quadratic in ``t`` (the ``b p^T`` term), so ``Q(t) = Q_0 + t Q_1 + t^2 Q_2`` is interpolated
    exactly from its values at ``t = 0, 1/2, 1``."""

    dtype = np.dtype(np.complex128)

    def __init__(self, patch, start, target):
        self.patch = np.asarray(patch, dtype=complex)
        p0 = [np.asarray(v, dtype=complex) for v in start]  # B (6, 3), P (6, 3), c (6,)
        p1 = [np.asarray(v, dtype=complex) for v in target]
        qa, qm, qb = (quadrics(*[u + s * (w - u) for u, w in zip(p0, p1)]) for s in (0.0, 0.5, 1.0))
        c2 = 2 * (qa + qb) - 4 * qm
        c1 = qb - qa - c2
        self.coef = [
            np.ascontiguousarray(q.transpose(2, 0, 1).reshape(8, 56)) for q in (qa, c1, c2)
        ]
        self.q1 = qb

    def _y(self, x, t):
        q0, q1, q2 = self.coef
        tt = t[:, None]
        y1, y2 = x @ q1, x @ q2
        y = (x @ q0 + tt * y1 + tt * tt * y2).reshape(-1, 7, 8)
        yt = (y1 + 2 * tt * y2).reshape(-1, 7, 8)
        return y, yt

    def h(self, x, t, rows):
        y, _ = self._y(x, t)
        out = np.empty((len(x), 8), dtype=complex)
        out[:, :7] = (y @ x[:, :, None])[..., 0]
        out[:, 7] = x @ self.patch - 1
        return out

    def all(self, x, t, rows):
        y, yt = self._y(x, t)
        h = np.empty((len(x), 8), dtype=complex)
        h[:, :7] = (y @ x[:, :, None])[..., 0]
        h[:, 7] = x @ self.patch - 1
        j = np.empty((len(x), 8, 8), dtype=complex)
        j[:, :7] = 2 * y
        j[:, 7] = self.patch
        ht = np.zeros((len(x), 8), dtype=complex)
        ht[:, :7] = (yt @ x[:, :, None])[..., 0]
        return h, j, ht

    def ht(self, x, t, rows):
        return self.all(x, t, rows)[2]

    def target_quadrics(self, rows):
        return np.broadcast_to(self.q1, (len(rows), 7, 8, 8))


# ------------------------------------------------------------------------------------------ tracking
def track(
    hom,
    x0: np.ndarray,
    *,
    h0: float = 0.05,
    hmax: float = 0.5,
    hmin: float = 1e-7,
    max_steps: int = 400,
    tau: float = 2e-3,
    blowup: float = 1e7,
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Track every path of ``hom`` from ``t = 0`` (``x0`` (K, 8)) to ``t = 1``.

    Predictor: cubic Hermite extrapolation through the last two points and their tangents (Euler on
    the first step); corrector: three chord-Newton iterations with the inverse Jacobian at the
    predicted point (one 8x8 inversion per step; the same inverse gives the next tangent). A step is
    accepted when the corrections contract (``|d2| <= 0.2 |d1|``, ``|d3| <= 0.2 |d2|``) and the first
    is below ``0.1 (1 + |x|)``; the step size adapts to the predictor error (target ``tau``).
    Returns ``(x (K, 8), reached (K,) bool, steps (K,) int)``; a path fails when its step falls
    below ``hmin``, it takes ``max_steps`` or ``|x|`` exceeds ``blowup``."""
    k = len(x0)
    dtype = getattr(hom, "dtype", np.dtype(np.complex128))
    x = np.array(x0, dtype=dtype)
    floor = 100 * np.finfo(dtype).eps
    t = np.zeros(k)
    h = np.full(k, h0)
    steps = np.zeros(k, dtype=np.int64)
    reached = np.zeros(k, dtype=bool)
    rows = np.arange(k)
    _, j, ht = hom.all(x, t, rows)
    jinv, ok = _inv(j)
    v = -np.einsum("kij,kj->ki", jinv, ht)
    xp, vp, tp = x.copy(), v.copy(), t.copy()
    have_prev = np.zeros(k, dtype=bool)
    active = rows[ok]
    failed = ~ok
    while active.size:
        xa, ta, va = x[active], t[active], v[active]
        ha = np.minimum(h[active], 1.0 - ta)
        t1 = ta + ha
        # predictor
        pred = xa + ha[:, None] * va
        hp = have_prev[active]
        if hp.any():
            i = np.flatnonzero(hp)
            dt = (ta[i] - tp[active[i]])[:, None]
            s = ha[i, None] / dt
            a_ = xp[active[i]] - xa[i] + dt * va[i]
            b_ = dt * (vp[active[i]] - va[i])
            c3 = b_ + 2 * a_
            c2 = 3 * a_ + b_
            pred[i] = xa[i] + dt * va[i] * s + c2 * s * s + c3 * s * s * s
        pred = pred.astype(dtype, copy=False)
        _, j, ht = hom.all(pred, t1, active)
        jinv, okinv = _inv(j)
        scale = 1.0 + np.linalg.norm(pred, axis=-1)
        x1 = pred
        norms = []
        for _ in range(3):
            d = (jinv @ hom.h(x1, t1, active)[:, :, None])[..., 0]
            x1 = x1 - d
            norms.append(np.linalg.norm(d, axis=-1))
        n1, n2, n3 = norms
        with np.errstate(all="ignore"):
            good = (
                okinv
                & np.isfinite(n3)
                & (n1 < 0.1 * scale)
                & (n2 <= 0.2 * n1 + floor * scale)
                & (n3 <= 0.2 * n2 + floor * scale)
            )
        steps[active] += 1
        # accepted: move, new tangent (inverse at the predicted point: error O(|d1|), fine for a predictor)
        ga = active[good]
        if ga.size:
            xp[ga], vp[ga], tp[ga] = xa[good], va[good], ta[good]
            have_prev[ga] = True
            x[ga] = x1[good]
            t[ga] = t1[good]
            ht1 = hom.ht(x1[good], t1[good], ga)
            v[ga] = -(jinv[good] @ ht1[:, :, None])[..., 0]
            with np.errstate(all="ignore", divide="ignore"):
                fac = np.clip(0.9 * (tau / np.maximum(n1[good], 1e-300)) ** (1 / 3), 0.5, 3.0)
            h[ga] = np.minimum(ha[good] * fac, hmax)
            if dtype != np.complex128:
                v[ga] = v[ga].astype(dtype)
        ba = active[~good]
        h[ba] = ha[~good] * 0.5
        done = t[active] >= 1.0
        reached[active[done]] = True
        lost = (
            (h[active] < hmin)
            | (steps[active] >= max_steps)
            | ~(np.linalg.norm(x[active], axis=-1) < blowup)
        )
        failed[active[lost & ~done]] = True
        active = active[~done & ~lost]
    return x, reached & ~failed, steps


def newton_refine(q: np.ndarray, patch: np.ndarray, x: np.ndarray, iters: int = 3):
    """Full Newton on ``x^T Q_k x = 0, patch . x = 1`` (``q`` (K, 7, 8, 8) per path, complex or real).

    Returns ``(x, beta, jinv_norm)``: the last iterate, ``beta = |J^-1 F|`` there and the Frobenius
    norm of ``J^-1`` (an upper bound of its spectral norm)."""
    dtype = np.result_type(q, x, patch)
    for it in range(iters + 1):
        y = np.einsum("kmij,kj->kmi", q, x)
        f = np.empty((len(x), 8), dtype=dtype)
        f[:, :7] = np.einsum("kmi,ki->km", y, x)
        f[:, 7] = x @ patch - 1
        j = np.empty((len(x), 8, 8), dtype=dtype)
        j[:, :7] = 2 * y
        j[:, 7] = patch
        jinv, ok = _inv(j)
        d = np.einsum("kij,kj->ki", jinv, f)
        if it == iters:
            beta = np.where(ok, np.linalg.norm(d, axis=-1), np.inf)
            return x, beta, np.where(ok, np.linalg.norm(jinv, axis=(-2, -1)), np.inf)
        x = np.where(ok[:, None], x - d, x)


def certify(q: np.ndarray, beta: np.ndarray, jinv_norm: np.ndarray) -> np.ndarray:
    """Smale's ``alpha = beta * gamma`` with ``gamma <= |J^-1| sqrt(sum_k |Q_k|_F^2)`` (the system is
    quadratic: ``D^2 f / 2`` is the constant bilinear map ``(u, v) -> (u^T Q_k v)_k``)."""
    qn = np.sqrt(np.sum(np.abs(q) ** 2, axis=(-3, -2, -1)))
    with np.errstate(invalid="ignore"):
        return beta * jinv_norm * qn


#: the robust alpha theorem's bound on alpha (Blum, Cucker, Shub & Smale 1998, Ch. 8, as stated by
#: Hauenstein & Sottile 2012, below): with alpha(x) <= 0.03, every y within 1/(20 gamma(x)) of x is an approximate
#: zero with the same associated zero as x
ALPHA_ROBUST = 0.03
#: a bound on the relative rounding error of evaluating ``x^T Q x`` in double precision (16 ulps:
#: 8 products and 8 sums per row), added to beta so that the reality test never rests on noise
EVAL_ULPS = 16 * np.finfo(float).eps


def real_decision(q: np.ndarray, x: np.ndarray, iters: int = 3) -> tuple[np.ndarray, np.ndarray]:
    """Certified reality of approximate zeros ``x`` (K, 8) of real quadrics ``q`` (K, 7, 8, 8):
    ``(y, decision)``, ``decision`` +1 (the associated zero is real), -1 (it is not), 0 (undecided);
    ``y`` (K, 8) the refined point in the real chart ``y_k = 1`` of its largest coordinate.

    The test is alphaCertified's local one (Hauenstein & Sottile 2012, "Algorithm 921:
    alphaCertified", ACM TOMS 38(4) 28, the section on real solutions; its implementation's
    ``determine_real_solution``), with ``pi(y) = Re y`` the nearest real point: for a real system
    and an approximate zero ``y`` with associated zero ``xi``, ``|y - xi| <= 2 beta(y)``, so

    * ``|Im y| > 2 beta(y)``: ``xi`` is not real (a real ``xi`` would be within ``2 beta`` of
      ``Re y``, the real point nearest ``y``);
    * ``alpha(y) <= 0.03`` and ``|Im y| <= 1 / (20 gamma(y))``: ``Re y`` is an approximate zero
      with the same associated zero (the robust alpha theorem, :data:`ALPHA_ROBUST`), and Newton's
      iterates from a real point of a real system stay real: ``xi`` is real;
    * otherwise undecided (near a double root, where gamma is large).

    The test needs a chart that conjugation maps to itself: the fibre homotopy's chart is complex,
    so each point is moved to the coordinate chart ``y_k = 1`` of its largest coordinate (real;
    the same point of P^7, so the same zero) and refined there by ``iters`` Newton steps (on a real
    system a near-real point's imaginary part falls quadratically). ``beta = |J^-1 F| +`` a bound
    of the rounding error of ``F`` times ``|J^-1|_F`` (:data:`EVAL_ULPS`), ``gamma`` as
    :func:`certify`."""
    qn = np.sqrt(np.sum(np.abs(q) ** 2, axis=(-3, -2, -1)))
    with np.errstate(all="ignore"):
        k = np.argmax(np.nan_to_num(np.abs(x)), axis=-1)
        chart = np.eye(8)[k]
        y = x / np.take_along_axis(x, k[:, None], -1)
        for it in range(iters + 1):
            g = np.einsum("kmij,kj->kmi", q, y)
            f = np.concatenate(
                [np.einsum("kmi,ki->km", g, y), np.sum(chart * y, -1)[:, None] - 1], -1
            )
            jinv, ok = _inv(np.concatenate([2 * g, chart[:, None].astype(complex)], 1))
            d = np.einsum("kij,kj->ki", jinv, f)
            if it < iters:
                y = np.where(ok[:, None], y - d, y)
        gamma = np.where(ok, np.linalg.norm(jinv, axis=(-2, -1)) * qn, np.inf)
        beta = np.linalg.norm(d, axis=-1) + EVAL_ULPS * gamma * np.sum(np.abs(y) ** 2, -1)
        im = np.linalg.norm(y.imag, axis=-1)
        real = (beta * gamma <= ALPHA_ROBUST) & (20 * gamma * im <= 1)
        decision = np.where(im > 2 * beta, -1, np.where(real, 1, 0))
    return y, np.where(ok & np.all(np.isfinite(y), -1), decision, 0)


def distinct(x: np.ndarray, beta: np.ndarray, ok: np.ndarray, alpha: np.ndarray) -> np.ndarray:
    """Per row of (n, m, 8): mask of certified solutions whose 2 beta balls (where the associated zero
    lies) do not meet an earlier kept one's: every kept solution is a different zero. ``beta``
    gets its rounding floor ``EVAL_ULPS gamma |x|^2`` (``gamma = alpha / beta``), as in
    :func:`real_decision`: at an ill-conditioned zero the computed beta is rounding, not a bound
    on the distance to the zero, and two paths ending on one zero near a fold were once kept as
    two (the 10^6 census's one odd count, docs/census.md)."""
    n, m, _ = x.shape
    keep = ok.copy()
    with np.errstate(invalid="ignore", divide="ignore"):
        gamma = np.where(beta > 0, alpha / beta, 0.0)
        radius = beta + EVAL_ULPS * gamma * np.sum(np.abs(x) ** 2, -1)
        d = np.linalg.norm(x[:, :, None, :] - x[:, None, :, :], axis=-1)
        clash = d <= 2 * (radius[:, :, None] + radius[:, None, :]) + 1e-12
    for i in range(1, m):
        prev = clash[:, i, :i] & keep[:, :i]
        keep[:, i] &= ~prev.any(-1)
    return keep


# ------------------------------------------------------------------------------------------ start system
def random_problem(rng: np.random.Generator):
    """Random complex geometry ``(B, P)`` (6, 3) each and leg constants ``c`` (6,)."""
    cn = lambda *s: (rng.normal(size=s) + 1j * rng.normal(size=s)) / np.sqrt(2)  # noqa: E731
    return cn(6, 3), cn(6, 3), cn(6)


def generate_start(seed: int = 20250611, *, expected: int = 40, max_loops: int = 40):
    """The generic start system and all its solutions, by monodromy.

    A random complex geometry ``(B0, P0)`` and a random complex pose give one solution and fix
    ``c0``; loops ``p0 -> p1 -> p2 -> p0`` through random complex parameters (all of B, P, c) permute
    the solutions, and every new endpoint is added. Stops after the set has reached ``expected`` and
    two further loops found nothing new (``expected`` is the literature's count: 40). Returns a dict
    ``base, platform, c, patch, solutions (40, 8), loops``."""
    rng = np.random.default_rng(seed)
    b0, p0, _ = random_problem(rng)
    patch = (rng.normal(size=8) + 1j * rng.normal(size=8)) / 4
    e = rng.normal(size=4) + 1j * rng.normal(size=4)
    t = rng.normal(size=3) + 1j * rng.normal(size=3)
    g = _qmul_pure_left(t, e)
    x = np.concatenate([e, g])
    x = x / (patch @ x)
    qz = quadrics(b0, p0, np.zeros(6))
    rest = np.einsum("mij,i,j->m", qz[1:], x, x)
    c0 = -rest / np.sum(x[:4] * x[:4])
    sols = x[None].copy()
    quiet = 0
    loops = 0
    start = (b0, p0, c0)
    while loops < max_loops:
        loops += 1
        p1, p2 = random_problem(rng), random_problem(rng)
        cur = sols.copy()
        okall = np.ones(len(cur), dtype=bool)
        for a, z in ((start, p1), (p1, p2), (p2, start)):
            hom = GeneralHomotopy(patch, a, z)
            cur, ok, _ = track(hom, cur, h0=0.02, tau=5e-4)
            okall &= ok
        cur = cur[okall]
        q = np.broadcast_to(quadrics(b0, p0, c0), (len(cur), 7, 8, 8))
        cur, beta, jn = newton_refine(q, patch, cur, iters=4)
        alpha = certify(q, beta, jn)
        new = 0
        for xi, ai in zip(cur, alpha):
            if not ai < ALPHA0:
                continue
            if np.min(np.linalg.norm(sols - xi, axis=-1)) > 1e-6:
                sols = np.concatenate([sols, xi[None]])
                new += 1
        quiet = quiet + 1 if (new == 0 and len(sols) >= expected) else 0
        if quiet >= 2:
            break
    q = np.broadcast_to(quadrics(b0, p0, c0), (len(sols), 7, 8, 8))
    sols, _, _ = newton_refine(q, patch, sols, iters=3)
    return {
        "base": b0,
        "platform": p0,
        "c": c0,
        "patch": patch,
        "solutions": sols,
        "loops": loops,
        "seed": seed,
    }
