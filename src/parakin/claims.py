"""Claims: one published number, our value for it and a verdict that cannot flatter.

Each paper module (:mod:`parakin.papers`) turns its pipeline outputs into :class:`Claim` objects
(``claims(figures_dir, reference)``); :mod:`parakin.report` collects them into ``REPORT.md`` and
``report.csv``. Our values are always read from pipeline outputs, never typed in; published values
come from ``data/reference/<paper>.csv`` exactly as printed, so the rounding of the print is known,
and so does the tolerance of each comparison (the ``tolerance`` column, declared there before the
comparison; :func:`resolve` applies it). This module imports no paper, so papers, the report and
the tests all depend on it, never the reverse.

The verdicts (:data:`VERDICTS`), from the strongest:

- *reproduced*: an independent computation agrees within the tolerance declared in
  ``data/reference`` (or within a bound's / an order of magnitude's stated sense);
- *reproduced within rounding*: within half a unit of the last printed digit;
- *bound satisfied*: the paper states a bound (``≤ 20 ms``) and ours meets it;
- *consistent after fitting or assuming*: agreement that rests on something fitted to the same
  numbers or assumed because it matches (the claim names it, ``basis``); never counted as reproduced;
- *differs — cause shown*: ours differs and an artefact or test shows why (``evidence``);
- *differs — cause unknown*: ours differs and nothing shows why;
- *not comparable*: the published number is lost, qualitative, or a wall-clock time of another
  machine (the reason says which);
- *input*: a set-up value the paper gives (geometry, masses, solver settings), not a result.

A chaotic computation (a genetic algorithm, a particle swarm, a network's training) is judged by
the distribution of independent runs, never by one trajectory (:meth:`Claim.from_runs`): ours is
the median of the runs, shown with its confidence interval (:func:`run_summary`) and the runs'
range, and the comparison asks whether the paper's number lies in that range (within the declared
tolerance; an order of magnitude: whether the range reaches within half a decade of it). A bound is
met when the median run meets it (a typical run; the share of runs that meet it is shown). The
paper reports one run: a number inside our runs' range is one our runs can give.

One published number may be judged by several computations of ours, its *readings* (a region, a
variant of a method, the stated or a fitted geometry). A favourable reading must not hide the
others, so :func:`decide` gives the number the verdict of **one declared reading** where a claim
declares itself (``declared``: why this reading, chosen before the comparison, is the one that
judges the number, e.g. "the geometry the paper states"; at most one per number, and never one that
rests on a fit or an assumption, ``basis``), else the verdict of **the weakest reading** (the last
in :data:`VERDICTS`). Every reading is listed beside the verdict (``report.csv``'s ``readings``
column), with its value, its own verdict and its evidence.

A number that is one part of a result judged as a whole (a coordinate of a pose that must solve the
paper's input as a whole) cannot agree on its own: ``whole_agrees=False`` makes it differ whatever
its own value (a single coordinate within rounding of a row that is no solution is a coincidence).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field, replace
from pathlib import Path

import numpy as np
import pandas as pd

from parakin.config import ROOT

__all__ = [
    "Claim",
    "judge",
    "half_ulp",
    "load_reference",
    "printed_value",
    "claims_table",
    "REFERENCE_DIR",
    "REPRODUCED",
    "WITHIN_ROUNDING",
    "BOUND",
    "CONSISTENT",
    "DIFFERS_SHOWN",
    "DIFFERS_UNKNOWN",
    "NOT_COMPARABLE",
    "INPUT",
    "NOT_JUDGED",
    "VERDICTS",
    "DIFFERS",
    "parse_tolerance",
    "resolve",
    "reference_row",
    "row_verdicts",
    "decide",
    "readings_text",
    "ROLES",
    "run_summary",
    "CI_LEVEL",
]

REFERENCE_DIR = ROOT / "data" / "reference"

REPRODUCED = "reproduced"
WITHIN_ROUNDING = "reproduced within rounding"
BOUND = "bound satisfied"
CONSISTENT = "consistent after fitting or assuming"
DIFFERS_SHOWN = "differs — cause shown"
DIFFERS_UNKNOWN = "differs — cause unknown"
NOT_COMPARABLE = "not comparable"
INPUT = "input"
#: a published result no artefact judges yet (the tests require none; it keeps the counts honest)
NOT_JUDGED = "not judged yet"
#: every verdict, strongest first; a published number judged by several readings gets its declared
#: reading's verdict, else the weakest (the last in this order; :func:`decide`)
VERDICTS = (
    REPRODUCED,
    WITHIN_ROUNDING,
    BOUND,
    CONSISTENT,
    DIFFERS_SHOWN,
    DIFFERS_UNKNOWN,
    NOT_COMPARABLE,
    INPUT,
    NOT_JUDGED,
)
#: the raw outcome of a comparison before basis and evidence are applied
DIFFERS = "differs"

#: the ``role`` column of a reference CSV: a result to judge, a set-up value, or a number that
#: cannot be compared (lost, qualitative, another machine's clock; the note says why)
ROLES = ("result", "input", "not comparable")


def half_ulp(printed: str) -> float:
    """Half a unit in the last printed place: '0.42' -> 0.005, '4.51e-8' -> 5e-11, '3' -> 0.5."""
    text = printed.strip().lower()
    mantissa, _, exponent = text.partition("e")
    decimals = len(mantissa.split(".")[1]) if "." in mantissa else 0
    return 0.5 * 10.0 ** (-decimals + (int(exponent) if exponent else 0))


#: how a printed number is compared: its value, a bound it states, or its order of magnitude
KINDS = ("value", "upper", "lower", "order")


#: confidence level of the interval of the median over independent runs (report and check alike)
CI_LEVEL = 0.99


def run_summary(values, level: float = CI_LEVEL) -> dict[str, float]:
    """``runs, median, ci_low, ci_high, min, max`` of independent runs of a chaotic computation.

    The interval is the distribution-free confidence interval of the median by order statistics
    (the ``j``-th smallest and largest of ``n`` runs, ``j`` the largest with ``P(Binom(n, 1/2) < j)
    <= (1 - level) / 2``); with too few runs for ``level`` it is the whole range. Non-finite runs
    (a run that failed) count as runs: they sort above every finite value."""
    from scipy.stats import binom

    x = np.sort(np.where(np.isfinite(v := np.asarray(values, dtype=float)), v, np.inf))
    n = len(x)
    if n == 0:
        raise ValueError("run_summary needs at least one run")
    j = 1
    while j < n // 2 and binom.cdf(j, n, 0.5) <= (1 - level) / 2:
        j += 1  # P(Binom < j + 1) <= alpha/2: the (j+1)-th order statistics still cover
    return {
        "runs": n,
        "median": float(np.median(x)) if np.isfinite(np.median(x)) else math.inf,
        "ci_low": float(x[j - 1]),
        "ci_high": float(x[n - j]),
        "min": float(x[0]),
        "max": float(x[-1]),
    }


def _gap(printed: float, spread: tuple[float, float]) -> float:
    """Distance from the printed value to the runs' range (0 inside)."""
    lo, hi = spread
    return max(lo - printed, printed - hi, 0.0)


def judge(
    printed: str,
    ours: float,
    tol: float | None = None,
    kind: str = "value",
    margin: float = 1.0,
    spread: tuple[float, float] | None = None,
) -> str:
    """The raw outcome of comparing our value with the printed one.

    ``kind="value"``: ``reproduced`` when ``|ours - paper| <= tol`` (a tolerance declared in the
    reference CSV), ``reproduced within rounding`` within half a unit of the last printed digit
    (not for a tolerance declared exact, ``tol = 0``), ``differs`` otherwise. ``kind="upper"`` / ``"lower"``: the paper states a bound: ``bound
    satisfied`` when ours meets it with the declared ``margin`` (``ours * margin <= paper`` for an
    upper bound). ``kind="order"``: an order of magnitude ("10^-4 level"): ``reproduced`` within
    half a decade. ``spread = (min, max)`` of independent runs (``ours`` their median): a value
    or an order is judged by the printed number's distance to that range, a bound by the median.
    """
    if kind not in KINDS:
        raise ValueError(f"kind = {kind!r} must be one of {KINDS}")
    if not math.isfinite(float(ours)) and (spread is None or kind in ("upper", "lower")):
        return DIFFERS
    if kind == "upper":
        return BOUND if float(ours) * margin <= float(printed) else DIFFERS
    if kind == "lower":
        return BOUND if float(ours) >= float(printed) * margin else DIFFERS
    if kind == "order":
        lo, hi = spread if spread is not None else (float(ours), float(ours))
        p = float(printed)
        ok = (
            hi > 0
            and math.log10(p) - 0.5 <= math.log10(hi)
            and (lo <= 0 or math.log10(lo) <= math.log10(p) + 0.5)
        )
        return REPRODUCED if ok and math.isfinite(lo) else DIFFERS
    diff = _gap(float(printed), spread) if spread is not None else abs(float(ours) - float(printed))
    if tol is not None and diff <= tol:
        return REPRODUCED
    if tol == 0.0:  # declared exact (counts, symbolic results, a printed zero width): no rounding
        return DIFFERS
    if diff <= half_ulp(printed) * (1 + 1e-9):
        return WITHIN_ROUNDING
    return DIFFERS


def parse_tolerance(text: str, printed: str) -> tuple[str, float | None, float]:
    """``(kind, tol, margin)`` of a reference CSV's ``tolerance`` cell.

    ``""``: rounding only (half a printed digit); ``abs:X`` / ``rel:X``: agreement within X
    (absolute, or relative to the printed value); ``exact``: abs:0 (counts, symbolic results);
    ``upper`` / ``lower`` (optionally ``upper:M``: met with a margin of M, e.g. a time bound met
    10x over); ``order``: within half a decade.
    """
    text = (text or "").strip()
    if not text:
        return "value", None, 1.0
    name, _, arg = text.partition(":")
    if name == "exact":
        return "value", 0.0, 1.0
    if name == "abs":
        return "value", float(arg), 1.0
    if name == "rel":
        return "value", float(arg) * abs(float(printed)), 1.0
    if name in ("upper", "lower"):
        return name, None, float(arg) if arg else 1.0
    if name == "order":
        return "order", None, 1.0
    raise ValueError(
        f"unknown tolerance {text!r} (one of '', exact, abs:X, rel:X, upper[:M], lower[:M], order)"
    )


@dataclass(frozen=True)
class Claim:
    """One published number, our value for it and the verdict.

    ``basis`` names what was fitted or assumed *because it matches* (the verdict is then at most
    "consistent after fitting or assuming"); ``evidence`` names the artefact or test that shows why
    ours differs (without it a difference is "cause unknown"); ``comparable=False`` marks a number
    that cannot be compared (``reason`` says why). ``tol`` / ``kind`` / ``margin`` are set by
    :func:`resolve` from the reference CSV's ``tolerance`` cell, the one place a tolerance is declared;
    paper code never passes them (``tests/test_report.py`` checks). ``declared`` makes this claim
    the one reading that judges its published number (see :func:`decide`; the text says why it was
    chosen before the comparison, and a claim with a ``basis`` cannot declare itself).
    """

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
    basis: str = (
        ""  #: what was fitted or assumed to get agreement ("" = an independent computation)
    )
    evidence: str = ""  #: the file or test that shows the cause of a difference
    comparable: bool = (
        True  #: False: lost, qualitative or another machine's clock (reason says why)
    )
    margin: float = 1.0  #: a bound must be met this many times over
    tolerance: str = ""  #: the declared tolerance as written in the reference CSV (set by resolve)
    #: the range (min, max) of the independent runs whose median ``ours`` is (see :meth:`from_runs`)
    spread: tuple[float, float] | None = None
    #: False: one part of a result judged as a whole that does not agree (see the module's notes)
    whole_agrees: bool | None = None
    #: why this reading, and no other, judges the published number (chosen before the comparison:
    #: e.g. "the geometry the paper states"); "" = one reading among others (:func:`decide`)
    declared: str = ""
    outcome: str = field(
        init=False
    )  #: raw comparison: reproduced / within rounding / bound satisfied / differs
    verdict: str = field(init=False)

    def __post_init__(self) -> None:
        if self.declared and self.basis:
            raise ValueError(
                f"{self.paper} {self.artefact}/{self.quantity}: a declared reading cannot rest on "
                f"something fitted or assumed ({self.basis!r}): it is chosen before the comparison"
            )
        outcome = judge(self.printed, self.ours, self.tol, self.kind, self.margin, self.spread)
        if self.whole_agrees is False:
            outcome = DIFFERS
        object.__setattr__(self, "outcome", outcome)
        if not self.comparable:
            verdict = NOT_COMPARABLE
        elif outcome == DIFFERS:
            verdict = DIFFERS_SHOWN if self.evidence else DIFFERS_UNKNOWN
        elif self.basis:
            verdict = CONSISTENT
        else:
            verdict = outcome
        object.__setattr__(self, "verdict", verdict)

    @classmethod
    def from_runs(
        cls,
        paper: str,
        artefact: str,
        quantity: str,
        printed: str,
        runs,
        unit: str,
        variant: str = "",
        *,
        what: str = "runs",
        **fields,
    ) -> Claim:
        """The claim judged on independent runs of a chaotic computation: ours = their median, the
        variant names how many ``what`` (e.g. "GA seeds"), the confidence interval of the median
        (:func:`run_summary`) and the range, which the printed number is judged against."""
        s = run_summary(runs)
        text = (
            f"median of {s['runs']} {what} {_fmt(s['median'])}, {100 * CI_LEVEL:g} % CI "
            f"[{_fmt(s['ci_low'])}, {_fmt(s['ci_high'])}], range [{_fmt(s['min'])}, {_fmt(s['max'])}]"
        )
        return cls(
            paper,
            artefact,
            quantity,
            printed,
            s["median"],
            unit,
            f"{variant}: {text}" if variant else text,
            spread=(s["min"], s["max"]),
            **fields,
        )

    @property
    def diff(self) -> float:
        return float(self.ours) - float(self.printed)

    @property
    def differs(self) -> bool:
        return self.verdict in (DIFFERS_SHOWN, DIFFERS_UNKNOWN)


def load_reference(paper: str, reference_dir: Path = REFERENCE_DIR) -> pd.DataFrame:
    """The transcribed published numbers of ``paper``; ``value`` kept as the printed string.

    Columns: paper, artefact, quantity, value, unit, note, and (optional) ``role`` (one of
    :data:`ROLES`, default ``result``) and ``tolerance`` (see :func:`parse_tolerance`)."""
    path = Path(reference_dir) / f"{paper}.csv"
    ref = pd.read_csv(path, dtype=str, keep_default_na=False)
    missing = {"paper", "artefact", "quantity", "value", "unit", "note"} - set(ref.columns)
    if missing:
        raise ValueError(f"{path}: missing columns {sorted(missing)}")
    for col, default in (("role", "result"), ("tolerance", "")):
        if col not in ref.columns:
            ref[col] = default
        ref[col] = ref[col].replace("", default)
    bad = sorted(set(ref["role"]) - set(ROLES))
    if bad:
        raise ValueError(f"{path}: unknown role(s) {bad}; one of {ROLES}")
    return ref


def reference_row(ref: pd.DataFrame, artefact: str, quantity: str) -> pd.Series:
    rows = ref[(ref["artefact"] == artefact) & (ref["quantity"] == quantity)]
    if len(rows) != 1:
        raise KeyError(
            f"reference has {len(rows)} rows for ({artefact!r}, {quantity!r}), expected 1"
        )
    return rows.iloc[0]


def printed_value(ref: pd.DataFrame, artefact: str, quantity: str) -> str:
    """The printed value of one reference entry (exactly one must exist)."""
    return str(reference_row(ref, artefact, quantity)["value"])


def resolve(claim: Claim, ref: pd.DataFrame) -> Claim:
    """The claim judged with the tolerance its reference row declares.

    The printed value must be the reference row's (nothing typed in code); the tolerance is the
    reference CSV's, never the code's; an ``input`` row's claims are set-up echoes (verdict input)."""
    row = reference_row(ref, claim.artefact, claim.quantity)
    if str(row["value"]) != claim.printed:
        raise ValueError(
            f"{claim.paper} {claim.artefact}/{claim.quantity}: claim prints {claim.printed!r}, "
            f"the reference {row['value']!r}"
        )
    kind, tol, margin = parse_tolerance(row["tolerance"], claim.printed)
    out = replace(claim, kind=kind, tol=tol, margin=margin, tolerance=row["tolerance"])
    if row["role"] == "input":
        object.__setattr__(out, "verdict", INPUT)
    elif row["role"] == "not comparable" and out.verdict != NOT_COMPARABLE:
        out = replace(
            out, comparable=False, reason=(out.reason + "; " if out.reason else "") + row["note"]
        )
    return out


#: how :func:`decide` chose the reading: the only one, the declared one, or the weakest of several
DECIDED_BY = ("only reading", "declared reading", "weakest reading")


def decide(readings: list[Claim]) -> tuple[Claim | None, str]:
    """The reading whose verdict one published number gets, and how it was chosen
    (:data:`DECIDED_BY`): the claim that declares itself (``declared``; more than one is an error),
    else the weakest (the last in :data:`VERDICTS`; among equals the first given). A favourable
    reading never hides an unfavourable one unless a reading was declared before the comparison."""
    if not readings:
        return None, ""
    declared = [c for c in readings if c.declared]
    if len(declared) > 1:
        c = declared[0]
        raise ValueError(
            f"{c.paper} {c.artefact}/{c.quantity}: {len(declared)} readings declare themselves "
            f"({', '.join(repr(d.variant) for d in declared)}); at most one may"
        )
    if declared:
        return declared[0], DECIDED_BY[1]
    weakest = max(
        readings, key=lambda c: VERDICTS.index(c.verdict)
    )  # max keeps the first of equals
    return weakest, DECIDED_BY[0] if len(readings) == 1 else DECIDED_BY[2]


def readings_text(readings: list[Claim], chosen: Claim | None, decided_by: str) -> str:
    """Every reading of one published number, as the report's ``readings`` column states them:
    how the verdict was chosen, then each reading's value, verdict and evidence ("" for a number
    with one undeclared reading)."""
    if chosen is None or decided_by == DECIDED_BY[0]:
        return ""
    if decided_by == DECIDED_BY[1]:
        head = f"declared reading: {chosen.variant or 'ours'} ({chosen.declared})"
    else:
        head = f"the weakest of {len(readings)} readings decides: {chosen.variant or 'ours'}"
    if len(readings) == 1:
        return head
    items = [
        f"[{k}] {c.variant or 'ours'}: {_fmt(c.ours)} → {c.verdict}"
        + (f" (evidence: {c.evidence})" if c.evidence else "")
        for k, c in enumerate(readings, start=1)
    ]
    return f"{head}. All {len(readings)} readings: " + "; ".join(items)


def row_verdicts(claims: list[Claim], ref: pd.DataFrame) -> pd.DataFrame:
    """One row per reference row: its verdict (its role's, or that of the reading :func:`decide`
    chooses among its resolved claims), the claim that decided it (``None`` for inputs and lost
    numbers without a claim), how it was chosen (``decided_by``) and all its ``readings``."""
    by_row: dict[tuple[str, str], list[Claim]] = {}
    for c in claims:
        by_row.setdefault((c.artefact, c.quantity), []).append(c)
    rows = []
    for _, r in ref.iterrows():
        cs = by_row.get((r["artefact"], r["quantity"]), [])
        chosen, decided_by = decide(cs)
        if r["role"] == "input":
            verdict = INPUT
        elif r["role"] == "not comparable" and chosen is None:
            verdict = NOT_COMPARABLE
        else:
            verdict = chosen.verdict if chosen is not None else NOT_JUDGED
        rows.append(
            {
                "artefact": r["artefact"],
                "quantity": r["quantity"],
                "verdict": verdict,
                "claim": chosen,
                "decided_by": decided_by,
                "readings": cs,
                "ref": r,
            }
        )
    return pd.DataFrame(rows)


def _fmt(x: float) -> str:
    if x == 0 or not math.isfinite(x):
        return str(x)
    return f"{x:.6g}"


def _paper_cell(c: Claim) -> str:
    """The published number exactly as printed (transcribed in data/reference): how it is compared
    (a bound of ours or the paper's, an order of magnitude) is the ``tolerance``, never the cell."""
    return c.printed


def _decides(claims: list[Claim]) -> list[str]:
    """Per claim: whether it is the reading that decides its published number's verdict
    (:func:`decide`) where that number has several readings or a declared one, else ""."""
    by_row: dict[tuple[str, str], list[Claim]] = {}
    for c in claims:
        by_row.setdefault((c.artefact, c.quantity), []).append(c)
    out = []
    for c in claims:
        readings = by_row[(c.artefact, c.quantity)]
        chosen, how = decide(readings)
        if how == DECIDED_BY[0]:
            out.append("")
        else:
            word = "declared" if how == DECIDED_BY[1] else "weakest"
            out.append(f"decides ({word})" if chosen is c else f"one of {len(readings)}")
    return out


def claims_table(claims: list[Claim]) -> pd.DataFrame:
    """Every claim (every reading of every published number) with its own verdict; ``reading``
    says which of a number's readings decides its verdict (:func:`decide`)."""
    return pd.DataFrame(
        {
            "artefact": [c.artefact for c in claims],
            "quantity": [c.quantity for c in claims],
            "variant": [c.variant for c in claims],
            "paper": [_paper_cell(c) for c in claims],
            "ours": [_fmt(c.ours) for c in claims],
            "difference": [_fmt(c.diff) for c in claims],
            "unit": [c.unit for c in claims],
            "tolerance": [c.tolerance for c in claims],
            "verdict": [c.verdict for c in claims],
            "reading": _decides(claims),
            "reason": [
                (
                    "; ".join(
                        x
                        for x in (
                            f"{'fitted/assumed' if c.basis else ''}{': ' + c.basis if c.basis else ''}",
                            c.reason,
                            f"evidence: {c.evidence}" if c.evidence else "",
                        )
                        if x
                    )
                )
                for c in claims
            ],
        }
    )
