"""Fuzz: the ``parakin`` command line on hostile argument vectors, in process.

Property (issue 16): whatever the arguments (numbers in any notation and sign, non-finite or huge
values, wrong counts, unknown or class-attribute parameters, unknown solvers, garbage strings),
``parakin`` exits 0, 1 or 2 without a traceback; an error is one line on stderr; exit 0 never
comes with a non-finite value on stdout; ``--json`` output is strict JSON; and a successful ``fk``
is a right answer (its pose's IK gives back the joints). More than 1,000 argument vectors per run
(``EXAMPLES`` x the tests below); fixed, derandomized settings keep a run reproducible and short.
"""

from __future__ import annotations

import contextlib
import io
import json
import math

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from parakin import mechanisms
from parakin.cli import main, parameters_of
from parakin.units import to_si

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


def run(argv: list[str]) -> tuple[int, str, str]:
    """``main(argv)`` in process: exit status, stdout, stderr (argparse's exits included)."""
    out, err = io.StringIO(), io.StringIO()
    with contextlib.redirect_stdout(out), contextlib.redirect_stderr(err):
        try:
            code = main(argv)
        except SystemExit as exc:
            code = exc.code if isinstance(exc.code, int) else (0 if exc.code is None else 2)
    return code, out.getvalue(), err.getvalue()


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
    x = to_si(np.asarray(out["x"], dtype=float), out["pose_units"])
    q = to_si(np.asarray(out["joints"], dtype=float), out["joint_units"])
    tol = 1e-10 if "--tol" not in argv else float(argv[argv.index("--tol") + 1])
    joint_tol = max(1e-8, 100 * tol)
    assert np.max(np.abs(mech.ik(x) - q)) <= joint_tol * (1 + 1e-9) + 1e-15, argv


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


@st.composite
def file_argv(draw):
    """ik/fk --input FILE with hostile CSV content (headers, counts, notations), or .npy of any shape."""
    import tempfile

    command = draw(st.sampled_from(["ik", "fk"]))
    name = draw(st.sampled_from(sorted(mechanisms.REGISTRY)))
    folder = tempfile.mkdtemp(prefix="parakin-fuzz-")
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
