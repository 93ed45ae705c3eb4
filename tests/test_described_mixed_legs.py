"""The bodies of a described mechanism whose legs mix all three types, interleaved: each leg's
joint, actuator and rod where its index says (the leg types are built group by group, the rods
joined back in leg order). Tolerances declared before looking: 1e-14 m or rad for the joints
against the IK (the same closed forms), 1e-10 relative for their Jacobian."""

from __future__ import annotations

from pathlib import Path

import numpy as np

import parakin.dynamics.jet as jet
from parakin.mechanisms import from_file
from parakin.mechanisms.described import from_dict

EXAMPLES = Path(__file__).resolve().parents[1] / "examples"


def mixed(pattern: str):
    """The 6-RSS with leg i turned into a length leg (L) or a slider along its home direction (S)
    as ``pattern[i]`` says (C: the crank kept)."""
    rss6 = from_file(EXAMPLES / "rss6.yaml")
    data = rss6.to_dict()
    top = rss6.platform_world(rss6.home())
    legs = []
    for i, (leg, kind) in enumerate(zip(data["legs"], pattern)):
        if kind == "L":
            leg = {"type": "length", "base": leg["base"], "platform": leg["platform"]}
        elif kind == "S":
            u = (top[i] - rss6.base_points[i]) / np.linalg.norm(top[i] - rss6.base_points[i])
            leg = {"type": "slider-rod", "base": leg["base"], "axis": u.tolist(), "rod": leg["rod"]}
            leg |= {"platform": data["legs"][i]["platform"], "branch": 1}
        legs.append(leg)
    masses = {"platform": 0.3, "cylinder": 0.2, "piston": 0.1, "slider": 0.1, "crank": 0.05}
    return from_dict({**data, "name": "mixed", "legs": legs, "masses": masses | {"rod": 0.02}})


def test_mixed_legs_keep_their_joints_actuators_and_rods_in_leg_order():
    mech = mixed("LSCLSC")
    rng = np.random.default_rng(3)
    lo, hi = mech.pose_bounds()
    x = mech.home() + 0.05 * (hi - lo) * rng.uniform(-1, 1, (4, 6))
    b = mech.bodies(jet.variable(x, np.zeros_like(x)))
    assert [g.kind for g in b.groups] == [
        "platform",
        "cylinder",
        "piston",
        "slider",
        "crank",
        "rod",
    ]
    assert b.actuators == ("piston1", "slider2", "crank3", "piston4", "slider5", "crank6")
    rod = b.group("rod")
    assert rod.names == ("rod2", "rod3", "rod5", "rod6")
    assert rod.parents == ("slider2", "crank3", "slider5", "crank6")
    assert [c.first for c in b.closures] == [("piston1", "piston4"), rod.names]
    assert np.max(np.abs(b.joints.value - mech.ik(x))) <= 1e-14
    jac = mech.velocity_jacobian(x)
    assert np.max(np.abs(b.joints.jacobian - jac)) <= 1e-10 * np.max(np.abs(jac))
