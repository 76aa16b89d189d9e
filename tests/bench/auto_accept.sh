#!/bin/sh
# auto_accept.sh: the acceptance table of --method auto (docs/auto.md): every shipped scene at
# equal wall time, BDPT, each fixed PCBPT K of the grid and auto (pilot included), 3 seeds;
# prints one CSV row per render, then per scene the median estimated beauty relMSE of each
# configuration and auto's ratios to the best fixed one and to BDPT. The relMSE is each image's
# own estimate (docs/variance.md), so any size works without a reference.
#   tests/bench/auto_accept.sh [SECONDS [SIZE [SEEDS [SCENES...]]]]   (default 60 256 "1 2 3", all)
set -eu
BIN=${BIN:-build/pcbpt-coord}
T=${1:-60}; S=${2:-256}; SEEDS=${3:-"1 2 3"}
[ $# -ge 3 ] && shift 3 || set --
SCENES=${*:-"cornell-box furnace ajar-door slit-room open-room glossy-glass glossy-floor glass-lamp outdoor"}
OUT=$(mktemp -d)
trap 'rm -rf "$OUT"' EXIT
CSV=$OUT/rows.csv
echo "scene,config,seed,iterations,seconds,relmse_est,chose" | tee "$CSV"
for sc in $SCENES; do
  for seed in $SEEDS; do
    for cfg in bdpt k1 k2 k4 k8 auto; do
      case $cfg in
        bdpt) flags="--method bdpt" ;;
        auto) flags="--method auto" ;;
        k*) flags="--method pcbpt --pcbpt-k ${cfg#k}" ;;
      esac
      # shellcheck disable=SC2086
      log=$("$BIN" render "scenes/$sc/scene.xml" $flags --time "$T" --width "$S" --height "$S" --seed "$seed" \
            --quiet --out "$OUT/img.exr")
      it=$(echo "$log" | sed -n 's/^[a-z]*: \([0-9]*\) iterations.*/\1/p')
      secs=$(echo "$log" | sed -n 's/^[a-z]*: [0-9]* iterations, \([0-9.]*\) s.*/\1/p')
      rel=$(echo "$log" | sed -n 's/.*est. relMSE \([0-9.e+-]*\).*/\1/p')
      chose=$(echo "$log" | sed -n 's/^auto: chose \([^(]*\) (.*/\1/p' | sed 's/ *$//')
      echo "$sc,$cfg,$seed,$it,$secs,$rel,$chose" | tee -a "$CSV"
    done
  done
done
python3 - "$CSV" <<'PY'
import csv, statistics, sys
rows = list(csv.DictReader(open(sys.argv[1])))
print("\nscene          " + "".join("%-11s" % c for c in ("bdpt", "k1", "k2", "k4", "k8", "auto")) + " auto/best auto/bdpt  auto chose")
for sc in dict.fromkeys(r["scene"] for r in rows):
    med = {}
    for c in ("bdpt", "k1", "k2", "k4", "k8", "auto"):
        v = [float(r["relmse_est"]) for r in rows if r["scene"] == sc and r["config"] == c and r["relmse_est"]]
        med[c] = statistics.median(v) if v else float("nan")
    best = min(med[c] for c in ("bdpt", "k1", "k2", "k4", "k8"))
    chose = ";".join(r["chose"] for r in rows if r["scene"] == sc and r["config"] == "auto")
    print("%-15s" % sc + "".join("%-11.4g" % med[c] for c in ("bdpt", "k1", "k2", "k4", "k8", "auto"))
          + " %-9.3f %-9.3f %s" % (med["auto"] / best, med["auto"] / med["bdpt"], chose))
PY
