#!/usr/bin/env bash
# A single-node SLURM cluster on this host, for tests/test_slurm.py and for trying the
# workflow's SLURM profile by hand:
#
#   tests/slurm/cluster.sh start     install (Debian packages) if missing, configure, start,
#                                    wait until the node is usable; again: does nothing more
#   tests/slurm/cluster.sh status    the daemons and the node; exit 0 when usable, 3 when not
#   tests/slurm/cluster.sh stop      cancel every job, stop the daemons; packages stay
#
# Needs root (it writes /etc/slurm and /etc/munge and starts daemons) and no systemd: the
# daemons are started directly and stopped by the pids they recorded. Traffic stays on
# 127.0.0.1. One partition, `debug`, marked default; no accounting daemon (slurmdbd), so
# `sacct` answers "accounting storage is disabled" and the workflow's SLURM profile asks
# `squeue` for job states, which keeps finished jobs for MinJobAge (600 s, below).
set -euo pipefail

CONF=/etc/slurm/slurm.conf
LOGDIR=/var/log/slurm
CTLD_PID=/run/slurmctld.pid
SLURMD_PID=/run/slurmd.pid
MUNGE_PID=/run/munge/munged.pid
MUNGE_KEY=/etc/munge/munge.key
PARTITION=debug
# memory left to the OS, the snakemake that submits and the local (figure, aggregation) jobs
MEM_MARGIN_MB=${SLURM_MEM_MARGIN_MB:-2048}
# seconds to wait for the node to become usable after the daemons start
START_TIMEOUT=${SLURM_START_TIMEOUT:-60}
NODE=$(hostname -s)
# the first line of the slurm.conf this script writes: it never touches another one
MARK="# Written by tests/slurm/cluster.sh: a single-node cluster on localhost."

die() { echo "cluster.sh: $*" >&2; exit 1; }

alive() {   # the process recorded in pid file $1 is program $2 and not a zombie (the
            # container's pid 1 may be slow to reap the daemons it inherits)
    local pid comm state
    [[ -s $1 ]] || return 1
    pid=$(<"$1")
    { read -r _ comm state _ <"/proc/$pid/stat"; } 2>/dev/null || return 1
    [[ $comm == "($2)" && $state != Z ]]
}

install_packages() {
    local missing=()
    command -v slurmctld >/dev/null || missing+=(slurmctld)
    command -v slurmd >/dev/null || missing+=(slurmd)
    command -v sbatch >/dev/null || missing+=(slurm-client)
    command -v munged >/dev/null || missing+=(munge)
    ((${#missing[@]})) || return 0
    local t0=$SECONDS
    echo "cluster.sh: installing ${missing[*]} (apt-get)"
    export DEBIAN_FRONTEND=noninteractive
    # an image without package lists knows no candidate: update once, then install
    if ! apt-cache show slurmctld >/dev/null 2>&1; then
        apt-get update -q >/dev/null
    fi
    apt-get install -y -q --no-install-recommends \
        -o Dpkg::Options::=--force-confdef -o Dpkg::Options::=--force-confold \
        "${missing[@]}" >"$LOGDIR/apt-get.log" 2>&1 \
        || die "apt-get install ${missing[*]} failed: read $LOGDIR/apt-get.log"
    echo "cluster.sh: installed in $((SECONDS - t0)) s"
}

ours() {   # no slurm.conf, or the one this script wrote
    [[ ! -e $CONF ]] || [[ $(head -n 1 "$CONF") == "$MARK" ]]
}

write_conf() {
    # The node as slurmd sees it (sockets, cores, threads), its memory less the margin.
    local hw mem
    ours || die "$CONF was not written by this script: it stays (a real cluster's?)"
    hw=$(slurmd -C | head -n 1 | sed -E 's/^NodeName=[^ ]+ //; s/ ?RealMemory=[0-9]+//')
    mem=$(( $(awk '/^MemTotal:/ {print int($2 / 1024)}' /proc/meminfo) - MEM_MARGIN_MB ))
    ((mem > 1024)) || die "too little memory: ${mem} MB after a ${MEM_MARGIN_MB} MB margin"
    mkdir -p /etc/slurm
    cat >"$CONF.new" <<EOF
$MARK
ClusterName=localhost
SlurmctldHost=$NODE(127.0.0.1)
# root runs every daemon: a throw-away test cluster, no separate slurm account needed
SlurmUser=root
SlurmdUser=root
AuthType=auth/munge
StateSaveLocation=/var/spool/slurmctld
SlurmdSpoolDir=/var/spool/slurmd
SlurmctldPidFile=$CTLD_PID
SlurmdPidFile=$SLURMD_PID
SlurmctldLogFile=$LOGDIR/slurmctld.log
SlurmdLogFile=$LOGDIR/slurmd.log
# Scheduling by CPU and memory, so jobs share the node as their requests allow
SchedulerType=sched/backfill
SelectType=select/cons_tres
SelectTypeParameters=CR_CPU_Memory
# linuxproc tracks a job's processes by parentage: no cgroups, no systemd (a container)
ProctrackType=proctrack/linuxproc
# binds a job's tasks to its allocated CPUs (rules with threads > 1)
TaskPlugin=task/affinity
MpiDefault=none
SwitchType=switch/none
# No accounting daemon: sacct cannot answer, job states come from squeue
AccountingStorageType=accounting_storage/none
JobAcctGatherType=jobacct_gather/none
JobCompType=jobcomp/none
# squeue shows a finished job for this long: well above the SLURM plugin's polling
# interval (40 s at first, up to 180 s); the plugin falls back to sacct below 120 s
MinJobAge=600
# a node that was down (host restarted) is usable again as soon as its slurmd registers
ReturnToService=2
SlurmdTimeout=60
KillWait=10
NodeName=$NODE NodeAddr=127.0.0.1 $hw RealMemory=$mem State=UNKNOWN
# Each CPU may be given to up to 4 jobs at once: the SLURM plugin waits 10 s longer at each
# status check that finds no job finished, so jobs queued one after another for CPUs made most
# of a small build's wall time; the requests (CPUs, memory) are still the jobs' own
PartitionName=$PARTITION Nodes=$NODE Default=YES MaxTime=INFINITE State=UP OverSubscribe=FORCE:4
EOF
    if cmp -s "$CONF.new" "$CONF"; then
        rm "$CONF.new"
        return 1
    fi
    mv "$CONF.new" "$CONF"
}

setup_munge() {
    mkdir -p /etc/munge /run/munge /var/lib/munge /var/log/munge
    if [[ ! -s $MUNGE_KEY ]]; then
        dd if=/dev/urandom of="$MUNGE_KEY" bs=1 count=1024 status=none
    fi
    chown munge:munge "$MUNGE_KEY" /run/munge /var/lib/munge /var/log/munge
    chmod 0400 "$MUNGE_KEY"
    chmod 0700 /etc/munge /var/lib/munge /var/log/munge
    chmod 0755 /run/munge
}

node_state() {
    sinfo --noheader --nodes="$NODE" --format=%T 2>/dev/null | head -n 1
}

usable() {
    alive "$MUNGE_PID" munged && alive "$CTLD_PID" slurmctld && alive "$SLURMD_PID" slurmd \
        && [[ $(node_state) =~ ^(idle|mixed|allocated|completing)$ ]]
}

start() {
    [[ $(id -u) == 0 ]] || die "start needs root (it installs packages and starts daemons)"
    mkdir -p "$LOGDIR" /var/spool/slurmctld /var/spool/slurmd
    install_packages
    local changed=0
    write_conf && changed=1
    if ((changed)) && { alive "$CTLD_PID" slurmctld || alive "$SLURMD_PID" slurmd; }; then
        echo "cluster.sh: $CONF changed: restarting the daemons"
        stop_daemons
    fi
    setup_munge
    local t0=$SECONDS
    local logs="$LOGDIR/slurmctld.log and $LOGDIR/slurmd.log (munge: /var/log/munge/)"
    alive "$MUNGE_PID" munged || runuser -u munge -- /usr/sbin/munged --pid-file="$MUNGE_PID" \
        || die "munged did not start: read /var/log/munge/munged.log"
    alive "$CTLD_PID" slurmctld || slurmctld || die "slurmctld did not start: read $logs"
    alive "$SLURMD_PID" slurmd || slurmd || die "slurmd did not start: read $logs"
    local state
    until usable; do
        state=$(node_state)
        if [[ $state =~ ^(down|drained|draining)$ ]] && alive "$SLURMD_PID" slurmd; then
            # left down by an earlier, unclean stop: slurmd runs, so take it back
            scontrol update nodename="$NODE" state=resume 2>/dev/null || true
        fi
        if ((SECONDS - t0 > START_TIMEOUT)); then
            die "node $NODE not usable after ${START_TIMEOUT} s" \
                "(state: '${state:-no answer}'): read $logs"
        fi
        sleep 1
    done
    echo "cluster.sh: node $NODE $(node_state) in partition $PARTITION ($((SECONDS - t0)) s)"
}

stop_one() {   # SIGTERM the process of pid file $1 (program $2), SIGKILL after 20 s
    alive "$1" "$2" || return 0
    local pid
    pid=$(<"$1")
    kill "$pid"
    for _ in $(seq 40); do
        alive "$1" "$2" || return 0
        sleep 0.5
    done
    echo "cluster.sh: $2 ($pid) ignored SIGTERM for 20 s: SIGKILL" >&2
    kill -KILL "$pid" 2>/dev/null || true
}

stop_daemons() {
    stop_one "$SLURMD_PID" slurmd
    stop_one "$CTLD_PID" slurmctld
}

stop() {
    [[ $(id -u) == 0 ]] || die "stop needs root"
    if alive "$CTLD_PID" slurmctld; then
        # a job left running would hold its CPUs in the next start's node
        scancel --full --quiet --partition="$PARTITION" 2>/dev/null || true
        for _ in $(seq 20); do
            [[ -z $(squeue --noheader --states=pending,running,completing) ]] && break
            sleep 0.5
        done
    fi
    stop_daemons
    stop_one "$MUNGE_PID" munged
    # With a slurm.conf and no controller, every SLURM client waits ~9 s for it, and so does
    # every snakemake start (the SLURM plugin runs `scontrol show config` for its --help
    # text); without one they fail at once. `start` writes it again.
    if ours; then
        rm -f "$CONF"
    fi
    echo "cluster.sh: stopped"
}

status() {
    local name file
    for name in munged slurmctld slurmd; do
        case $name in
            munged) file=$MUNGE_PID ;;
            slurmctld) file=$CTLD_PID ;;
            slurmd) file=$SLURMD_PID ;;
        esac
        if alive "$file" "$name"; then
            echo "$name: running (pid $(<"$file"))"
        else
            echo "$name: stopped"
        fi
    done
    if usable; then
        sinfo
        return 0
    fi
    return 3
}

case ${1:-} in
    start) start ;;
    stop) stop ;;
    status) status ;;
    *) echo "usage: $0 start|stop|status" >&2; exit 2 ;;
esac
