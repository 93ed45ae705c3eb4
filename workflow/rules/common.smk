# Shared set-up: validate the merged config against its schema, load the artefact registry.
import json
import shlex

from snakemake.utils import validate

from parakin import registry
from parakin.config import validate as validate_config

validate(config, schema="../../config/schema.yaml")
validate_config(config)  # the checks JSON Schema cannot express (e.g. lower bound < upper bound)

FIG = config["figures_dir"]
GEN = config["generated_dir"]
RESULTS = str(Path(FIG).parent)
RECORD = config.get("record_dir")
LOGS = f"{RESULTS}/logs"
REFERENCE = "data/reference"

#: "study:name" -> Artefact, from the study modules the config names (config key `studies`)
ARTEFACTS = registry.load(config["studies"])


def outputs(item):
    return item.output_paths(FIG, GEN)


def upstream(item):
    return [path for key in item.needs for path in outputs(ARTEFACTS[key])]


def reference(item):
    path = f"{REFERENCE}/{item.study}.csv"
    return [path] if item.reference and Path(path).exists() else []


ALL_OUTPUTS = [path for item in ARTEFACTS.values() for path in outputs(item)]
