"""Fuzz: the ``parakin`` command line on hostile argument vectors, in process.

Property (issue 16): whatever the arguments (numbers in any notation and sign, non-finite or huge
values, wrong counts, unknown or class-attribute parameters, unknown solvers, garbage strings),
``parakin`` exits 0, 1 or 2 without a traceback; an error is one line on stderr; exit 0 never
comes with a non-finite value on stdout; ``--json`` output is strict JSON; and a successful ``fk``
is a right answer (its pose's IK gives back the joints). More than 1,000 argument vectors per run
(``EXAMPLES`` x the tests below); fixed, derandomized settings keep a run reproducible and short.
"""

from __future__ import annotations

import collections
import contextlib
import copy
import dataclasses
import functools
import io
import json
import math
import subprocess
import sys
import tempfile
from pathlib import Path

import numpy as np
import pandas as pd
import pytest
import yaml
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from parakin import mechanisms
from parakin.cli import main, parameters_of
from parakin.units import to_si
from parakin.workspace import sample_reachable

EXAMPLES = 350
FUZZ = settings(
    max_examples=EXAMPLES,
    derandomize=True,
    deadline=None,
    database=None,
    suppress_health_check=[HealthCheck.too_slow, HealthCheck.data_too_large],
)

NUMBERS = [
    "0",
    "1",
    "-1",
    "0.5",
    "-0.5",
    ".5",
    "-.5",
    "1e-3",
    "-1e-3",
    "-2.1e-17",
    "1E+2",
    "-1.5E-02",
    "1e308",
    "-1e308",
    "1e-320",
    "nan",
    "-nan",
    "inf",
    "-inf",
    "Infinity",
    "abc",
    "",
    "1e",
    "--",
    "0x10",
    "1_000",
    "9" * 400,
    "0.592",
    "0.43",
    "0.025",
    "-0.08",
    "3",
]
SOLVERS = [
    "newton",
    "broyden",
    "bfgs",
    "lm",
    "gauss-newton",
    "broyden-ls",
    "scipy-root",
    "closed-form",
    "all-solutions",
    "pso",
    "hybrid",
    "magic",
    "",
]
ITERS = ["0", "1", "5", "50", "1e2", "-1", "2.5", "1e6", "abc", "nan"]
TOLS = ["1e-10", "0", "-1e-3", "1e-300", "inf", "nan", "1", "abc"]


#: exit status -> how many argument vectors of this module's tests ended so (printed with -s)
TALLY: collections.Counter = collections.Counter()


def run(argv: list[str]) -> tuple[int, str, str]:
    """``main(argv)`` in process: exit status, stdout, stderr (argparse's exits included)."""
    out, err = io.StringIO(), io.StringIO()
    with contextlib.redirect_stdout(out), contextlib.redirect_stderr(err):
        try:
            code = main(argv)
        except SystemExit as exc:
            code = exc.code if isinstance(exc.code, int) else (0 if exc.code is None else 2)
    TALLY[code] += 1
    return code, out.getvalue(), err.getvalue()


@pytest.fixture(scope="module", autouse=True)
def _report_tally():
    """The counts the issue asks for: vectors tried, answers (exit 0), reported failures (1),
    one-line errors (2); every exit-0 fk --json answer is checked right by _check."""
    yield
    print(
        f"\nCLI fuzz: {sum(TALLY.values())} vectors: {TALLY[0]} answers (exit 0), "
        f"{TALLY[1]} solver failures reported (exit 1), {TALLY[2]} one-line errors (exit 2), "
        f"other {sum(v for k, v in TALLY.items() if k not in (0, 1, 2))}"
    )


def _strict_json(text: str):
    def reject(name):
        raise AssertionError(f"non-strict JSON constant {name}")

    return json.loads(text, parse_constant=reject)


def _numbers(draw, mech_n: int) -> list[str]:
    count = draw(
        st.sampled_from([0, 1, mech_n - 1, mech_n, mech_n, mech_n, 2 * mech_n, mech_n + 1])
    )
    plain = draw(st.booleans())  # half the vectors: realistic finite values only
    pool = NUMBERS[:10] + ["0.592", "0.43", "0.025", "-0.08", "3"] if plain else NUMBERS
    return [draw(st.sampled_from(pool)) for _ in range(max(count, 0))]


@st.composite
def clean_vectors(draw) -> list[str]:
    """A realistic call: a pose near home (ik) or its joints (fk), printed in some notation."""
    command = draw(st.sampled_from(["ik", "fk"]))
    name = draw(st.sampled_from(sorted(mechanisms.REGISTRY)))
    mech = mechanisms.REGISTRY[name]()
    lo, hi = mech.pose_bounds()
    u = np.array(draw(st.lists(st.floats(-1, 1), min_size=mech.n_pose, max_size=mech.n_pose)))
    pose = mech.home() + 0.2 * u * (hi - lo) / 2
    fmt = draw(st.sampled_from(["{!r}", "{:.10g}", "{:e}", "{:.17E}"]))
    if command == "ik":
        argv = ["ik", name, "--pose", *(fmt.format(float(v)) for v in pose)]
    else:
        argv = ["fk", name, "--joints", *(fmt.format(float(v)) for v in mech.ik(pose))]
        if draw(st.booleans()):
            argv += ["--solver", draw(st.sampled_from(SOLVERS[:-2]))]
        if draw(st.booleans()):
            argv += [
                "--x0",
                *(fmt.format(float(v)) for v in mech.home() + 0.01 * (hi - lo) * u[::-1]),
            ]
        if draw(st.booleans()):
            argv += ["--tol", draw(st.sampled_from(["1e-10", "1e-12", "1e-8", "0"]))]
    return argv + (["--json"] if draw(st.booleans()) else [])


@st.composite
def argv_vectors(draw) -> list[str]:
    if draw(st.integers(0, 2)) == 0:
        return draw(clean_vectors())
    command = draw(st.sampled_from(["ik", "fk", "fk", "ik", "nope"]))
    name = draw(st.sampled_from([*sorted(mechanisms.REGISTRY), "nope"]))
    cls = mechanisms.REGISTRY.get(name, mechanisms.P3P4S)
    argv = [command, name]
    if command == "ik":
        argv += ["--pose", *_numbers(draw, len(cls.pose_names))]
    else:
        n_joints = 12 if name == "stewart12" else len(cls.joint_names)
        argv += ["--joints", *_numbers(draw, n_joints)]
        if draw(st.booleans()):
            argv += ["--solver", draw(st.sampled_from(SOLVERS))]
        if draw(st.booleans()):
            argv += ["--x0", *_numbers(draw, len(cls.pose_names))]
        if draw(st.booleans()):
            argv += ["--tol", draw(st.sampled_from(TOLS))]
        if draw(st.booleans()):
            argv += ["--maxiter", draw(st.sampled_from(ITERS))]
    for _ in range(draw(st.integers(0, 2))):
        key = draw(
            st.sampled_from(
                [*parameters_of(cls), "name", "stroke_limits", "branch", "pose_names", "x"]
            )
        )
        value = draw(
            st.sampled_from(["1", "0", "-1", "35deg", "120mm", "1e308", "inf", "nan", "abc", "0.2"])
        )
        argv += ["--param", draw(st.sampled_from([f"{key}={value}", key]))]
    if draw(st.booleans()):
        argv += ["--units", draw(st.sampled_from(["si", "paper", "imperial"]))]
    if draw(st.booleans()):
        argv.append("--json")
    return argv


def _check_right_answer(argv: list[str], out: dict) -> None:
    """A successful fk: ik of the printed pose gives back the printed joints (both in their units)."""
    cls = mechanisms.REGISTRY[out["mechanism"]]
    params = {k: v for k, v in out["parameters"].items() if k in parameters_of(cls)}
    mech = cls(**params)
    q = to_si(np.asarray(out["joints"], dtype=float), out["joint_units"])
    if "solutions" in out:  # --all: every printed solution of each input gives its joints back,
        # on its own assembly (a 2-UPS "branch -1" pose is one of UPS2(branch=-1))
        triples = [
            (
                dataclasses.replace(mech, branch=-1) if "branch -1" in s["assembly"] else mech,
                to_si(np.asarray(s["x"], dtype=float), out["pose_units"]),
                q[i],
            )
            for i, rows in enumerate(out["solutions"])
            for s in rows
        ]
        joint_tol = 1e-8
    else:
        triples = [(mech, to_si(np.asarray(out["x"], dtype=float), out["pose_units"]), q)]
        tol = 1e-10 if "--tol" not in argv else float(argv[argv.index("--tol") + 1])
        joint_tol = max(1e-8, 100 * tol)
    for m, x, qi in triples:
        assert np.max(np.abs(m.ik(x) - qi)) <= joint_tol * (1 + 1e-9) + 1e-15, argv


def _check(argv: list[str]) -> None:
    code, stdout, stderr = run(argv)
    assert code in (0, 1, 2), (argv, code)
    assert "Traceback" not in stderr and "Traceback" not in stdout, (argv, stderr)
    if code == 2:
        assert stderr.strip() and len(stderr.strip().splitlines()) == 1, (argv, stderr)
    if code == 0:
        tokens = stdout.replace(",", " ").replace("[", " ").replace("]", " ").split()
        assert not any(
            t.lower().strip('"') in ("nan", "inf", "-inf", "infinity", "-infinity") for t in tokens
        ), argv
        if "--json" in argv:
            out = _strict_json(stdout)
            if argv[0] == "fk":
                _check_right_answer(argv, out)
        else:
            for value in (t for t in tokens if t[:1].isdigit() or t[:1] == "-"):
                assert math.isfinite(float(value)), (argv, value)


@FUZZ
@given(argv=argv_vectors())
def test_ik_and_fk_survive_hostile_arguments(argv):
    _check(argv)


@FUZZ
@given(argv=argv_vectors())
def test_ik_and_fk_survive_hostile_arguments_json(argv):
    _check([*argv, "--json"] if "--json" not in argv else argv)


@FUZZ
@given(
    values=st.lists(
        st.floats(allow_nan=True, allow_infinity=True, width=64), min_size=3, max_size=3
    ),
    fmt=st.sampled_from(["{!r}", "{:.10g}", "{:e}", "{:.3E}"]),
)
def test_any_float_in_any_notation(values, fmt):
    """Every float python prints, in every notation, reads back (negative scientific included)."""
    argv = ["ik", "3p4s", "--pose", *(fmt.format(v) for v in values)]
    code, _, stderr = run(argv)
    assert code in (0, 2) and "unrecognized arguments" not in stderr and "expected" not in stderr, (
        argv,
        stderr,
    )
    if all(math.isfinite(v) for v in values) and code == 2:
        assert "unreachable" in stderr or "not finite" in stderr, (argv, stderr)


def test_printed_values_paste_back():
    """fk prints values such as -2.1e-17; they go back into ik and give the joints again."""
    code, stdout, _ = run(
        ["fk", "3p4s", "--joints", "0.4315827775", "0.4315827775", "0.4315827775"]
    )
    assert code == 0
    pose = [t for t in stdout.split() if t[:1].isdigit() or t[:1] == "-"]
    assert any("e-" in p for p in pose), stdout  # x, y ~ 1e-17: scientific notation
    code, stdout2, stderr = run(["ik", "3p4s", "--pose", *pose])
    assert code == 0, stderr
    assert stdout2.count("0.4315827775") == 3


@pytest.mark.parametrize(
    "argv, message",
    [
        (["ik", "3p4s", "--pose", "0", "-1e-3", "0.59"], None),
        (["ik", "3p4s", "--pose", "1e308", "0", "0.592"], "is not finite"),
        (
            [
                "fk",
                "3p4s",
                "--joints",
                "0.4315827775067641",
                "0.4315827775067643",
                "0.4315827775067641",
                "--x0",
                "-1e6",
                "-1e6",
                "-1e6",
                "--solver",
                "newton",
            ],
            "converged on another assembly",
        ),
        (
            ["ik", "3p4s", "--pose", "0", "0", "0.59", "--param", "name=1"],
            "unknown parameter(s) ['name']",
        ),
        (
            ["ik", "2ups", "--pose", "0", "0", "0", "--param", "stroke_limits=1"],
            "expected an array of shape (3,), got shape ()",
        ),
        (
            ["ik", "3p4s", "--pose", "0", "0", "0.59", "--param", "L=1e308"],
            "must be finite numbers <= 1e+06 in magnitude",
        ),
        (
            ["fk", "stewart12", "--joints", *["0.025"] * 12, "--param", "compat_tol=inf", "--json"],
            "compat_tol=inf",
        ),
        (
            ["fk", "3p4s", "--joints", "0.43", "0.43", "0.43", "--tol", "inf"],
            "'inf' is not a finite number",
        ),
        (
            [
                "fk",
                "3p4s",
                "--joints",
                "0.43",
                "0.43",
                "0.43",
                "--solver",
                "pso",
                "--maxiter",
                "100000000000",
            ],
            "must be an integer in [0, 100000]",
        ),
    ],
)
def test_issue_cases(argv, message):
    code, stdout, stderr = run(argv)
    if message is None:
        assert code == 0 and "l1 = " in stdout
    else:
        assert code in (1, 2) and message in stderr and "Traceback" not in stderr, stderr


def test_version():
    code, stdout, _ = run(["--version"])
    assert code == 0 and stdout.startswith("parakin ")


# ------------------------------------------------------------ hostile files and --all (issue 18)
CELLS = [
    "0",
    "0.43",
    "-0.08",
    "0.592",
    "1e308",
    "nan",
    "inf",
    "",
    "abc",
    "x",
    "x [m]",
    "l1 [mm]",
    "1e-3",
    '"1"',
]


#: one scratch folder for the whole module, removed when its tests end (a folder per example used
#: to be left in the temporary directory: thousands after a few suite runs; removed at exit, it
#: added a second to the end of the run)
_SCRATCH = tempfile.TemporaryDirectory(prefix="parakin-fuzz-")


@pytest.fixture(scope="module", autouse=True)
def _scratch_removed_after_the_module():
    yield
    _SCRATCH.cleanup()


@st.composite
def file_argv(draw):
    """ik/fk --input FILE with hostile CSV content (headers, counts, notations), or .npy of any shape."""
    command = draw(st.sampled_from(["ik", "fk"]))
    name = draw(st.sampled_from(sorted(mechanisms.REGISTRY)))
    folder = tempfile.mkdtemp(dir=_SCRATCH.name)
    if draw(st.booleans()):
        rows = draw(
            st.lists(
                st.lists(st.sampled_from(CELLS), min_size=0, max_size=7), min_size=0, max_size=4
            )
        )
        path = f"{folder}/in.csv"
        with open(path, "w") as fh:
            fh.write("\n".join(draw(st.sampled_from([",", ";", ", "])).join(r) for r in rows))
    else:
        shape = draw(st.sampled_from([(3,), (2, 3), (1, 6), (2, 12), (0, 3), (3, 3, 3), (4,)]))
        values = draw(st.sampled_from([0.0, 0.43, -0.08, 1e308, np.nan, np.inf]))
        path = f"{folder}/in.npy"
        np.save(path, np.full(shape, values))
    argv = [command, name, "--input", path]
    if command == "fk" and name in ("2ups", "stewart36") and draw(st.booleans()):
        argv.append("--all")
    if draw(st.booleans()):
        argv += ["--output", f"{folder}/out" + draw(st.sampled_from([".csv", ".npy", ".txt"]))]
    if draw(st.booleans()):
        argv += ["--units", draw(st.sampled_from(["si", "paper"]))]
    if draw(st.booleans()):
        argv.append("--json")
    return argv


@settings(
    max_examples=120,
    derandomize=True,
    deadline=None,
    database=None,
    suppress_health_check=[HealthCheck.too_slow],
)
@given(argv=file_argv())
def test_input_files_survive_hostile_content(argv):
    _check(argv)
    folder = Path(argv[3]).parent  # nothing but the input and the output: no debris, no other file
    assert {p.name for p in folder.iterdir()} <= {Path(argv[3]).name, "out.csv", "out.npy"}
    if "--output" in argv:
        out = argv[argv.index("--output") + 1]
        code, _, _ = run(argv)
        if code == 0 and out.endswith(".npy"):
            a = np.load(out)
            assert "--all" in argv or np.all(np.isfinite(a))


@settings(
    max_examples=60,
    derandomize=True,
    deadline=None,
    database=None,
    suppress_health_check=[HealthCheck.too_slow],
)
@given(name=st.sampled_from(["2ups", "stewart36"]), values=st.data())
def test_fk_all_every_listed_solution_is_right(name, values):
    """--all on any joints: exit 0/1/2, strict JSON, and every listed solution's IK gives the joints."""
    cls = mechanisms.REGISTRY[name]
    joints = values.draw(
        st.lists(
            st.sampled_from(NUMBERS[:13] + ["0.5", "1.8", "2.93", "3.2"]),
            min_size=len(cls.joint_names),
            max_size=len(cls.joint_names),
        )
    )
    argv = ["fk", name, "--joints", *joints, "--all", "--json"]
    code, stdout, stderr = run(argv)
    assert code in (0, 1, 2) and "Traceback" not in stderr, (argv, stderr)
    if code == 2:
        assert len(stderr.strip().splitlines()) == 1
        return
    out = _strict_json(stdout)
    q = np.asarray(out["joints"], dtype=float)[0]
    assert (code == 0) == (out["n_real"][0] > 0)
    for s in out["solutions"][0]:
        mech = cls(branch=-1) if "branch -1" in s["assembly"] else cls()
        assert np.max(np.abs(mech.ik(np.asarray(s["x"])) - q)) <= 1e-7 * max(
            1.0, np.max(np.abs(q))
        ), (argv, s)


# ------------------------------------- hostile files, configs and near-singular poses (issue 26)
ROOT = Path(__file__).resolve().parents[1]
#: a 700-byte YAML alias bomb under an unknown key: 9^12 values once expanded
ALIAS_BOMB = "bomb:\n  a0: &a0 [1.5, 1.5, 1.5, 1.5, 1.5, 1.5, 1.5, 1.5, 1.5]\n" + "".join(
    f"  a{i}: &a{i} [{', '.join([f'*a{i - 1}'] * 9)}]\n" for i in range(1, 12)
)


def _one_error_line(code: int, stderr: str, *needles: str) -> str:
    lines = stderr.strip().splitlines()
    assert code == 2 and len(lines) == 1 and "Traceback" not in stderr, stderr
    assert ".tmp" not in lines[0], lines[0]  # never the hidden temporary file
    assert all(n in lines[0] for n in needles), (needles, lines[0])
    return lines[0]


def test_output_never_follows_a_planted_symlink(tmp_path):
    """Finding 1: symlinks at the old fixed temporary name and at the target itself are never
    followed; the file they point to keeps its bytes; the target becomes our file."""
    victim = tmp_path / "victim.txt"
    victim.write_text("keep\n")
    out = tmp_path / "d"
    out.mkdir()
    (out / ".out.csv.tmp").symlink_to(victim)
    (out / "linked.csv").symlink_to(victim)
    for target in ("out.csv", "linked.csv"):
        code, _, stderr = run(
            ["ik", "3p4s", "--pose", "0", "0", "0.592", "--output", str(out / target)]
        )
        assert code == 0, stderr
        assert not (out / target).is_symlink() and "l1 [m]" in (out / target).read_text()
    assert victim.read_text() == "keep\n"
    assert sorted(p.name for p in out.iterdir()) == [".out.csv.tmp", "linked.csv", "out.csv"]


def test_concurrent_writers_of_one_output_each_succeed(tmp_path):
    """Finding 1: concurrent `parakin ik --output same.csv` all succeed; the file is one of theirs."""
    procs = [
        subprocess.Popen(
            [sys.executable, "-m", "parakin.cli", "ik", "3p4s", "--pose", "0", "0", f"0.59{k}"]
            + ["--output", str(tmp_path / "same.csv")],
            stdout=subprocess.PIPE,
            stderr=subprocess.PIPE,
            text=True,
        )
        for k in range(4)
    ]
    results = [p.communicate(timeout=120) for p in procs]
    assert [p.returncode for p in procs] == [0] * 4, [err for _, err in results]
    lines = (tmp_path / "same.csv").read_text().splitlines()
    assert lines[0] == "l1 [m],l2 [m],l3 [m]" and len(lines) == 2
    assert [p.name for p in tmp_path.iterdir()] == ["same.csv"]  # no debris


@pytest.mark.parametrize("name", sorted(mechanisms.REGISTRY))
@pytest.mark.parametrize("fmt", [".csv", ".npy"])
def test_what_ik_and_fk_write_reads_back_as_the_others_input(tmp_path, name, fmt):
    """Finding 2: ik --output -> fk --input and fk --output -> ik --input, both formats, right answers."""
    mech = mechanisms.REGISTRY[name]()
    lo, hi = mech.pose_bounds()
    pose = mech.home() + 0.05 * (hi - lo) * np.array(
        [[0.3, -0.2, 0.1, 0.2, -0.1, 0.3][: mech.n_pose]]
    )
    pose = np.vstack([mech.home(), pose])
    np.save(tmp_path / "pose.npy", pose)
    joints, back = tmp_path / f"joints{fmt}", tmp_path / f"pose{fmt}"
    code, _, err = run(["ik", name, "--input", str(tmp_path / "pose.npy"), "--output", str(joints)])
    assert code == 0, err
    code, _, err = run(
        ["fk", name, "--input", str(joints), "--output", str(back), "--solver", "newton"]
    )
    assert code == 0, err
    again = tmp_path / f"again{fmt}"
    code, _, err = run(["ik", name, "--input", str(back), "--output", str(again)])
    assert code == 0, err
    q = np.load(again) if fmt == ".npy" else np.loadtxt(again, delimiter=",", skiprows=1, ndmin=2)
    np.testing.assert_allclose(q, mech.ik(pose), atol=1e-9)


@pytest.mark.parametrize("name", ["2ups", "stewart36"])
@pytest.mark.parametrize("fmt", [".csv", ".npy"])
def test_fk_all_output_reads_back_as_ik_input(tmp_path, name, fmt):
    """Every real solution that fk --all lists (quoted assembly labels, NaN-padded .npy) goes back
    into ik: the rows read are the solutions written, and the working ones give the joints again."""
    mech = mechanisms.REGISTRY[name]()
    q = mech.ik(np.vstack([mech.home(), mech.home()]))
    np.save(tmp_path / "q.npy", q)
    out = tmp_path / f"all{fmt}"
    code, _, err = run(
        ["fk", name, "--input", str(tmp_path / "q.npy"), "--all", "--output", str(out)]
    )
    assert code == 0, err
    code, stdout, err = run(["ik", name, "--input", str(out), "--json"])
    assert code == 0, err
    read = np.asarray(json.loads(stdout)["pose"])
    if fmt == ".npy":
        written = np.load(out).reshape(-1, mech.n_pose)
        written = written[~np.isnan(written).all(-1)]
    else:
        table = pd.read_csv(out)
        written = table.iloc[:, 2 : 2 + mech.n_pose].to_numpy()
        working = table["working"].to_numpy()
        joints = np.asarray(json.loads(stdout)["joints"])[working]
        np.testing.assert_allclose(joints, q[: working.sum()], atol=1e-9)
    np.testing.assert_array_equal(read, written)
    assert len(read) >= 4


def _npy_bytes(kind: str) -> bytes:
    buf = io.BytesIO()
    arrays = {
        "strings": np.array([["a", "b", "c"]]),
        "complex": np.ones((1, 3), dtype=complex),
        "bool": np.ones((1, 3), dtype=bool),
        "0-d": np.array(0.5),
        "rows0": np.zeros((0, 3)),
    }
    if kind == "objects":
        np.save(buf, np.array([[1, "x", None]], dtype=object), allow_pickle=True)
    elif kind == "npz":
        np.savez(buf, a=np.zeros((1, 3)))
    else:
        np.save(buf, arrays.get(kind, np.full((4, 3), 0.43)))
    data = buf.getvalue()
    return {
        "empty": b"",
        "magic-only": data[:6],
        "header-cut": data[:40],
        "data-cut": data[:-9],
    }.get(kind, data)


@pytest.mark.parametrize(
    "kind",
    ["empty", "magic-only", "header-cut", "data-cut", "strings", "complex", "bool", "0-d", "rows0"]
    + ["objects", "npz"],
)
def test_broken_npy_inputs_are_one_line(tmp_path, kind):
    """Finding 3: empty, truncated and wrongly-typed .npy files: one line naming the file."""
    path = tmp_path / f"{kind}.npy"
    path.write_bytes(_npy_bytes(kind))
    code, _, stderr = run(["fk", "3p4s", "--input", str(path)])
    _one_error_line(code, stderr, str(path))


@pytest.mark.parametrize(
    "content, needle",
    [
        (b"", "no rows"),
        (b"x [m],y [m],z [m]\n", "a header and no rows"),
        (b"\xff\xfe0\x000\x00", "not UTF-8"),
        ("x,y,z\n0,0,0.59\n".encode("utf-16"), "not UTF-8"),
        (b"0,0,0.5\x00\n", "are not all numbers"),
        (b"x [m],y [m],z [m],s\n0,0,0.59\n", "3 values, expected 4"),
        (b'x,y,z,label\n0,0,0.592,"a, b"\n', None),  # quoted comma: read by name, a right answer
    ],
)
def test_broken_csv_inputs_are_one_line(tmp_path, content, needle):
    path = tmp_path / "in.csv"
    path.write_bytes(content)
    code, stdout, stderr = run(["ik", "3p4s", "--input", str(path)])
    if needle is None:
        assert code == 0 and "l1 = 0.4315827775 m" in stdout, stderr
    else:
        _one_error_line(code, stderr, str(path), needle)


def test_alias_bomb_is_refused_at_once(tmp_path):
    """Finding 4: the 700-byte alias bomb: one line from parakin, no hang."""
    bomb = tmp_path / "bomb.yaml"
    bomb.write_text(ALIAS_BOMB)
    assert len(ALIAS_BOMB) < 800
    cli = subprocess.run(
        [sys.executable, "-m", "parakin.cli", "reproduce", "zhao2017_3p4s", "table1"]
        + ["--config", str(bomb)],
        capture_output=True,
        text=True,
        timeout=60,
    )
    _one_error_line(cli.returncode, cli.stderr, "bomb.yaml", "more than the limit 100000")


@pytest.mark.parametrize(
    "text, needle",
    [
        (ALIAS_BOMB, "config error: config expands to"),
        ("studies: [os]\n", "config error: config key 'studies': 'os' declares no @artefact"),
    ],
    ids=["alias-bomb", "studies-os"],
)
def test_snakemake_refuses_bad_configs_in_one_line(tmp_path, text, needle):
    """Finding 4 through the pipeline (workflow/rules/common.smk): no hang, no traceback."""
    path = tmp_path / "bad.yaml"
    path.write_text(text)
    smk = subprocess.run(
        [sys.executable, "-m", "snakemake", "-n", "--cores", "1", "--configfile", str(path)],
        cwd=ROOT,
        capture_output=True,
        text=True,
        timeout=120,
    )
    output = smk.stdout + smk.stderr
    assert smk.returncode != 0 and "Traceback" not in output and needle in output, output[-2000:]


@pytest.mark.parametrize(
    "text, needles",
    [
        ("studies: [os]\n", ["'os' declares no @artefact", "parakin.papers.zhao2017_3p4s"]),
        ("studies: [parakin.papers.zhao2017]\n", ["'parakin.papers.zhao2017' is not a module"]),
        ("studies: [no_such_pkg.study]\n", ["is not a module"]),
        ("seeed: 1\n", ["'seeed' was unexpected"]),
        ("seed: [1\n", ["is not valid YAML"]),
        ("a: &x [1, *x]\n", ["refers to itself"]),
        ("a: " + "[" * 200 + "]" * 200 + "\n", ["nests deeper than the limit 64"]),
        ("- 1\n", ["must hold a mapping"]),
    ],
)
def test_config_typos_are_one_line(tmp_path, text, needles):
    """Finding 4: typos in `studies` and elsewhere: one line naming the key, the known studies."""
    path = tmp_path / "typo.yaml"
    path.write_text(text)
    code, _, stderr = run(["reproduce", "zhao2017_3p4s", "table1", "--config", str(path)])
    _one_error_line(code, stderr, *needles)


@pytest.mark.parametrize("encoding", ["utf-16", "binary"])
def test_non_utf8_config_is_one_line(tmp_path, encoding):
    path = tmp_path / "cfg.yaml"
    path.write_bytes("seed: 1\n".encode("utf-16") if encoding == "utf-16" else bytes(range(256)))
    code, _, stderr = run(["report", "--config", str(path)])
    _one_error_line(code, stderr, str(path), "not UTF-8 text")


def test_check_merges_an_overlay_as_the_pipeline_does(tmp_path):
    """Finding 5: `parakin check --config config/quick.yaml` reads quick as an overlay of config.yaml."""
    code, stdout, stderr = run(
        ["check", "--config", str(ROOT / "config" / "quick.yaml")]
        + ["--results", str(tmp_path / "figures"), "--out", str(tmp_path / "check")]
    )
    assert code == 0 and "reproduction check:" in stdout and not stderr, stderr
    assert (tmp_path / "check.csv").is_file()


@pytest.mark.parametrize(
    "argv, needles",
    [
        (["fk", "3p4s", "--joints", "0.43", "0.43", "0.43", "--solver", ""], ["--solver", "empty"]),
        (["ik", "3p4s", "--pose", "0", "0", "0.59", "--output", ""], ["--output", "empty"]),
        (["ik", "3p4s", "--input", ""], ["--input", "empty"]),
        (["reproduce", "zhao2017_3p4s", "table1", "--config", " "], ["--config", "empty"]),
        (
            ["ik", "stewart36", "--pose", "1e308", "0", "0", "0", "0", "1"],
            ["alpha = 1e+308 rad", "1000 rad"],
        ),
        (
            ["ik", "2ups", "--pose", "0", "-1e9", "0", "--units", "paper"],
            ["gamma = 1e+09 deg", "57295.8 deg"],
        ),
        (
            ["fk", "stewart36", "--joints", *["3"] * 6, "--x0", "0", "0", "1e5", "0", "0", "1"],
            ["--x0: gamma"],
        ),
    ],
)
def test_messages_name_the_value_and_the_limit(argv, needles):
    """Finding 6: an empty option is an error, not the default; an absurd angle names the limit."""
    code, _, stderr = run(argv)
    _one_error_line(code, stderr, *needles)


def test_write_errors_name_the_users_file(tmp_path):
    """Finding 6: never the hidden temporary file."""
    (tmp_path / "taken.csv").mkdir()
    (tmp_path / "file").write_text("")
    for target, needle in [("taken.csv", "Is a directory"), ("file/out.csv", "Not a directory")]:
        code, _, stderr = run(
            ["ik", "3p4s", "--pose", "0", "0", "0.59", "--output", str(tmp_path / target)]
        )
        _one_error_line(code, stderr, needle, str(tmp_path / target))


def test_readme_blames_the_file_without_markers(tmp_path):
    """Finding 6: `parakin readme --readme X.md` without markers names X.md, not the benchmarks."""
    readme = tmp_path / "X.md"
    readme.write_text("# no markers\n")
    for extra in ([], ["--check"]):
        code, _, stderr = run(["readme", "--readme", str(readme), *extra])
        _one_error_line(code, stderr, f"--readme {readme} has no <!-- benchmarks:begin -->")
    assert readme.read_text() == "# no markers\n"


def test_help_lists_every_command_on_one_line():
    """Finding 6: `parakin --help` comes from the parser: every subcommand, one line each."""
    from parakin.cli import build_parser

    code, stdout, _ = run(["--help"])
    assert code == 0 and "``" not in stdout
    parser = build_parser()
    commands = next(a for a in parser._actions if a.choices and a.dest == "command").choices
    assert len(commands) >= 9
    for name in commands:
        line = next(row for row in stdout.splitlines() if row.split()[:1] == [name])
        assert len(line.split()) > 2, line  # the name and its help on the same line


@functools.cache
def _worst_poses(name: str) -> tuple[np.ndarray, np.ndarray]:
    """The 40 worst-conditioned of 3,000 random poses of ``name`` and their joints (seeded)."""
    mech = mechanisms.REGISTRY[name]()
    pool = sample_reachable(mech, 3000, np.random.default_rng(0))
    joints = mech.ik(pool)
    worst = np.argsort(-np.linalg.cond(mech.jacobian_pose(pool, joints)), kind="stable")[:40]
    return pool[worst], joints[worst]


@settings(max_examples=40, derandomize=True, deadline=None, database=None)
@given(
    name=st.sampled_from(["stewart36", "stewart66"]),
    row=st.integers(0, 39),
    offset=st.lists(st.floats(-1e-3, 1e-3), min_size=6, max_size=6),
)
def test_near_singular_poses_through_the_cli(name, row, offset):
    """Near-singular joints, Newton from 1e-3 off the true pose: a right answer (exit 0, checked
    by _check) that, where it is not the pose we started near, says so in one warning line."""
    truth, joints = _worst_poses(name)
    x0 = truth[row] + np.asarray(offset)
    argv = ["fk", name, "--joints", *map(repr, joints[row].tolist()), "--solver", "newton"]
    argv += ["--x0", *map(repr, x0.tolist()), "--json"]
    _check(argv)
    code, stdout, stderr = run(argv)
    if code == 0:
        out = _strict_json(stdout)
        mech = mechanisms.REGISTRY[name]()
        moved = np.max(np.abs(mech.pose_difference(np.asarray(out["x"]), truth[row]))) > 1e-6
        assert not moved or out["near_singular"], (argv, out["x"])
        warned = [line for line in stderr.splitlines() if "warning: near a singularity" in line]
        assert len(warned) == int(out["near_singular"]), stderr


# ------------------------------- dynamics, --geometry and --mechanism files (issue 46)
#: hostile values for a parameter, a leg field or a pose cell (YAML-dumpable)
HOSTILE_VALUES = [
    0,
    -1,
    0.5,
    1e308,
    -1e308,
    float("nan"),
    float("inf"),
    10**30,
    True,
    False,
    None,
    "",
    "abc",
    "35deg",
    "120mm",
    "1e3",
    [],
    [1, 2],
    [[1, 2, 3]] * 7,
    {"a": 1},
    "[" * 40,
]
DYNAMIC = sorted(n for n, c in mechanisms.REGISTRY.items() if c().mass_model() is not None)
EXAMPLES_DIR = ROOT / "examples"


def _structural(draw) -> bytes | None:
    """A hostile file whatever its meaning (one draw in four): an alias bomb, nesting 30-200
    deep, a recursive alias, a tab, bytes that are not UTF-8, a list or a scalar at the top."""
    kind = draw(st.integers(0, 11))
    if kind == 0:
        levels = draw(st.integers(2, 12))
        rows = ["a0: &a0 [1, 1, 1, 1, 1, 1, 1, 1, 1]"]
        rows += [f"a{i}: &a{i} [{', '.join([f'*a{i - 1}'] * 9)}]" for i in range(1, levels)]
        return ("\n".join(rows) + "\n").encode()
    if kind == 1:
        depth = draw(st.sampled_from([30, 33, 64, 65, 200]))
        return f"x: {'[' * depth}1{']' * depth}\n".encode()
    if kind == 2:
        return b"a: &x [1, *x]\n"
    if kind == 3:
        return b"a:\n\tb: 1\n"
    if kind == 4:
        return bytes(draw(st.lists(st.integers(128, 255), min_size=1, max_size=8)))
    if kind == 5:
        return draw(st.sampled_from([b"- 1\n- 2\n", b"3\n", b"", b"~\n", b"{}", b"[]"]))
    return None


def _dump(draw, data) -> bytes:
    """``data`` as YAML or JSON (NaN and inf as JSON's non-standard tokens), sometimes cut short."""
    if draw(st.booleans()):
        text = yaml.safe_dump(data, sort_keys=False)
    else:
        text = json.dumps(data)
    raw = text.encode()
    if draw(st.integers(0, 9)) == 0:
        raw = raw[: draw(st.integers(0, len(raw)))]
    return raw


def _common(argv: list[str]) -> tuple[int, str, str]:
    """The properties every command keeps: exit 0, 1 or 2; no traceback; an error is one line;
    ``--json`` is strict JSON."""
    code, stdout, stderr = run(argv)
    assert code in (0, 1, 2), (argv, code, stderr)
    assert "Traceback" not in stderr + stdout, (argv, stderr[-2000:])
    if code == 2:
        assert len(stderr.strip().splitlines()) == 1, (argv, stderr)
    if code == 0 and "--json" in argv:
        _strict_json(stdout)
    return code, stdout, stderr


@st.composite
def geometry_argv(draw):
    """ik or fk of a registered mechanism with a hostile --geometry file (and --param)."""
    name = draw(st.sampled_from(sorted(mechanisms.REGISTRY)))
    cls = mechanisms.REGISTRY[name]
    mech = cls()
    raw = _structural(draw)
    if raw is None:
        known = parameters_of(cls)
        keys = draw(
            st.lists(
                st.sampled_from([*known, "name", "nope", "pose_names"]), min_size=0, max_size=3
            )
        )
        data = {}
        for key in keys:
            default = known.get(key, 1.0)
            if draw(st.booleans()):  # near the default: a real geometry, scaled
                scale = draw(st.sampled_from([1.0, 0.9, 1.1, -1.0, 0.0, 1e3]))
                data[key] = (np.asarray(default, dtype=float) * scale).tolist()
            else:
                data[key] = draw(st.sampled_from(HOSTILE_VALUES))
        raw = _dump(draw, data)
    folder = Path(tempfile.mkdtemp(dir=_SCRATCH.name))
    path = folder / draw(st.sampled_from(["g.yaml", "g.json"]))
    path.write_bytes(raw)
    home = mech.home()
    if draw(st.booleans()):
        argv = ["ik", name, "--pose", *map(repr, home.tolist())]
    else:
        argv = ["fk", name, "--joints", *map(repr, mech.ik(home).tolist())]
    argv += ["--geometry", str(path)]
    if draw(st.integers(0, 3)) == 0:
        key = draw(st.sampled_from(sorted(parameters_of(cls))))
        argv += ["--param", f"{key}={draw(st.sampled_from(['1', '0.2', 'true', '[1]', 'x']))}"]
    return argv + ["--json"]


@settings(
    max_examples=450,
    derandomize=True,
    deadline=None,
    database=None,
    suppress_health_check=[HealthCheck.too_slow, HealthCheck.data_too_large],
)
@given(argv=geometry_argv())
def test_hostile_geometry_files(argv):
    """Whatever a --geometry file holds: exit 0/1/2, one line, strict JSON, and an answer is right
    for the geometry it prints (ik: those joints; fk: its pose gives the joints back)."""
    code, stdout, _ = _common(argv)
    if code != 0:
        return
    out = _strict_json(stdout)
    if argv[0] == "fk":
        _check_right_answer(argv, out)
    else:
        cls = mechanisms.REGISTRY[out["mechanism"]]
        mech = cls(**{k: v for k, v in out["parameters"].items() if k in parameters_of(cls)})
        np.testing.assert_allclose(mech.ik(np.asarray(out["pose"])), out["joints"], rtol=1e-12)


@st.composite
def dynamics_argv(draw):
    """parakin dynamics with a hostile trajectory CSV (rows, times, cells, columns) and options."""
    name = draw(st.sampled_from(DYNAMIC))
    mech = mechanisms.REGISTRY[name]()
    lo, hi = mech.pose_bounds()
    clean = draw(st.integers(0, 2)) > 0  # two in three: a trajectory that should be answered
    k = draw(st.sampled_from([4, 6, 12] if clean else [0, 1, 3, 4, 12]))
    t = np.linspace(0.0, 1.0, k)
    order = "up" if clean else draw(st.sampled_from(["up", "flat", "down"]))
    if order == "flat":
        t[:] = 0.5
    elif order == "down":
        t = t[::-1]
    amp = draw(st.sampled_from([0.0, 0.02, 0.1] if clean else [0.3, 2.0, 100.0]))
    wave = np.sin(np.outer(t * 6.0, np.arange(1, 7)))[:, : mech.n_pose]
    pose = mech.home() + amp * 0.5 * (hi - lo) * wave
    names = ["t", *mech.pose_names]
    cells = [[repr(float(v)) for v in (ti, *row)] for ti, row in zip(t, pose)]
    if name == "rpr3" and draw(st.integers(0, 3)) == 0:  # through a singular pose
        names, cells = ["t", "x", "y", "phi"], [r.split(",") for r in SINGULAR_RPR3]
    for _ in range(0 if clean else draw(st.integers(0, 2))):
        if cells:
            i, j = draw(st.integers(0, len(cells) - 1)), draw(st.integers(0, len(names) - 1))
            cells[i][j] = draw(st.sampled_from(["nan", "inf", "abc", "", "1e308", '"1', "-0"]))
    if not clean and draw(st.booleans()):
        names = names[:-1] if draw(st.booleans()) else [*names, "extra"]
    folder = Path(tempfile.mkdtemp(dir=_SCRATCH.name))
    path = folder / "traj.csv"
    path.write_text("\n".join([",".join(names), *(",".join(r) for r in cells)]) + "\n")
    argv = ["dynamics", name, "--trajectory", str(path)]
    if draw(st.booleans()):
        argv.append("--flag-singular")
    if draw(st.integers(0, 3)) == 0:
        argv += ["--wrench", *draw(st.lists(st.sampled_from(NUMBERS[:20]), min_size=6, max_size=6))]
    if draw(st.integers(0, 3)) == 0:
        argv += ["--output", str(folder / draw(st.sampled_from(["f.csv", "f.npy", "f.txt"])))]
    if draw(st.booleans()):
        argv.append("--json")
    return argv


#: the rows of a 3-RPR trajectory through a singular pose (its third sample)
SINGULAR_RPR3 = [
    "0,0,0,0",
    "0.1,0.1,0.01,-0.5",
    "0.2,0.29763715,0.03302491,-1.04719755",
    "0.3,0.2,0.02,-0.8",
    "0.4,0,0,0",
]


@settings(
    max_examples=300,
    derandomize=True,
    deadline=None,
    database=None,
    suppress_health_check=[HealthCheck.too_slow, HealthCheck.data_too_large],
)
@given(argv=dynamics_argv())
def test_hostile_trajectories(argv):
    """Whatever the trajectory: exit 0/1/2, one line, strict JSON; a force is null (JSON) or NaN
    (text) only where its sample is flagged singular or unbalanced, and a JSON answer is the
    library's own inverse dynamics of that file (no silent wrong answer)."""
    code, stdout, stderr = _common(argv)
    if code != 0:
        return
    flagged = "singular or unbalanced" in stderr
    if "--json" not in argv:
        if not flagged and "--output" not in argv:
            assert "nan" not in stdout.lower() and "inf" not in stdout.lower(), (argv, stdout)
        return
    out = _strict_json(stdout)
    from parakin import dynamics
    from parakin.dynamics.trajectory import read_trajectory

    mech = mechanisms.REGISTRY[argv[1]]()
    traj = read_trajectory(argv[3], mech)
    wrench = None
    if "--wrench" in argv:
        i = argv.index("--wrench")
        wrench = [float(v) for v in argv[i + 1 : i + 7]]
    want = dynamics.inverse_dynamics(mech, *traj.state(traj.t), wrench=wrench, on_singular="flag")
    bad = np.asarray(out["singular"]) | np.asarray(out["unbalanced"])
    assert flagged == bool(bad.any()), (argv, stderr)
    force = np.array([[np.nan if f is None else f for f in row] for row in out["force"]])
    assert np.array_equal(np.isnan(force).any(-1), bad), (argv, out)
    np.testing.assert_allclose(force, want.force, rtol=1e-12, equal_nan=True)


def _takes_mechanism_files() -> bool:
    import argparse

    from parakin.cli import build_parser

    sub = next(a for a in build_parser()._actions if isinstance(a, argparse._SubParsersAction))
    return any("--mechanism" in a.option_strings for a in sub.choices["ik"]._actions)


@functools.cache
def _example(path: str):
    """An example description (as loaded), its mechanism's home and the home's joints."""
    from parakin.mechanisms import from_file

    mech = from_file(path)
    return yaml.safe_load(Path(path).read_text()), mech.home(), mech.ik(mech.home())


@functools.cache
def _descriptions() -> list[str]:
    """The files of examples/ that describe a mechanism (others there are --geometry files)."""
    from parakin.errors import ParakinError

    out = []
    for path in sorted(EXAMPLES_DIR.glob("*.yaml")):
        try:
            _example(str(path))
        except (ParakinError, ValueError):
            continue
        out.append(str(path))
    return out


def _mutate_leaf(draw, node):
    """``node`` (a description) with one field deleted, or set to a hostile value."""
    node = copy.deepcopy(node)
    paths = []

    def walk(n, at):
        if isinstance(n, dict):
            for k, v in n.items():
                paths.append((*at, k))
                walk(v, (*at, k))
        elif isinstance(n, list):
            for i, v in enumerate(n):
                paths.append((*at, i))
                walk(v, (*at, i))

    walk(node, ())
    if not paths:
        return node
    path = draw(st.sampled_from(paths))
    parent = node
    for key in path[:-1]:
        parent = parent[key]
    if draw(st.integers(0, 3)) == 0:
        del parent[path[-1]]
    else:
        parent[path[-1]] = draw(st.sampled_from(HOSTILE_VALUES))
    return node


@st.composite
def mechanism_file_argv(draw):
    """ik or fk with --mechanism FILE: an example description with a field deleted or made
    hostile, or a file hostile whatever its meaning."""
    example = draw(st.sampled_from(_descriptions()))
    data, home, joints = _example(example)
    raw = _structural(draw)
    if raw is None:
        for _ in range(draw(st.integers(0, 2))):
            data = _mutate_leaf(draw, data)
        raw = _dump(draw, data)
    folder = Path(tempfile.mkdtemp(dir=_SCRATCH.name))
    path = folder / draw(st.sampled_from(["m.yaml", "m.json"]))
    path.write_bytes(raw)
    if draw(st.booleans()):
        argv = ["ik", "--mechanism", str(path), "--pose", *map(repr, home.tolist())]
    else:
        argv = ["fk", "--mechanism", str(path), "--joints", *map(repr, joints.tolist())]
    return argv + ["--json"]


@pytest.mark.slow  # ~20 s: every case builds a described mechanism
@pytest.mark.skipif(not _takes_mechanism_files(), reason="no --mechanism option yet (issue 43)")
@settings(
    max_examples=250,
    derandomize=True,
    deadline=None,
    database=None,
    suppress_health_check=[HealthCheck.too_slow, HealthCheck.data_too_large],
)
@given(argv=mechanism_file_argv())
def test_hostile_mechanism_files(argv):
    """Whatever a mechanism file holds: exit 0/1/2, one line naming the file, strict JSON, and an
    answer is right for the mechanism that file describes."""
    code, stdout, _ = _common(argv)
    if code != 0:
        return
    from parakin.mechanisms import from_file

    out = _strict_json(stdout)
    mech = from_file(argv[2])
    if argv[0] == "ik":
        np.testing.assert_allclose(mech.ik(np.asarray(out["pose"])), out["joints"], rtol=1e-12)
    else:
        x, q = np.asarray(out["x"], dtype=float), np.asarray(out["joints"], dtype=float)
        assert np.max(mech.joint_error(x, q)) < 1e-8, (argv, out)
