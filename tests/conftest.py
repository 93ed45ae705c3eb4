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


#: the test files that go first: the quick pipeline (a quarter of the suite's CPU, on one worker)
#: started last, when the other worker had little left, and was then the whole run's tail
FIRST = ("tests/test_pipeline.py",)


def pytest_collection_modifyitems(config, items):
    """The notebooks (collected by nbmake from notebooks/) are slow: each runs a paper's walk-through
    in a kernel of its own. The files of :data:`FIRST` run first (xdist hands files to its
    workers in this order, ``--dist loadfile``)."""
    for item in items:
        if item.nodeid.endswith(".ipynb"):
            item.add_marker(pytest.mark.slow)
    items.sort(key=lambda item: item.nodeid.split("::")[0] not in FIRST)  # stable: else as found
