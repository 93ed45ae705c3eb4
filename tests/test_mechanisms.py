"""Every registered mechanism keeps the protocol's promises (parametrised over the registry: a
mechanism added to parakin is tested here without an edit): IK and residual agree, the Jacobian is
the residual's derivative, FK gives the pose back, the drawing works, and the command line offers
its declared parameters, reads them from ``--param`` and ``--geometry`` and solves with them.
The compiled path of the same mechanisms: tests/test_kernels.py."""

from __future__ import annotations

import contextlib
import io
import json
import os

import numpy as np
import pytest

from parakin import mechanisms
from parakin.cli import main, parameters_of
from parakin.mechanisms.base import _central_difference
from parakin.solvers import solve_fk

NAMES = list(mechanisms.REGISTRY)


def _poses(mech, n: int, seed: int) -> np.ndarray:
    rng = np.random.default_rng(seed)
    lo, hi = mech.pose_bounds()
    home = mech.home()
    x = home + 0.3 * (rng.uniform(lo, hi, size=(4 * n, mech.n_pose)) - home)
    return x[mech.in_domain(x)][:n]


def _cli(*argv: str) -> tuple[int, str, str]:
    out, err = io.StringIO(), io.StringIO()
    with contextlib.redirect_stdout(out), contextlib.redirect_stderr(err):
        code = main(list(argv))
    return code, out.getvalue(), err.getvalue()


def test_the_registry_lists_the_papers_mechanisms_and_the_3rpr():
    assert {"3p4s", "2ups", "stewart12", "stewart36", "stewart66", "rpr3"} <= set(NAMES)
    assert mechanisms.get("rpr3").__module__ == "parakin.mechanisms.rpr3"
    with pytest.raises(KeyError, match="unknown mechanism 'nope'; known: 2ups, 3p4s"):
        mechanisms.get("nope")


@pytest.mark.parametrize("name", NAMES)
def test_ik_residual_and_jacobian_agree(name):
    mech = mechanisms.get(name)()
    x = _poses(mech, 40, seed=1)
    assert len(x) >= 20
    q = mech.ik(x)
    assert q.shape == (len(x), mech.n_joints)
    np.testing.assert_allclose(mech.residual(x, q), 0.0, atol=1e-12 * (1 + np.abs(q).max() ** 2))
    q1 = q + 1e-3
    jac = mech.jacobian_pose(x, q1)
    fd = _central_difference(lambda xx: mech.residual(xx, q1), x)
    np.testing.assert_allclose(jac, fd, rtol=1e-5, atol=1e-6 * np.abs(jac).max())
    assert mech.in_domain(x).all() and mech.on_assembly(x, q).all()


@pytest.mark.parametrize("name", NAMES)
def test_fk_gives_the_pose_back(name):
    """Newton from starts 2 % of the way towards home: the true pose, verified."""
    mech = mechanisms.get(name)()
    x = _poses(mech, 30, seed=2)
    x0 = x + 0.02 * (mech.home() - x)
    res = solve_fk(mech, mech.ik(x), x0, method="newton", maxiter=100)
    assert res.success.mean() >= 0.95
    ok = res.success
    np.testing.assert_allclose(mech.ik(res.x[ok]), mech.ik(x[ok]), atol=1e-8)  # right answers
    same = np.all(np.abs(mech.pose_difference(res.x[ok], x[ok])) < 1e-7, axis=-1)
    assert same.mean() >= 0.9  # and the true pose (the 6-6 may land on another of its assemblies)


@pytest.mark.parametrize("name", NAMES)
def test_the_drawing_shows_the_assembly(name):
    from parakin.plot import draw_mechanism

    mech = mechanisms.get(name)()
    sk = mech.skeleton(mech.home())
    assert sk.segments and all(np.all(np.isfinite(seg)) for _, seg in sk.segments)
    ax = draw_mechanism(mech, mech.home())
    assert ax is not None


@pytest.mark.parametrize("name", NAMES)
def test_cli_offers_the_declared_parameters(name, tmp_path):
    """``--param`` and ``--geometry`` take every declared parameter (its default value gives the
    default mechanism back) and the CLI solves with them: ik, then fk from those joints."""
    cls = mechanisms.get(name)
    known = parameters_of(cls)
    assert known  # every mechanism has parameters a user can set
    default = cls()
    assert cls(**known) == default
    geometry = tmp_path / "geometry.json"
    geometry.write_text(json.dumps({k: np.asarray(v).tolist() for k, v in known.items()}))
    home = [repr(float(v)) for v in default.home()]
    code, out, err = _cli("ik", name, "--pose", *home, "--geometry", str(geometry), "--json")
    assert code == 0, err
    joints = json.loads(out)["joints"]
    np.testing.assert_allclose(joints, default.ik(default.home()), rtol=1e-12)
    first = next(iter(known))
    value = json.dumps(np.asarray(known[first]).tolist())
    code, out, err = _cli(
        "fk", name, "--joints", *map(repr, joints), "--solver", "newton", "--json",
        "--param", f"{first}={value}",
    )  # fmt: skip
    assert code == 0, err
    np.testing.assert_allclose(
        default.pose_difference(json.loads(out)["x"], default.home()), 0.0, atol=1e-8
    )


def test_geometry_file_solves_ones_own_6_6_platform(tmp_path):
    """``parakin fk stewart66 --geometry my_platform.yaml --joints ... --all``: a platform of one's
    own (YAML, arrays as lists), every real assembly listed, each reproducing the legs; and the
    same through ``--param base=[[...]]``."""
    rng = np.random.default_rng(3)
    base, platform = rng.normal(size=(6, 3)), 0.5 * rng.normal(size=(6, 3))
    mech = mechanisms.Stewart66(base=base, platform=platform)
    truth = mech.home() + np.array([0.1, -0.05, 0.2, 0.05, 0.0, 0.1])
    joints = mech.ik(truth)
    path = tmp_path / "my_platform.yaml"
    rows = lambda a: "\n".join(f"  - [{', '.join(repr(float(v)) for v in r)}]" for r in a)  # noqa: E731
    path.write_text(f"base:\n{rows(base)}\nplatform:\n{rows(platform)}\n")
    argv = ["fk", "stewart66", "--geometry", str(path), "--joints", *map(str, joints.tolist())]
    argv.append("--all")
    code, out, err = _cli(*argv, "--json")
    assert code == 0, err
    found = np.array([s["x"] for s in json.loads(out)["solutions"][0]])
    assert np.min(np.max(np.abs(mech.pose_difference(found, truth)), axis=-1)) < 1e-8
    np.testing.assert_allclose(mech.ik(found), np.broadcast_to(joints, (len(found), 6)), atol=1e-8)
    as_param = json.dumps(base.tolist())
    code2, out2, err2 = _cli(*argv[:2], "--param", f"base={as_param}", "--geometry", str(path),
                             *argv[4:], "--json")  # fmt: skip
    assert code2 == 0 and json.loads(out2)["solutions"] == json.loads(out)["solutions"], err2


@pytest.mark.parametrize(
    ("argv", "message"),
    [
        (["--param", "base=[[0, 0, 0]]"], "expected an array of shape (6, 3), got shape (1, 3)"),
        (["--param", "base=[[0, 0"], "is not valid YAML"),
        (["--param", "base=[[1e9, 0, 0]" + ", [0, 0, 0]" * 5 + "]"], "finite numbers <= 1e+06"),
        (["--param", "allow_coincident=1"], "unknown parameter(s) ['allow_coincident']"),
        (["--geometry", "GEOM"], "unknown parameter(s) ['legs']"),
        (["--geometry", "MISSING"], "does not exist"),
    ],
)
def test_bad_parameters_get_one_line(argv, message, tmp_path):
    geom = tmp_path / "g.yaml"
    geom.write_text("legs: 6\n")
    argv = [
        a.replace("GEOM", str(geom)).replace("MISSING", str(tmp_path / "no.yaml")) for a in argv
    ]
    code, out, err = _cli("ik", "stewart66", "--pose", *["0.1"] * 6, *argv)
    assert code == 2 and len(err.strip().splitlines()) == 1 and message in err, err


def test_a_short_command_does_not_load_compiled_code():
    """``parakin fk`` of a few inputs runs the kernels on numpy (numba is not imported), a long
    one (or PARAKIN_KERNELS=1) compiled; the answers agree."""
    import subprocess
    import sys

    code = (
        "import sys\n"
        "from parakin.cli import main\n"
        "main(['fk', 'rpr3', '--joints', '0.44', '0.43', '0.45', '--solver', 'newton'])\n"
        "print('numba' in sys.modules)\n"
    )
    env = {k: v for k, v in os.environ.items() if k != "PARAKIN_KERNELS"}
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, env=env)
    assert out.returncode == 0, out.stderr
    assert out.stdout.split("\n")[1] == "False", out.stdout
    forced = subprocess.run(
        [sys.executable, "-c", code],
        capture_output=True,
        text=True,
        env={**env, "PARAKIN_KERNELS": "1"},
    )
    assert forced.returncode == 0, forced.stderr
    assert forced.stdout.split("\n") == [out.stdout.split("\n")[0], "True", ""]


def test_docs_quote_the_3rpr_as_it_is():
    """docs/kernels.md walks through the 3-RPR with excerpts of its two files (blocks opening with
    ``# file: PATH``): each is that file's text, so the walk-through cannot drift from the code."""
    import re
    from pathlib import Path

    root = Path(__file__).resolve().parents[1]
    text = (root / "docs" / "kernels.md").read_text()
    blocks = re.findall(r"```python\n# file: (\S+)\n(.*?)```", text, re.S)
    assert {path for path, _ in blocks} == {
        "src/parakin/kernels/rpr3.py",
        "src/parakin/mechanisms/rpr3.py",
    }
    for path, body in blocks:
        assert body in (root / path).read_text(), f"docs/kernels.md quotes {path} as it was"


def test_discovery_is_explicit_and_skips_nothing_in_silence(monkeypatch):
    """Every module of parakin.mechanisms is listed (a mechanism module in MODULES, imported and
    registered; a helper in HELPERS); one listed nowhere, underscore or not, is an ImportError that
    names it."""
    import pkgutil

    import parakin.mechanisms as pm

    assert pm.unlisted_modules() == []
    assert {cls.__module__.rsplit(".", 1)[1] for cls in pm.REGISTRY.values()} == set(pm.MODULES)
    real = pkgutil.iter_modules

    def with_new_module(path):
        yield from real(path)
        yield pkgutil.ModuleInfo(None, "delta_robot", False)

    monkeypatch.setattr(pm.pkgutil, "iter_modules", with_new_module)
    with pytest.raises(ImportError, match="delta_robot are listed neither in MODULES"):
        pm.discover()
