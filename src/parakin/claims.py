"""Claims: one published number, our value for it and a verdict.

Each paper module (:mod:`parakin.papers`) turns its pipeline outputs into :class:`Claim` objects
(``claims(figures_dir, reference)``); :mod:`parakin.report` collects them into ``REPORT.md``.
Our values are always read from pipeline outputs, never typed in; published values come from
``data/reference/<paper>.csv`` exactly as printed, so the rounding of the print is known. This
module imports no paper, so papers, the report and the tests all depend on it, never the reverse.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from pathlib import Path

import pandas as pd

from parakin.config import ROOT

__all__ = ["Claim", "judge", "half_ulp", "load_reference", "printed_value", "claims_table", "REFERENCE_DIR",
           "REPRODUCED", "WITHIN_ROUNDING", "DIFFERS"]

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
