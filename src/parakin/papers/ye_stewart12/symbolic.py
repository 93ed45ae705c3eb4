"""Ye et al. §3.1, Table 2: the features of the constraint equations (12)-(20) before and of the
compatibility equations (21)-(26) after the simplification, counted symbolically with sympy.

The equations are written, as in the paper, in the coordinates of M = (x0, y0, z0) and
B_i = (x_i, y_i, z_i), i = 1..3, plus the leg lengths l1, l3, l5. Through the linear FK (docs/ye_stewart12.md#s1.5)
M has degree 2 and B_i degree 4 in the leg lengths, so a term's degree in l is the weighted degree
with weights 2 (M), 4 (B) and 1 (l). The "number of highest-degree terms" counts the terms of that
weighted degree (products of two B-coordinates), in this B-coordinate form.
"""

from __future__ import annotations

from functools import lru_cache
from pathlib import Path
from typing import TYPE_CHECKING

import pandas as pd

from parakin.claims import Claim, printed_value
from parakin.io import write_table
from parakin.papers.sections import table_text
from parakin.papers.ye_stewart12.common import KEY, artefact
from parakin.registry import EXACT

if TYPE_CHECKING:  # sympy is imported where it is used: the table's job alone needs it
    import sympy as sp


@lru_cache(maxsize=1)
def equations() -> dict[str, object]:
    import sympy as sp

    n, L = sp.symbols("n L", positive=True)
    a = n + L
    m = sp.Matrix(sp.symbols("x0 y0 z0"))
    b = [sp.Matrix(sp.symbols(f"x{i} y{i} z{i}")) for i in (1, 2, 3)]
    l1, l3, l5 = sp.symbols("l1 l3 l5")
    base = {1: sp.Matrix([0, a, -n]), 3: sp.Matrix([-n, a, 0]), 5: sp.Matrix([n, 0, -a])}

    def sq(v: sp.Matrix) -> sp.Expr:
        return (v.T * v)[0]

    c = [
        sq(b[0] - base[1]) - l1**2,
        sq(b[1] - base[3]) - l3**2,
        sq(b[2] - base[5]) - l5**2,
        sq(b[0] - m) - 2 * n**2,
        sq(b[1] - m) - 2 * n**2,
        sq(b[2] - m) - 2 * n**2,
        sq(b[0] - b[1]) - 2 * n**2,
        sq(b[1] - b[2]) - 6 * n**2,
        sq(b[0] - b[2]) - 2 * n**2,
    ]
    f = [
        c[0] - c[3],
        c[1] - c[4],
        c[2] - c[5],
        -(c[0] + c[1] - c[6]),
        -(c[1] + c[2] - c[7]),
        -(c[0] + c[2] - c[8]),
    ]
    weights = {s: 2 for s in m} | {s: 4 for v in b for s in v} | {l1: 1, l3: 1, l5: 1}
    return {
        "before": [sp.expand(e) for e in c],
        "after": [sp.expand(e) for e in f],
        "weights": weights,
        "M": list(m),
    }


def _terms(expr: sp.Expr, weights: dict) -> list[tuple[int, sp.Expr]]:
    import sympy as sp

    out = []
    for term in sp.Add.make_args(expr):
        powers = term.as_powers_dict()
        out.append((sum(int(p) * weights.get(s, 0) for s, p in powers.items()), term))
    return out


def features() -> dict[str, dict[str, int]]:
    eq = equations()
    w = eq["weights"]
    res = {}
    for stage in ("before", "after"):
        terms = [_terms(e, w) for e in eq[stage]]
        top = max(d for t in terms for d, _ in t)
        res[stage] = {
            "equations": len(eq[stage]),
            "highest_degree": top,
            "highest_terms": sum(1 for t in terms for d, _ in t if d == top),
        }
    # the paper's remarks: 8th-degree terms vanish from f, g, v; 6th-degree (x0 x_i) from u, w, h
    after = [_terms(e, w) for e in eq["after"]]
    before = [_terms(e, w) for e in eq["before"]]
    res["remarks"] = {
        "fgv_max_degree": max(d for t in after[:3] for d, _ in t),
        "fgv_parts_max_degree": max(d for t in before[:6] for d, _ in t),
        "uwh_degree6_terms": sum(1 for t in after[3:] for d, _ in t if d == 6),
    }
    return res


@artefact("table2", outputs=["table2.csv", "table2.md"], config=[KEY], tolerance=EXACT)
def table2(config: dict, outdir: Path) -> list[Path]:
    """Table 2: number of equations, highest degree in l, number of highest-degree terms."""
    f = features()
    df = pd.DataFrame(
        [
            {"feature": k, "before": f["before"][k], "after": f["after"][k]}
            for k in ("equations", "highest_degree", "highest_terms")
        ]
        + [
            {
                "feature": "max degree of f, g, v (before: of (12)-(17))",
                "before": f["remarks"]["fgv_parts_max_degree"],
                "after": f["remarks"]["fgv_max_degree"],
            },
            {
                "feature": "degree-6 terms in u, w, h",
                "before": None,
                "after": f["remarks"]["uwh_degree6_terms"],
            },
        ]
    )
    return write_table(
        df,
        outdir / "table2",
        title="Table 2: equation features before/after simplification",
        notes=(
            "Counted with sympy in the B-coordinate form (x_i, y_i, z_i of degree 4 and x0, y0, z0 "
            "of degree 2 in the leg lengths, through our linear FK)."
        ),
    )


def claims(figdir: Path, ref: pd.DataFrame) -> list[Claim]:
    p = figdir / "table2.csv"
    if not p.exists():
        return []
    t = pd.read_csv(p).set_index("feature")
    out = []
    for feat in ("equations", "highest_degree", "highest_terms"):
        for stage in ("before", "after"):
            out.append(
                Claim(
                    KEY,
                    "table2",
                    f"{feat}.{stage}",
                    printed_value(ref, "table2", f"{feat}.{stage}"),
                    float(t.loc[feat, stage]),
                    "1",
                    reason="C2; counted in the B-coordinate form",
                )
            )
    return out


def _table2_sentence(table: pd.DataFrame) -> str:
    """Table 2: the equations and degrees before and after the elimination."""
    t = table.set_index("feature")
    return (
        f"Table 2 (sympy): {int(t.loc['equations', 'before'])} -> {int(t.loc['equations', 'after'])} equations, "
        f"highest degree {int(t.loc['highest_degree', 'before'])} -> {int(t.loc['highest_degree', 'after'])}, "
        f"highest-degree terms {int(t.loc['highest_terms', 'before'])} -> {int(t.loc['highest_terms', 'after'])}; "
        f"f, g, v drop to degree {int(t.loc['max degree of f, g, v (before: of (12)-(17))', 'after'])}."
    )


def summary(figdir: Path, ref: pd.DataFrame) -> str:
    return table_text(figdir, {"table2.csv": _table2_sentence})
