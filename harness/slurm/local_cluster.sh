# A throw-away single-node Slurm cluster on this machine, for make test-slurm.
# Sourced by bash:
#
#   source harness/slurm/local_cluster.sh
#   cluster_start DIR   # munged, slurmctld, slurmd; exports SLURM_CONF=DIR/slurm.conf
#                       # (DIR's parents must be searchable by all users: munged checks)
#   ...                 # sbatch, squeue, scancel, scontrol now talk to it
#   cluster_stop        # cancels its jobs, stops the daemons; safe to call twice
#
# Everything lives in DIR: a generated slurm.conf (its own ports on 127.0.0.1), a munge key
# and socket of its own, the daemons' state, spool, pid files and logs; nothing in /etc, no
# systemd. Debian 12's slurm-wlm 22.05 and munge 0.5 (make slurm-deps). Plugins that need
# no cgroups (a container has no systemd to delegate them): proctrack/linuxproc, task/none,
# no accounting. Daemons run as root, jobs as the submitting user.

cluster_start() {
    CLUSTER_DIR=$1
    local d=$CLUSTER_DIR host ports ctld_port slurmd_port t
    host=$(hostname -s)
    mkdir -p "$d"/{munge,state,spool,log}
    # munged checks that its socket's directories are reachable by all and not writable by others.
    chmod 755 "$d" "$d/munge"
    mungekey --create --keyfile="$d/munge/munge.key"
    munged --socket="$d/munge/munge.socket" --key-file="$d/munge/munge.key" --pid-file="$d/munge/munged.pid" \
        --log-file="$d/log/munged.log" --seed-file="$d/munge/munged.seed"
    # Two free ports on 127.0.0.1 (the kernel's choice; released just before the daemons bind them).
    ports=$(python3 -c 'import socket
s = [socket.socket() for _ in range(2)]
for x in s: x.bind(("127.0.0.1", 0))
print(*[x.getsockname()[1] for x in s])')
    read -r ctld_port slurmd_port <<< "$ports"
    # NoCtldInAddrAny/NoInAddrAny: the daemons bind the address their host name resolves
    # to (127.0.0.1 here), not every interface. config_overrides: the node is what this
    # file says (no draining over detected sockets or memory).
    cat > "$d/slurm.conf" <<CONF
ClusterName=accelbench-test
SlurmctldHost=$host(127.0.0.1)
SlurmctldPort=$ctld_port
SlurmdPort=$slurmd_port
CommunicationParameters=NoCtldInAddrAny,NoInAddrAny
SlurmUser=$(id -un)
SlurmdUser=root
AuthType=auth/munge
CredType=cred/munge
AuthInfo=socket=$d/munge/munge.socket
StateSaveLocation=$d/state
SlurmdSpoolDir=$d/spool
SlurmctldPidFile=$d/slurmctld.pid
SlurmdPidFile=$d/slurmd.pid
SlurmctldLogFile=$d/log/slurmctld.log
SlurmdLogFile=$d/log/slurmd.log
ProctrackType=proctrack/linuxproc
TaskPlugin=task/none
JobAcctGatherType=jobacct_gather/none
AccountingStorageType=accounting_storage/none
JobCompType=jobcomp/none
SwitchType=switch/none
MpiDefault=none
SelectType=select/cons_tres
SelectTypeParameters=CR_CPU
ReturnToService=2
MinJobAge=3600
MailProg=/bin/true
SlurmdParameters=config_overrides
NodeName=$host NodeAddr=127.0.0.1 CPUs=$(nproc) State=UNKNOWN
PartitionName=accelbench Nodes=$host Default=YES MaxTime=INFINITE State=UP
CONF
    export SLURM_CONF=$d/slurm.conf
    slurmctld -f "$SLURM_CONF"
    slurmd -f "$SLURM_CONF"
    for ((t = 0; t < 60; t++)); do
        [ "$(sinfo -h -o %T 2>/dev/null)" = idle ] && { echo "cluster: up in $d (slurmctld 127.0.0.1:$ctld_port, slurmd :$slurmd_port)"; return 0; }
        sleep 0.5
    done
    echo "cluster: the node did not become idle in 30 s; sinfo says '$(sinfo -h -o '%T %E' 2>&1)'" >&2
    tail -n 20 "$d/log/slurmctld.log" "$d/log/slurmd.log" >&2 || true
    return 1
}

# Waits up to $2 seconds (default 10) for process $1 to end; then kills it.
cluster_stop_pid() {
    local pid=$1 t
    [ -n "$pid" ] && kill -0 "$pid" 2>/dev/null || return 0
    kill "$pid" 2>/dev/null || true
    for ((t = 0; t < ${2:-10} * 10; t++)); do kill -0 "$pid" 2>/dev/null || return 0; sleep 0.1; done
    kill -9 "$pid" 2>/dev/null || true
}

cluster_stop() {
    [ -n "${CLUSTER_DIR:-}" ] || return 0
    local d=$CLUSTER_DIR t pid
    # Jobs first: a step daemon outlives a stopped slurmd.
    if [ -f "$d/slurmctld.pid" ] && kill -0 "$(cat "$d/slurmctld.pid")" 2>/dev/null; then
        scancel --user="$(id -un)" 2>/dev/null || true
        for ((t = 0; t < 100; t++)); do
            [ -z "$(squeue -h -o %i 2>/dev/null)" ] && break
            sleep 0.2
        done
    fi
    for f in slurmd.pid slurmctld.pid munge/munged.pid; do
        [ -f "$d/$f" ] && cluster_stop_pid "$(cat "$d/$f")"
    done
    # Whatever else runs from this directory (a job's task left by a stuck step).
    for pid in $(pgrep -f -- "$d" || true); do cluster_stop_pid "$pid" 2; done
    unset CLUSTER_DIR SLURM_CONF
}
