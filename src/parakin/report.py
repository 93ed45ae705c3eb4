"""The claim-by-claim report: every published number beside the value our pipeline computed.

The claims come from the paper modules (:mod:`parakin.papers`, built on :mod:`parakin.claims`)
and the studies beyond the papers; this module judges each with the tolerance its reference row
declares (:func:`parakin.claims.resolve`), gives every row of ``data/reference/*.csv`` exactly one
verdict, and writes ``REPORT.md`` and, beside it, the machine-readable ``report.csv`` (one row per
published number; what the README's status table and results block are generated from).
"""

from __future__ import annotations

import io
from pathlib import Path

import pandas as pd

from parakin.claims import (
    NOT_JUDGED,
    REFERENCE_DIR,
    VERDICTS,
    Claim,
    _fmt,
    _paper_cell,
    claims_table,
    load_reference,
    readings_text,
    resolve,
    row_verdicts,
)

# what notebooks and tests read from here beside the report: :mod:`parakin.claims` defines them
from parakin.claims import half_ulp as half_ulp
from parakin.claims import judge as judge
from parakin.claims import printed_value as printed_value
from parakin.glance import (
    CONSISTENT,
    REPRODUCED_GROUP,
    glance_block,
    item_table,
    load_items,
    readme_glance,
)
from parakin.io import atomic_write_text, markdown_table
from parakin.papers import PAPERS
from parakin.studies import solver_atlas

#: the report's own API; it also hands on the claims' API (Claim, judge, load_reference, ...)
__all__ = [
    "build_report",
    "write_report",
    "report_rows",
    "paper_claims",
    "REPORT_COLUMNS",
]

#: the columns of report.csv
REPORT_COLUMNS = [
    "paper",
    "artefact",
    "quantity",
    "variant",
    "paper value",
    "ours",
    "difference",
    "unit",
    "tolerance",
    "verdict",
    "reason",
    "evidence",
    "readings",
]

VERDICT_TEXT = """Verdicts (one per published number):

- **reproduced**: an independent computation agrees within the tolerance declared in `data/reference/` (the
  `tolerance` column, written before the comparison), or within half a decade of a stated order of magnitude;
- **reproduced within rounding**: within half a unit of the last printed digit;
- **bound satisfied**: the paper states a bound (or a statement of it is encoded as one, the reference note
  says how) and ours meets it;
- **consistent after fitting or assuming**: agreement that rests on something fitted to the same numbers or
  assumed (named in the reason); never counted as reproduced;
- **differs — cause shown**: an artefact or test shows why (named under evidence);
- **differs — cause unknown**: nothing we have shows why;
- **not comparable**: lost in the extraction, qualitative, not identifiable, or another machine's clock (the
  reason says which);
- **input**: a set-up value the paper gives, not a result;
- **not judged yet**: a published result no artefact judges (should be none).

Every row of `data/reference/<paper>.csv` has exactly one verdict, listed in `report.csv` beside this file
(paper value, ours, difference, tolerance, reason, evidence, readings). Nothing here is typed in by hand. The
paper value is the number as the paper prints it; how it is compared (a bound, an order of magnitude, a
tolerance) is the `tolerance` column.

**One verdict from several readings.** Where several computations of ours judge one published number (a region,
a variant of a method, the stated and a fitted geometry: its *readings*), the number gets the verdict of the one
reading declared for it before the comparison (the row says which and why; never a reading that rests on a fit
or an assumption), and otherwise the verdict of the **weakest** reading, so that a favourable reading cannot
hide the others. The `readings` column of `report.csv` lists every reading with its value, its own verdict and
its evidence, and the tables below show each reading as a line of its own (`reading`: which one decides).

A number a chaotic computation produces (the GA, the PSO runs, a network's training) is judged on independent
runs, never on one: ours is the median of the runs (at least 30 seeds; 10 trainings per region), shown with its
99 % confidence interval and the runs' range, and the comparison asks whether the paper's number (one run of its
own) lies in that range, within the declared tolerance; a bound must be met by the median run. No verdict rests
on a wall-clock time: a time of another machine is not comparable, and a speed claim is judged on iterations or
on the ratio of two computations timed in the same run."""


def _evidence_files(key: str, figdir: Path) -> dict[str, str]:
    """Paper artefact label -> a file of ours named after it (``table1`` -> ``<key>/table1.md``)."""
    out: dict[str, str] = {}
    if not figdir.is_dir():
        return out
    for p in sorted(figdir.iterdir()):
        stem = p.stem
        label = stem.split("_")[0]
        for name in (stem, label):
            if name not in out or (p.suffix == ".md" and not out[name].endswith(".md")):
                if p.suffix in (".md", ".csv", ".png") and (name not in out or p.suffix == ".md"):
                    out[name] = f"{key}/{p.name}"
    return out


def paper_claims(
    key: str, figures_dir: Path, reference_dir: Path = REFERENCE_DIR
) -> tuple[pd.DataFrame, list[Claim]]:
    """The reference of one paper and its claims judged with the reference tolerances."""
    module = PAPERS[key]
    ref = load_reference(key, reference_dir)
    claims = [resolve(c, ref) for c in module.claims(Path(figures_dir) / key, ref)]
    return ref, claims


def report_rows(key: str, ref: pd.DataFrame, claims: list[Claim], figdir: Path) -> pd.DataFrame:
    """One row per published number of ``key`` (the rows of report.csv)."""
    files = _evidence_files(key, figdir)
    rows = []
    for _, r in row_verdicts(claims, ref).iterrows():
        c, ref_row, readings = r["claim"], r["ref"], r["readings"]
        base = {
            "paper": key,
            "artefact": r["artefact"],
            "quantity": r["quantity"],
            "paper value": ref_row["value"],
            "unit": ref_row["unit"],
            "tolerance": ref_row["tolerance"],
            "verdict": r["verdict"],
        }
        if c is None:
            rows.append(
                {
                    **base,
                    "variant": "",
                    "ours": "",
                    "difference": "",
                    "reason": ref_row["note"],
                    "evidence": "",
                    "readings": "",
                }
            )
            continue
        reason = "; ".join(
            x for x in (f"fitted/assumed: {c.basis}" if c.basis else "", c.reason) if x
        )
        # the deciding reading's evidence, else another reading's (listed under readings), else
        # the file of ours named after the artefact
        evidence = (
            c.evidence
            or next((x.evidence for x in readings if x.evidence), "")
            or files.get(c.artefact, "")
        )
        rows.append(
            {
                **base,
                "variant": c.variant,
                "paper value": _paper_cell(c),
                "ours": _fmt(c.ours),
                "difference": _fmt(c.diff),
                "reason": reason,
                "evidence": evidence,
                "readings": readings_text(readings, c, r["decided_by"]),
            }
        )
    return pd.DataFrame(rows, columns=REPORT_COLUMNS)


def _build(figures_dir: Path, reference_dir: Path) -> tuple[str, pd.DataFrame]:
    lines = [
        "# parakin reproduction report",
        "",
        "Generated by `parakin report` from the pipeline outputs in this "
        "folder and the published numbers transcribed in `data/reference/`.",
        "",
        VERDICT_TEXT,
        "",
    ]
    summary, sections, tables = [], [], []
    for key, module in PAPERS.items():
        if not (Path(figures_dir) / key).is_dir():
            continue
        ref, claims = paper_claims(key, figures_dir, reference_dir)
        rows = report_rows(key, ref, claims, Path(figures_dir) / key)
        tables.append(rows)
        counts = rows["verdict"].value_counts()
        summary.append(
            {
                "paper": key,
                "published numbers": len(ref),
                **{v: int(counts.get(v, 0)) for v in VERDICTS},
            }
        )
        sections += [
            f"## {module.TITLE}",
            "",
            module.summary(Path(figures_dir) / key, ref).strip(),
            "",
        ]
        items = item_table(rows, Path(figures_dir), load_items(Path(reference_dir) / "items.csv"))
        items = items[items["paper"] == key].drop(columns="paper")
        if len(items):
            sections += [
                "Tables and figures of the paper (status from the verdicts of their published numbers):",
                "",
                markdown_table(items),
                "",
            ]
        sections += [markdown_table(claims_table(claims)), ""]
        rest = rows[
            [
                r["verdict"] in ("input", "not comparable", NOT_JUDGED)
                and not r["variant"]
                and r["ours"] == ""
                for _, r in rows.iterrows()
            ]
        ]
        if len(rest):
            sections += [
                f"Published numbers of this paper without a computation of ours ({len(rest)}):",
                "",
                markdown_table(
                    rest[["artefact", "quantity", "paper value", "unit", "verdict", "reason"]]
                ),
                "",
            ]
    glance = pd.DataFrame(summary)
    if len(glance):
        glance = glance[
            ["paper", "published numbers"]
            + [v for v in VERDICTS if v != NOT_JUDGED or glance[v].any()]
        ]
    lines += [
        "## At a glance",
        "",
        "Each published number counted once, so each row adds up to its paper's published numbers.",
        "",
        markdown_table(glance) if summary else "(no outputs yet)",
        "",
    ]
    beyond = solver_atlas.summary(Path(figures_dir))
    if beyond:
        sections += [f"## {solver_atlas.TITLE}", "", beyond, ""]
    table = pd.concat(tables, ignore_index=True) if tables else pd.DataFrame(columns=REPORT_COLUMNS)
    return "\n".join(lines + sections), table


def build_report(figures_dir: Path, reference_dir: Path = REFERENCE_DIR) -> str:
    """REPORT.md text for every paper whose outputs exist under ``figures_dir``."""
    return _build(Path(figures_dir), reference_dir)[0]


def write_report(figures_dir: Path, out: Path, reference_dir: Path = REFERENCE_DIR) -> Path:
    """Build the report; write it atomically to ``out`` and ``report.csv`` beside it."""
    text, table = _build(Path(figures_dir), reference_dir)
    buf = io.StringIO()
    table.to_csv(buf, index=False, lineterminator="\n")
    atomic_write_text(Path(out).with_name("report.csv"), buf.getvalue())
    return atomic_write_text(out, text)


# ------------------------------------------------------------------------------ README status block
STATUS_BEGIN = "<!-- status:begin -->"
STATUS_END = "<!-- status:end -->"
#: verdict groups of the README's status table
PARTIAL_GROUP = (CONSISTENT,)


def status_block(report_csv: Path) -> str:
    """README's status table, generated from ``report.csv`` and the artefact registry (markers included):
    per paper the artefacts we make, the published numbers and how many of them get each verdict."""
    from parakin.pipeline import artefacts

    table = pd.read_csv(report_csv, dtype=str, keep_default_na=False)
    found = artefacts()
    rows = []
    for key, module in PAPERS.items():
        t = table[table["paper"] == key]
        if not len(t):
            continue
        counts = t["verdict"].value_counts()
        results = t[~t["verdict"].isin(["input"])]
        n_art = sum(1 for a in found.values() if a.study == key)
        rows.append(
            {
                "paper key": f"`{key}`",
                "paper": module.TITLE,
                "artefacts (ours)": n_art,
                "published numbers": len(t),
                "inputs": int(counts.get("input", 0)),
                "reproduced": int(sum(counts.get(v, 0) for v in REPRODUCED_GROUP)),
                "partial (after fitting/assuming)": int(
                    sum(counts.get(v, 0) for v in PARTIAL_GROUP)
                ),
                "differs (cause shown / unknown)": f"{int(counts.get('differs — cause shown', 0))} / "
                f"{int(counts.get('differs — cause unknown', 0))}",
                "not comparable": int(counts.get("not comparable", 0)),
                "results judged": f"{len(results) - int(counts.get(NOT_JUDGED, 0))}/{len(results)}",
            }
        )
    note = (
        "Generated by `parakin readme` from `figures/report.csv` (one verdict per published number, "
        "see `figures/REPORT.md`) and the artefact registry; *reproduced* counts reproduced, within rounding and "
        "bounds satisfied, never a fit or an assumption."
    )
    return "\n".join([STATUS_BEGIN, markdown_table(pd.DataFrame(rows)), "", note, STATUS_END])


def readme_status(readme_text: str) -> str:
    """The status block of a README (markers included)."""
    i, j = readme_text.find(STATUS_BEGIN), readme_text.find(STATUS_END)
    if i < 0 or j < i:
        raise ValueError(f"README has no {STATUS_BEGIN} ... {STATUS_END} block")
    return readme_text[i : j + len(STATUS_END)]


def readme_glance_block(report_csv: Path) -> str:
    """README's "Results at a glance" block for every paper (see :mod:`parakin.glance`)."""
    return glance_block(report_csv, {key: module.TITLE for key, module in PAPERS.items()})


def readme_blocks_match(readme_text: str, report_csv: Path) -> bool:
    """Whether README's status and glance blocks are the ones ``report_csv`` generates."""
    return readme_status(readme_text) == status_block(report_csv) and readme_glance(
        readme_text
    ) == readme_glance_block(report_csv)


def sync_status(readme: Path, report_csv: Path) -> Path:
    """Replace README's status and glance blocks by those generated from ``report_csv`` (atomically)."""
    text = Path(readme).read_text()
    text = text.replace(readme_status(text), status_block(report_csv))
    text = text.replace(readme_glance(text), readme_glance_block(report_csv))
    return atomic_write_text(readme, text)
