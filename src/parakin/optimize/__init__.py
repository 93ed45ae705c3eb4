"""Design optimisation: the paper's GA with the normalised weighted sum (Zhao 2017 §3.4, eqs 38-40)
NSGA-II through pymoo for the Pareto front (beyond the paper), and a deterministic grid and
pattern search for the normalisation extremes of eq. 38."""

from parakin.optimize.ga import GAOptions, GAResult, ga, normalised_sum, rank_expectation
from parakin.optimize.pareto import ParetoResult, non_dominated, nsga2
from parakin.optimize.pattern import PatternResult, box_grid, pattern_search

__all__ = [
    "GAOptions",
    "GAResult",
    "ga",
    "normalised_sum",
    "rank_expectation",
    "ParetoResult",
    "non_dominated",
    "nsga2",
    "PatternResult",
    "box_grid",
    "pattern_search",
]
