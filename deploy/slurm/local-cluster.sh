#!/usr/bin/env bash
# local-cluster.sh: a one-node Slurm cluster (munged, slurmctld, slurmd) on this machine, kept
# entirely under DIR: for trying the sbatch scripts and for tests/deploy/slurm.sh. Needs root
# and Debian's slurm-wlm and munge (deploy/install-deps.sh installs them).
#   deploy/slurm/local-cluster.sh start DIR [PORT_BASE]   # then: export SLURM_CONF=DIR/slurm.conf
#   deploy/slurm/local-cluster.sh stop DIR
# PORT_BASE (default 16817) and PORT_BASE+1 are slurmctld's and slurmd's ports.
# Jobs may share cores (OverSubscribe=FORCE:4), so a coordinator job and workers fit one small machine.
set -euo pipefail
cmd=${1:?usage: local-cluster.sh start|stop DIR [PORT_BASE]}
D=${2:?usage: local-cluster.sh start|stop DIR [PORT_BASE]}
case "$cmd" in
start)
  base=${3:-16817}
  for p in munged slurmctld slurmd; do
    command -v "$p" >/dev/null || PATH=$PATH:/usr/sbin
    command -v "$p" >/dev/null || { echo "local-cluster: $p not installed (deploy/install-deps.sh)" >&2; exit 2; }
  done
  mkdir -p "$D"/{state,spool,log,munge}
  D=$(cd "$D" && pwd)
  chmod 700 "$D/munge"
  [ -s "$D/munge/munge.key" ] || { head -c 1024 /dev/urandom > "$D/munge/munge.key"; chmod 400 "$D/munge/munge.key"; }
  node=$(hostname -s)
  cat > "$D/slurm.conf" <<CONF
ClusterName=pcbpt-local
SlurmctldHost=$node(127.0.0.1)
SlurmctldPort=$base
SlurmdPort=$((base + 1))
AuthType=auth/munge
AuthInfo=socket=$D/munge/munge.sock
CredType=cred/munge
SlurmUser=root
SlurmdUser=root
StateSaveLocation=$D/state
SlurmdSpoolDir=$D/spool
SlurmctldPidFile=$D/slurmctld.pid
SlurmdPidFile=$D/slurmd.pid
SlurmctldLogFile=$D/log/slurmctld.log
SlurmdLogFile=$D/log/slurmd.log
ProctrackType=proctrack/linuxproc
TaskPlugin=task/none
JobAcctGatherType=jobacct_gather/none
AccountingStorageType=accounting_storage/none
SchedulerType=sched/backfill
SelectType=select/cons_tres
SelectTypeParameters=CR_Core
KillWait=5
ReturnToService=2
MpiDefault=none
NodeName=$node NodeAddr=127.0.0.1 CPUs=$(nproc) State=UNKNOWN
PartitionName=local Nodes=$node Default=YES MaxTime=INFINITE State=UP OverSubscribe=FORCE:4
CONF
  munged --key-file="$D/munge/munge.key" --socket="$D/munge/munge.sock" --pid-file="$D/munge/munged.pid" \
    --log-file="$D/log/munged.log" --seed-file="$D/munge/seed" --force
  slurmctld -f "$D/slurm.conf"
  slurmd -f "$D/slurm.conf"
  for _ in $(seq 100); do
    SLURM_CONF=$D/slurm.conf sinfo -h -o %t 2>/dev/null | grep -qx idle && { echo "local-cluster: up ($D/slurm.conf)"; exit 0; }
    sleep 0.2
  done
  echo "local-cluster: the node did not become idle; see $D/log/" >&2
  exit 1
  ;;
stop)
  for pf in "$D/slurmd.pid" "$D/slurmctld.pid" "$D/munge/munged.pid"; do
    [ -s "$pf" ] || continue
    pid=$(cat "$pf")
    kill "$pid" 2>/dev/null || continue
    for _ in $(seq 50); do kill -0 "$pid" 2>/dev/null || break; sleep 0.1; done
    kill -9 "$pid" 2>/dev/null || true
  done
  ;;
*) echo "usage: local-cluster.sh start|stop DIR [PORT_BASE]" >&2; exit 2 ;;
esac
