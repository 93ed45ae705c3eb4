"""The claim-by-claim report: every published number beside the value our pipeline computed.

Each paper module (:mod:`parakin.papers`) turns its pipeline outputs into :class:`Claim` objects
(``claims(figures_dir, reference)``); this module judges them and writes ``figures/REPORT.md``.
Our values are always read from pipeline outputs, never typed in; published values come from
``data/reference/<paper>.csv`` exactly as printed, so the rounding of the print is known.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from pathlib import Path

import pandas as pd

from parakin.config import ROOT
from parakin.io import atomic_write_text, markdown_table

__all__ = ["Claim", "judge", "half_ulp", "load_reference", "build_report", "write_report", "REFERENCE_DIR"]

REFERENCE_DIR = ROOT / "data" / "reference"

REPRODUCED = "reproduced"
WITHIN_ROUNDING = "reproduced within rounding"
DIFFERS = "differs"


def half_ulp(printed: str) -> float:
    """Half a unit in the last printed place: '0.42' -> 0.005, '4.51e-8' -> 5e-11, '3' -> 0.5."""
    text = printed.strip().lower()
    mantissa, _, exponent = text.partition("e")
    decimals = len(mantissa.split(".")[1]) if "." in mantissa else 0
    return 0.5 * 10.0 ** (-decimals + (int(exponent) if exponent else 0))


#: how a printed number is compared: its value, a bound it states, or its order of magnitude
KINDS = ("value", "upper", "lower", "order")


def judge(printed: str, ours: float, tol: float | None = None, kind: str = "value") -> str:
    """Verdict for our value against the printed one.

    ``kind="value"``: ``reproduced`` when ``|ours - paper| <= tol`` (a claim-specific tolerance,
    e.g. a solver's accuracy), ``reproduced within rounding`` when the difference is within half a
    unit of the last printed digit, ``differs`` otherwise. ``kind="upper"`` / ``"lower"``: the
    paper states a bound ("within 20 ms", "at least ..."): ``reproduced`` when ours meets it.
    ``kind="order"``: the paper states an order of magnitude ("10^-4 level"): ``reproduced``
    when ours lies within half a decade of it.
    """
    if kind not in KINDS:
        raise ValueError(f"kind = {kind!r} must be one of {KINDS}")
    if not math.isfinite(float(ours)):
        return DIFFERS
    if kind == "upper":
        return REPRODUCED if float(ours) <= float(printed) else DIFFERS
    if kind == "lower":
        return REPRODUCED if float(ours) >= float(printed) else DIFFERS
    if kind == "order":
        ok = float(ours) > 0 and abs(math.log10(float(ours) / float(printed))) <= 0.5
        return REPRODUCED if ok else DIFFERS
    diff = abs(float(ours) - float(printed))
    if tol is not None and diff <= tol:
        return REPRODUCED
    if diff <= half_ulp(printed) * (1 + 1e-9):
        return WITHIN_ROUNDING
    return DIFFERS


@dataclass(frozen=True)
class Claim:
    """One published number, our value for it and the verdict."""

    paper: str
    artefact: str
    quantity: str
    printed: str
    ours: float
    unit: str
    variant: str = ""  #: which of our computations (e.g. "stated geometry")
    tol: float | None = None  #: claim-specific tolerance for "reproduced"
    reason: str = ""  #: why it differs, or what was assumed
    kind: str = "value"  #: "value", "upper"/"lower" (a bound the paper states), "order" (see judge)
    verdict: str = field(init=False)

    def __post_init__(self) -> None:
        object.__setattr__(self, "verdict", judge(self.printed, self.ours, self.tol, self.kind))

    @property
    def diff(self) -> float:
        return float(self.ours) - float(self.printed)


def load_reference(paper: str, reference_dir: Path = REFERENCE_DIR) -> pd.DataFrame:
    """The transcribed published numbers of ``paper``; ``value`` kept as the printed string."""
    path = Path(reference_dir) / f"{paper}.csv"
    ref = pd.read_csv(path, dtype={"value": str}, keep_default_na=False)
    missing = {"paper", "artefact", "quantity", "value", "unit", "note"} - set(ref.columns)
    if missing:
        raise ValueError(f"{path}: missing columns {sorted(missing)}")
    return ref


def printed_value(ref: pd.DataFrame, artefact: str, quantity: str) -> str:
    """The printed value of one reference entry (exactly one must exist)."""
    rows = ref[(ref["artefact"] == artefact) & (ref["quantity"] == quantity)]
    if len(rows) != 1:
        raise KeyError(f"reference has {len(rows)} rows for ({artefact!r}, {quantity!r}), expected 1")
    return str(rows["value"].iloc[0])


def _fmt(x: float) -> str:
    if x == 0 or not math.isfinite(x):
        return str(x)
    return f"{x:.6g}"


def claims_table(claims: list[Claim]) -> pd.DataFrame:
    return pd.DataFrame(
        {
            "artefact": [c.artefact for c in claims],
            "quantity": [c.quantity for c in claims],
            "variant": [c.variant for c in claims],
            "paper": [{"upper": "≤ ", "lower": "≥ ", "order": "~"}.get(c.kind, "") + c.printed for c in claims],
            "ours": [_fmt(c.ours) for c in claims],
            "difference": [_fmt(c.diff) for c in claims],
            "unit": [c.unit for c in claims],
            "verdict": [c.verdict for c in claims],
            "reason": [c.reason for c in claims],
        }
    )


def build_report(figures_dir: Path, reference_dir: Path = REFERENCE_DIR) -> str:
    """REPORT.md text for every paper whose outputs exist under ``figures_dir``."""
    from parakin.papers import PAPERS  # late import: paper modules import this module

    lines = [
        "# parakin reproduction report",
        "",
        "Generated by `parakin report` from the pipeline outputs in this folder and the published",
        "numbers transcribed in `data/reference/`. Verdicts: **reproduced** (within the stated",
        "tolerance), **reproduced within rounding** (within half a unit of the last printed digit),",
        "**differs** (with the reason we found). Nothing here is typed in by hand.",
        "",
    ]
    summary = []
    sections = []
    for key, module in PAPERS.items():
        if not (Path(figures_dir) / key).is_dir():
            continue
        ref = load_reference(key, reference_dir)
        claims = module.claims(Path(figures_dir) / key, ref)
        compared = {(c.artefact, c.quantity) for c in claims}
        counts = pd.Series([c.verdict for c in claims]).value_counts()
        summary.append(
            {
                "paper": key,
                "published numbers": len(ref),
                "compared so far": len(compared),
                REPRODUCED: int(counts.get(REPRODUCED, 0)),
                WITHIN_ROUNDING: int(counts.get(WITHIN_ROUNDING, 0)),
                DIFFERS: int(counts.get(DIFFERS, 0)),
            }
        )
        sections += [f"## {module.TITLE}", "", module.summary(Path(figures_dir) / key, ref).strip(), ""]
        sections += [markdown_table(claims_table(claims)), ""]
    lines += ["## At a glance", "", markdown_table(pd.DataFrame(summary)) if summary else "(no outputs yet)", ""]
    from parakin import extras

    beyond = extras.summary(Path(figures_dir))
    if beyond:
        sections += [f"## {extras.TITLE}", "", beyond, ""]
    return "\n".join(lines + sections)


def write_report(figures_dir: Path, out: Path, reference_dir: Path = REFERENCE_DIR) -> Path:
    """Build the report and write it atomically to ``out``."""
    return atomic_write_text(out, build_report(Path(figures_dir), reference_dir))
