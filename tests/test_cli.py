"""The `parakin` command line: results, JSON fields, and one clear line for bad input."""

import json
import subprocess
import sys

import numpy as np
import pytest

from parakin.cli import main
from parakin.mechanisms import P3P4S


def run(*args: str) -> subprocess.CompletedProcess:
    return subprocess.run(
        [sys.executable, "-m", "parakin.cli", *args], capture_output=True, text=True, timeout=120
    )


def test_ik_prints_strokes(capsys):
    assert main(["ik", "3p4s", "--pose", "0", "0", "0.592"]) == 0
    out = capsys.readouterr().out
    assert "l1 = 0.4315827775 m" in out


def test_ik_batch_json_and_parameters(capsys):
    assert (
        main(
            [
                "ik",
                "3p4s",
                "--pose",
                "0",
                "0",
                "0.592",
                "0.03",
                "-0.01",
                "0.565",
                "--param",
                "phi=35deg",
                "--json",
            ]
        )
        == 0
    )
    out = json.loads(capsys.readouterr().out)
    mech = P3P4S(phi=np.deg2rad(35))
    assert np.allclose(out["joints"], mech.ik([[0, 0, 0.592], [0.03, -0.01, 0.565]]), atol=1e-15)
    assert out["parameters"]["phi"] == pytest.approx(np.deg2rad(35))


@pytest.mark.parametrize("solver", ["newton", "broyden", "bfgs", "lm", "closed-form", "scipy-root"])
def test_fk_json_carries_result_fields(capsys, solver):
    q = P3P4S().ik([0.02, 0.01, 0.576])
    assert (
        main(
            [
                "fk",
                "3p4s",
                "--joints",
                *map(repr, q.tolist()),
                "--solver",
                solver,
                "--tol",
                "1e-12",
                "--json",
            ]
        )
        == 0
    )
    out = json.loads(capsys.readouterr().out)
    assert {"x", "success", "nit", "nfev", "residual", "wall_time", "method", "message"} <= set(out)
    assert out["success"] is True and out["method"] == solver
    assert np.allclose(out["x"], [0.02, 0.01, 0.576], atol=1e-9)


@pytest.mark.parametrize(
    "args, message",
    [
        (
            ["ik", "3p4s", "--pose", "0", "0"],
            "--pose needs a multiple of 3 values (x, y, z), got 2",
        ),
        (
            ["ik", "3p4s", "--pose", "0", "0", "0.9"],
            "is unreachable: limb 1 needs L^2 - x_u^2 - z_u^2",
        ),
        (
            ["fk", "3p4s", "--joints", "0.4", "0.4", "0.4", "--solver", "magic"],
            "unknown solver 'magic'",
        ),
        (
            ["fk", "3p4s", "--joints", "0", "1.5", "0"],
            "the three spheres of radius L = 0.38 m do not meet",
        ),
        (
            ["ik", "3p4s", "--pose", "0", "0", "0.5", "--param", "phi=95deg"],
            "must lie in (0, pi/2)",
        ),
        (
            ["ik", "3p4s", "--pose", "0", "0", "0.5", "--param", "rb=0.7"],
            "unknown parameter(s) ['rb']",
        ),
        (
            [
                "fk",
                "3p4s",
                "--joints",
                "0.4",
                "0.4",
                "0.4",
                "--solver",
                "hybrid",
                "--network",
                "/nonexistent/net.npz",
            ],
            "/nonexistent/net.npz",
        ),
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
    res = run(
        "fk", "3p4s", "--joints", *map(repr, q.tolist()), "--solver", "newton", "--maxiter", "1"
    )
    assert res.returncode == 1
    assert "did not converge within maxiter=1" in res.stderr and "--maxiter" in res.stderr


# ------------------------------------------------------------------ batches from files, all solutions
def _fk_all_json(capsys, *args) -> dict:
    code = main(["fk", *args, "--all", "--json"])
    out = json.loads(capsys.readouterr().out)
    return code, out


@pytest.mark.parametrize("suffix", [".csv", ".npy"])
def test_ik_then_fk_through_files(tmp_path, capsys, suffix):
    """ik --input poses -> --output joints -> fk --input joints gives the poses back (CSV or .npy)."""
    poses = np.array([[0.0, 0.0, 0.592], [0.03, -0.01, 0.565], [-0.02, 0.01, 0.58]])
    src = tmp_path / f"poses{suffix}"
    if suffix == ".csv":
        src.write_text(
            "# three poses\nx [m],y [m],z [m]\n"
            + "\n".join(",".join(map(repr, p)) for p in poses.tolist())
            + "\n"
        )
    else:
        np.save(src, poses)
    joints, back = tmp_path / f"q{suffix}", tmp_path / f"x{suffix}"
    assert main(["ik", "3p4s", "--input", str(src), "--output", str(joints)]) == 0
    assert (
        main(
            [
                "fk",
                "3p4s",
                "--input",
                str(joints),
                "--output",
                str(back),
                "--solver",
                "newton",
                "--tol",
                "1e-13",
            ]
        )
        == 0
    )
    if suffix == ".csv":
        import pandas as pd

        q = pd.read_csv(joints)
        assert list(q.columns) == ["l1 [m]", "l2 [m]", "l3 [m]"]
        assert np.allclose(q.to_numpy(), P3P4S().ik(poses), atol=1e-15)
        x = pd.read_csv(back)
        assert {"success", "status", "nit", "residual"} <= set(x.columns) and x["success"].all()
        assert (x["status"] == "CONVERGED").all()
        x = x[["x [m]", "y [m]", "z [m]"]].to_numpy()
    else:
        assert np.allclose(np.load(joints), P3P4S().ik(poses), atol=1e-15)
        x = np.load(back)
    assert np.allclose(x, poses, atol=1e-9)


def test_csv_columns_by_name_and_unit_checked(tmp_path, capsys):
    """A header picks the columns by name (any order, extra columns ignored); a unit that is not the
    one --units reads is an error, not a silent misreading."""
    f = tmp_path / "p.csv"
    f.write_text("note,z,x,y\na,0.592,0,0\n")
    assert main(["ik", "3p4s", "--input", str(f), "--json"]) == 0
    assert np.allclose(json.loads(capsys.readouterr().out)["joints"], P3P4S().ik([0, 0, 0.592]))
    f.write_text("beta [deg],gamma [deg],Y [mm]\n1,2,3\n")
    assert main(["ik", "2ups", "--input", str(f)]) == 2
    assert "is in deg but these --units read beta in rad" in capsys.readouterr().err
    assert main(["ik", "2ups", "--input", str(f), "--units", "paper"]) == 0


@pytest.mark.parametrize(
    "content, message",
    [
        ("", "holds no rows"),
        ("0,0\n", "2 values, expected 3"),
        ("0,0,nan\n", "row 1 is not finite"),
        ("0,0,abc\n", "are not all numbers"),
        ("a,b,c,d\n1,2,3,4\n", "names neither the columns"),
    ],
)
def test_bad_input_files_one_line(tmp_path, capsys, content, message):
    f = tmp_path / "bad.csv"
    f.write_text(content)
    assert main(["ik", "3p4s", "--input", str(f)]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and message in err[0]


def test_file_options_errors(tmp_path, capsys):
    assert main(["ik", "3p4s", "--input", str(tmp_path / "none.csv")]) == 2
    assert "none.csv" in capsys.readouterr().err
    assert (
        main(["ik", "3p4s", "--pose", "0", "0", "0.592", "--output", str(tmp_path / "q.txt")]) == 2
    )
    assert "must end in .csv or .npy" in capsys.readouterr().err
    assert main(["ik", "3p4s"]) == 2
    assert "give --pose VALUES or --input FILE" in capsys.readouterr().err
    np.save(tmp_path / "wrong.npy", np.zeros((2, 4)))
    assert main(["fk", "3p4s", "--input", str(tmp_path / "wrong.npy")]) == 2
    assert "shape (N, 3)" in capsys.readouterr().err


def test_fk_all_lists_every_real_solution_2ups(capsys):
    from parakin.mechanisms import UPS2

    mech = UPS2()
    q = mech.ik([np.deg2rad(10), np.deg2rad(-20), 0.03])
    code, out = _fk_all_json(capsys, "2ups", "--joints", *map(repr, q.tolist()))
    assert code == 0 and out["n_real"][0] == len(out["solutions"][0]) >= 2
    working = [s for s in out["solutions"][0] if s["working"]]
    assert len(working) == 1 and np.allclose(
        working[0]["x"], [np.deg2rad(10), np.deg2rad(-20), 0.03], atol=1e-9
    )
    for s in out["solutions"][0]:  # each is a right answer on its own branch
        branch = 1 if "branch +1" in s["assembly"] else -1
        assert np.allclose(UPS2(branch=branch).ik(s["x"]), q, atol=1e-9)


def test_fk_all_stewart36_text_labels_and_dimensionless_units(capsys):
    from parakin.mechanisms import Stewart36

    q = Stewart36().ik(Stewart36().home())
    assert main(["fk", "stewart36", "--joints", *map(repr, q.tolist()), "--all"]) == 0
    out = capsys.readouterr().out
    lines = out.strip().splitlines()
    assert "8 real solution(s)" in lines[0] and len(lines) == 9
    assert sum("above the base" in line for line in lines) == 4 and out.count("working") == 1
    assert " 1 " not in out and not out.rstrip().endswith(" 1")  # dimensionless: no unit "1"


def test_fk_all_to_csv_and_npy(tmp_path, capsys):
    from parakin.mechanisms import UPS2

    q = UPS2().ik([[0.1, 0.1, 0.01], [0.0, 0.0, 0.0]])
    src = tmp_path / "q.npy"
    np.save(src, q)
    assert (
        main(["fk", "2ups", "--input", str(src), "--all", "--output", str(tmp_path / "all.csv")])
        == 0
    )
    import pandas as pd

    t = pd.read_csv(tmp_path / "all.csv")
    assert list(t.columns[:2]) == ["input", "solution"] and set(t["input"]) == {1, 2}
    assert t.groupby("input")["working"].sum().tolist() == [1, 1]
    assert (
        main(["fk", "2ups", "--input", str(src), "--all", "--output", str(tmp_path / "all.npy")])
        == 0
    )
    a = np.load(tmp_path / "all.npy")
    assert a.shape[0] == 2 and a.shape[2] == 3 and np.isfinite(a).all(-1).sum() == len(t)


def test_fk_all_needs_an_all_solutions_method(capsys):
    assert main(["fk", "3p4s", "--joints", "0.43", "0.43", "0.43", "--all"]) == 2
    err = capsys.readouterr().err
    assert "has no all-solutions method; --all works on 2ups, rpr3, stewart36" in err
    assert "--mechanism FILE" in err  # and on every described mechanism


def test_fk_all_no_real_solution_exits_1(capsys):
    assert main(["fk", "stewart36", "--joints", *["1.8"] * 6, "--all"]) == 1
    assert "no real solution" in capsys.readouterr().err


def test_help_lists_solvers_and_units(capsys):
    from parakin.solvers import METHODS

    with pytest.raises(SystemExit):
        main(["fk", "--help"])
    out = capsys.readouterr().out
    assert all(f"  {name} " in out for name in METHODS)
    assert "2ups" in out and "(paper: deg deg mm)" in out


def test_units_paper_says_when_it_is_si(capsys):
    assert main(["ik", "3p4s", "--pose", "0", "0", "0.592", "--units", "paper"]) == 0
    captured = capsys.readouterr()
    assert "l1 = 0.4315827775 m" in captured.out and "same as --units si" in captured.err
    assert main(["ik", "2ups", "--pose", "10", "-20", "30", "--units", "paper"]) == 0
    captured = capsys.readouterr()
    assert " mm" in captured.out and not captured.err


def test_cold_start_imports_no_heavy_module():
    """A cold `parakin fk` must stay under 1 s (issue 17): importing the CLI, the solvers and the
    mechanisms loads neither scipy.optimize (0.35 s; imported by the scipy-root solver when used)
    nor numba, pandas, torch or matplotlib (each imported where it is used)."""
    code = (
        "import sys, parakin.cli, parakin.solvers, parakin.mechanisms; "
        "print(sorted(m for m in ('scipy.optimize', 'numba', 'pandas', 'torch', 'matplotlib') "
        "if m in sys.modules))"
    )
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=120)
    assert out.returncode == 0, out.stderr
    assert out.stdout.strip() == "[]"


def test_a_failed_fk_prints_no_pose(capsys):
    """A diverged solve says so on stderr and prints no pose on stdout; in a batch each failed
    input keeps a marked line without numbers; JSON gives its pose as null and the last iterate
    under its own name."""
    argv = [
        "fk",
        "3p4s",
        "--joints",
        "0.43",
        "0.43",
        "0.43",
        "--solver",
        "newton",
        "--maxiter",
        "1",
    ]
    assert main(argv) == 1
    captured = capsys.readouterr()
    assert captured.out == "" and "did not converge" in captured.err
    q = P3P4S().ik([0.0, 0.0, 0.59])  # the second input: solved at its start, no iteration
    batch = ["fk", "3p4s", "--joints", "0.43", "0.43", "0.43", *map(repr, q.tolist()),
             "--solver", "newton", "--maxiter", "1", "--x0", "0", "0", "0.59"]  # fmt: skip
    assert main(batch) == 1
    lines = capsys.readouterr().out.splitlines()
    assert lines[0] == "# not solved (MAXITER)" and lines[1].startswith("x = ")
    assert main([*argv, "--json"]) == 1
    out = json.loads(capsys.readouterr().out)
    assert out["x"] is None and len(out["last_iterate"]) == 3 and out["success"] is False
    assert out["startup"] >= 0.0


def test_fk_json_says_when_wall_time_includes_compiling(capsys, monkeypatch):
    """FKResult.startup: the seconds of wall_time spent loading or compiling; the JSON names it."""
    monkeypatch.setattr("parakin.kernels._LOAD_SECONDS", [0.0])
    assert (
        main(["fk", "rpr3", "--joints", "0.44", "0.43", "0.45", "--solver", "newton", "--json"])
        == 0
    )
    out = json.loads(capsys.readouterr().out)
    assert (
        "startup" in out and out["startup_note"] is None
    )  # numpy path (few inputs): nothing loaded


def test_the_parser_is_built_once_and_a_patched_command_still_runs(capsys, monkeypatch):
    """``main`` builds its parser once per process and looks each command's function up by name
    when it runs: a command replaced after the parser was built is the one that runs, and the
    original again once the replacement is undone."""
    from parakin import cli
    from parakin.cli import kinematics

    argv = ["ik", "3p4s", "--pose", "0", "0", "0.592"]
    assert main(argv) == 0
    assert cli._parser() is cli._parser()
    monkeypatch.setattr(kinematics, "cmd_ik", lambda args: 7)
    assert main(argv) == 7
    monkeypatch.undo()
    capsys.readouterr()
    assert main(argv) == 0
    assert "l1 = 0.4315827775 m" in capsys.readouterr().out
