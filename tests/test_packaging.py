"""Packaging: the wheel, installed into a fresh virtual environment, works outside the checkout.

The wheel is built from the files a fresh clone has (git's tracked and not-ignored files) and
installed without dependencies into a new virtual environment; the environment running the tests
lends its installed packages (numpy, scipy, ...) through a ``.pth`` file, so nothing is downloaded
and the only parakin the new environment sees is the wheel's. Every command runs from an empty
folder, so nothing can come from the checkout or from the working folder.
"""

from __future__ import annotations

import json
import os
import shutil
import subprocess
import sys
import sysconfig
import venv
import zipfile
from importlib.metadata import PackageNotFoundError, version
from pathlib import Path

import numpy as np
import pandas as pd
import pytest

import parakin
from parakin.config import load_config
from parakin.mechanisms import P3P4S

pytestmark = pytest.mark.packaging

ROOT = Path(__file__).resolve().parents[1]
#: what a build needs when git cannot list a fresh clone's files
BUILD_INPUTS = (
    "pyproject.toml",
    "setup.py",
    "MANIFEST.in",
    "README.md",
    "LICENSE",
    "CITATION.cff",
    "CHANGELOG.md",
    "src",
    "config",
    "data/reference",
)
RUNTIME_DEPS = (
    "numpy",
    "scipy",
    "pandas",
    "matplotlib",
    "pyyaml",
    "jsonschema",
    "mujoco",
    "pymoo",
    "sympy",
)


def _clone_files(dest: Path) -> None:
    """Copy the files of a fresh clone (tracked, and untracked but not ignored) to ``dest``."""
    try:
        listed = (
            subprocess.run(
                ["git", "ls-files", "-z", "--cached", "--others", "--exclude-standard"],
                cwd=ROOT,
                capture_output=True,
                check=True,
                timeout=60,
            )
            .stdout.decode()
            .split("\0")
        )
    except (OSError, subprocess.SubprocessError):
        listed = []
    files = [f for f in listed if f and (ROOT / f).is_file()]
    if not files:  # not a git checkout: the build inputs, less caches
        for name in BUILD_INPUTS:
            src = ROOT / name
            if src.is_dir():
                shutil.copytree(
                    src, dest / name, ignore=shutil.ignore_patterns("__pycache__", "*.egg-info")
                )
            elif src.is_file():
                shutil.copy2(src, dest / name)
        return
    for f in files:
        (dest / f).parent.mkdir(parents=True, exist_ok=True)
        shutil.copy2(ROOT / f, dest / f)


def _outer_site_dirs() -> list[str]:
    """The running environment's site-packages folders (never the checkout's src/)."""
    dirs = [sysconfig.get_paths()["purelib"], sysconfig.get_paths()["platlib"]]
    dirs += [p for p in sys.path if Path(p).name in ("site-packages", "dist-packages")]
    return list(dict.fromkeys(d for d in dirs if Path(d).is_dir()))


class Installed:
    def __init__(self, tmp: Path):
        self.tmp = tmp
        clone, wheels, self.env, self.work = (tmp / n for n in ("clone", "wheels", "venv", "work"))
        for d in (clone, wheels, self.work):
            d.mkdir()
        _clone_files(clone)
        self.base_env = {
            k: v
            for k, v in os.environ.items()
            if k not in ("PYTHONPATH", "PYTHONHOME", "PYTHONSTARTUP")
        }
        self.base_env.update(
            MPLBACKEND="Agg", PIP_DISABLE_PIP_VERSION_CHECK="1", PYTHONNOUSERSITE="1"
        )
        # the running environment's setuptools builds the wheel (no download); without a recent
        # one, pip builds it in an isolated environment (which needs the package index)
        try:
            recent = int(version("setuptools").split(".")[0]) >= 77
        except PackageNotFoundError:
            recent = False
        build = ["--no-build-isolation"] if recent else []
        self._check(
            [
                sys.executable,
                "-m",
                "pip",
                "wheel",
                "--no-deps",
                *build,
                "-w",
                str(wheels),
                str(clone),
            ],
            cwd=tmp,
            timeout=300,
        )
        (self.wheel,) = wheels.glob("parakin-*.whl")
        venv.create(self.env, with_pip=False, symlinks=os.name != "nt")
        paths = sysconfig.get_paths(vars={"base": str(self.env), "platbase": str(self.env)})
        self.site = Path(paths["purelib"])
        self.scripts = Path(paths["scripts"])
        self.python = self.scripts / ("python.exe" if os.name == "nt" else "python")
        (self.site / "_outer_environment.pth").write_text("\n".join(_outer_site_dirs()) + "\n")
        self._check(
            [str(self.python), "-m", "pip", "install", "--no-deps", "--no-index", str(self.wheel)],
            cwd=self.work,
            timeout=120,
        )

    def _check(self, cmd: list[str], cwd: Path, timeout: float) -> subprocess.CompletedProcess:
        res = subprocess.run(
            cmd, cwd=cwd, env=self.base_env, capture_output=True, text=True, timeout=timeout
        )
        assert res.returncode == 0, (
            f"{' '.join(cmd)} failed:\n{res.stdout[-3000:]}\n{res.stderr[-3000:]}"
        )
        return res

    def parakin(self, *args: str, timeout: float = 120) -> subprocess.CompletedProcess:
        exe = self.scripts / ("parakin.exe" if os.name == "nt" else "parakin")
        return subprocess.run(
            [str(exe), *args],
            cwd=self.work,
            env=self.base_env,
            capture_output=True,
            text=True,
            timeout=timeout,
        )

    def python_json(self, code: str):
        res = self._check([str(self.python), "-c", code], cwd=self.work, timeout=120)
        return json.loads(res.stdout)


@pytest.fixture(scope="module")
def installed(tmp_path_factory) -> Installed:
    return Installed(tmp_path_factory.mktemp("packaging"))


def test_wheel_ships_config_reference_data_network_and_metadata(installed):
    with zipfile.ZipFile(installed.wheel) as whl:
        names = set(whl.namelist())
        meta = next(n for n in names if n.endswith(".dist-info/METADATA"))
        metadata = whl.read(meta).decode()
    for name in ("config.yaml", "quick.yaml", "schema.yaml"):
        assert f"parakin/_project/config/{name}" in names
    for f in (ROOT / "data" / "reference").glob("*.csv"):
        assert f"parakin/_project/data/reference/{f.name}" in names
    assert {"parakin/py.typed", "parakin/nn/data/zhao2017_3p4s_bp.npz"} <= names
    package = ROOT / "src" / "parakin"  # every data file of the package (networks, start systems)
    data = {
        f"parakin/{f.relative_to(package).as_posix()}"
        for f in package.rglob("*")
        if f.is_file() and f.suffix not in (".py", ".pyc") and "__pycache__" not in f.parts
    }
    assert data <= names, f"not in the wheel: {sorted(data - names)}"
    assert any(n.endswith(".dist-info/licenses/LICENSE") for n in names)
    assert f"Version: {parakin.__version__}\n" in metadata
    requires = [
        line.split(":", 1)[1].strip().lower()
        for line in metadata.splitlines()
        if line.startswith("Requires-Dist:")
    ]
    for dep in RUNTIME_DEPS:
        assert any(r.startswith(dep) and "extra ==" not in r for r in requires), (
            f"{dep} is not a dependency"
        )
    assert any(r.startswith("torch") and 'extra == "nn"' in r for r in requires)


def test_installed_parakin_is_the_wheel_with_the_checkouts_config(installed):
    got = installed.python_json(
        "import json, parakin; from parakin.config import ROOT, DEFAULT_CONFIG, load_config; "
        "print(json.dumps({'file': parakin.__file__, 'root': str(ROOT), 'version': parakin.__version__, "
        "'config': load_config(DEFAULT_CONFIG)}))"
    )
    package = Path(got["file"]).resolve().parent
    assert package == (installed.site / "parakin").resolve(), (
        f"imported {got['file']}, not the wheel's parakin"
    )
    assert Path(got["root"]).resolve() == package / "_project"
    assert got["version"] == parakin.__version__
    assert got["config"] == json.loads(json.dumps(load_config()))


def test_version_option(installed):
    res = installed.parakin("--version")
    if res.returncode == 2 and "--version" not in installed.parakin("--help").stdout:
        pytest.skip("the CLI has no --version option yet")
    assert res.returncode == 0, res.stderr
    assert parakin.__version__ in res.stdout + res.stderr


def test_ik_outside_the_checkout(installed):
    res = installed.parakin("ik", "3p4s", "--pose", "0", "0", "0.59")
    assert res.returncode == 0, res.stderr
    assert "l1 = " in res.stdout


def test_fk_hybrid_uses_the_shipped_network(installed):
    pose = [0.02, 0.01, 0.576]
    q = P3P4S().ik(pose)
    res = installed.parakin(
        "fk", "3p4s", "--joints", *map(repr, q.tolist()), "--solver", "hybrid", "--json"
    )
    assert res.returncode == 0, res.stderr
    out = json.loads(res.stdout)
    assert out["success"] is True and out["method"] == "hybrid"
    assert np.allclose(out["x"], pose, atol=1e-9)


def test_reproduce_outside_the_checkout(installed):
    out = installed.tmp / "out"
    res = installed.parakin("reproduce", "zhao2017_3p4s", "table1", "--outdir", str(out))
    assert res.returncode == 0, res.stderr
    got = pd.read_csv(out / "table1.csv", dtype={"paper": str})
    committed = ROOT / "figures" / "zhao2017_3p4s" / "table1.csv"
    if committed.exists():  # the full config's table, as the pipeline committed it
        pd.testing.assert_frame_equal(
            got, pd.read_csv(committed, dtype={"paper": str}), check_exact=False, rtol=1e-9
        )
    assert not (installed.work / "figures").exists() and not (installed.work / "data").exists()


def test_citation_and_changelog_follow_the_version():
    import yaml

    assert yaml.safe_load((ROOT / "CITATION.cff").read_text())["version"] == parakin.__version__
    changelog = (ROOT / "CHANGELOG.md").read_text()
    assert f"## [{parakin.__version__}]" in changelog or "## [Unreleased]" in changelog


def test_shipped_network_is_the_pipelines_and_guesses_well(tmp_path):
    from parakin.nn import BPNetwork, load_network, packaged_network_path

    net = load_network()
    assert net.n_weights == 73 and (net.n_in, net.hidden, net.n_out) == (3, 10, 3)
    # trained by the full config's `train` artefact: 10000 samples, 70/15/15 split
    assert net.meta["n_train"] + net.meta["n_val"] + net.meta["n_test"] == 10000
    mech = P3P4S.zhao2017()
    poses = np.array([[0.0, 0.0, 0.59], [0.03, -0.02, 0.56], [-0.05, 0.04, 0.55]])
    assert np.max(np.abs(net.predict(mech.ik(poses)) - poses)) < 5e-3  # m: a guess for the hybrid
    # a path is read as given; with fallback, a missing one falls back to the shipped network
    other = tmp_path / "net.npz"
    BPNetwork.load(packaged_network_path()).save(other)
    assert np.array_equal(load_network(other).W1, net.W1)
    assert np.array_equal(load_network(tmp_path / "missing.npz", fallback=True).W1, net.W1)
    with pytest.raises(FileNotFoundError):
        load_network(tmp_path / "missing.npz")
