"""Zhao 2017 forward kinematics: the hybrid network + quasi-Newton solver against the closed form,
every numeric solver against the closed form, unreachable strokes, reproducible training."""

import numpy as np
import pandas as pd
import pytest

from parakin.mechanisms import P3P4S
from parakin.nn import BPNetwork
from parakin.papers.zhao2017_3p4s import fk
from parakin.solvers import Status, solve_fk
from parakin.workspace import sample_reachable


@pytest.fixture(scope="module")
def trained(tmp_path_factory, quick_config):
    """Samples + training on the quick config, into temporary folders."""
    base = tmp_path_factory.mktemp("fk")
    config = {**quick_config, "generated_dir": str(base / "generated")}
    outdir = base / "figures"
    fk.samples(config, outdir)
    fk.train(config, outdir)
    return config, outdir


@pytest.fixture(scope="module")
def network(trained) -> BPNetwork:
    return BPNetwork.load(fk.network_path(trained[0]))


@pytest.fixture(scope="module")
def inputs():
    mech = P3P4S()
    poses = sample_reachable(mech, 1500, np.random.default_rng(4))
    return mech, poses, mech.ik(poses)


def test_hybrid_accuracy_and_iterations(network, inputs):
    mech, poses, q = inputs
    res = solve_fk(mech, q, method="hybrid", network=network, eps=1e-7, tol=0.0)
    err = np.max(np.abs(res.x - poses), axis=-1)
    assert res.success.all()
    assert np.mean(err <= 1e-8) >= 0.99  # the paper's "1e-8 level"
    assert np.mean((err <= 1e-8) & (res.nit <= 3)) >= 0.95  # ... with <= 3 quasi-Newton iterations
    guess = network.predict(q)
    assert np.median(np.max(np.abs(guess - poses), axis=-1)) > 100 * np.median(
        err
    )  # the refinement matters


@pytest.mark.parametrize("method", ["newton", "broyden", "bfgs", "lm", "scipy-root"])
def test_closed_form_agrees_with_every_numeric_solver(inputs, method):
    mech, poses, q = inputs
    n = 100 if method == "scipy-root" else len(q)
    closed = mech.fk(q[:n])
    res = solve_fk(mech, q[:n], method=method, tol=1e-13, maxiter=200)
    assert res.success.all(), res.message
    assert np.max(np.abs(res.x - closed)) <= 1e-10


def test_hybrid_flags_unreachable_strokes_without_aborting_the_batch(network):
    """Strokes whose spheres do not meet, or that assemble only in the other mode, get their own
    status; the reachable row of the same batch is still solved."""
    res = solve_fk(
        P3P4S(),
        [[0.43, 0.43, 0.43], [0.0, 1.5, 0.0], [0.0, 0.9, 0.2]],
        method="hybrid",
        network=network,
    )
    assert res.success.tolist() == [True, False, False]
    assert np.all(res.status[1:] == Status.UNREACHABLE)


def test_training_is_reproducible(trained, tmp_path):
    config, _ = trained
    again = {**config, "generated_dir": str(tmp_path / "generated")}
    fk.samples(again, tmp_path / "figures")
    fk.train(again, tmp_path / "figures")
    a = np.load(fk.network_path(config))
    b = np.load(fk.network_path(again))
    assert set(a.files) == set(b.files)
    for key in a.files:
        assert np.array_equal(a[key], b[key]), key


def test_table2_on_quick_config(trained):
    config, outdir = trained
    fk.table2(config, outdir)
    tab = pd.read_csv(outdir / "table2.csv")
    assert len(tab) == 5 and tab["converged"].all()
    assert (tab["e3"] <= 1e-8).all() and (tab["iterations"] <= 3).all()
    assert (tab["time_ms"] < 20).all()
    # the network alone is far from 1e-8: the quasi-Newton step is what makes the accuracy
    assert (tab["e3_guess"] > 1e-6).all()


def test_cli_hybrid_with_trained_network(trained, capsys):
    import json

    from parakin.cli import main

    q = P3P4S().ik([0.03, -0.01, 0.565])
    args = [
        "fk",
        "3p4s",
        "--joints",
        *map(repr, q.tolist()),
        "--solver",
        "hybrid",
        "--network",
        str(fk.network_path(trained[0])),
        "--json",
    ]
    assert main(args) == 0
    out = json.loads(capsys.readouterr().out)
    assert out["method"] == "hybrid" and out["success"] and out["nit"] <= 3
    assert np.allclose(out["x"], [0.03, -0.01, 0.565], atol=1e-9)


def test_benchmark_harness_reports_ratios(network, inputs):
    from parakin.bench import SolverSpec, bench_fk

    mech, poses, q = inputs
    specs = [
        SolverSpec("hybrid", "hybrid", {"network": network}, start="network"),
        SolverSpec("closed", "closed-form"),
        SolverSpec("root", "scipy-root", batched=False),
    ]
    df = bench_fk(mech, specs, (q[:5], poses[:5]), (q, poses), repeats=1).set_index("solver")
    assert (df["success_rate"] == 1.0).all()
    assert df.loc["root", "speedup_single"] == 1.0 and df.loc["root", "speedup_per_solve"] == 1.0
    # timings are reported, not asserted (speed claims live in the benchmark table)
    assert (
        np.isfinite(
            df[["median_latency_us", "throughput_per_s", "speedup_single", "speedup_per_solve"]]
        )
        .all()
        .all()
    )
    assert df.loc["closed", "median_nit"] == 0 and df.loc["hybrid", "max_err_m"] <= 1e-8
