"""The `parakin` command line: results, JSON fields, and one clear line for bad input."""

import json
import subprocess
import sys

import numpy as np
import pytest

from parakin.cli import main
from parakin.mechanisms import P3P4S


def run(*args: str) -> subprocess.CompletedProcess:
    return subprocess.run([sys.executable, "-m", "parakin.cli", *args], capture_output=True, text=True, timeout=120)


def test_ik_prints_strokes(capsys):
    assert main(["ik", "3p4s", "--pose", "0", "0", "0.592"]) == 0
    out = capsys.readouterr().out
    assert "l1 = 0.4315827775 m" in out


def test_ik_batch_json_and_parameters(capsys):
    assert main(["ik", "3p4s", "--pose", "0", "0", "0.592", "0.03", "-0.01", "0.565", "--param", "phi=35deg", "--json"]) == 0
    out = json.loads(capsys.readouterr().out)
    mech = P3P4S(phi=np.deg2rad(35))
    assert np.allclose(out["joints"], mech.ik([[0, 0, 0.592], [0.03, -0.01, 0.565]]), atol=1e-15)
    assert out["parameters"]["phi"] == pytest.approx(np.deg2rad(35))


@pytest.mark.parametrize("solver", ["newton", "broyden", "bfgs", "lm", "closed-form", "scipy-root"])
def test_fk_json_carries_result_fields(capsys, solver):
    q = P3P4S().ik([0.02, 0.01, 0.576])
    assert main(["fk", "3p4s", "--joints", *map(repr, q.tolist()), "--solver", solver, "--tol", "1e-12", "--json"]) == 0
    out = json.loads(capsys.readouterr().out)
    assert {"x", "success", "nit", "nfev", "residual", "wall_time", "method", "message"} <= set(out)
    assert out["success"] is True and out["method"] == solver
    assert np.allclose(out["x"], [0.02, 0.01, 0.576], atol=1e-9)


@pytest.mark.parametrize(
    "args, message",
    [
        (["ik", "3p4s", "--pose", "0", "0"], "--pose needs a multiple of 3 values (x, y, z), got 2"),
        (["ik", "3p4s", "--pose", "0", "0", "0.9"], "is unreachable: limb 1 needs L^2 - x_u^2 - z_u^2"),
        (["fk", "3p4s", "--joints", "0.4", "0.4", "0.4", "--solver", "magic"], "unknown solver 'magic'"),
        (["fk", "3p4s", "--joints", "0", "1.5", "0"], "the three spheres of radius L = 0.38 m do not meet"),
        (["ik", "3p4s", "--pose", "0", "0", "0.5", "--param", "phi=95deg"], "must lie in (0, pi/2)"),
        (["ik", "3p4s", "--pose", "0", "0", "0.5", "--param", "rb=0.7"], "unknown parameter(s) ['rb']"),
        (["fk", "3p4s", "--joints", "0.4", "0.4", "0.4", "--solver", "hybrid", "--network", "/nonexistent/net.npz"],
         "/nonexistent/net.npz"),
        (["reproduce", "zhao2017_3p4s", "table9"], "unknown artefact 'table9'"),
    ],
)
def test_bad_input_exits_nonzero_with_one_line(args, message):
    res = run(*args)
    assert res.returncode == 2
    lines = res.stderr.strip().splitlines()
    assert len(lines) == 1 and "Traceback" not in res.stderr
    assert message in lines[0]


def test_fk_that_does_not_converge_exits_1():
    q = P3P4S().ik([0.07, 0.07, 0.53])
    res = run("fk", "3p4s", "--joints", *map(repr, q.tolist()), "--solver", "newton", "--maxiter", "1")
    assert res.returncode == 1
    assert "did not converge within maxiter=1" in res.stderr and "--maxiter" in res.stderr
