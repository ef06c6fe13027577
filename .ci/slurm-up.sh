#!/usr/bin/env bash
# A one-node Slurm cluster on 127.0.0.1 for tests/slurm.rs (docs/CLUSTER.md): installs Debian's
# slurm-wlm and munge if missing, writes slurm.conf and a munge key under $NONLIN3D_SLURM_DIR
# (default /tmp/nonlin3d-slurm), starts munged, slurmctld and slurmd from there (as the calling
# user; root on CI) and waits until `sinfo` shows the node idle. Prints the line to export
# SLURM_CONF, which the clients (sbatch, squeue, scancel, sinfo) need; .ci/slurm-down.sh stops
# the three daemons by the pids recorded here. Any failure exits non-zero with the logs shown.
set -euo pipefail
D="${NONLIN3D_SLURM_DIR:-/tmp/nonlin3d-slurm}"

need=()
for tool in munged slurmctld slurmd sbatch; do
  command -v "$tool" >/dev/null 2>&1 || need+=("$tool")
done
if [ "${#need[@]}" -gt 0 ]; then
  echo "slurm-up: installing slurm-wlm and munge (missing: ${need[*]})" >&2
  export DEBIAN_FRONTEND=noninteractive
  apt-get update -qq
  apt-get install -y -qq slurm-wlm munge >/dev/null
fi

# A cluster of ours still running from an earlier call is stopped first.
if [ -d "$D" ]; then
  "$(dirname "$0")/slurm-down.sh" >/dev/null 2>&1 || true
fi
rm -rf "$D"
mkdir -p -m 700 "$D" "$D/state" "$D/spool" "$D/munge"
chmod 700 "$D/munge"

# Munge: a fresh key and a socket of our own (nothing shared with a system munged).
dd if=/dev/urandom of="$D/munge/munge.key" bs=1024 count=1 status=none
chmod 400 "$D/munge/munge.key"
munged --force --foreground --socket="$D/munge/munge.socket" --key-file="$D/munge/munge.key" \
  --pid-file="$D/munge/munged.pid" --log-file="$D/munge/munged.log" \
  --seed-file="$D/munge/munged.seed" >"$D/munge/munged.out" 2>&1 &
echo $! > "$D/munged.pid"

user="$(id -un)"
mem_mib=$(( $(awk '/^MemTotal:/ {print $2}' /proc/meminfo) / 1024 ))
# Slurm wants RealMemory at or below what slurmd finds; leave it 5 % of headroom.
mem_mib=$(( mem_mib * 95 / 100 ))
cat > "$D/slurm.conf" <<CONF
ClusterName=nonlin3d
SlurmctldHost=localhost(127.0.0.1)
SlurmctldPort=6817
SlurmdPort=6818
SlurmUser=$user
SlurmdUser=$user
AuthType=auth/munge
CredType=cred/munge
AuthInfo=socket=$D/munge/munge.socket
StateSaveLocation=$D/state
SlurmdSpoolDir=$D/spool
SlurmctldPidFile=$D/slurmctld.pidfile
SlurmdPidFile=$D/slurmd.pidfile
SlurmctldLogFile=$D/slurmctld.log
SlurmdLogFile=$D/slurmd.log
ProctrackType=proctrack/linuxproc
TaskPlugin=task/none
SelectType=select/cons_tres
SelectTypeParameters=CR_Core_Memory
DefMemPerCPU=1024
SchedulerType=sched/backfill
AccountingStorageType=accounting_storage/none
JobAcctGatherType=jobacct_gather/none
JobCompType=jobcomp/none
MpiDefault=none
ReturnToService=2
SchedulerParameters=sched_interval=1
MessageTimeout=10
KillWait=2
InactiveLimit=0
MinJobAge=300
NodeName=localhost NodeAddr=127.0.0.1 CPUs=2 RealMemory=$mem_mib State=UNKNOWN
PartitionName=debug Nodes=localhost Default=YES MaxTime=INFINITE State=UP
CONF
export SLURM_CONF="$D/slurm.conf"

for _ in $(seq 50); do
  [ -S "$D/munge/munge.socket" ] && break
  sleep 0.1
done
slurmctld -D -f "$SLURM_CONF" -i >"$D/slurmctld.out" 2>&1 &
echo $! > "$D/slurmctld.pid"
slurmd -D -f "$SLURM_CONF" -N localhost >"$D/slurmd.out" 2>&1 &
echo $! > "$D/slurmd.pid"

# The node idle within 60 s, or the logs and a failure.
for _ in $(seq 120); do
  state="$(sinfo -h -n localhost -o %t 2>/dev/null || true)"
  if [ "$state" = "idle" ]; then
    echo "slurm-up: node localhost idle (RealMemory=$mem_mib MiB, CPUs=2, $D)" >&2
    echo "export SLURM_CONF=$SLURM_CONF"
    exit 0
  fi
  sleep 0.5
done
echo "slurm-up: the node is not idle after 60 s (sinfo: '${state:-no answer}')" >&2
for log in munge/munged.log munge/munged.out slurmctld.log slurmctld.out slurmd.log slurmd.out; do
  echo "--- $D/$log" >&2
  tail -n 30 "$D/$log" >&2 || true
done
exit 1
