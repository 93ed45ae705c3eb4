# Shared set-up: run this checkout's code, validate the merged config (one place:
# parakin.config.validate, i.e. the schema config/schema.yaml plus the orderings a schema cannot
# express; one short line per bad key), load the artefact registry of the config's studies (each
# checked: parakin.pipeline.check_studies).
import functools
import hashlib
import json
import os
import shlex
import sys

CHECKOUT_SRC = Path(workflow.basedir) / "src"
_prefix = "set -euo pipefail; "
#: this checkout's own code comes first, here and in every job (shell prefix below), whatever
#: parakin the Python environment has installed (a virtual environment shared between clones
#: would otherwise run, and track, the other clone's src/); a copy of the workflow without src/
#: (tests/test_pipeline.py) runs the installed parakin
if (CHECKOUT_SRC / "parakin").is_dir():
    sys.path.insert(0, str(CHECKOUT_SRC))
    _src = shlex.quote(os.path.relpath(CHECKOUT_SRC))
    _prefix += f"export PYTHONPATH={_src}${{{{PYTHONPATH:+:$PYTHONPATH}}}}; "
shell.prefix(_prefix)

from parakin import registry
from parakin.config import merge as merge_config
from parakin.config import validate as validate_config
from parakin.errors import ConfigError
from parakin.pipeline import artefacts as load_studies

try:
    validate_config(config)
    #: "study:name" -> Artefact, from the study modules the config names (config key `studies`)
    ARTEFACTS = load_studies(config["studies"])
except (ConfigError, ValueError) as error:  # a bad value, or studies that need missing ones
    sys.exit(f"config error: {error}")

FIG = config["figures_dir"]
GEN = config["generated_dir"]
RESULTS = str(Path(FIG).parent)
RECORD = config.get("record_dir")
LOGS = f"{RESULTS}/logs"
REFERENCE = "data/reference"


def outputs(item):
    return item.output_paths(FIG, GEN)


def relative(path):
    """``path`` relative to the working directory when it lies inside it (rule inputs that do not
    depend on where the clone is), else as it is (an installed parakin)."""
    rel = os.path.relpath(path)
    return path if rel.startswith("..") else rel


@functools.cache
def _file_digest(path):
    return hashlib.sha256(Path(path).read_bytes()).hexdigest()


def code_digest(*items):
    """One digest of the parakin source files the artefacts run (their modules and all they
    import, by path and content). It is a param of the job's rule, so that editing any of them
    reruns the job (Snakemake's params trigger) without making every one of those files an
    input: ~50 inputs per rule cost the scheduler millions of stat calls a run."""
    h = hashlib.sha256()
    for path in sorted({path for item in items for path in item.sources()}):
        h.update(f"{relative(path)}\0{_file_digest(path)}\n".encode())
    return h.hexdigest()


def scattered(item):
    """Chunk files the artefact gathers: its study module's ``chunk_files(config)``, each written
    by the study's scatter rule (workflow/rules/census.smk); none for the others."""
    return sys.modules[item.module].chunk_files(config) if registry.gathers(item) else []


def union(lists):
    """The paths of ``lists`` in order, each once (the inputs of a job of several artefacts)."""
    return list(dict.fromkeys(path for paths in lists for path in paths))


def upstream(item):
    return [path for key in item.needs for path in outputs(ARTEFACTS[key])]


def reference(item):
    path = f"{REFERENCE}/{item.study}.csv"
    return [path] if item.reference and Path(path).exists() else []


#: the software of every rule (used with --sdm conda; otherwise the active environment)
ENV = "../envs/parakin.yaml"
#: what every job reserves unless its artefact declares more (runtime in minutes; profiles/slurm)
DEFAULT_RESOURCES = {"runtime": 15, "mem_mb": 1000}
#: figures and tables shown in the report (snakemake --report); data files stay out of it
SHOWN = (".png", ".svg", ".pdf", ".csv")


def resources_of(item):
    return {**DEFAULT_RESOURCES, **dict(item.resources)}


def group_of(job):
    """Jobs that need no more than the defaults (one core, 15 min) and are linked to no other job
    form the group "small": on a cluster, `group-components` (profiles/slurm) sends several in one
    submission, so that SLURM's queue and scheduling are paid once per batch (each job is still
    its own step inside it). Artefacts with upstream or downstream artefacts, or chunks to gather,
    stay alone (a group may not wait on a job outside it that waits on the group, and one waiting
    on the census would hold its whole batch back). A local run ignores groups."""
    return "small" if job.small else None


def rst_escape(text):
    """``text`` as literal reStructuredText (the report's captions are rst)."""
    return "".join(f"\\{c}" if c in "\\`*_|[]<>" else c for c in text)


def verbatim(text):
    """A param that is ``text`` as it is (a plain string param is formatted: braces would be wildcards)."""
    return lambda wildcards: text


def report_outputs(job):
    """The job's outputs, figures and tables marked for the report with their artefact's caption
    (a job of several artefacts: workflow/report/artefacts.rst captions each by its name)."""
    caption = "../report/artefact.rst" if len(job.items) == 1 else "../report/artefacts.rst"
    return [report(path, caption=caption, category=item.study if item.study_folder else "beyond the papers",
                   subcategory=item.name, labels={"artefact": item.name, "file": Path(path).name})
            if path.endswith(SHOWN) and path.startswith(FIG) else path
            for item in job.items for path in outputs(item)]


def outdir_of(job):
    """The job's output folder, derived from its first output (a param that is a path prefix
    must come from the output, so that a remote or cluster run rewrites it with the file); the
    artefacts of one job share their study's folder."""
    folders = {item.study_folder for item in job.items}
    if len(folders) > 1:
        sys.exit(f"pipeline error: the artefacts of job {job.rule} write to several folders {sorted(folders)}")
    item = job.items[0]
    if not item.outputs:
        return lambda wildcards: str(Path(FIG) / item.study_folder)
    depth = len(Path(item.outputs[0]).parts)
    return lambda wildcards, output: str(Path(output[0]).parents[depth - 1])


#: artefacts that another artefact needs (the heads of the pipeline's chains)
UPSTREAM = {key for item in ARTEFACTS.values() for key in item.needs}


def threads_of(job):
    """The cores the job takes: what its artefacts declare, at most the config's ``max_threads``
    (the quick sizes: 1). The runs of a chaotic computation give the same results on any number
    of cores (parakin.papers.runs), so this moves no result, timings aside (tests/test_pipeline.py
    checks the bytes of a run on two cores a job against the quick run's on one)."""
    declared = max(item.threads for item in job.items)
    return min(declared, config.get("max_threads", declared))


def priority_of(job):
    """Snakemake starts the ready job of highest priority first: the jobs that others wait on
    (2: the network's samples and training, the GA runs, the solver atlas, ...), then the other
    jobs that take both cores (1: the network-convergence trainings), then the rest, so that the
    chains start early (a full run without priorities started the training chain's samples after
    4.5 of its 12.4 min; the next, with them, took 12.1 min, within the spread between runs).
    Snakemake reserves no cores: a two-core job still waits until no one-core job is ready."""
    if any(item.key in UPSTREAM for item in job.items):
        return 2
    return 1 if threads_of(job) > 1 else 0


def job_config(job):
    """The config sections the job's artefacts declare, and the seed (registry.prune_config), as
    one JSON argument: editing a section reruns only the jobs whose artefacts read it."""
    merged = {}
    for item in job.items:
        merged = merge_config(merged, registry.prune_config(config, item))
    return shlex.quote(json.dumps(merged, sort_keys=True))


#: one job per artefact, or per module for its small artefacts (parakin.registry.jobs)
JOBS = registry.jobs(ARTEFACTS)
ALL_OUTPUTS = [path for item in ARTEFACTS.values() for path in outputs(item)]
