#!/usr/bin/env bash
# CI's cluster check (.ci/run): part of the quick pipeline through `--profile profiles/slurm` on a
# real single-node SLURM (workflow/slurm/start-local.sh), then the reproduction check of its
# outputs against the same part run locally (parakin.check, each artefact's declared tolerance).
# One job of each kind: network training, an FK table, a GA, a dynamics study, drawings,
# the 6-6 census (scatter-gather). Where SLURM cannot be started (not root, no apt-get) it says so
# in one line and exits 0: the step is skipped, never faked.
set -euo pipefail
cd "$(dirname "$0")/../.."

TARGETS=(
    zhao2017_3p4s_train           # training (Levenberg-Marquardt), 2 threads
    zhao2017_3p4s_table2          # FK table (the trained network + quasi-Newton)
    zhao2017_3p4s_table3          # GA
    zhao2017_3p4s_dynamics        # dynamics: one job that makes ten small artefacts
    li2017_stewart36_solutions    # drawings and tables: one job of six
    stewart66_census_census       # the census: scatter (chunks) and gather
)
OUT=${SLURM_CI_DIR:-build/slurm-ci}

# no process outlives the command: a cluster this script starts is stopped when it ends, however
# it ends; one that was already running is left as it was
if ! sinfo -h -o %T 2>/dev/null | grep -q -E "idle|mix|alloc"; then
    trap 'bash workflow/slurm/start-local.sh stop' EXIT
fi
status=0
bash workflow/slurm/start-local.sh || status=$?
if [ "$status" = 3 ]; then
    echo "== SLURM profile check skipped (see the line above)"
    exit 0
elif [ "$status" != 0 ]; then
    exit "$status"
fi

run() {  # run NAME [snakemake options...]: the targets into $OUT/NAME
    local name=$1; shift
    rm -rf "$OUT/$name"
    local start=$SECONDS
    # max_threads=2: the quick sizes run every job on one core; here the training keeps its two
    # (a SLURM job that asks for two cores)
    snakemake "${TARGETS[@]}" --configfile config/quick.yaml --quiet rules \
        --config figures_dir="$OUT/$name/figures" generated_dir="$OUT/$name/generated" \
        max_threads=2 "$@"
    echo "== $name run: $((SECONDS - start)) s"
}

run local --cores 2
since=$(date +%Y-%m-%dT%H:%M:%S)
# the profile as a user runs it, with the account this script made (the plugin cannot guess it
# here) and the first status query after 5 s instead of 40 (quick jobs: CI time)
run slurm --profile profiles/slurm --default-resources slurm_account=parakin runtime=15 mem_mb=1000 \
    --slurm-init-seconds-before-status-checks 5

python - "$OUT" "$since" "${TARGETS[@]}" <<'EOF'
"""The SLURM run's outputs equal the local run's within each artefact's declared tolerance, and
every job went through SLURM and completed."""
import subprocess
import sys
from pathlib import Path

from parakin.check import check_artefact
from parakin.pipeline import artefacts
from parakin.registry import jobs

out, since, targets = Path(sys.argv[1]), sys.argv[2], set(sys.argv[3:])
picked = [job for job in jobs(artefacts()) if job.rule in targets]
assert len(picked) == len(targets), f"unknown targets {targets - {j.rule for j in picked}}"
items = [a for job in picked for a in job.items]
needed = {k for a in items for k in a.needs}
items += [a for k, a in artefacts().items() if k in needed and a not in items]
bad = []
for item in items:
    for c in check_artefact(item, out / "slurm" / "figures", out / "local" / "figures"):
        print(f"  {c.study}:{c.artefact} {c.file}: {c.status} {c.column} {c.detail}".rstrip())
        if c.status in ("differs", "missing"):
            bad.append(c)
jobs = subprocess.run(
    ["sacct", "-X", "-n", "-P", "-o", "JobID,JobName,State,Elapsed,AllocCPUS", "-S", since],
    capture_output=True, text=True, check=True,
).stdout.split()
states = [line.split("|")[2] for line in jobs]
print(f"== SLURM jobs of this run: {len(jobs)}, states {sorted(set(states))}")
assert jobs, "no SLURM job ran: the profile did not submit anything"
assert set(states) == {"COMPLETED"}, f"SLURM jobs not completed: {jobs}"
assert bad == [], f"{len(bad)} output(s) of the SLURM run differ from the local run"
print(f"== SLURM profile check: {len(items)} artefacts, outputs equal to the local run's "
      "within their declared tolerances")
EOF
