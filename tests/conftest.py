"""Shared fixtures: the quick config, seeded generators, sampled reachable poses."""

from __future__ import annotations

from collections import Counter

import numpy as np
import pytest

from parakin.config import DEFAULT_CONFIG, QUICK_CONFIG, load_config
from parakin.mechanisms import P3P4S


def pytest_configure(config):
    """One garbage collection where a session ends, not pytest's five. pytest collects five times
    when it unconfigures, to surface unraisable exceptions raised by objects in reference cycles;
    each pass walks every object of the process, and a worker that has compiled the kernels holds
    0.8-0.9 million: 0.4-0.6 s a pass, 2-3 s on the tail of every run. Unraisable exceptions are
    still collected after each test and at the end. (The stash key is pytest's own, kept for
    pytester to set; without it, pytest's default stays.)"""
    try:
        from _pytest.unraisableexception import gc_collect_iterations_key
    except ImportError:
        return
    config.stash[gc_collect_iterations_key] = 1


@pytest.fixture(scope="session")
def quick_config() -> dict:
    return load_config([DEFAULT_CONFIG, QUICK_CONFIG])


@pytest.fixture
def rng() -> np.random.Generator:
    return np.random.default_rng(20171010)


@pytest.fixture(params=["stated", "optimised"])
def p3p4s(request) -> P3P4S:
    return P3P4S.zhao2017() if request.param == "stated" else P3P4S.zhao2017_optimised()


#: the quick pipeline (a fifth of the suite's CPU) goes after the files that compile the kernels,
#: so that it loads them from the shared cache instead of compiling them beside the other worker
PIPELINE = "tests/test_pipeline.py"
#: ... and before these, which run in processes of their own (a notebook's kernel, fresh
#: interpreters, the kernel-cache tests' private caches): the other worker runs them while the
#: pipeline's chain of jobs (samples, training, the tables that use the network) leaves a core
#: free. About as much work as the pipeline's 2.5-3 minutes beside them: with the kernel-cache
#: tests before the pipeline, the pipeline's worker finished 72 s after the other (a cold run,
#: 481 against 409 s); with the pipeline last, that core idled at the end
AFTER_PIPELINE = ("tests/test_kernel_cache.py", "tests/test_stability.py", "notebooks/")


def _file(item) -> str:
    return item.nodeid.split("::")[0]


def _phase(path: str) -> int:
    return 2 if path.startswith(AFTER_PIPELINE) else 1 if path == PIPELINE else 0


def pytest_collection_modifyitems(config, items):
    """The notebooks (collected by nbmake from notebooks/) are slow: each runs a paper's walk-through
    in a kernel of its own. Files go to the workers (xdist ``--dist loadfile``, in this order:
    ``--no-loadscope-reorder``) by their number of tests, most first, as xdist would order them,
    with the quick pipeline after the others (:data:`PIPELINE`, :data:`AFTER_PIPELINE`)."""
    for item in items:
        if item.nodeid.endswith(".ipynb"):
            item.add_marker(pytest.mark.slow)
    count = Counter(_file(item) for item in items)
    items.sort(key=lambda item: (_phase(_file(item)), -count[_file(item)]))  # stable
