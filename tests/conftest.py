"""Shared fixtures: the quick config, seeded generators, sampled reachable poses."""

from __future__ import annotations

from collections import Counter

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


#: the test files that go last: the quick pipeline (a fifth of the suite's CPU). Run after the
#: other files have compiled the kernels, it loads them from the shared cache instead of compiling
#: them beside the other worker, and its two-core jobs fill the run's end, when the other worker
#: has no file left to start
LAST = ("tests/test_pipeline.py",)


def _file(item) -> str:
    return item.nodeid.split("::")[0]


def pytest_collection_modifyitems(config, items):
    """The notebooks (collected by nbmake from notebooks/) are slow: each runs a paper's walk-through
    in a kernel of its own. Files go to the workers (xdist ``--dist loadfile``, in this order:
    ``--no-loadscope-reorder``) by their number of tests, most first, as xdist would order them,
    except :data:`LAST`, which go last."""
    for item in items:
        if item.nodeid.endswith(".ipynb"):
            item.add_marker(pytest.mark.slow)
    count = Counter(_file(item) for item in items)
    items.sort(key=lambda item: (_file(item) in LAST, -count[_file(item)]))  # stable: else as found
