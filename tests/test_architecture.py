"""The house shows its architecture (issue 14): generic code accepts any Mechanism.

Every top-level module (``src/parakin/*.py``) and every solver (``src/parakin/solvers/*.py``)
works on the :class:`~parakin.mechanisms.base.Mechanism` protocol alone; mechanism-specific code
(its kernels in ``parakin.kernels``, ...) lives beside its mechanism and is reached through a
hook of the protocol (``kernel()``, ``torch_residual()``). The CLI, the studies and the papers name
mechanisms on purpose and are not checked.
"""

from __future__ import annotations

import ast
import subprocess
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
SRC = ROOT / "src"

#: modules of parakin.mechanisms that any module may import: the protocol and shared helpers
GENERIC_MODULES = {"base"}
#: names that ``from parakin.mechanisms import ...`` may bring in without naming a mechanism
GENERIC_NAMES = GENERIC_MODULES | {"Mechanism"}
#: top-level files allowed to name concrete mechanisms, with the reason (the command line, a
#: package of its own, maps mechanism names to classes and is not checked)
ALLOWED: dict[str, str] = {}


def _module_name(path: Path) -> tuple[str, str]:
    mod = ".".join(path.relative_to(SRC).with_suffix("").parts).removesuffix(".__init__")
    package = mod if path.name == "__init__.py" else mod.rpartition(".")[0]
    return mod, package


def _imports(source: str, package: str) -> list[tuple[int, str, list[str]]]:
    """``(line, module, imported names)`` of every import in ``source``, a module of ``package``
    (late ones included, relative ones resolved)."""
    out = []
    for node in ast.walk(ast.parse(source)):
        if isinstance(node, ast.Import):
            out += [(node.lineno, a.name, []) for a in node.names]
        elif isinstance(node, ast.ImportFrom):
            base = node.module or ""
            if node.level:
                parts = package.split(".")[: len(package.split(".")) - node.level + 1]
                base = ".".join([*parts, base] if base else parts)
            out.append((node.lineno, base, [a.name for a in node.names]))
    return out


def _concrete_imports(source: str, package: str) -> list[str]:
    """Each import of ``source`` that reaches a concrete mechanism, as ``"line: what"``."""
    bad = []
    for line, module, names in _imports(source, package):
        if module == "parakin" and "mechanisms" in names:
            bad.append(f"{line}: from parakin import mechanisms")
        elif module == "parakin.mechanisms":
            if not names:  # import parakin.mechanisms
                bad.append(f"{line}: import parakin.mechanisms")
            bad += [f"{line}: from {module} import {n}" for n in names if n not in GENERIC_NAMES]
        elif module.startswith("parakin.mechanisms."):
            sub = module.split(".")[2]
            if sub not in GENERIC_MODULES:
                bad.append(f"{line}: {module}")
    return bad


def _checked_files() -> list[Path]:
    files = sorted((SRC / "parakin").glob("*.py")) + sorted((SRC / "parakin/solvers").glob("*.py"))
    return [p for p in files if p.relative_to(SRC).as_posix() not in ALLOWED]


@pytest.mark.parametrize("path", _checked_files(), ids=lambda p: p.relative_to(SRC).as_posix())
def test_generic_modules_import_no_concrete_mechanism(path):
    bad = _concrete_imports(path.read_text(), _module_name(path)[1])
    assert not bad, f"{path.relative_to(SRC)} imports concrete mechanisms: {bad}"


def test_the_checker_sees_concrete_imports():
    """The AST check itself: every form of import that reaches a mechanism is caught."""
    code = "\n".join(
        [
            "from parakin.mechanisms.base import Mechanism",
            "from parakin.mechanisms import Mechanism",
            "from parakin.mechanisms.p3p4s import P3P4S",
            "import parakin.mechanisms.ups2",
            "from parakin.mechanisms import Stewart36",
            "from parakin import mechanisms",
            "import parakin.mechanisms",
            "def late():",
            "    from ..mechanisms.stewart12 import ActiveLegs",
            "    from ..mechanisms import base",
        ]
    )
    bad = _concrete_imports(code, "parakin.solvers")
    assert [b.split(":")[0] for b in bad] == ["3", "4", "5", "6", "7", "9"]


def test_torch_newton_reaches_mechanisms_only_through_the_protocol():
    path = SRC / "parakin" / "solvers" / "torch_newton.py"
    found = _imports(path.read_text(), "parakin.solvers")
    mechanism_imports = {m for _, m, _ in found if m.startswith("parakin.mechanisms")}
    assert mechanism_imports == {"parakin.mechanisms.base"}


def test_packages_import_without_torch():
    """torch is imported lazily (the kernels' torch binding, :func:`parakin.kernels.torch_kernel`):
    with torch missing the mechanisms and the torch solver still import, and asking for a torch
    residual says torch is missing."""
    code = "\n".join(
        [
            "import sys",
            "sys.modules['torch'] = None  # import torch -> ImportError",
            "import parakin.mechanisms as m",
            "import parakin.solvers.torch_newton as t",
            "assert not t.gpu_available()",
            "import parakin.kernels as k",
            "assert m.Stewart12().torch_residual() is None",
            "try:",
            "    k.torch_kernel(m.P3P4S().kernel())",
            "except ImportError:",
            "    pass",
            "else:",
            "    raise AssertionError('torch kernels built without torch')",
            "try:",
            "    t.torch_residual(m.P3P4S())",
            "except ImportError as e:",
            "    assert 'needs torch' in str(e)",
        ]
    )
    run = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, cwd=ROOT)
    assert run.returncode == 0, run.stderr


#: arrows up that another change is removing (the lead drops an entry once its file is fixed; a
#: fixed file then passes, an entry that is still needed fails loudly nowhere else)
KNOWN_UPWARD: dict[str, str] = {}
#: what mechanisms and kernels must never import: the layers built on them
UPPER = ("parakin.cli", "parakin.studies", "parakin.papers")


@pytest.mark.parametrize(
    "path",
    sorted((SRC / "parakin/mechanisms").glob("*.py"))
    + sorted((SRC / "parakin/kernels").glob("*.py")),
    ids=lambda p: p.relative_to(SRC).as_posix(),
)
def test_mechanisms_and_kernels_import_only_downward(path):
    """No arrow up: a mechanism or a kernel never imports the command line, a study or a paper."""
    rel = path.relative_to(SRC).as_posix()
    up = [
        f"{line}: {module}"
        for line, module, names in _imports(path.read_text(), _module_name(path)[1])
        if module.startswith(UPPER)
        or (module == "parakin" and {"cli", "studies", "papers"} & set(names))
    ]
    if up and rel in KNOWN_UPWARD:
        pytest.xfail(KNOWN_UPWARD[rel])
    assert not up, f"{rel} imports upward: {up}"
