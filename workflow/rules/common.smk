# Shared set-up: validate the merged config against its schema, and the paths every rule uses.
import json
import shlex

from snakemake.utils import validate

validate(config, schema="../../config/schema.yaml")

FIG = config["figures_dir"]
GEN = config["generated_dir"]
# The whole (validated, merged) config travels to the CLI as one JSON argument, so a rule sees
# exactly what Snakemake sees, --configfile overrides included.
CONFIG_JSON = shlex.quote(json.dumps(config, sort_keys=True))
