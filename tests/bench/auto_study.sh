#!/bin/sh
# auto_study.sh (benchmark, not a test): issue 14's acceptance table as equal-time farm studies.
# Per scene, one study renders BDPT, PT, PCBPT with K = 1, 2, 4, 8 and auto (its pilot charged to
# its budget) interleaved on the same farm, RUNS seeds, SECONDS each, so the machine's other
# load falls on every configuration alike. Prints per scene the median final beauty relMSE
# of each configuration (scaled from its last snapshot's time to the budget: relMSE falls as
# 1/time), auto's ratio to the best fixed one and to BDPT, and what auto chose.
# Errors are against REFS_DIR/ref-<scene>.exr when that exists at the study's size, else each
# image's own estimate (docs/variance.md).
#   tests/bench/auto_study.sh SECONDS SIZE RUNS [SCENES...]   (REFS_DIR, BIN, HOST/TOKEN, THREADS,
#   OUT and FIXED from the environment; with OUT of an earlier run, scenes already studied there
#   are kept, so two runs over halves of the scenes with THREADS=1 can share a 2-core machine and
#   one table; FIXED, e.g. "bdpt,pcbpt-k1,pcbpt-k2", studies only those fixed configurations beside
#   auto, where the others are known to lose, and the table's best is the best of those)
set -eu
BIN=${BIN:-build/pcbpt-coord}
T=${1:?seconds}; S=${2:?size}; RUNS=${3:?runs}
shift 3
SCENES=${*:-"cornell-box furnace ajar-door slit-room open-room glossy-glass glossy-floor glass-lamp outdoor env-constant env-white-map env-objects thin-glass"}
OUT=${OUT:-$(mktemp -d)}
FIXED=${FIXED:-bdpt,pt,pcbpt-k1,pcbpt-k2,pcbpt-k4,pcbpt-k8}
mkdir -p "$OUT"
far=""
[ -n "${HOST:-}" ] && far="--host $HOST --token-file $TOKEN"
[ -n "${THREADS:-}" ] && far="$far --threads $THREADS"
for sc in $SCENES; do
  [ -f "$OUT/$sc/$sc/study.json" ] && continue
  ref=""
  [ -n "${REFS_DIR:-}" ] && [ -f "$REFS_DIR/ref-$sc.exr" ] && ref="--reference $REFS_DIR/ref-$sc.exr"
  # shellcheck disable=SC2086
  "$BIN" study "scenes/$sc/scene.xml" --methods "$FIXED,auto" --seconds "$T" \
    --runs "$RUNS" --width "$S" --height "$S" --out "$OUT/$sc" $ref $far > "$OUT/$sc.log" 2>&1 ||
    { echo "$sc: study failed: $(tail -3 "$OUT/$sc.log")"; continue; }
done
python3 - "$OUT" $SCENES <<'PY'
import json, os, re, statistics, sys
out, scenes = sys.argv[1], sys.argv[2:]
cfgs = ("bdpt", "pt", "pcbpt-k1", "pcbpt-k2", "pcbpt-k4", "pcbpt-k8", "auto")
print("scene          " + "".join("%-11s" % c.replace("pcbpt-", "") for c in cfgs) +
      "auto/best auto/bdpt per-run auto/bdpt  errors     auto chose (pilot worker-s)")
for sc in scenes:
    p = os.path.join(out, sc, sc, "study.json")
    if not os.path.exists(p):
        print("%-15s (no study)" % sc); continue
    d = json.load(open(p))
    # A method's last snapshot comes when the ranges in flight at its budget have finished, up to
    # 5% past the budget and differently per method; relMSE falls as 1/time, so each is scaled
    # to the budget itself, the equal time the table is about.
    def at_budget(r):
        s = r["snapshots"][-1]
        e = s["layers"]["beauty"]["relmse"]
        return None if e is None else e * s["seconds"] / d["seconds"]
    med, chose, last = {}, [], {}
    for r in d["methods"]:
        if r["snapshots"]:
            last[(r["run"], r["method"])] = at_budget(r)
    per_run = ",".join("%.2f" % (last[(k, "auto")] / last[(k, "bdpt")])
                       for k in sorted({k for k, _ in last}) if last.get((k, "auto")) and last.get((k, "bdpt")))
    for c in cfgs:
        v = [at_budget(r) for r in d["methods"] if r["method"] == c and r["snapshots"]]
        v = [x for x in v if x is not None]
        med[c] = statistics.median(v) if v else float("nan")
    for r in d["methods"]:
        if r["method"] == "auto" and r.get("auto"):
            m = re.match(r"chose (.*) \(pilot ([0-9.]+) s\)", r["auto"])
            chose.append("%s (%s s)" % m.groups() if m else r["auto"].split(";")[0])
    best = min(med[c] for c in cfgs[:-1] if med[c] == med[c])
    kind = "reference" if d.get("reference") else "estimated"
    print("%-15s" % sc + "".join("%-11.4g" % med[c] for c in cfgs) +
          "%-9.3f %-9.3f %-20s %-10s %s" % (med["auto"] / best, med["auto"] / med["bdpt"], per_run, kind, "; ".join(chose)))
PY
echo "(studies in $OUT)"
