"""Symbolic (sympy) checks of Li 2020 §1.2-§2: alpha = 0 from the constraints (6), P from (12)-(14),
and the vector IK (9)-(11) against our scalar closed forms (and against the printed (16)).

Independent of :mod:`parakin.mechanisms.ups2`: everything is rebuilt from the paper's equations.
"""

from __future__ import annotations

from functools import lru_cache

import numpy as np

__all__ = ["derivation", "loop_closure_model"]


@lru_cache(maxsize=1)
def derivation() -> dict[str, object]:
    """Run the derivation; returns named results (sympy expressions and booleans).

    * ``B2B3``: ``R (B3' - B2')`` with ``R = Rz(alpha) Ry(beta) Rx(gamma)`` -- equals eq (7);
    * ``constraint_y``: ``B2B3 . e_y`` = ``-sqrt2 b sin(alpha) cos(beta)`` (eq 6, first);
    * ``alpha_solutions``: the solutions of it in alpha for cos(beta) != 0: {0, pi};
    * ``X_of_Z``: eq (8) at alpha = 0, ``X = Z tan(beta)``;
    * ``P_ok``: ``P = (rho sin b, Y, rho cos b)`` satisfies (6) and (12) identically;
    * ``ik_ok``: |l_j|^2 of the vector form (9)-(11) minus our closed forms simplifies to 0 (j = 1..3);
    * ``printed16_differs``: the printed (16) (Y missing in the y term) is not the vector form.
    """
    import sympy as sp

    al, be, ga = sp.symbols("alpha beta gamma", real=True)
    a, b, c = sp.symbols("a b c", positive=True)
    X, Y, Z = sp.symbols("X Y Z", real=True)
    rz = sp.Matrix([[sp.cos(al), -sp.sin(al), 0], [sp.sin(al), sp.cos(al), 0], [0, 0, 1]])
    ry = sp.Matrix([[sp.cos(be), 0, sp.sin(be)], [0, 1, 0], [-sp.sin(be), 0, sp.cos(be)]])
    rx = sp.Matrix([[1, 0, 0], [0, sp.cos(ga), -sp.sin(ga)], [0, sp.sin(ga), sp.cos(ga)]])
    R = rz * ry * rx
    k = sp.sqrt(2) / 2 * b
    b2l, b3l = sp.Matrix([k, k, 0]), sp.Matrix([-k, k, 0])
    P = sp.Matrix([X, Y, Z])
    B2, B3 = P + R * b2l, P + R * b3l
    b2b3 = sp.simplify(B3 - B2)
    eq7 = sp.Matrix(
        [
            -sp.sqrt(2) * b * sp.cos(al) * sp.cos(be),
            -sp.sqrt(2) * b * sp.sin(al) * sp.cos(be),
            sp.sqrt(2) * b * sp.sin(be),
        ]
    )
    eq7_ok = sp.simplify(b2b3 - eq7) == sp.zeros(3, 1)
    cons_y = sp.simplify(b2b3.dot(sp.Matrix([0, 1, 0])))
    # cos(beta) != 0 (|beta| < 90 deg): divide it out and solve for alpha in [0, 2 pi)
    alpha_solutions = sp.solveset(
        sp.simplify(cons_y / (-sp.sqrt(2) * b * sp.cos(be))), al, sp.Interval.Ropen(0, 2 * sp.pi)
    )
    cons_p = sp.simplify(b2b3.dot(P).subs(al, 0))
    x_of_z = sp.solve(cons_p, X)
    rho = sp.sqrt(c**2 - Y**2)
    P14 = {X: rho * sp.sin(be), Z: rho * sp.cos(be)}
    p_ok = (
        sp.simplify(cons_p.subs(P14)) == 0
        and sp.simplify((X**2 + Y**2 + Z**2 - c**2).subs(P14)) == 0
    )
    # vector IK (9)-(11) at alpha = 0 with (14)
    h = sp.sqrt(3) / 2 * a
    A1, A2, A3 = sp.Matrix([0, h, 0]), sp.Matrix([a / 2, h, 0]), sp.Matrix([-a / 2, h, 0])
    R0 = R.subs(al, 0)
    P0 = sp.Matrix([rho * sp.sin(be), Y, rho * sp.cos(be)])
    legs = [sp.Rational(2, 3) * P0 - A1, P0 + R0 * b2l - A2, P0 + R0 * b3l - A3]
    sq = [sp.expand(v.dot(v)) for v in legs]
    u = rho + k * sp.sin(ga)
    Q = u**2 + k**2 + a**2 / 4 + (k * sp.cos(ga) + Y - h) ** 2 - a * k * sp.cos(be)
    closed = [
        sp.Rational(4, 9) * c**2 + sp.Rational(3, 4) * a**2 - 2 / sp.sqrt(3) * a * Y,
        Q - a * u * sp.sin(be),
        Q + a * u * sp.sin(be),
    ]
    ik_ok = [sp.simplify(sp.expand_trig(s - cf)) == 0 for s, cf in zip(sq, closed)]
    printed16 = (
        (rho * sp.sin(be) + k * (sp.cos(be) + sp.sin(ga) * sp.sin(be)) - a / 2) ** 2
        + (k * sp.cos(ga) - sp.sqrt(3) / 2 * a) ** 2
        + (rho * sp.cos(be) + k * (-sp.sin(be) + sp.cos(be) * sp.sin(ga))) ** 2
    )
    diff16 = sp.simplify(sp.expand(printed16 - sq[1]))
    return {
        "B2B3": b2b3,
        "eq7_ok": bool(eq7_ok),
        "constraint_y": cons_y,
        "alpha_solutions": sorted(float(s) for s in alpha_solutions),
        "X_of_Z": x_of_z,
        "P_ok": bool(p_ok),
        "ik_ok": [bool(v) for v in ik_ok],
        "printed16_minus_vector": diff16,
        "printed16_differs": diff16 != 0,
    }


def loop_closure_model(
    n: int,
    rng: np.random.Generator,
    c: float = 0.3,
    a: float = 0.15,
    max_tilt: float = np.deg2rad(45.0),
    max_roll: float = np.deg2rad(90.0),
) -> dict[str, np.ndarray]:
    """An independent joint-level model of the (S+SPR)R unit (docs/li2020_2ups.md#g5), sampled ``n`` times.

    The SR link points along a random unit vector ``n_l`` (tilt up to ``max_tilt`` from z, any
    azimuth); the R axis at B1 is perpendicular both to the link and to the SPR leg A1B0
    (B0 = 2c/3 n_l), so ``u = unit(A1 x n_l)``; the platform turns about ``u`` by a random R angle.
    Returns the ZYX Euler angles (alpha, beta, gamma) of the platform and P = c n_l -- no use of
    the paper's constraint equations.
    """
    from parakin.geometry import euler_zyx_from_matrix

    tilt = rng.uniform(0, max_tilt, n)
    az = rng.uniform(-np.pi, np.pi, n)
    roll = rng.uniform(-max_roll, max_roll, n)
    nl = np.stack([np.sin(tilt) * np.cos(az), np.sin(tilt) * np.sin(az), np.cos(tilt)], axis=-1)
    a1 = np.array([0.0, np.sqrt(3) / 2 * a, 0.0])
    u = np.cross(a1, nl)
    u /= np.linalg.norm(u, axis=-1, keepdims=True)
    v0 = np.cross(nl, u)
    v = np.cos(roll)[:, None] * v0 + np.sin(roll)[:, None] * nl
    w = np.cross(u, v)
    R = np.stack([u, v, w], axis=-1)
    angles = euler_zyx_from_matrix(R)
    return {"alpha": angles[:, 0], "beta": angles[:, 1], "gamma": angles[:, 2], "P": c * nl}
