"""What each paper contains and what we made of it: the item table of ``REPORT.md`` and the
"At a glance" block of the results page (``docs/results.md``), generated from ``figures/report.csv``, the files in ``figures/`` and
``data/reference/items.csv`` (the paper's tables and figures, transcribed from its captions).

An item's status is derived, never typed: from the verdicts of its published numbers in
``report.csv`` (inputs left out), else from whether a file of ours draws it. Only the items we
do *not* compute carry a typed ``coverage`` ("not computable": a flowchart, a CAD view, a lost
table; "illustration": drawn, but from a surrogate that is judged as nothing) with the reason.
"""

from __future__ import annotations

from pathlib import Path

import pandas as pd

from parakin.claims import REFERENCE_DIR, REPRODUCED, WITHIN_ROUNDING

__all__ = [
    "ITEMS_CSV",
    "STATUSES",
    "load_items",
    "item_status",
    "item_table",
    "glance_block",
    "readme_glance",
    "GLANCE_BEGIN",
    "GLANCE_END",
]

ITEMS_CSV = REFERENCE_DIR / "items.csv"
GLANCE_BEGIN = "<!-- glance:begin -->"
GLANCE_END = "<!-- glance:end -->"

#: verdicts that count as reproduced (never a fit or an assumption)
REPRODUCED_GROUP = (REPRODUCED, WITHIN_ROUNDING, "bound satisfied")
DIFFERS_GROUP = ("differs — cause shown", "differs — cause unknown")
CONSISTENT = "consistent after fitting or assuming"
NOT_COMPARABLE = "not comparable"

#: item statuses, in the order the README lists them
STATUSES = (
    "reproduced",
    "partly reproduced",
    "consistent after fitting or assuming",
    "differs",
    "not comparable",
    "drawn, no published numbers",
    "inputs only",
    "illustration",
    "not computable",
    "missing",
)


def load_items(path: Path = ITEMS_CSV) -> pd.DataFrame:
    """The transcribed list of each paper's tables and figures (paper, item, kind, title, coverage, reason)."""
    items = pd.read_csv(path, dtype=str, keep_default_na=False)
    bad = set(items["coverage"]) - {"", "not computable", "illustration"}
    if bad:
        raise ValueError(
            f"{path}: unknown coverage {sorted(bad)}; allowed: '', not computable, illustration"
        )
    return items


def item_status(verdicts: pd.Series) -> str:
    """Status of an item from the verdicts of its published results (inputs excluded; non-empty)."""
    v = list(verdicts)
    n_rep = sum(x in REPRODUCED_GROUP for x in v)
    if n_rep == len(v):
        return "reproduced"
    if n_rep:
        return "partly reproduced"
    if any(x in DIFFERS_GROUP for x in v):
        return "differs"
    if any(x == CONSISTENT for x in v):
        return "consistent after fitting or assuming"
    return "not comparable"


def _normal(label: str) -> str:
    """``fig2`` and ``fig02`` name the same item."""
    head = label.rstrip("0123456789")
    tail = label[len(head) :]
    return f"{head}{int(tail)}" if tail and head in ("fig", "table") else label


def _files(figdir: Path, item: str) -> list[str]:
    if not figdir.is_dir():
        return []
    return sorted(p.name for p in figdir.iterdir() if p.name.startswith((f"{item}_", f"{item}.")))


def _verdict_counts(verdicts: pd.Series) -> str:
    counts = verdicts.value_counts()
    return ", ".join(f"{n} {v}" for v, n in counts.items())


def item_table(
    report: pd.DataFrame, figures_dir: Path, items: pd.DataFrame | None = None
) -> pd.DataFrame:
    """One row per item of every paper: its files, its published results and their verdicts, its status."""
    items = load_items() if items is None else items
    rows = []
    for it in items.itertuples(index=False):
        labels = report["artefact"].map(_normal)
        judged = report[(report["paper"] == it.paper) & (labels == _normal(it.item))]
        results = judged[judged["verdict"] != "input"]["verdict"]
        files = _files(Path(figures_dir) / it.paper, it.item)
        if it.coverage:
            status, why = it.coverage, it.reason
        elif len(results):
            status, why = item_status(results), _verdict_counts(results)
        elif len(judged):
            status, why = "inputs only", f"{len(judged)} input(s) the paper gives"
        elif files:
            status, why = "drawn, no published numbers", ""
        else:
            status, why = "missing", "no file of ours draws it"
        rows.append(
            {
                "paper": it.paper,
                "item": it.item,
                "title": it.title,
                "status": status,
                "published results": len(results),
                "reproduced": int(results.isin(REPRODUCED_GROUP).sum()),
                "verdicts / reason": why,
                "ours": ", ".join(files),
            }
        )
    return pd.DataFrame(rows)


def _label(item: str) -> str:
    """``fig05`` -> ``Fig. 5``, ``table1`` -> ``Table 1``."""
    for prefix, name in (("fig", "Fig. "), ("table", "Table ")):
        if item.startswith(prefix) and item[len(prefix) :].isdigit():
            return name + str(int(item[len(prefix) :]))
    return item


#: the kind of a claim's tolerance, as README's headline lines say it beside the printed value
_BOUND_WORDS = {"upper": " (upper bound)", "lower": " (lower bound)", "order": " (order)"}


def _headline(report: pd.DataFrame, key: str) -> list[str]:
    """The abstract's and conclusions' claims of one paper, each with its verdict."""
    rows = report[(report["paper"] == key) & report["artefact"].isin(["abstract", "conclusion"])]
    seen, out = set(), []
    for r in rows.itertuples(index=False):
        q = r.quantity
        if q in seen:  # the same claim in abstract and conclusion: one line
            continue
        seen.add(q)
        unit = f" {r.unit}" if r.unit not in ("", "1") else ""
        evidence = f" ([evidence](../figures/{r.evidence}))" if r.evidence else ""  # from docs/
        # the paper value as printed; what kind of claim it is comes from the tolerance column
        how = _BOUND_WORDS.get(str(r.tolerance).split(":")[0], "")
        out.append(
            f"  - {r.artefact} `{q}`: paper {r[4]}{unit}{how}, ours {r.ours or '—'} → **{r.verdict}**{evidence}"
        )
    return out


def glance_block(report_csv: Path, titles: dict[str, str]) -> str:
    """README's "Results at a glance" block (markers included), from ``report.csv``, the files beside it
    and ``items.csv``: per paper, its items by status and its headline claims with their verdicts."""
    report_csv = Path(report_csv)
    report = pd.read_csv(report_csv, dtype=str, keep_default_na=False)
    table = item_table(report, report_csv.parent)
    lines = [GLANCE_BEGIN]
    for key, title in titles.items():
        t = table[table["paper"] == key]
        if not len(t):
            continue
        results = report[(report["paper"] == key) & (report["verdict"] != "input")]
        n_rep = int(results["verdict"].isin(REPRODUCED_GROUP).sum())
        lines.append(
            f"- **{title}** — {len(t)} tables and figures; {len(results)} published results, "
            f"{n_rep} reproduced (within tolerance, rounding or bound)."
        )
        for status in STATUSES:
            s = t[t["status"] == status]
            if len(s):
                names = [
                    _label(r.item) + (f" ({r.reproduced} of {n})" if (n := r[4]) else "")
                    for r in s.itertuples(index=False)
                ]
                lines.append(f"  - {status} ({len(s)}): {', '.join(names)}")
        items = set(t["item"].map(_normal))
        text = results[~results["artefact"].map(_normal).isin(items)]
        if len(text):
            lines.append(
                f"  - in the text and equations ({len(text)} results): {_verdict_counts(text['verdict'])}"
            )
        head = _headline(report, key)
        if head:
            lines.append("  - headline claims (abstract, conclusions):")
            lines += ["  " + h for h in head]
    lines += [
        "",
        "Generated by `parakin readme` from `figures/report.csv`, the files in `figures/` and "
        "`data/reference/items.csv` (each paper's tables and figures); an item's status comes from "
        "the verdicts of its published numbers. Item by item, with reasons: `figures/REPORT.md`.",
        GLANCE_END,
    ]
    return "\n".join(lines)


def readme_glance(readme_text: str) -> str:
    """The glance block of a README (markers included)."""
    i, j = readme_text.find(GLANCE_BEGIN), readme_text.find(GLANCE_END)
    if i < 0 or j < i:
        raise ValueError(f"README has no {GLANCE_BEGIN} ... {GLANCE_END} block")
    return readme_text[i : j + len(GLANCE_END)]
