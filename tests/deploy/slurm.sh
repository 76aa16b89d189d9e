# slurm.sh: the farm under a real Slurm (a one-node cluster on localhost made by
# deploy/slurm/local-cluster.sh): the coordinator and an array of two workers are sbatch jobs
# (deploy/slurm/*.sbatch), a job renders to completion with one worker scancel'ed mid-job,
# counts exactly its iterations, and its merged sums equal a single-process render.
# Exit 77 (skipped) only where this machine cannot run Slurm's daemons.
set -euo pipefail
B=${PCBPT_BINARY_DIR:?}
S=${PCBPT_SOURCE_DIR:?}
export PATH=$PATH:/usr/sbin
for p in munged slurmctld slurmd sbatch scancel squeue; do
  command -v "$p" >/dev/null || { echo "SKIP: $p is not installed (deploy/install-deps.sh installs slurm-wlm and munge)"; exit 77; }
done
[ "$(id -u)" = 0 ] || { echo "SKIP: a local Slurm cluster needs root"; exit 77; }
T=$(mktemp -d /tmp/pcbpt-slurm-XXXXXX)
CL=$T/cluster
cleanup() {
  [ -n "${SLURM_CONF:-}" ] && scancel --full $(squeue -h -o %A 2>/dev/null) 2>/dev/null || true
  "$S/deploy/slurm/local-cluster.sh" stop "$CL" || true
  if [ "${KEEP:-0}" = 0 ]; then rm -rf "$T"; fi
}
trap cleanup EXIT
fail() {
  echo "FAIL: $*"
  for f in "$T"/farm/*.out "$CL"/log/slurmctld.log; do [ -f "$f" ] && { echo "--- $f"; tail -25 "$f"; }; done
  exit 1
}
# Free ports for slurmctld/slurmd, so a system Slurm or a parallel test is not disturbed.
base=$(python3 -c 'import socket
for p in range(20000, 60000, 2):
    try:
        a = socket.socket(); a.bind(("127.0.0.1", p)); b = socket.socket(); b.bind(("127.0.0.1", p + 1))
        a.close(); b.close(); print(p); break
    except OSError: pass')
if ! "$S/deploy/slurm/local-cluster.sh" start "$CL" "$base" >"$T/cluster.log" 2>&1; then
  cat "$T/cluster.log"; tail -5 "$CL"/log/*.log 2>/dev/null
  echo "SKIP: this machine does not run Slurm's daemons (see above)"; exit 77
fi
export SLURM_CONF=$CL/slurm.conf
F=$T/farm; mkdir -p "$F"
echo "slurm-test-token-$$-$RANDOM" > "$F/token"; chmod 600 "$F/token"
export PCBPT_BIN=$B PCBPT_LISTEN=127.0.0.1 PCBPT_ADVERTISE=127.0.0.1 PCBPT_THREADS=1
CJ=$(sbatch --parsable -c1 -o "$F/coord-%j.out" "$S/deploy/slurm/pcbpt-coord.sbatch" "$F" 0) || fail "sbatch coordinator"
WJ=$(sbatch --parsable --array=1-2 -n1 -c1 -o "$F/worker-%A_%a.out" "$S/deploy/slurm/pcbpt-workers.sbatch" "@$F/coord.addr" "$F/token") \
  || fail "sbatch workers"
for _ in $(seq 300); do [ -s "$F/coord.addr" ] && break; sleep 0.2; done
[ -s "$F/coord.addr" ] || fail "the coordinator job $CJ published no address"
H="--host $(cat "$F/coord.addr") --token-file $F/token"
workers() { "$B/pcbpt-coord" workers $H --json | python3 -c 'import json,sys; print(len(json.load(sys.stdin)))'; }
for _ in $(seq 300); do [ "$(workers 2>/dev/null || echo 0)" = 2 ] && break; sleep 0.2; done
[ "$(workers)" = 2 ] || fail "two workers did not connect"
# Long enough (seconds) that the scancel, which Slurm may deliver a second or two late on a busy
# machine, lands while the worker still holds a range: 960 iterations were done in 2.5 s on a
# faster machine, before the status polls below had seen the job start.
SPP=3840
J=$("$B/pcbpt-coord" submit "$S/scenes/cornell-box/scene.xml" --method pt --spp $SPP --width 64 --height 64 $H | tail -1) \
  || fail "submit"
field() { "$B/pcbpt-coord" status "$J" $H --json | python3 -c "import json,sys; print(json.load(sys.stdin)['$1'])"; }
for _ in $(seq 300); do [ "$(field iterations)" -gt 0 ] && break; sleep 0.1; done
[ "$(field state)" = running ] || fail "the job is $(field state) before the cancel"
scancel "${WJ}_1" || fail "scancel ${WJ}_1"
timeout 120 "$B/pcbpt-coord" wait "$J" $H >/dev/null || fail "wait"
[ "$(field state)" = done ] || fail "state $(field state)"
[ "$(field iterations)" = $SPP ] || fail "iterations $(field iterations) != $SPP"
squeue -h -j "${WJ}_1" -t R 2>/dev/null | grep -q . && fail "the cancelled worker is still running"
grep -q "orphaned (.*-1 gone)" "$F"/coord-*.out || fail "the cancelled worker held no range: nothing was tested"
ck=$(ls "$F/data/jobs/$J"/ckpt.* | sort -t. -k2 -n | tail -1)
"$B/tests/farm_tool" exact "$ck" "$S/scenes/cornell-box/scene.xml" --spp $SPP --method pt --width 64 --height 64 \
  || fail "the farm's sums differ from a single-process render"
"$B/pcbpt-coord" fetch "$J" --out "$T/out.exr" $H >/dev/null || fail "fetch"
echo PASS
