#!/usr/bin/env bash
# Run a creepfit sweep as a Slurm job array on a one-node Slurm cluster on this machine, merge
# the shards into OUT and stop what was started: the test of scripts/slurm/{submit.sh,
# sweep.sbatch, merge.sbatch} on a real Slurm (CI runs it through scripts/slurm/check.sh).
#
#   scripts/slurm/run-local.sh CONFIG STARTS TASKS OUT
#   scripts/slurm/run-local.sh --stop        # stop a cluster kept with CREEPFIT_SLURM_KEEP=1
#
# Needs root (slurmd runs jobs as their user, and the daemons run as root here). Steps:
#  1. Installs Debian's slurmctld, slurmd, slurm-client and munge (--no-install-recommends:
#     8 packages) when slurmctld, slurmd, sbatch or munged is missing.
#  2. Writes a private cluster into $CREEPFIT_SLURM_STATE (default /tmp/creepfit-slurm):
#     slurm.conf for one node, `hostname -s` at 127.0.0.1, with the CPUs of nproc and 90 % of
#     the memory slurmd detects; its own munge key and munged socket, state, spool, logs and pid
#     files. Nothing in /etc is changed, and a system Slurm or munge is left alone (other
#     ports: $CREEPFIT_SLURM_PORT and the next one, default 16817/16818).
#  3. Starts munged, slurmctld and slurmd, or reuses the ones a previous run left running in
#     that folder (CREEPFIT_SLURM_KEEP=1), and waits until sinfo shows the node idle.
#  4. Builds the crate (cargo build --release; a no-op when up to date) unless CREEPFIT names a
#     binary, submits the sweep with submit.sh (a job array of TASKS tasks, 1 CPU each, and the
#     dependent merge job), waits for both, checks every task and the merge completed, and
#     leaves the merged result in OUT (OUT/ranked.csv …; shards in OUT/shard-I-of-TASKS/,
#     Slurm logs in OUT/logs/).
#  5. On exit, success or not, stops the daemons it started (unless CREEPFIT_SLURM_KEEP=1).
#     On a failure it prints the reason and the tails of the slurmctld, slurmd and munged logs
#     and of the job logs, and exits non-zero.
#
# The configuration, which runs jobs on this project's machines (Debian 12, Slurm 22.05.8, a
# gVisor sandbox as root) and needs nothing a container may withhold: no cgroups at all
# (ProctrackType=proctrack/linuxproc tracks job processes by parent pid; TaskPlugin=task/none,
# no CPU binding; JobAcctGatherType=jobacct_gather/none; no cgroup.conf; the cgroup plugins
# were not tried), no accounting database (slurmdbd), select/cons_tres with CR_Core (CPUs are
# the consumable resource; memory is not enforced), SlurmUser=root, munge authentication over
# a private socket (AuthInfo=socket=…).
#
# Environment: CREEPFIT_SLURM_STATE (state folder), CREEPFIT_SLURM_PORT (slurmctld port;
# slurmd uses the next), CREEPFIT_SLURM_KEEP=1 (leave the cluster running for the next run),
# CREEPFIT_SLURM_TIMEOUT (seconds to wait for the jobs, default 1200), CREEPFIT (binary).
set -euo pipefail

repo=$(cd "$(dirname "$0")/../.." && pwd)
state=${CREEPFIT_SLURM_STATE:-/tmp/creepfit-slurm}
port=${CREEPFIT_SLURM_PORT:-16817}
keep=${CREEPFIT_SLURM_KEEP:-0}
timeout_s=${CREEPFIT_SLURM_TIMEOUT:-1200}
partition=creepfit
t_start=$(date +%s)

log() { echo "run-local: $*" >&2; }
elapsed() { echo "$(($(date +%s) - t_start)) s"; }

# Pids of the daemons this script started in this run (stopped on exit).
started=()
failed_msg=""

fail() {
    failed_msg="$*"
    exit 1
}

tail_logs() {
    local f
    for f in "$state"/log/slurmctld.log "$state"/log/slurmd.log "$state"/log/munged.log; do
        if [ -s "$f" ]; then
            echo "---- last lines of $f" >&2
            tail -n 25 "$f" >&2
        fi
    done
    if [ -n "${out:-}" ] && [ -d "$out/logs" ]; then
        for f in "$out"/logs/*.log; do
            [ -s "$f" ] || continue
            echo "---- last lines of $f" >&2
            tail -n 15 "$f" >&2
        done
    fi
}

# A pid from a pid file, if that process is alive and runs the named program.
live_pid() {
    local file=$1 name=$2 pid
    [ -s "$file" ] || return 1
    pid=$(cat "$file")
    [ -n "$pid" ] && [ -r "/proc/$pid/comm" ] || return 1
    [ "$(cat "/proc/$pid/comm")" = "$name" ] || return 1
    echo "$pid"
}

stop_pid() {
    local pid=$1 i
    kill "$pid" 2>/dev/null || return 0
    for i in $(seq 1 100); do
        [ -e "/proc/$pid" ] || return 0
        sleep 0.1
    done
    kill -KILL "$pid" 2>/dev/null || true
}

# Stop the daemons of the cluster in $state, newest first.
stop_cluster() {
    local name pid
    for name in slurmd slurmctld munged; do
        if pid=$(live_pid "$state/run/$name.pid" "$name"); then
            stop_pid "$pid"
        fi
    done
}

on_exit() {
    local rc=$?
    if [ "$rc" -ne 0 ]; then
        log "FAILED after $(elapsed): ${failed_msg:-a command failed (exit status $rc)}"
        tail_logs
    fi
    if [ "${#started[@]}" -gt 0 ] && [ "$keep" != 1 ]; then
        log "stopping the cluster this run started"
        stop_cluster
    elif [ "${#started[@]}" -gt 0 ]; then
        log "cluster left running (CREEPFIT_SLURM_KEEP=1); stop it with $0 --stop"
    fi
    exit "$rc"
}

export SLURM_CONF="$state/slurm.conf"

if [ "${1:-}" = "--stop" ]; then
    stop_cluster
    log "stopped the cluster in $state"
    exit 0
fi
if [ $# -ne 4 ]; then
    sed -n '2,8p' "$0" >&2
    exit 2
fi
config=$1
starts=$2
tasks=$3
out=$4
case "$starts" in '' | *[!0-9]*) echo "error: STARTS must be a positive integer: '$starts'" >&2; exit 2 ;; esac
case "$tasks" in '' | *[!0-9]*) echo "error: TASKS must be a positive integer: '$tasks'" >&2; exit 2 ;; esac
[ -f "$config" ] || { echo "error: $config: no such configuration file" >&2; exit 2; }
config=$(realpath "$config")
out=$(realpath -m "$out")
trap on_exit EXIT

# 1. Slurm and munge from the distribution's packages.
install_packages() {
    local pkgs=(slurmctld slurmd slurm-client munge) t0
    [ "$(id -u)" -eq 0 ] || fail "slurm/munge missing and not root: apt-get install ${pkgs[*]}"
    command -v apt-get >/dev/null || fail "slurm/munge missing and no apt-get: install ${pkgs[*]}"
    t0=$(date +%s)
    log "installing ${pkgs[*]} (apt-get, --no-install-recommends)"
    export DEBIAN_FRONTEND=noninteractive
    apt-get update -qq >"$state/log/apt.log" 2>&1 || fail "apt-get update failed (see $state/log/apt.log)"
    apt-get install -y -qq --no-install-recommends "${pkgs[@]}" >>"$state/log/apt.log" 2>&1 ||
        { tail -n 20 "$state/log/apt.log" >&2; fail "apt-get install ${pkgs[*]} failed"; }
    log "installed in $(($(date +%s) - t0)) s"
}

mkdir -p "$state/log" "$state/run"
need_install=0
for c in slurmctld slurmd sbatch squeue sinfo scontrol munged mungekey; do
    command -v "$c" >/dev/null || need_install=1
done
[ "$need_install" = 0 ] || install_packages

node=$(hostname -s)
[ -n "$node" ] || fail "hostname -s printed nothing"

# 2./3. The cluster: reuse a running one of this folder, else start one.
cluster_up() {
    live_pid "$state/run/munged.pid" munged >/dev/null &&
        live_pid "$state/run/slurmctld.pid" slurmctld >/dev/null &&
        live_pid "$state/run/slurmd.pid" slurmd >/dev/null &&
        sinfo -h >/dev/null 2>&1
}

write_config() {
    local cpus mem
    cpus=$(nproc)
    mem=$(slurmd -C 2>/dev/null | sed -n 's/.*RealMemory=\([0-9]*\).*/\1/p')
    [ -n "$mem" ] || mem=$(awk '/MemTotal/ {print int($2 / 1024)}' /proc/meminfo)
    mem=$((mem * 9 / 10))
    cat >"$state/slurm.conf" <<EOF
# One-node Slurm for scripts/slurm/run-local.sh (written by it; see the comments there).
ClusterName=creepfit-local
SlurmctldHost=$node(127.0.0.1)
SlurmctldPort=$port
SlurmdPort=$((port + 1))
SlurmUser=root
SlurmdUser=root
AuthType=auth/munge
CredType=cred/munge
AuthInfo=socket=$state/run/munge.socket
StateSaveLocation=$state/spool/ctld
SlurmdSpoolDir=$state/spool/d
SlurmctldPidFile=$state/run/slurmctld.pid
SlurmdPidFile=$state/run/slurmd.pid
SlurmctldLogFile=$state/log/slurmctld.log
SlurmdLogFile=$state/log/slurmd.log
# No cgroups: track job processes by parent pid, no CPU binding, no accounting.
ProctrackType=proctrack/linuxproc
TaskPlugin=task/none
JobAcctGatherType=jobacct_gather/none
AccountingStorageType=accounting_storage/none
JobCompType=jobcomp/none
MpiDefault=none
SwitchType=switch/none
SchedulerType=sched/backfill
SelectType=select/cons_tres
SelectTypeParameters=CR_Core
ReturnToService=2
# Finished jobs stay visible to scontrol for 10 minutes (no accounting database here).
MinJobAge=600
NodeName=$node NodeAddr=127.0.0.1 NodeHostname=$node CPUs=$cpus RealMemory=$mem State=UNKNOWN
PartitionName=$partition Nodes=$node Default=YES MaxTime=INFINITE State=UP
EOF
}

# Start a daemon (NAME COMMAND…) that writes $state/run/NAME.pid, and wait up to 5 s for it.
start_daemon() {
    local name=$1 pid="" i
    shift
    "$@" || fail "$name did not start"
    for i in $(seq 1 50); do
        pid=$(live_pid "$state/run/$name.pid" "$name") && break
        sleep 0.1
    done
    [ -n "$pid" ] || fail "$name did not start (no live process in $state/run/$name.pid)"
    started+=("$pid")
}

start_cluster() {
    local t0 pid i st=""
    t0=$(date +%s)
    stop_cluster # leftovers of an earlier run of this folder, if any
    rm -rf "$state/spool" "$state/run"
    mkdir -p "$state/spool/ctld" "$state/spool/d" "$state/run" "$state/log"
    chmod 755 "$state/run"
    : >"$state/log/slurmctld.log"
    : >"$state/log/slurmd.log"
    : >"$state/log/munged.log"
    if [ ! -s "$state/munge.key" ]; then
        mungekey --create --keyfile="$state/munge.key" >/dev/null 2>&1 ||
            dd if=/dev/urandom of="$state/munge.key" bs=1024 count=1 status=none
    fi
    chmod 600 "$state/munge.key"
    write_config
    # --force: munged refuses to run as root or with a key outside /etc/munge otherwise.
    munged --force --socket="$state/run/munge.socket" --key-file="$state/munge.key" \
        --pid-file="$state/run/munged.pid" --seed-file="$state/run/munged.seed" \
        --log-file="$state/log/munged.log" || fail "munged did not start"
    pid=$(live_pid "$state/run/munged.pid" munged) || fail "munged did not start"
    started+=("$pid")
    munge --socket="$state/run/munge.socket" -n | unmunge --socket="$state/run/munge.socket" >/dev/null ||
        fail "munge cannot encode and decode a credential"
    start_daemon slurmctld slurmctld
    start_daemon slurmd slurmd -N "$node"
    for i in $(seq 1 120); do
        st=$(sinfo -h -n "$node" -o %t 2>/dev/null || true)
        [ "$st" = idle ] && break
        sleep 0.5
    done
    if [ "$st" != idle ]; then
        sinfo -R >&2 || true
        fail "node $node is '${st:-unknown}' after 60 s, not idle"
    fi
    log "one-node cluster up in $(($(date +%s) - t0)) s: node $node idle, $(nproc) CPUs, ports $port/$((port + 1)), state in $state"
}

if cluster_up; then
    log "reusing the cluster running from $state"
else
    [ "$(id -u)" -eq 0 ] || fail "starting slurmd needs root"
    start_cluster
fi

# 4. The binary, the jobs, the wait.
if [ -z "${CREEPFIT:-}" ]; then
    log "cargo build --release"
    (cd "$repo" && cargo build --release --quiet) || fail "cargo build --release failed"
    export CREEPFIT="$repo/target/release/creepfit"
fi
[ -x "$CREEPFIT" ] || fail "$CREEPFIT: no executable"

# The shards of an earlier run in OUT would be resumed (same sweep) or refused (another one):
# start from an empty folder.
if [ -d "$out" ] && [ -n "$(ls -A "$out")" ]; then
    fail "$out exists and is not empty: choose a new OUT"
fi
mkdir -p "$out"
t_jobs=$(date +%s)
submitted=$("$repo/scripts/slurm/submit.sh" "$config" "$starts" "$tasks" "$out" \
    --partition="$partition" --cpus-per-task=1 --time=00:30:00) ||
    fail "submission failed: $submitted"
echo "$submitted" | sed 's/^/run-local: /' >&2
array=$(echo "$submitted" | awk '/^submitted:/ {print $3}')
merge=$(echo "$submitted" | awk '/^submitted:/ {print $5}')
[ -n "$array" ] && [ -n "$merge" ] || fail "could not read the job ids from: $submitted"

job_states() { # JobState of every job (array tasks too) with this id, one per line
    scontrol -o show job "$1" 2>/dev/null | sed -n 's/.*JobState=\([A-Z_]*\).*/\1/p'
}
deadline=$(($(date +%s) + timeout_s))
while :; do
    st=$(job_states "$merge")
    case "$st" in
        COMPLETED | FAILED | CANCELLED | TIMEOUT | NODE_FAIL | OUT_OF_MEMORY | BOOT_FAIL | DEADLINE) break ;;
    esac
    if [ "$(date +%s)" -gt "$deadline" ]; then
        squeue >&2 || true
        fail "the jobs did not finish within $timeout_s s (merge job $merge: ${st:-unknown})"
    fi
    sleep 1
done
log "jobs finished in $(($(date +%s) - t_jobs)) s"
tasks_done=$(job_states "$array" | grep -c '^COMPLETED$' || true)
if [ "$tasks_done" -ne "$tasks" ]; then
    scontrol -o show job "$array" | sed -n 's/^JobId=\([0-9]*\) .*ArrayTaskId=\([0-9]*\) .*JobState=\([A-Z_]*\).*ExitCode=\([0-9:]*\).*/  task \2: \3 (exit \4)/p' >&2
    fail "$tasks_done of $tasks array tasks completed"
fi
[ "$st" = COMPLETED ] || fail "merge job $merge: $st"
[ -s "$out/ranked.csv" ] || fail "merge job $merge completed but $out/ranked.csv is missing"
log "all $tasks tasks and the merge completed; merged result in $out ($(elapsed) in all)"
