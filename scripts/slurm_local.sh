#!/usr/bin/env bash
# slurm_local.sh - a throw-away single-node Slurm cluster on localhost: the
# Slurm test (tests/app/test_rows.cpp) runs `gabion submit slurm` on it, and a
# user can try a job array with it before going to a real cluster
# (docs/cluster.md).
#
#   slurm_local.sh install      install slurm-wlm + munge with apt-get if missing
#   slurm_local.sh start DIR    start munged, slurmctld, slurmd; all files under DIR;
#                               prints "export SLURM_CONF=DIR/slurm.conf" on stdout
#                               (also written to DIR/env.sh); waits for node "idle"
#   slurm_local.sh stop DIR     cancel jobs, stop the daemons started for DIR
#   slurm_local.sh status DIR   exit 0 if all daemons for DIR are running
#
# Usage in a test:  eval "$(slurm_local.sh start "$dir")" || skip "$msg"
# Only "export ..." lines go to stdout; progress and errors go to stderr.
# Any failure exits non-zero with a one-line "slurm_local: ERROR: ..." message.
# Env knobs: SLURM_LOCAL_TIMEOUT (seconds to wait for idle node, default 60),
#            SLURM_LOCAL_KEEP_ON_FAILURE=1 (do not stop daemons when start fails).
#
# Requires root (SlurmUser=root).  Nothing is written to /etc: munged is a private
# instance (own key, socket, pid, log under DIR).  Exception: unix sockets have a
# 108-byte path limit, so if DIR is long, the munge socket and slurmd spool dir live
# in a short mktemp dir /tmp/slurm-local.XXXXXX (symlinked as DIR/sock, removed by stop).
set -euo pipefail

PROG=slurm_local
PARTITION=local
BINS=(slurmctld slurmd sinfo squeue sbatch scontrol scancel munged munge unmunge)

log() { printf '%s: %s\n' "$PROG" "$*" >&2; }
die() { printf '%s: ERROR: %s\n' "$PROG" "$*" >&2; exit 1; }

missing_bins() {
    local b out=()
    for b in "${BINS[@]}"; do
        command -v "$b" >/dev/null 2>&1 || [ -x "/usr/sbin/$b" ] || out+=("$b")
    done
    echo "${out[*]:-}"
}

need_root() {
    [ "$(id -u)" -eq 0 ] || die "must run as root (got uid $(id -u)); this helper runs SlurmUser=root"
}

# ----------------------------------------------------------------------------- install
cmd_install() {
    local miss; miss=$(missing_bins)
    if [ -z "$miss" ]; then log "slurm + munge already installed"; return 0; fi
    need_root
    command -v apt-get >/dev/null 2>&1 || die "apt-get not available; cannot install slurm-wlm/munge (missing: $miss)"
    export DEBIAN_FRONTEND=noninteractive
    # Keep package postinst scripts from starting system munge/slurm daemons.
    local policy=/usr/sbin/policy-rc.d created_policy=0
    if [ ! -e "$policy" ]; then
        printf '#!/bin/sh\nexit 101\n' >"$policy" && chmod 755 "$policy" && created_policy=1
        trap 'rm -f /usr/sbin/policy-rc.d' EXIT
    fi
    local aptlog; aptlog=$(mktemp /tmp/slurm-local-apt.XXXXXX)
    local opts=(-y -qq --no-install-recommends -o DPkg::Lock::Timeout=300
                -o Dpkg::Options::=--force-confdef -o Dpkg::Options::=--force-confold)
    local rc=0
    log "installing slurm-wlm munge (missing: $miss)"
    if ! apt-get install "${opts[@]}" slurm-wlm munge >"$aptlog" 2>&1; then
        # Package lists absent/stale (typical in containers): update and retry once.
        { apt-get update -qq -o DPkg::Lock::Timeout=300 && \
          apt-get install "${opts[@]}" slurm-wlm munge; } >>"$aptlog" 2>&1 || rc=$?
    fi
    if [ "$created_policy" = 1 ]; then rm -f "$policy"; trap - EXIT; fi
    if [ "$rc" -ne 0 ]; then
        tail -n 15 "$aptlog" >&2
        rm -f "$aptlog"
        die "apt-get install slurm-wlm munge failed (rc=$rc)"
    fi
    rm -f "$aptlog"
    miss=$(missing_bins)
    [ -z "$miss" ] || die "still missing after install: $miss"
    log "installed: slurm $(slurmd -V 2>/dev/null | awk "{print \$2}")"
}

# ----------------------------------------------------------------------------- helpers
alive() {   # pid exists and is not a zombie (orphans may stay unreaped if PID 1 is no init)
    local st
    st=$(sed -e 's/^.*) //' "/proc/$1/stat" 2>/dev/null | cut -c1) || return 1
    [ -n "$st" ] && [ "$st" != Z ] && [ "$st" != X ]
}

# Print "alive" pid from pid file if the process exists and its name matches.
pid_of() {   # pidfile expected-comm-prefix
    local f=$1 name=$2 pid comm
    [ -s "$f" ] || return 1
    pid=$(tr -dc '0-9' <"$f")
    [ -n "$pid" ] && alive "$pid" || return 1
    comm=$(cat "/proc/$pid/comm" 2>/dev/null) || return 1
    case "$comm" in "$name"*) echo "$pid" ;; *) return 1 ;; esac
}

port_in_use() {   # port -> 0 if some tcp socket (v4/v6) uses it as local port
    local hex; hex=$(printf ':%04X ' "$1")
    cat /proc/net/tcp /proc/net/tcp6 2>/dev/null | awk '{print $2" "}' | grep -qi -- "$hex"
}

pick_port() {     # pick a free port in 20000-31999 (below the usual ephemeral range)
    local p i exclude=${1:-0}
    for i in $(seq 1 200); do
        p=$(( 20000 + (RANDOM * 32768 + RANDOM) % 12000 ))
        [ "$p" != "$exclude" ] || continue
        port_in_use "$p" || { echo "$p"; return 0; }
    done
    die "could not find a free TCP port"
}

show_logs() {
    local d=$1 f
    for f in "$d"/log/munged.log "$d"/log/slurmctld.log "$d"/log/slurmd.log "$d"/log/*.stdout; do
        [ -s "$f" ] || continue
        printf '%s: ---- tail %s ----\n' "$PROG" "$f" >&2
        tail -n 25 "$f" >&2
    done
}

rm_sockdir() {    # remove DIR/sock symlink and its short /tmp target (created for long DIRs)
    local t
    [ -L "$1/sock" ] || return 0
    t=$(readlink "$1/sock")
    case "$t" in /tmp/slurm-local.*) rm -rf "$t" ;; esac
    rm -f "$1/sock"
}

resolve_dir() {   # create and print absolute physical path
    [ -n "${1:-}" ] || die "usage: $0 start|stop|status DIR"
    mkdir -p "$1" || die "cannot create $1"
    (cd "$1" && pwd -P)
}

# ----------------------------------------------------------------------------- start
cmd_start() {
    need_root
    local miss; miss=$(missing_bins)
    [ -z "$miss" ] || die "slurm/munge not installed (missing: $miss); run '$0 install'"
    export PATH="$PATH:/usr/sbin:/sbin"
    local D; D=$(resolve_dir "${1:-}")
    if pid_of "$D/run/slurmctld.pid" slurmctld >/dev/null || pid_of "$D/run/slurmd.pid" slurmd >/dev/null \
       || pid_of "$D/run/munged.pid" munged >/dev/null; then
        die "a cluster is already running for $D; run '$0 stop $D' first"
    fi
    # On any failure from here on, stop whatever was started (unless asked to keep it).
    if [ -z "${SLURM_LOCAL_KEEP_ON_FAILURE:-}" ]; then
        CLEANUP_DIR=$D
        trap 'rc=$?; if [ $rc -ne 0 ] && [ -n "${CLEANUP_DIR:-}" ]; then
                  log "start failed; stopping daemons started for $CLEANUP_DIR"
                  ( cmd_stop "$CLEANUP_DIR" ) >/dev/null 2>&1 || true; fi' EXIT
    fi

    local node cpus mem_kb mem_mb
    node=$(hostname -s 2>/dev/null || true); [ -n "$node" ] || node=$(uname -n); node=${node%%.*}
    [ -n "$node" ] || die "cannot determine short hostname"
    cpus=$(nproc)
    mem_kb=$(awk '/^MemTotal:/{print $2}' /proc/meminfo)
    mem_mb=$(( mem_kb / 1024 * 90 / 100 )); [ "$mem_mb" -ge 1 ] || mem_mb=1

    mkdir -p "$D"/{log,run,state/slurmctld}
    rm -f "$D"/run/*.pid
    # Unix socket paths are limited to 107 bytes: munge socket + slurmd spool
    # (slurmd creates "<spool>/<node>_<jobid>.<stepid>" sockets).
    local S="$D/sock"
    rm_sockdir "$D"
    if [ $(( ${#S} + ${#node} + 40 )) -gt 104 ]; then
        local short; short=$(mktemp -d /tmp/slurm-local.XXXXXX)
        ln -s "$short" "$S"
        S=$short
        log "DIR path is long; sockets/spool in $S (symlink $D/sock)"
    else
        mkdir -p "$S"
    fi
    mkdir -p "$S/munge" "$S/slurmd"
    chmod 755 "$S" "$S/munge" "$S/slurmd"

    # ---- munge (private instance)
    local key="$D/munge.key"
    if [ ! -s "$key" ]; then
        ( umask 077; dd if=/dev/urandom of="$key" bs=1024 count=1 status=none ) || die "cannot create $key"
    fi
    chmod 400 "$key"
    local msock="$S/munge/munge.socket.2"
    rm -f "$msock" "$msock.lock"
    munged --force --socket="$msock" --key-file="$key" --pid-file="$D/run/munged.pid" \
        --log-file="$D/log/munged.log" --seed-file="$D/state/munged.seed" \
        </dev/null >>"$D/log/munged.stdout" 2>&1 || { show_logs "$D"; die "munged failed to start"; }
    local i
    for i in $(seq 1 50); do [ -S "$msock" ] && break; sleep 0.1; done
    munge -n -S "$msock" 2>/dev/null | unmunge -S "$msock" >/dev/null 2>&1 \
        || { show_logs "$D"; die "munge self-test failed (socket $msock)"; }

    # ---- slurm.conf
    local ctld_port slurmd_port
    ctld_port=$(pick_port); slurmd_port=$(pick_port "$ctld_port")
    cat >"$D/slurm.conf" <<EOF
# generated by slurm_local.sh - throw-away single-node cluster
ClusterName=local
SlurmctldHost=${node}(127.0.0.1)
SlurmUser=root
SlurmdUser=root
SlurmctldPort=${ctld_port}
SlurmdPort=${slurmd_port}
AuthType=auth/munge
AuthInfo=socket=${msock}
CredType=cred/munge
StateSaveLocation=${D}/state/slurmctld
SlurmdSpoolDir=${S}/slurmd
SlurmctldPidFile=${D}/run/slurmctld.pid
SlurmdPidFile=${D}/run/slurmd.pid
SlurmctldLogFile=${D}/log/slurmctld.log
SlurmdLogFile=${D}/log/slurmd.log
SlurmctldDebug=info
SlurmdDebug=info
MailProg=/bin/true
ProctrackType=proctrack/linuxproc
TaskPlugin=task/none
JobAcctGatherType=jobacct_gather/none
AccountingStorageType=accounting_storage/none
JobCompType=jobcomp/none
SwitchType=switch/none
MpiDefault=none
SelectType=select/cons_tres
SelectTypeParameters=CR_Core
SchedulerType=sched/backfill
SchedulerParameters=bf_interval=1
SlurmdParameters=config_overrides
PropagateResourceLimits=NONE
ReturnToService=2
SlurmctldTimeout=30
SlurmdTimeout=30
MessageTimeout=10
InactiveLimit=0
KillWait=5
Waittime=0
MinJobAge=300
MaxArraySize=10001
EnforcePartLimits=ALL
NodeName=${node} NodeAddr=127.0.0.1 NodeHostname=${node} CPUs=${cpus} RealMemory=${mem_mb} State=UNKNOWN
PartitionName=${PARTITION} Nodes=${node} Default=YES MaxTime=INFINITE State=UP
EOF
    printf 'export SLURM_CONF=%q\n' "$D/slurm.conf" >"$D/env.sh"
    export SLURM_CONF="$D/slurm.conf"

    # ---- daemons (they daemonize; detach stdio so "$(...)" callers do not hang)
    slurmctld </dev/null >>"$D/log/slurmctld.stdout" 2>&1 || { show_logs "$D"; die "slurmctld failed to start"; }
    for i in $(seq 1 100); do
        scontrol ping 2>/dev/null | grep -q 'UP' && break
        pid_of "$D/run/slurmctld.pid" slurmctld >/dev/null || [ "$i" -lt 10 ] \
            || { show_logs "$D"; die "slurmctld died during startup"; }
        sleep 0.2
    done
    slurmd -N "$node" </dev/null >>"$D/log/slurmd.stdout" 2>&1 || { show_logs "$D"; die "slurmd failed to start"; }

    # ---- wait for node idle
    local timeout=${SLURM_LOCAL_TIMEOUT:-60} t0=$SECONDS state=""
    while :; do
        state=$(sinfo -h -N -n "$node" -o '%T' 2>/dev/null | head -n1 || true)
        [ "$state" = idle ] && break
        if [ $(( SECONDS - t0 )) -ge "$timeout" ]; then
            show_logs "$D"
            die "node $node not idle after ${timeout}s (state: '${state:-unknown}'); logs in $D/log"
        fi
        if [ $(( SECONDS - t0 )) -ge 3 ]; then
            local dname
            for dname in munged slurmctld slurmd; do
                pid_of "$D/run/$dname.pid" "$dname" >/dev/null \
                    || { show_logs "$D"; die "$dname is not running (node state '${state:-unknown}')"; }
            done
        fi
        sleep 0.3
    done
    CLEANUP_DIR=""
    log "cluster up: node $node ($cpus CPUs, ${mem_mb} MB) partition $PARTITION, ctld port $ctld_port, slurmd port $slurmd_port"
    cat "$D/env.sh"
}

# ----------------------------------------------------------------------------- stop
stop_pids() {   # name... : TERM all daemons in parallel, wait up to 10 s, then KILL
    local n pid i pids=() left
    for n in "$@"; do
        if pid=$(pid_of "$D/run/$n.pid" "$n"); then kill -TERM "$pid" 2>/dev/null || true; pids+=("$pid"); fi
    done
    for i in $(seq 1 100); do
        left=""
        for pid in "${pids[@]}"; do alive "$pid" && left="$left $pid"; done
        [ -z "$left" ] && break
        sleep 0.1
    done
    if [ -n "$left" ]; then
        log "pids$left did not exit on TERM; sending KILL"
        kill -KILL $left 2>/dev/null || true
        sleep 0.2
    fi
    for n in "$@"; do rm -f "$D/run/$n.pid"; done
}

cmd_stop() {
    [ -n "${1:-}" ] || die "usage: $0 stop DIR"
    [ -d "$1" ] || { log "nothing to stop ($1 does not exist)"; return 0; }
    export PATH="$PATH:/usr/sbin:/sbin"
    local D; D=$(cd "$1" && pwd -P)
    export SLURM_CONF="$D/slurm.conf"
    local i
    # Cancel remaining jobs so slurmstepd/job processes do not outlive slurmd.
    if pid_of "$D/run/slurmctld.pid" slurmctld >/dev/null && pid_of "$D/run/slurmd.pid" slurmd >/dev/null; then
        if [ -n "$(squeue -h -o %i 2>/dev/null | head -n1)" ]; then
            scancel --partition="$PARTITION" 2>/dev/null || true
            for i in $(seq 1 50); do
                [ -z "$(squeue -h -o %i 2>/dev/null | head -n1)" ] && break
                sleep 0.2
            done
        fi
    fi
    stop_pids slurmd slurmctld munged
    # Kill leftovers of this cluster: slurmstepd and job processes (both carry
    # SLURM_CONF=DIR/slurm.conf in their environment; jobs also SLURM_JOB_ID).
    local p pid anc=" $$ " q=$$ killed=""
    while q=$(sed -e 's/^.*) //' "/proc/$q/stat" 2>/dev/null | awk '{print $2}') && [ -n "$q" ] && [ "$q" -gt 1 ]; do
        anc="$anc$q "
    done
    for p in /proc/[0-9]*; do
        pid=${p#/proc/}
        case "$anc" in *" $pid "*) continue ;; esac
        grep -qzxF "SLURM_CONF=$D/slurm.conf" "$p/environ" 2>/dev/null || continue
        alive "$pid" || continue
        [ "$(cat "$p/comm" 2>/dev/null)" = slurmstepd ] || grep -qz '^SLURM_JOB_ID=' "$p/environ" 2>/dev/null || continue
        if kill -KILL "$pid" 2>/dev/null; then killed="$killed $pid"; fi
    done
    [ -z "$killed" ] || log "killed leftover job/slurmstepd processes:$killed"
    rm_sockdir "$D"
    log "stopped cluster in $D"
}

cmd_status() {
    [ -n "${1:-}" ] || die "usage: $0 status DIR"
    local D; D=$(cd "$1" 2>/dev/null && pwd -P) || die "$1 does not exist"
    local n rc=0
    for n in munged slurmctld slurmd; do
        if pid=$(pid_of "$D/run/$n.pid" "$n"); then log "$n running (pid $pid)"; else log "$n NOT running"; rc=1; fi
    done
    return $rc
}

case "${1:-}" in
    install) cmd_install ;;
    start)   cmd_start "${2:-}" ;;
    stop)    cmd_stop "${2:-}" ;;
    status)  cmd_status "${2:-}" ;;
    *) echo "usage: $0 install | start DIR | stop DIR | status DIR" >&2; exit 2 ;;
esac
