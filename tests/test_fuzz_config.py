"""Seeded random config fuzz (issue 26): whatever a config file holds, a clear answer at once.

Each case mutates ``config/quick.yaml`` (a leaf set to a hostile value, a key deleted or
misspelt, a section replaced, an unknown key, a ``studies`` list of known, misspelt and foreign
modules, an alias bomb, a file cut short, a tab, bytes that are not UTF-8, a list nested up to
10^5 deep, the config as JSON) and runs
``parakin reproduce zhao2017_3p4s no-such-artefact --config FILE`` in process: the answer is exit 2
with one line, either the config's error (naming the key or the file) or, for a config that is
valid, "unknown artefact" or, where its studies leave Zhao's out, "unknown study" (so the config was loaded, merged and checked all the way). Never a
traceback, never another exception, never a hang (each case is bounded by an alarm).
"""

from __future__ import annotations

import contextlib
import copy
import io
import json
import signal
from pathlib import Path

import numpy as np
import pytest
import yaml

from parakin.cli import main
from parakin.config import QUICK_CONFIG

SEED = 26
CASES = 200
#: seconds one case may take before it counts as a hang
PER_CASE = 20

HOSTILE = [
    -1,
    0,
    0.5,
    1e308,
    -1e308,
    float("nan"),
    float("inf"),
    10**30,
    2**63,
    "abc",
    "",
    "1e3",
    None,
    True,
    [],
    {},
    [1, 2, 3],
    {"x": 1},
    [[5, 100, 1e-12]],
]
STUDIES = [
    "parakin.papers.zhao2017_3p4s",
    "parakin.papers.li2020_2ups",
    "parakin.studies.solver_atlas",
    "parakin.papers.zhao2017",
    "parakin.papers",
    "os",
    "json",
    "no_such_module",
    "a..b",
    "",
]


def _paths(node, prefix=()):
    """Every key path of the nested dict ``node``."""
    if isinstance(node, dict):
        for k, v in node.items():
            yield (*prefix, k)
            yield from _paths(v, (*prefix, k))


def _at(config, path):
    node = config
    for k in path[:-1]:
        node = node[k]
    return node


def _mutate(config: dict, g: np.random.Generator) -> dict:
    paths = list(_paths(config))
    path = paths[g.integers(len(paths))]
    parent, key = _at(config, path), path[-1]
    op = g.integers(6)
    if op == 0:
        parent[key] = copy.deepcopy(HOSTILE[g.integers(len(HOSTILE))])
    elif op == 1:
        del parent[key]
    elif op == 2:  # a typo: two letters swapped, or one more
        k = str(key)
        i = int(g.integers(max(len(k) - 1, 1)))
        typo = k[:i] + k[i + 1 : i + 2] + k[i : i + 1] + k[i + 2 :] if len(k) > 1 else k + "x"
        parent[typo if typo != k else k + "s"] = parent.pop(key)
    elif op == 3:
        parent[f"unknown_{g.integers(100)}"] = 1
    elif op == 4:
        chosen = g.choice(len(STUDIES), size=g.integers(1, 4), replace=False)
        config["studies"] = [STUDIES[i] for i in chosen]
    else:
        config["seed"] = int(g.integers(-5, 2**40))
    return config


def _bomb(g: np.random.Generator) -> str:
    levels, width = int(g.integers(2, 13)), int(g.integers(2, 10))
    rows = [f"  a0: &a0 [{', '.join(['1'] * width)}]"]
    rows += [f"  a{i}: &a{i} [{', '.join([f'*a{i - 1}'] * width)}]" for i in range(1, levels)]
    return f"{['bomb', 'seed', 'zhao2017_3p4s'][int(g.integers(3))]}:\n" + "\n".join(rows) + "\n"


def _case(g: np.random.Generator, base: dict) -> bytes:
    """One hostile config file's bytes."""
    kind = g.integers(10)
    if kind == 0:
        return _bomb(g).encode()
    config = copy.deepcopy(base)
    for _ in range(int(g.integers(1, 4))):
        config = _mutate(config, g)
    text = yaml.safe_dump(config, sort_keys=False).encode()
    if kind == 1:  # cut short
        return text[: int(g.integers(len(text)))]
    if kind == 2:  # a tab in the indentation
        lines = text.split(b"\n")
        i = int(g.integers(len(lines)))
        lines[i] = b"\t" + lines[i]
        return b"\n".join(lines)
    if kind == 3:  # bytes that are not UTF-8
        i = int(g.integers(len(text) + 1))
        return text[:i] + bytes(g.integers(128, 256, size=3).tolist()) + text[i:]
    if kind == 4:  # nested deep under some key (10^5 deep crashed libyaml's composer; issue 46)
        depth = int(g.choice([33, 64, 65, 1000, 100_000]))
        return text + f"deep: {'[' * depth}1{']' * depth}\n".encode()
    if kind == 5:  # the same config as JSON (what another tool writes)
        return json.dumps(config).encode()
    return text


def _run(argv: list[str]) -> tuple[int, str, str]:
    out, err = io.StringIO(), io.StringIO()
    with contextlib.redirect_stdout(out), contextlib.redirect_stderr(err):
        try:
            code = main(argv)
        except SystemExit as exc:
            code = exc.code if isinstance(exc.code, int) else 2
    return code, out.getvalue(), err.getvalue()


def _alarm(signum, frame):
    raise TimeoutError(f"a config case ran longer than {PER_CASE} s")


@pytest.mark.skipif(not hasattr(signal, "SIGALRM"), reason="needs SIGALRM to bound each case")
def test_random_configs_get_one_clear_line(tmp_path):
    base = yaml.safe_load(Path(QUICK_CONFIG).read_text())
    g = np.random.default_rng(SEED)
    tally = {"config error": 0, "valid (unknown artefact)": 0}
    previous = signal.signal(signal.SIGALRM, _alarm)
    try:
        for k in range(CASES):
            path = tmp_path / f"case{k}.yaml"
            path.write_bytes(_case(g, base))
            signal.alarm(PER_CASE)
            code, stdout, stderr = _run(
                ["reproduce", "zhao2017_3p4s", "no-such-artefact", "--config", str(path)]
            )
            signal.alarm(0)
            lines = stderr.strip().splitlines()
            assert code == 2 and len(lines) == 1 and not stdout, (
                k,
                path.read_bytes()[:300],
                stderr,
            )
            assert "Traceback" not in stderr and len(lines[0]) < 3000, (k, lines[0][:300])
            if "unknown artefact 'no-such-artefact'" in lines[0] or "unknown study" in lines[0]:
                tally["valid (unknown artefact)"] += 1  # studies without zhao's: unknown study
            else:
                assert "config" in lines[0] or "studies" in lines[0], (k, lines[0])
                tally["config error"] += 1
    finally:
        signal.alarm(0)
        signal.signal(signal.SIGALRM, previous)
    print(f"config fuzz: {CASES} cases, {tally}")
    assert tally["config error"] > CASES / 2 and tally["valid (unknown artefact)"] > 0
