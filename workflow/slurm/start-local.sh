#!/usr/bin/env bash
# A real single-node SLURM cluster with accounting on this machine, for CI and for trying the
# profile (profiles/slurm, docs/cluster.md) without a cluster account.
#
#   bash workflow/slurm/start-local.sh          # install (Debian/Ubuntu, as root) and start
#   bash workflow/slurm/start-local.sh stop     # stop the daemons this script started and put
#                                               # back the SLURM config files it replaced
#
# It installs Debian's slurm-wlm, slurmdbd, munge and mariadb-server, writes a slurm.conf for this
# one node (all its cores and memory, partition "local") and starts munged, mariadbd, slurmdbd,
# slurmctld and slurmd by hand (no systemd: CI runs in a container). Accounting (slurmdbd) is not
# optional: the Snakemake SLURM executor asks `sacct` for the state of its jobs.
# Exit status: 0 = SLURM answers (`sinfo` shows the node idle); 3 = this machine cannot run it
# (not root, or no apt-get), with one line saying why; anything else = a real failure.
set -euo pipefail

STATE=/var/lib/parakin-slurm        # the daemons' logs and state (not the repository)
CLUSTER=parakin
ACCOUNT=parakin
#: the config files this script writes. Left behind with no controller answering, a slurm.conf
#: makes every `scontrol show config` wait ~9 s, and the Snakemake SLURM executor plugin asks it
#: when it is imported: every later `snakemake` command on this machine, local runs included,
#: started 9 s late (docs/cluster.md). So `stop` removes them, or puts back what was there.
CONFIGS=(/etc/slurm/slurm.conf /etc/slurm/slurmdbd.conf)
MARK="# written by parakin's workflow/slurm/start-local.sh; its 'stop' removes it"

keep_configs() {  # a config file this script did not write is kept in $STATE, once
    local f
    for f in "${CONFIGS[@]}"; do
        if [ -f "$f" ] && ! grep -qxF "$MARK" "$f" && [ ! -e "$STATE/kept/${f##*/}" ]; then
            mkdir -p "$STATE/kept" && cp -p "$f" "$STATE/kept/${f##*/}"
        fi
    done
}

restore_configs() {  # each config file back as this script found it: removed if there was none
    local f
    for f in "${CONFIGS[@]}"; do
        if [ -e "$STATE/kept/${f##*/}" ]; then
            mv -f "$STATE/kept/${f##*/}" "$f"
        elif [ -f "$f" ] && grep -qxF "$MARK" "$f"; then
            rm -f "$f"
        fi
    done
}

stop() {  # the daemons whose pid files are in $STATE, SLURM's first; waits until they have ended
    local pids=() pid d alive
    for d in slurmd slurmctld slurmdbd mariadb munged; do
        [ -f "$STATE/$d.pid" ] || continue
        for pid in $(cat "$STATE/$d.pid"); do kill "$pid" 2>/dev/null && pids+=("$pid"); done
        rm -f "$STATE/$d.pid"  # never read again: a stale number could be another process by then
    done
    for _ in $(seq 60); do  # up to 30 s (MariaDB flushes its tables)
        alive=0
        for pid in "${pids[@]}"; do kill -0 "$pid" 2>/dev/null && alive=1; done
        [ "$alive" = 0 ] && return 0
        sleep 0.5
    done
    echo "SLURM: daemons still running after 30 s: ${pids[*]}" >&2
    return 0
}

if [ "${1:-}" = "stop" ]; then stop; restore_configs; exit 0; fi

if [ "$(id -u)" != 0 ]; then echo "SLURM: not root, cannot install or start a local cluster"; exit 3; fi
if ! command -v apt-get >/dev/null; then echo "SLURM: no apt-get on this machine, cannot install a local cluster"; exit 3; fi

if sinfo -h -o %T 2>/dev/null | grep -q -E "idle|mix|alloc"; then
    echo "SLURM: already running ($(sinfo -h -o '%P %D %c %T' | head -1))"
    exit 0
fi

if ! command -v slurmctld >/dev/null || ! command -v slurmdbd >/dev/null \
    || ! command -v munged >/dev/null || ! command -v mariadbd >/dev/null; then
    apt-get update -qq
    DEBIAN_FRONTEND=noninteractive apt-get install -y -qq --no-install-recommends \
        slurm-wlm slurmdbd munge mariadb-server >/dev/null
fi

mkdir -p "$STATE" /etc/slurm /run/munge /var/spool/slurmctld /var/spool/slurmd /run/mysqld
host=$(hostname -s)

# --- munge: the credentials every daemon and client checks
[ -s /etc/munge/munge.key ] || mungekey --create --keyfile=/etc/munge/munge.key
chown -R munge:munge /etc/munge /run/munge /var/lib/munge /var/log/munge 2>/dev/null || true
chmod 0700 /etc/munge && chmod 0400 /etc/munge/munge.key
if ! pgrep -x munged >/dev/null; then
    runuser -u munge -- /usr/sbin/munged 2>>"$STATE/munged.log"
    for _ in $(seq 20); do pgrep -n -x munged >"$STATE/munged.pid" && break; sleep 0.25; done
fi

# --- MariaDB: the accounting database
chown mysql:mysql /run/mysqld
if ! pgrep -x mariadbd >/dev/null; then
    [ -d /var/lib/mysql/mysql ] || mariadb-install-db --user=mysql >/dev/null
    runuser -u mysql -- /usr/sbin/mariadbd --skip-networking=0 --bind-address=127.0.0.1 \
        --socket=/run/mysqld/mysqld.sock >>"$STATE/mariadb.log" 2>&1 &
    for _ in $(seq 60); do mariadb -e "select 1" >/dev/null 2>&1 && break; sleep 0.5; done
    pgrep -n -x mariadbd >"$STATE/mariadb.pid"
fi
mariadb -e "CREATE DATABASE IF NOT EXISTS slurm_acct_db;
CREATE USER IF NOT EXISTS 'slurm'@'localhost' IDENTIFIED BY 'slurm';
GRANT ALL ON slurm_acct_db.* TO 'slurm'@'localhost'; FLUSH PRIVILEGES;"

# --- slurmdbd and slurm.conf
keep_configs
cat >/etc/slurm/slurmdbd.conf <<EOF
$MARK
AuthType=auth/munge
DbdHost=localhost
SlurmUser=root
LogFile=$STATE/slurmdbd.log
PidFile=$STATE/slurmdbd.pid
StorageType=accounting_storage/mysql
StorageHost=localhost
StorageUser=slurm
StoragePass=slurm
StorageLoc=slurm_acct_db
EOF
chmod 600 /etc/slurm/slurmdbd.conf

# this node as slurmd sees it (cores, sockets, memory), less 1 GB of memory for the daemons
node=$(slurmd -C | head -1 | sed -E 's/ UpTime=.*//')
mem=$(echo "$node" | sed -E 's/.*RealMemory=([0-9]+).*/\1/')
node=$(echo "$node" | sed -E "s/RealMemory=[0-9]+/RealMemory=$((mem > 2048 ? mem - 1024 : mem))/")
cat >/etc/slurm/slurm.conf <<EOF
$MARK
ClusterName=$CLUSTER
SlurmctldHost=$host(127.0.0.1)
SlurmUser=root
SlurmdUser=root
AuthType=auth/munge
StateSaveLocation=/var/spool/slurmctld
SlurmdSpoolDir=/var/spool/slurmd
SlurmctldPidFile=$STATE/slurmctld.pid
SlurmdPidFile=$STATE/slurmd.pid
SlurmctldLogFile=$STATE/slurmctld.log
SlurmdLogFile=$STATE/slurmd.log
# a container has no cgroup delegation: track processes by /proc, bind no tasks
ProctrackType=proctrack/linuxproc
TaskPlugin=task/none
JobAcctGatherType=jobacct_gather/linux
AccountingStorageType=accounting_storage/slurmdbd
AccountingStorageHost=localhost
# several jobs share the node, each on the cores and memory it asked for
SelectType=select/cons_tres
SelectTypeParameters=CR_Core_Memory
MinJobAge=600
ReturnToService=2
$node NodeAddr=127.0.0.1 State=UNKNOWN
PartitionName=local Nodes=$host Default=YES MaxTime=INFINITE State=UP
EOF

pgrep -x slurmdbd >/dev/null || slurmdbd
for _ in $(seq 60); do sacctmgr -n show cluster >/dev/null 2>&1 && break; sleep 0.5; done
sacctmgr -i add cluster "$CLUSTER" >/dev/null 2>&1 || true
sacctmgr -i add account "$ACCOUNT" cluster="$CLUSTER" description=parakin organization=parakin >/dev/null 2>&1 || true
sacctmgr -i add user "$(id -un)" account="$ACCOUNT" cluster="$CLUSTER" >/dev/null 2>&1 || true
pgrep -x slurmctld >/dev/null || slurmctld
pgrep -x slurmd >/dev/null || slurmd
for _ in $(seq 60); do
    if sinfo -h -o %T 2>/dev/null | grep -q -E "idle|mix|alloc"; then
        echo "SLURM: running ($(sinfo -h -o 'partition %P, %D node, %c cores, %m MB, %T'); accounting by slurmdbd)"
        exit 0
    fi
    sleep 0.5
done
echo "SLURM: the node did not come up; see $STATE/*.log" >&2
sinfo >&2 || true
exit 1
