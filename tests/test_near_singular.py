"""Near-singular FK answers (issue 26, finding 7): flagged, with the neighbour where it is predicted.

Newton started 1e-3 from the true pose at the 40 worst-conditioned of 3,000 random poses of the 3-6
and 6-6 Stewart platforms sometimes returns another solution of the same joints on the same
assembly: a right answer, but near a singularity, where the start decides which one comes back.
Such an answer must say so (``FKResult.near_singular``, the CLI's one-line warning, exit 0).
"""

from __future__ import annotations

import json
import pickle

import numpy as np
import pytest

from parakin import mechanisms
from parakin.cli import main
from parakin.solvers import solve_fk
from parakin.solvers.result import NEAR_SINGULAR, conditioning
from parakin.workspace import sample_reachable

SEEDS = (0, 1, 2)


def _worst_and_restarted(name: str, seed: int):
    """The 40 worst-conditioned of 3,000 random poses, and Newton from each plus U(-1e-3, 1e-3)."""
    mech = mechanisms.REGISTRY[name]()
    g = np.random.default_rng(seed)
    pool = sample_reachable(mech, 3000, g)
    joints = mech.ik(pool)
    worst = np.argsort(-np.linalg.cond(mech.jacobian_pose(pool, joints)), kind="stable")[:40]
    truth, q = pool[worst], joints[worst]
    res = solve_fk(mech, q, x0=truth + g.uniform(-1e-3, 1e-3, truth.shape), method="newton")
    return mech, truth, q, res


@pytest.mark.parametrize("name", ["stewart36", "stewart66"])
def test_a_newton_answer_that_moved_to_another_solution_is_flagged(name):
    moved_total = 0
    for seed in SEEDS:
        mech, truth, q, res = _worst_and_restarted(name, seed)
        away = np.max(np.abs(mech.pose_difference(res.x, truth)), axis=-1)
        moved = res.success & (away > 1e-6)  # a right answer, but not the pose we started near
        assert np.all(res.success[moved])  # it is a right answer: IK gives the joints back
        assert np.all(res.near_singular[moved]), (seed, away[moved & ~res.near_singular])
        moved_total += int(moved.sum())
    assert moved_total > 0  # the situation of the issue does occur on these seeds


@pytest.mark.parametrize("name", ["stewart36", "stewart66"])
def test_the_predicted_neighbour_exists_where_predicted(name):
    """Newton from ``x + neighbour`` finds a distinct solution, at about the predicted offset."""
    mech, _, q, res = _worst_and_restarted(name, 0)
    c = res.conditioning
    near = res.success & c.near_singular
    assert near.sum() >= 5
    other = solve_fk(mech, q[near], x0=res.x[near] + c.neighbour[near], method="newton")
    found = mech.pose_difference(other.x, res.x[near])
    width = np.subtract(*mech.pose_bounds()[::-1])
    distance = np.max(np.abs(found) / width, axis=-1)
    ok = other.success & (distance > 1e-9)
    assert ok.mean() >= 0.9, ok
    # the fold's estimate of the offset in box units; where it exceeds the box threshold, the
    # flag came from the drawn points' motion (c.distance is then in those units, not the box's)
    predicted = np.max(np.abs(c.neighbour[near]) / width, axis=-1)
    keep = predicted[ok] <= NEAR_SINGULAR
    assert keep.mean() >= 0.5
    ratio = distance[ok] / predicted[ok]
    assert np.all((ratio[keep] > 0.5) & (ratio[keep] < 2)), ratio
    assert np.all(c.distance[near] <= NEAR_SINGULAR)


@pytest.mark.parametrize("name", ["3p4s", "2ups", "stewart12"])
def test_well_conditioned_workspaces_are_never_flagged(name):
    """Random poses of mechanisms far from singular in their box: no flag, finite condition."""
    mech = mechanisms.REGISTRY[name]()
    pose = sample_reachable(mech, 500, np.random.default_rng(5))
    res = solve_fk(mech, mech.ik(pose), x0=pose)
    assert res.success.all() and not res.near_singular.any()
    assert np.all(np.isfinite(res.conditioning.condition))


def test_conditioning_is_computed_on_demand_and_travels_with_the_result():
    mech = mechanisms.Stewart36()
    q = mech.ik(mech.home())
    res = solve_fk(mech, np.stack([q, q]).reshape(1, 2, -1), method="newton")
    assert "conditioning" not in res.__dict__  # nothing paid until asked
    c = res.conditioning
    assert c.condition.shape == (1, 2) and c.neighbour.shape == (1, 2, 6)
    again = pickle.loads(pickle.dumps(res))
    np.testing.assert_array_equal(again.conditioning.distance, c.distance)
    flat = res.reshape((2,))
    assert flat.conditioning.distance.shape == (2,)
    direct = conditioning(mech, res.x)
    np.testing.assert_array_equal(direct.condition, c.condition)


def test_nonfinite_and_empty_answers_are_not_flagged():
    mech = mechanisms.Stewart36()
    bad = conditioning(mech, np.full((1, 6), np.nan))
    assert not bad.near_singular.any() and np.isinf(bad.distance).all()
    assert conditioning(mech, np.empty((0, 6))).distance.shape == (0,)


def test_cli_warns_in_one_line_and_exits_0(capsys):
    mech, truth, q, res = _worst_and_restarted("stewart36", 1)
    i = int(np.argmax(res.success & res.near_singular))
    argv = ["fk", "stewart36", "--joints", *map(repr, q[i].tolist()), "--solver", "newton"]
    argv += ["--x0", *map(repr, res.x[i].tolist())]
    assert main(argv) == 0
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and err[0].startswith("parakin fk: warning: near a singularity")
    assert "another solution of the same joints about" in err[0] and " rad" in err[0]
    assert main([*argv, "--json"]) == 0
    out = json.loads(capsys.readouterr().out)
    assert out["near_singular"] is True and out["condition"] > 1e3
    offset = np.asarray(out["nearest_other_solution_offset"])
    assert np.max(np.abs(offset)) > 0
