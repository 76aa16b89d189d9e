# variance_farm.sh: on a 2-worker farm, the relMSE each job reports (status --json, from the
# per-iteration squares its workers merged) agrees with the one measured against the furnace's
# exact image (2 everywhere), over 8 seeds of pt, bdpt and pcbpt: the mean difference is within
# 4 standard errors measured from the per-seed differences (tests/stat/test_variance.c does the
# same on one machine with more seeds and cornell-box). Jobs of 16x16 pixels and 32 iterations,
# all submitted at once so both workers take ranges of each.
. "$(dirname "$0")/lib.inc"
SCENE="$S/scenes/furnace/scene.xml"
RUNS=8
start_coord
start_worker w1
start_worker w2
declare -A JOBS
for m in pt bdpt pcbpt; do
  for seed in $(seq $RUNS); do
    JOBS[$m.$seed]=$("$B/pcbpt-coord" submit "$SCENE" --method $m --seed $seed --spp 32 --width 16 --height 16 \
      --pcbpt-m 20 --cache-fraction 0.05 $H | tail -1)
  done
done
for J in "${JOBS[@]}"; do timeout 55 "$B/pcbpt-coord" wait "$J" $H >/dev/null || fail "wait $J"; done
"$B/pcbpt-coord" status $H --json >"$T/status.json"
for m in pt bdpt pcbpt; do
  for seed in $(seq $RUNS); do
    J=${JOBS[$m.$seed]}
    CK=$(ls "$T/data/jobs/$J"/ckpt.* | sort -t. -k2 -n | tail -1)
    echo "$J $("$B/tests/farm_tool" relmse "$CK" 16 16 2)" >>"$T/$m.txt" || fail "relmse $J"
  done
  python3 - "$m" "$T/$m.txt" "$T/status.json" <<'PY' || fail "$m: estimated and measured relMSE disagree on the farm"
import json, math, sys
status = {j["job"]: j for j in json.load(open(sys.argv[3]))}
rows = []
for line in open(sys.argv[2]):
    job, est, meas = line.split()
    s = status[int(job)]
    assert s["state"] == "done" and s["iterations"] == 32, f"job {job}: {s['state']}, {s['iterations']} iterations"
    assert abs(s["relmse_estimate"] - float(est)) <= 1e-5 * float(est), f"job {job}: status {s['relmse_estimate']} != film {est}"
    rows.append((float(est), float(meas)))
d = [est - meas for est, meas in rows]
n = len(d); md = sum(d) / n
se = math.sqrt(sum((x - md) ** 2 for x in d) / (n - 1) / n)
me = sum(r[0] for r in rows) / n; mm = sum(r[1] for r in rows) / n
print(f"{sys.argv[1]:5s} farm, {n} seeds: estimated relMSE {me:.5f}, measured {mm:.5f}, difference {md:+.5f} +- {se:.5f} ({md / se:+.1f} se)")
sys.exit(abs(md) > 4 * se)
PY
done
echo PASS
