"""Shared fixtures: the quick config, seeded generators, sampled reachable poses."""

from __future__ import annotations

import numpy as np
import pytest

from parakin.config import DEFAULT_CONFIG, QUICK_CONFIG, load_config
from parakin.mechanisms import P3P4S


@pytest.fixture(scope="session")
def quick_config() -> dict:
    return load_config([DEFAULT_CONFIG, QUICK_CONFIG])


@pytest.fixture
def rng() -> np.random.Generator:
    return np.random.default_rng(20171010)


@pytest.fixture(params=["stated", "optimised"])
def p3p4s(request) -> P3P4S:
    return P3P4S.zhao2017() if request.param == "stated" else P3P4S.zhao2017_optimised()


def pytest_collection_modifyitems(config, items):
    """The notebooks (collected by nbmake from notebooks/) are slow: each runs a paper's walk-through
    in a kernel of its own."""
    for item in items:
        if item.nodeid.endswith(".ipynb"):
            item.add_marker(pytest.mark.slow)
