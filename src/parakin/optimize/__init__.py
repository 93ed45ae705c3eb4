"""Design optimisation: the paper's GA with the normalised weighted sum (Zhao 2017 §3.4, eqs 38-40)
and NSGA-II through pymoo for the Pareto front (beyond the paper)."""

from parakin.optimize.ga import GAOptions, GAResult, ga, normalised_sum, rank_expectation
from parakin.optimize.pareto import ParetoResult, non_dominated, nsga2

__all__ = [
    "GAOptions",
    "GAResult",
    "ga",
    "normalised_sum",
    "rank_expectation",
    "ParetoResult",
    "non_dominated",
    "nsga2",
]
