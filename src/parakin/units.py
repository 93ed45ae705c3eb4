"""Unit conversion at the edges: the library works in SI (m, rad); papers print mm and degrees."""

from __future__ import annotations

import numpy as np

#: factor that converts a value in the named unit to SI
TO_SI: dict[str, float] = {"m": 1.0, "mm": 1e-3, "rad": 1.0, "deg": float(np.pi / 180), "1": 1.0}


def to_si(values, units: tuple[str, ...]) -> np.ndarray:
    """Convert ``values`` (..., n) given in ``units`` (n names) to SI."""
    return np.asarray(values, dtype=float) * np.array([TO_SI[u] for u in units])


def from_si(values, units: tuple[str, ...]) -> np.ndarray:
    """Convert SI ``values`` (..., n) to ``units``."""
    return np.asarray(values, dtype=float) / np.array([TO_SI[u] for u in units])


def parse_quantity(text: str) -> float:
    """'0.38' -> 0.38; '35deg' -> 0.6109 rad; '120mm' -> 0.12 m (a unit suffix converts to SI)."""
    s = text.strip()
    for unit in sorted((u for u in TO_SI if u.isalpha()), key=len, reverse=True):
        if s.endswith(unit) and s[: -len(unit)].strip():
            try:
                return float(s[: -len(unit)]) * TO_SI[unit]
            except ValueError:
                break
    try:
        return float(s)
    except ValueError:
        raise ValueError(
            f"cannot read {text!r} as a number (optionally with a unit {sorted(TO_SI)})"
        ) from None
