"""The config schema rejects bad values with a message that names the key and the limit."""

import copy
import subprocess
import sys
from pathlib import Path

import pytest

from parakin.config import DEFAULT_CONFIG, QUICK_CONFIG, load_config, validate
from parakin.errors import ConfigError

ROOT = Path(__file__).resolve().parents[1]


def test_full_and_quick_configs_are_valid(quick_config):
    full = load_config(DEFAULT_CONFIG)
    assert quick_config["seed"] == full["seed"]  # quick overrides sizes, never the seed
    assert (
        quick_config["zhao2017_3p4s"]["table1"]["region"]["n_delta"]
        < full["zhao2017_3p4s"]["table1"]["region"]["n_delta"]
    )
    assert (
        quick_config["figures_dir"] != full["figures_dir"]
    )  # quick never overwrites committed figures


@pytest.mark.parametrize(
    "path, value, message",
    [
        (("seed",), -1, r"config key 'seed' = -1: -1 is less than the minimum of 0"),
        (
            ("zhao2017_3p4s", "table1", "region", "n_phi"),
            2,
            r"'zhao2017_3p4s.table1.region.n_phi' = 2: .*minimum 5, maximum 2001",
        ),
        (
            ("zhao2017_3p4s", "table1", "fit", "L"),
            "long",
            r"'zhao2017_3p4s.table1.fit.L' = \"long\": .* not of type 'number'",
        ),
        (
            ("zhao2017_3p4s", "table1", "fit", "phi_range_deg"),
            [40, 30],
            r"lower bound must be < upper bound",
        ),
        (
            ("zhao2017_3p4s", "table1", "fit", "phi_range_deg"),
            [10, 95],
            r"95 is greater than or equal to the maximum of 90",
        ),
    ],
)
def test_bad_values_are_rejected_by_name(quick_config, path, value, message):
    cfg = copy.deepcopy(quick_config)
    node = cfg
    for key in path[:-1]:
        node = node[key]
    node[path[-1]] = value
    with pytest.raises(ConfigError, match=message):
        validate(cfg)


def test_unknown_key_is_rejected(quick_config):
    cfg = copy.deepcopy(quick_config)
    cfg["zhao2017_3p4s"]["tabel1"] = {}
    with pytest.raises(ConfigError, match=r"'tabel1' was unexpected"):
        validate(cfg)


def test_missing_file(tmp_path):
    with pytest.raises(ConfigError, match="does not exist"):
        load_config(tmp_path / "nope.yaml")


#: in a fresh process: validate a good config and a bad one, then report what was imported
FRESH_VALIDATION = """
import copy, sys
from parakin.config import load_run_config, validate
from parakin.errors import ConfigError
cfg = load_run_config()
bad = copy.deepcopy(cfg)
bad["seed"] = -5
try:
    validate(bad)
    print("accepted")
except ConfigError as exc:
    print("rejected" if "seed" in str(exc) and "minimum" in str(exc) else f"other: {exc}")
print("rfc3987_syntax" in sys.modules)
import rfc3987_syntax
print(rfc3987_syntax.__name__)
"""


def test_validation_imports_no_costly_format_library():
    """Validating imports none of jsonschema's optional format libraries that cost seconds
    (rfc3987-syntax builds a grammar at import: 1.4-1.8 CPU-s of every Snakemake start; parakin
    checks no formats), still rejects a bad value by name, and leaves the library importable."""
    pytest.importorskip("rfc3987_syntax")
    res = subprocess.run(
        [sys.executable, "-c", FRESH_VALIDATION], capture_output=True, text=True, timeout=120
    )
    assert res.returncode == 0, res.stderr[-2000:]
    assert res.stdout.split() == ["rejected", "False", "rfc3987_syntax"], res.stdout


def test_snakemake_validates_the_config():
    """The Snakefile's own validation (snakemake.utils.validate) stops a malformed run."""
    res = subprocess.run(
        [
            sys.executable,
            "-m",
            "snakemake",
            "-n",
            "--cores",
            "1",
            "--configfile",
            str(QUICK_CONFIG),
            "--config",
            "seed=-5",
        ],
        cwd=ROOT,
        capture_output=True,
        text=True,
        timeout=120,
    )
    assert res.returncode != 0
    assert "seed" in res.stdout + res.stderr and "minimum" in res.stdout + res.stderr


# ------------------------------------------------------------------ hostile configs: rejected at the door
@pytest.mark.parametrize(
    "path, value, message",
    [
        (
            ("ye_stewart12", "d_grid_pct"),
            [[5, 100, 1e-12]],
            r"d_grid_pct.0' = \[5, 100, step 1e-12\]: .* more than the limit 100000",
        ),
        (("ye_stewart12", "d_grid_pct"), [[100, 5, 5]], r"start 100 must be <= stop 5"),
        (
            ("ye_stewart12", "basin_levels_pct"),
            [1e308],
            r"basin_levels_pct.0' = 1e\+308: .*maximum",
        ),
        (
            ("ye_stewart12", "structures_mm"),
            {"min": 30, "max": 10, "step": 10},
            r"start 30 must be <= stop 10",
        ),
        (
            ("zhao2017_3p4s", "optimization", "bounds", "L"),
            [0.45, 0.30],
            r"bounds.L' = \[0.45, 0.3\]: lower bound",
        ),
        (
            ("zhao2017_3p4s", "indices", "k"),
            float("nan"),
            r"'zhao2017_3p4s.indices.k' = nan: must be a finite number",
        ),
        (("li2020_2ups", "fig2_seed"), 10**30, r"fig2_seed"),
    ],
)
def test_hostile_values_are_rejected_by_name(quick_config, path, value, message):
    cfg = copy.deepcopy(quick_config)
    node = cfg
    for key in path[:-1]:
        node = node[key]
    node[path[-1]] = value
    with pytest.raises(ConfigError, match=message):
        validate(cfg)


def test_one_short_message_per_bad_key(quick_config):
    cfg = copy.deepcopy(quick_config)
    cfg["zhao2017_3p4s"]["table1"] = (
        "not a section"  # a whole section replaced: no dump of it or the schema
    )
    cfg["seed"] = -3
    with pytest.raises(ConfigError) as err:
        validate(cfg)
    text = str(err.value)
    assert text.count("config key") == 2 and len(text) < 600 and "\n" not in text


def test_yaml_syntax_error_is_one_line(tmp_path):
    bad = tmp_path / "tab.yaml"
    bad.write_text("seed: 1\nzhao2017_3p4s:\n\ttable1: {}\n")
    with pytest.raises(ConfigError, match=r"is not valid YAML \(line 3, column 1\)"):
        load_config(bad)


# ---------------------------------------------------- bounded loading, overlays, studies (issue 26)
def test_overlays_merge_onto_the_full_config(quick_config):
    from parakin.config import load_run_config

    assert load_run_config([QUICK_CONFIG]) == quick_config
    assert load_run_config() == load_config(DEFAULT_CONFIG)


@pytest.mark.parametrize(
    "text, message",
    [
        (
            "x:\n  a0: &a0 [1, 1, 1, 1, 1, 1, 1, 1, 1]\n"
            + "".join(f"  a{i}: &a{i} [{', '.join([f'*a{i - 1}'] * 9)}]\n" for i in range(1, 12)),
            r"expands to 3.\d+e\+11 values, more than the limit 100000",
        ),
        ("a: &x {b: *x}\n", "refers to itself"),
        ("a: " + "[" * 100 + "]" * 100 + "\n", "nests deeper than the limit 64"),
    ],
)
def test_config_expansion_is_bounded_before_any_walk(tmp_path, text, message):
    path = tmp_path / "c.yaml"
    path.write_text(text)
    with pytest.raises(ConfigError, match=message):
        load_config([DEFAULT_CONFIG, path])


def test_validate_bounds_a_config_loaded_elsewhere(quick_config):
    """What Snakemake loads itself reaches validate(): the bound holds there too."""
    node = [1] * 10
    for _ in range(6):
        node = [node] * 10
    with pytest.raises(ConfigError, match="config expands to .* more than the limit"):
        validate({**quick_config, "bomb": node})


@pytest.mark.parametrize(
    "names, message",
    [
        (["os"], "'os' declares no @artefact"),
        (["parakin.papers.zhao2017"], "'parakin.papers.zhao2017' is not a module"),
        (["parakin.papers.zhao2017_3p4s", "nope.nope"], "'nope.nope' is not a module"),
    ],
)
def test_studies_are_checked_against_what_is_registered(names, message):
    from parakin.pipeline import check_studies, known_studies

    with pytest.raises(ConfigError, match=message) as err:
        check_studies(names)
    assert all(s in str(err.value) for s in known_studies())
    check_studies(known_studies())  # every shipped study passes
