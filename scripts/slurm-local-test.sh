#!/bin/sh
# End-to-end test of scripts/slurm-render.sh on a one-node Slurm started here on localhost:
# munged, slurmctld and slurmd run as root with a minimal slurm.conf (no cgroup plugins, no
# accounting) under a scratch directory, a 4-task job array renders a small Cornell box and
# a dependent job merges it; the result must be bit-identical to one process rendering all
# the passes. The daemons are stopped by their PIDs at the end. Installs slurm-wlm and munge
# with apt-get if they are missing (about 20 s). Run from the repository root as root.
set -eu
repo=$(pwd)
bdpm="$repo/target/release/bdpm"
[ -x "$bdpm" ] || cargo build --release -p bdpm
if ! command -v slurmctld >/dev/null || ! command -v munged >/dev/null; then
    # A machine that cannot install the packages (no root, no apt, no package lists) cannot
    # run this test at all: say so and stop without failing; everything after this point
    # that fails is a failure of the recipe.
    if ! { [ "$(id -u)" = 0 ] && command -v apt-get >/dev/null &&
        { DEBIAN_FRONTEND=noninteractive apt-get install -y -q slurm-wlm munge >/dev/null 2>&1 ||
          { apt-get update -q >/dev/null 2>&1 &&
            DEBIAN_FRONTEND=noninteractive apt-get install -y -q slurm-wlm munge >/dev/null 2>&1; }; }; }; then
        echo "SKIPPED: the Slurm test needs root and the slurm-wlm and munge packages"
        exit 0
    fi
fi
dir=$(mktemp -d /tmp/bdpm-slurm.XXXXXX)
chmod 755 "$dir"  # munged runs as munge and must reach its socket directory
pids=""
stop() {
    for p in $pids; do kill "$p" 2>/dev/null || true; done
    for p in $pids; do while kill -0 "$p" 2>/dev/null; do sleep 0.1; done; done
}
trap stop EXIT INT TERM

node=$(hostname -s)
mkdir -p "$dir/state" "$dir/spool" "$dir/munge"
chown munge:munge "$dir/munge"
cat > "$dir/slurm.conf" <<CONF
ClusterName=bdpmtest
SlurmctldHost=$node
SlurmUser=root
SlurmdUser=root
AuthType=auth/munge
AuthInfo=socket=$dir/munge/munge.socket
CredType=cred/munge
StateSaveLocation=$dir/state
SlurmdSpoolDir=$dir/spool
SlurmctldPidFile=$dir/slurmctld.pid
SlurmdPidFile=$dir/slurmd.pid
SlurmctldLogFile=$dir/slurmctld.log
SlurmdLogFile=$dir/slurmd.log
SlurmctldPort=16817
SlurmdPort=16818
ProctrackType=proctrack/linuxproc
TaskPlugin=task/none
JobAcctGatherType=jobacct_gather/none
AccountingStorageType=accounting_storage/none
JobCompType=jobcomp/none
MpiDefault=none
SchedulerType=sched/backfill
SelectType=select/cons_tres
SelectTypeParameters=CR_Core
ReturnToService=2
NodeName=$node CPUs=$(nproc) State=UNKNOWN
PartitionName=test Nodes=ALL Default=YES MaxTime=INFINITE State=UP
CONF
export SLURM_CONF="$dir/slurm.conf"

runuser -u munge -- /usr/sbin/munged -F --socket="$dir/munge/munge.socket" \
    --pid-file="$dir/munge/munged.pid" --seed-file="$dir/munge/seed" \
    --log-file="$dir/munge/munged.log" 2>"$dir/munged.out" &
pids="$!"
sleep 1
/usr/sbin/slurmctld -D -i -f "$SLURM_CONF" >"$dir/slurmctld.out" 2>&1 &
pids="$pids $!"
/usr/sbin/slurmd -D -f "$SLURM_CONF" -N "$node" >"$dir/slurmd.out" 2>&1 &
pids="$pids $!"
for i in $(seq 1 100); do
    if sinfo -h -o %t 2>/dev/null | grep -qE '^(idle|mix|alloc)'; then break; fi
    sleep 0.2
done
sinfo

scene="$repo/scenes/cornell-lambert.toml"
flags="--resolution 32x32 --photons 5000 --spp 1 --threads 1"
set -- $flags
ids=$(BDPM="$bdpm" "$repo/scripts/slurm-render.sh" "$scene" 4 3 "$dir/out" "$@")
echo "submitted jobs: $ids"
merge_id=${ids#* }
for i in $(seq 1 600); do
    state=$(scontrol show job "$merge_id" 2>/dev/null | sed -n 's/.*JobState=\([A-Z_]*\).*/\1/p')
    case "$state" in COMPLETED|FAILED|CANCELLED|TIMEOUT|NODE_FAIL|OUT_OF_MEMORY) break ;; esac
    sleep 0.5
done
echo "merge job state: $state"
for f in "$dir"/out/part-*.log "$dir/out/merge.log"; do echo "== $f"; cat "$f"; done
[ "$state" = COMPLETED ] || { echo "FAIL: merge job $state" >&2; tail -20 "$dir/slurmctld.log" "$dir/slurmd.log" >&2; exit 1; }
"$bdpm" render "$scene" $flags --passes 12 --quiet -o "$dir/out/single.exr"
"$bdpm" compare --require-identical "$dir/out/single.exr" "$dir/out/merged.exr"
echo "PASS: 4 Slurm array tasks + merge are bit-identical to one 12-pass render ($dir)"
