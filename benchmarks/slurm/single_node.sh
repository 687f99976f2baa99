#!/usr/bin/env bash
# A real one-node SLURM cluster on this machine (Debian's slurm-wlm and munge): installs them
# if missing, writes /etc/slurm/slurm.conf for this host's cores and memory, and starts munged,
# slurmctld and slurmd.  Needs root (the daemons run as root; fine on a throw-away machine or
# container, not meant for a shared host).  Idempotent: a second call restarts the daemons.
#
#   sudo benchmarks/slurm/single_node.sh          # start
#   sudo benchmarks/slurm/single_node.sh stop     # stop the daemons
set -euo pipefail

if [[ "${1:-start}" == "stop" ]]; then
    pkill -x slurmd || true
    pkill -x slurmctld || true
    pkill -x munged || true
    exit 0
fi
if [[ $(id -u) -ne 0 ]]; then
    echo "single_node.sh: needs root (it installs packages and starts the SLURM daemons)" >&2
    exit 2
fi
if ! command -v slurmctld >/dev/null || ! command -v munged >/dev/null; then
    DEBIAN_FRONTEND=noninteractive apt-get install -y -q slurm-wlm munge >/dev/null
fi

host=$(hostname -s)
cpus=$(nproc)
mem_mb=$(awk '/MemTotal/ {printf "%d", $2 / 1024 * 0.9}' /proc/meminfo)

# munge: one key, daemon as root (no systemd in a container)
mkdir -p /etc/munge /var/log/munge /var/lib/munge /run/munge
if [[ ! -s /etc/munge/munge.key ]]; then
    dd if=/dev/urandom bs=1 count=1024 of=/etc/munge/munge.key status=none
fi
chmod 400 /etc/munge/munge.key
chown -R root:root /etc/munge /var/log/munge /var/lib/munge /run/munge
chmod 700 /etc/munge /var/log/munge /var/lib/munge
chmod 755 /run/munge
pkill -x munged || true
sleep 0.5
munged --force

mkdir -p /etc/slurm /var/spool/slurmctld /var/spool/slurmd /var/log/slurm
cat > /etc/slurm/slurm.conf <<CONF
# written by soilcal benchmarks/slurm/single_node.sh: one node, this host
ClusterName=soilcal
SlurmctldHost=${host}
SlurmUser=root
SlurmdUser=root
AuthType=auth/munge
StateSaveLocation=/var/spool/slurmctld
SlurmdSpoolDir=/var/spool/slurmd
SlurmctldLogFile=/var/log/slurm/slurmctld.log
SlurmdLogFile=/var/log/slurm/slurmd.log
SlurmctldPidFile=/run/slurmctld.pid
SlurmdPidFile=/run/slurmd.pid
ProctrackType=proctrack/linuxproc
TaskPlugin=task/none
MpiDefault=none
ReturnToService=2
SchedulerType=sched/backfill
SelectType=select/cons_tres
SelectTypeParameters=CR_Core_Memory
JobAcctGatherType=jobacct_gather/none
AccountingStorageType=accounting_storage/none
JobCompType=jobcomp/none
# squeue keeps finished jobs this long, so a status query by squeue still sees them
MinJobAge=600
NodeName=${host} CPUs=${cpus} RealMemory=${mem_mb} State=UNKNOWN
PartitionName=main Nodes=${host} Default=YES MaxTime=INFINITE State=UP
CONF

pkill -x slurmd || true
pkill -x slurmctld || true
sleep 1
slurmctld -c   # clear state left by an earlier cluster (jobs of a killed run)
slurmd
for _ in $(seq 1 30); do
    if sinfo -h -o '%T' 2>/dev/null | grep -q -E '^(idle|mixed|allocated)'; then
        sinfo
        exit 0
    fi
    sleep 1
done
echo "single_node.sh: the node did not become idle; see /var/log/slurm/*.log" >&2
sinfo >&2 || true
exit 1
