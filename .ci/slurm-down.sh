#!/usr/bin/env bash
# Stops the cluster of .ci/slurm-up.sh by the pids it recorded (slurmd, slurmctld, munged, in
# that order), waiting up to 10 s for each before SIGKILL, and removes its folder.
set -uo pipefail
D="${NONLIN3D_SLURM_DIR:-/tmp/nonlin3d-slurm}"
for name in slurmd slurmctld munged; do
  f="$D/$name.pid"
  [ -f "$f" ] || continue
  pid="$(cat "$f")"
  if kill -0 "$pid" 2>/dev/null; then
    kill "$pid"
    for _ in $(seq 100); do
      kill -0 "$pid" 2>/dev/null || break
      sleep 0.1
    done
    kill -0 "$pid" 2>/dev/null && kill -9 "$pid"
  fi
  rm -f "$f"
done
rm -rf "$D"
