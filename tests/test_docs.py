"""Every code block of README.md and docs/*.md works as written (issue 45).

A block is checked by its language:

* ``python``: the file's runnable Python blocks run in order as one script (a later block may use
  what an earlier one defined, as a reader types them), in a fresh interpreter whose working
  directory holds the repository's ``examples/``, ``config/``, ``data/`` and ``figures/``; a block
  that starts with ``# file: PATH`` is an excerpt of that file and must appear in it verbatim;
* ``bash``: every line that runs ``parakin`` runs (in the same kind of directory) and must exit 0;
* ``yaml``: parses.

A block preceded by ``<!-- doc-test: skip REASON -->`` is not run (a full pipeline run, an install,
a sketch with ``...``); the reason is required, and a test checks that every such block has one.
"""

from __future__ import annotations

import os
import re
import shlex
import subprocess
import sys
from dataclasses import dataclass
from pathlib import Path

import pytest
import yaml

ROOT = Path(__file__).resolve().parents[1]
DOCS = [ROOT / "README.md", *sorted((ROOT / "docs").glob("*.md"))]
#: what a reader's working directory has: the repository's shipped files, by symlink
SHIPPED = ("examples", "config", "data", "figures")
_FENCE = re.compile(r"^```(?P<lang>[\w-]*)[^\n]*\n(?P<body>.*?)^```[ \t]*$", re.M | re.S)
_SKIP = re.compile(r"<!--\s*doc-test:\s*skip\b\s*(?P<reason>[^>]*?)\s*-->\s*$")


@dataclass(frozen=True)
class Block:
    path: Path
    line: int
    lang: str
    body: str
    skip: str | None  # the reason, where the block is marked

    @property
    def name(self) -> str:
        return f"{self.path.relative_to(ROOT)}:{self.line}"


def blocks(path: Path) -> list[Block]:
    text = path.read_text()
    out = []
    for m in _FENCE.finditer(text):
        before = text[: m.start()].rstrip("\n").rsplit("\n", 1)[-1]
        marked = _SKIP.search(before)
        out.append(
            Block(
                path,
                text.count("\n", 0, m.start()) + 1,
                m.group("lang").lower(),
                m.group("body"),
                marked.group("reason") if marked else None,
            )
        )
    return out


ALL = [b for path in DOCS for b in blocks(path)]


def _reader_dir(tmp_path: Path) -> Path:
    for name in SHIPPED:
        (tmp_path / name).symlink_to(ROOT / name)
    return tmp_path


def _env(tmp_path: Path) -> dict[str, str]:
    return {**os.environ, "MPLBACKEND": "Agg", "TMPDIR": str(tmp_path)}


def _excerpt(block: Block) -> tuple[Path, str] | None:
    first, _, rest = block.body.partition("\n")
    m = re.match(r"#\s*file:\s*(\S+)", first.strip())
    return (ROOT / m.group(1), rest) if m else None


def _squeeze(text: str) -> str:
    """``text`` line by line without the lines' outer spaces (an excerpt of a class body is
    indented in the file) and without blank lines."""
    return "\n".join(s for line in text.splitlines() if (s := line.strip()))


def test_every_skipped_block_says_why():
    unexplained = [b.name for b in ALL if b.skip is not None and not b.skip.strip()]
    assert not unexplained


@pytest.mark.parametrize(
    "block", [b for b in ALL if b.lang == "python" and _excerpt(b)], ids=lambda b: b.name
)
def test_file_excerpts_are_verbatim(block):
    """A ``# file: PATH`` block quotes PATH as it is now (the docs drift otherwise)."""
    path, excerpt = _excerpt(block)
    assert path.exists(), f"{block.name} quotes {path}, which does not exist"
    assert _squeeze(excerpt) in _squeeze(path.read_text()), f"{block.name} differs from {path}"


@pytest.mark.parametrize("block", [b for b in ALL if b.lang == "yaml"], ids=lambda b: b.name)
def test_yaml_blocks_parse(block):
    assert yaml.safe_load(block.body) is not None


_PY_FILES = sorted(
    {b.path for b in ALL if b.lang == "python" and b.skip is None and not _excerpt(b)}
)


@pytest.mark.slow  # a fresh interpreter per page or command
@pytest.mark.parametrize("path", _PY_FILES, ids=lambda p: str(p.relative_to(ROOT)))
def test_python_blocks_run(path, tmp_path):
    """The file's Python blocks, in order, as one script: exit status 0."""
    script = "\n\n".join(
        b.body for b in blocks(path) if b.lang == "python" and b.skip is None and not _excerpt(b)
    )
    res = subprocess.run(
        [sys.executable, "-c", script],
        cwd=_reader_dir(tmp_path),
        env=_env(tmp_path),
        capture_output=True,
        text=True,
        timeout=600,
    )
    assert res.returncode == 0, res.stderr[-3000:]


def _commands(block: Block) -> list[str]:
    """The ``parakin`` command lines of a bash block (comments dropped, continuations joined)."""
    text = re.sub(r"\\\n\s*", " ", block.body)
    out = []
    for line in text.splitlines():
        line = line.split(" #", 1)[0].strip()
        if line.startswith("parakin "):
            out.append(line)
    return out


_COMMANDS = [
    (b, c) for b in ALL if b.lang in ("bash", "sh", "console") and b.skip is None
    for c in _commands(b)
]  # fmt: skip


def test_bash_blocks_run_parakin_only_or_say_why():
    """A bash block that is not skipped runs nothing but ``parakin`` (the rest would be an
    install or a pipeline run, which needs a reason to skip)."""
    other = [
        f"{b.name}: {line.strip()}"
        for b in ALL
        if b.lang in ("bash", "sh", "console") and b.skip is None
        for line in re.sub(r"\\\n\s*", " ", b.body).splitlines()
        if line.split("#", 1)[0].strip() and not line.strip().startswith("parakin ")
    ]
    assert not other


@pytest.mark.slow  # a fresh interpreter per page or command
@pytest.mark.parametrize("block, command", _COMMANDS, ids=lambda v: getattr(v, "name", v)[:60])
def test_parakin_commands_run(block, command, tmp_path):
    res = subprocess.run(
        [sys.executable, "-m", "parakin.cli", *shlex.split(command)[1:]],
        cwd=_reader_dir(tmp_path),
        env=_env(tmp_path),
        capture_output=True,
        text=True,
        timeout=600,
    )
    assert res.returncode == 0, f"{block.name}: {command}\n{res.stderr[-2000:]}"
