#!/usr/bin/env bash
# The study verb from the command line: help, flag errors that name the flag (one line, non-zero
# exit), and a tiny equal-time study (32x32, 2 s per method, pt and bdpt) on the embedded farm
# against a reference rendered here: every output file exists in the scene's folder and
# study.csv has one row per method, snapshot and layer, with the last snapshot at the end of
# the budget, and every method's heavy tails, per-iteration errors and strategy shares are in the
# table, study.json and report.html.
# (The farm studies: tests/farm/study_farm.sh.)
set -u
. "$(dirname "$0")/lib.inc"
scene="$src/scenes/cornell-box/scene.xml"
size=(--width 32 --height 32)
# Another seed than the study's, so the reference shares no samples with the methods.
check reference 0 "" -- "$bin" render "$scene" --method bdpt --spp 64 "${size[@]}" --seed 977 --threads 2 --quiet --out "$tmp/ref.exr"
ok=(--methods pt,bdpt --seconds 2 --reference "$tmp/ref.exr" --out "$tmp/s" "${size[@]}" --threads 2)

check help 0 "--target-error" -- "$bin" study --help
check verbs 0 "study" -- "$bin" --help
check unknown-flag 2 "--frob" -- "$bin" study "$scene" "${ok[@]}" --frob
check method-refused 2 "--methods" -- "$bin" study "$scene" "${ok[@]}" --method pt
check spp-refused 2 "--spp" -- "$bin" study "$scene" "${ok[@]}" --spp 4
check halt-noise-refused 2 "--halt-noise" -- "$bin" study "$scene" "${ok[@]}" --halt-noise 0.1
check bad-methods 2 "--methods" -- "$bin" study "$scene" "${ok[@]}" --methods pt,magic
check twice-methods 2 "twice" -- "$bin" study "$scene" "${ok[@]}" --methods pt,pt
check bad-k-method 2 "pcbpt-k0" -- "$bin" study "$scene" "${ok[@]}" --methods bdpt,pcbpt-k0
check bad-rate-method 2 "pcbpt-k1-r0" -- "$bin" study "$scene" "${ok[@]}" --methods bdpt,pcbpt-k1-r0
check bad-rate-method-high 2 "pcbpt-k1-r2" -- "$bin" study "$scene" "${ok[@]}" --methods bdpt,pcbpt-k1-r2
check bad-rate-method-k 2 "pcbpt-kx-r0.5" -- "$bin" study "$scene" "${ok[@]}" --methods bdpt,pcbpt-kx-r0.5
check bad-seconds 2 "--seconds" -- "$bin" study "$scene" "${ok[@]}" --seconds 0
check missing-value 2 "--snapshots" -- "$bin" study "$scene" "${ok[@]}" --snapshots
check bad-snapshots 2 "--snapshots" -- "$bin" study "$scene" "${ok[@]}" --snapshots 0
check bad-target 2 "--target-error" -- "$bin" study "$scene" "${ok[@]}" --target-error -1
check bad-layer 2 "--layer" -- "$bin" study "$scene" "${ok[@]}" --layer s2t2
check bad-render-flag 2 "--max-depth" -- "$bin" study "$scene" "${ok[@]}" --max-depth 0
check no-reference-layer 2 "--layer" -- "$bin" study "$scene" --methods pt --seconds 1 --out "$tmp/s" --layer inner
check no-scene 2 "SCENE" -- "$bin" study "${ok[@]}"
check missing-reference 1 "nope.exr" -- "$bin" study "$scene" --methods pt --seconds 2 --reference "$tmp/nope.exr" --out "$tmp/s" "${size[@]}"
check references-per-scene 2 "one per scene" -- "$bin" study "$scene" "$scene" "${ok[@]}"
check workers-embedded 2 "--workers" -- "$bin" study "$scene" "${ok[@]}" --workers 1,2
check host-token 2 "--token-file" -- "$bin" study "$scene" "${ok[@]}" --host 127.0.0.1:1
check bad-runs 2 "--runs" -- "$bin" study "$scene" "${ok[@]}" --runs 0
check bad-workers 2 "--workers" -- "$bin" study "$scene" "${ok[@]}" --workers 1,x
check bad-reference-render 2 "--reference-render" -- "$bin" study "$scene" --methods pt --seconds 1 --out "$tmp/s" --reference-render bdpt
check both-references 2 "--reference-render" -- "$bin" study "$scene" "${ok[@]}" --reference-render bdpt:1
check size-mismatch 1 "32x32 but the study renders 16x32" -- "$bin" study "$scene" "${ok[@]}" --width 16
[ -e "$tmp/s" ] && { echo "FAIL: a refused study created its output folder"; fail=1; }
check study 0 "needs .*x .* time than pt to reach beauty relMSE" -- "$bin" study "$scene" "${ok[@]}"
grep -q "^inner *bdpt" "$tmp/out" || { echo "FAIL study: table lacks the inner row of bdpt"; cat "$tmp/out"; fail=1; }
for f in ../report.html pt.exr pt.png bdpt.exr bdpt.png study.csv study.json study_beauty.png study_beauty.svg study_inner.png study_inner.svg \
         study_shares.png study_shares.svg study_iterations.png study_iterations.svg; do
  [ -s "$tmp/s/cornell-box/$f" ] || { echo "FAIL study: $f missing"; fail=1; }
done
csv="$tmp/s/cornell-box/study.csv"
[ "$(head -1 "$csv")" = "method,snapshot,seconds,iterations,layer,relmse,rmse,l1,workers,run,worker_seconds,wall_seconds" ] ||
  { echo "FAIL csv: header"; fail=1; }
for m in pt bdpt; do
  # Every snapshot has the five layers of the reference; 2..12 snapshots; the last one at >= 2 s.
  awk -F, -v m="$m" '
    NR > 1 && $1 == m { rows++; snaps[$2]++; layers[$2] = layers[$2] " " $5; last = $2; t = $3;
                        if ($6 !~ /^[0-9.e+-]+$/) bad = "relmse " $6 }
    END {
      n = 0; for (s in snaps) { n++; if (snaps[s] != 5 || layers[s] != " beauty pt nee lt inner") bad = "snapshot " s ": " layers[s] }
      if (n < 2 || n > 12) bad = n " snapshots"
      if (rows != 5 * n) bad = rows " rows"
      if (t + 0 < 2) bad = "last snapshot at " t " s"
      if (bad != "") { print "FAIL csv " m ": " bad; exit 1 }
    }' "$csv" || fail=1
done
if command -v python3 >/dev/null; then
  python3 -c 'import json,sys; d=json.load(open(sys.argv[1])); assert [m["method"] for m in d["methods"]]==["pt","bdpt"]; assert len(d["headline"])==1' \
    "$tmp/s/cornell-box/study.json" || { echo "FAIL json"; fail=1; }
  # Heavy tails of every final image: the largest single iteration over the pixel mean is at
  # least 1 (the mean is no larger than the largest) and at most N (the iterations), ordered
  # p50 <= p99 <= max, at a pixel of the image.
  python3 - "$tmp/s/cornell-box/study.json" <<'PY' || { echo "FAIL tails json"; fail=1; }
import json, sys
d = json.load(open(sys.argv[1]))
for m in d["methods"]:
    t = m["tails"]
    assert t is not None, m["method"]
    n = t["iterations"]
    assert n == m["iterations"] and n >= 2, (m["method"], t)
    assert 0 < t["pixels"] <= 32 * 32, t
    assert 1 - 1e-5 <= t["max_over_mean_p50"] <= t["max_over_mean_p99"] <= t["max_over_mean_max"] <= n * (1 + 1e-5), t
    x, y = t["max_pixel"]
    assert 0 <= x < 32 and 0 <= y < 32, t
PY
  # The error of each iteration: over its first iterations (all of them here), ordered
  # p50 <= p99 <= max, the worst 1% carrying between 1% and all of the summed error, the tail
  # points falling with the fraction.
  python3 - "$tmp/s/cornell-box/study.json" <<'PY' || { echo "FAIL iteration errors json"; fail=1; }
import json, sys
d = json.load(open(sys.argv[1]))
for m in d["methods"]:
    t = m["iteration_errors"]
    assert t is not None and t["grid"] == 8, (m["method"], t)
    n = t["iterations"]
    assert n == min(m["iterations"], 4096) and 0 <= t["worst_iteration"] < m["iterations"], (m["method"], n, t)
    assert 0 < t["p50"] <= t["p90"] <= t["p99"] <= t["max"] and t["mean"] <= t["max"], t
    assert 0.01 * (1 - 1e-9) <= t["top1_percent_share"] <= 1, t
    tail = t["tail"]
    assert len(tail) == min(13, n.bit_length() - 1) and tail == sorted(tail), t
PY
  grep -q "^error of each iteration" "$tmp/out" || { echo "FAIL study: no per-iteration error table"; fail=1; }
  grep -q "<h3>Stability: the error of single iterations</h3>" "$tmp/s/report.html" || { echo "FAIL study: no per-iteration error chart in report.html"; fail=1; }
  # Which strategies carry each final image: the layers' shares of the mean luminance sum to 1
  # (the layers sum to the beauty); pt traces no light paths, bdpt's light tracing and inner
  # connections carry part of the image.
  python3 - "$tmp/s/cornell-box/study.json" <<'PY' || { echo "FAIL shares json"; fail=1; }
import json, sys
d = json.load(open(sys.argv[1]))
for m in d["methods"]:
    s = m["shares"]
    assert s is not None and sorted(s) == ["inner", "lt", "nee", "pt"], (m["method"], s)
    assert all(v >= 0 for v in s.values()) and abs(sum(s.values()) - 1) < 1e-4, (m["method"], s)
    if m["method"] == "pt": assert s["lt"] == 0 and s["inner"] == 0 and s["nee"] > 0.5, s
    if m["method"] == "bdpt": assert s["lt"] > 0 and s["inner"] > 0, s
PY
  # pt weighs its strategies unlike the bdpt reference (its nee layer carries what bdpt's inner
  # and lt carry there): its strategy layers are left out of those comparisons, said before the
  # run and in the table; the beauty compares.
  python3 - "$tmp/s/cornell-box/study.json" <<'PY' || { echo "FAIL unlike layers json"; fail=1; }
import json, sys
d = json.load(open(sys.argv[1]))
m = {x["method"]: x for x in d["methods"]}
assert m["pt"]["weights"] == "pt balance" and m["pt"]["unlike_layers"] == ["pt", "nee", "lt", "inner"], m["pt"]
assert m["bdpt"]["weights"] == "bidirectional balance n_lt=1 n_inner=1" and m["bdpt"]["unlike_layers"] == [], m["bdpt"]
PY
  grep -q "^cornell-box: pt weighs its strategies unlike the reference (pt balance against bidirectional" "$tmp/out" ||
    { echo "FAIL study: no notice of pt's weights"; cat "$tmp/out"; fail=1; }
  grep -Eq "^nee +pt .*\(weighted unlike the reference\)" "$tmp/out" && grep -Eq "^nee +bdpt .* [0-9.]+ s " "$tmp/out" &&
    ! grep -Eq "^nee +bdpt .*unlike" "$tmp/out" ||
    { echo "FAIL study: pt's nee layer compared with bdpt's"; cat "$tmp/out"; fail=1; }
  grep -q "^strategies carrying the final images" "$tmp/out" || { echo "FAIL study: no strategy shares"; fail=1; }
  grep -q "strategies carrying the final images" "$tmp/s/report.html" || { echo "FAIL study: no strategy shares in report.html"; fail=1; }
  grep -q "<h3>Strategies carrying the final images</h3>" "$tmp/s/report.html" || { echo "FAIL study: no strategy shares chart in report.html"; fail=1; }
  grep -q "^heavy tails of the final images" "$tmp/out" || { echo "FAIL study: no heavy-tails table"; fail=1; }
  grep -Eq "^bdpt +1 +[0-9]+ +[0-9]+ " "$tmp/out" || { echo "FAIL study: no heavy-tails line of bdpt"; cat "$tmp/out"; fail=1; }
  grep -q "heavy tails of the final images" "$tmp/s/report.html" || { echo "FAIL study: no heavy tails in report.html"; fail=1; }
fi
[ $fail = 0 ] && echo "ok   study outputs"
# Without a reference: the beauty's error curves are the images' own estimates, and it says so.
check estimated 0 "relMSE estimated from each image's own iterations" -- "$bin" study "$scene" --methods pt,bdpt --seconds 1 \
  --out "$tmp/e" "${size[@]}" --threads 2
awk -F, 'NR > 1 { rows++; if ($5 != "beauty" || $6 !~ /^[0-9.e+-]+$/ || $8 != "nan") bad = $0 }
         END { if (rows < 4 || bad != "") { print "FAIL estimated csv: " rows " rows " bad; exit 1 } }' "$tmp/e/cornell-box/study.csv" || fail=1
if command -v python3 >/dev/null; then
  python3 -c 'import json,sys; d=json.load(open(sys.argv[1])); assert d["reference"] is None and d["errors"] == "estimated"' \
    "$tmp/e/cornell-box/study.json" || { echo "FAIL estimated json"; fail=1; }
fi
[ $fail = 0 ] && echo "ok   study without a reference"
# A reference that is an image of something else is said, where the user reads it (the embedded
# farm's log holds stderr meanwhile): other path lengths, other -D values, other scene files, and
# the study's own seed.
check reference-d3 0 "" -- "$bin" render "$scene" --method bdpt --spp 4 "${size[@]}" --max-depth 3 --seed 5 --threads 2 --quiet \
  --out "$tmp/d3.exr"
check other-reference 0 "d3.exr is of something else than the study renders (max depth 3 in the reference, 11 here" -- "$bin" study "$scene" --methods bdpt --seconds 0.5 \
  --reference "$tmp/d3.exr" --seed 5 --out "$tmp/d" "${size[@]}" --threads 2 -D zeta=1
grep -q "d3.exr was rendered with seed 5 too" "$tmp/err" || { echo "FAIL other-reference: no same-seed warning"; cat "$tmp/err"; fail=1; }
# zeta is no parameter of the scene: said once where the scene is read, and no difference
grep -q "warning: -D zeta=1: the scene names no \$zeta" "$tmp/err" ||
  { echo "FAIL other-reference: no warning of the unused -D"; cat "$tmp/err"; fail=1; }
grep -q "; -D '' in the reference" "$tmp/err" && { echo "FAIL other-reference: an unused -D taken for other values"; cat "$tmp/err"; fail=1; }
grep -q "other scene files" "$tmp/err" && { echo "FAIL other-reference: same scene taken for another"; fail=1; }
cp -r "$(dirname "$scene")" "$tmp/edited" && sed -i 's/value="17, 12, 4"/value="17, 12, 5"/' "$tmp/edited/scene.xml"
check reference-edited 0 "" -- "$bin" render "$tmp/edited/scene.xml" --method bdpt --spp 4 "${size[@]}" --seed 5 --threads 2 --quiet \
  --out "$tmp/edited.exr"
check edited-reference 0 "edited.exr is of something else than the study renders (other scene files in the reference" -- "$bin" study "$scene" --methods bdpt \
  --seconds 0.5 --reference "$tmp/edited.exr" --out "$tmp/d" "${size[@]}" --threads 2
# A reference the study rendered and kept is reused for the same scene and flags, and rendered
# again for another max depth.
check kept-reference 0 "rendering the reference" -- "$bin" study "$scene" --methods bdpt --seconds 0.5 --reference-render bdpt:0.5 \
  --out "$tmp/k" "${size[@]}" --threads 2
check kept-reused 0 "reusing the reference" -- "$bin" study "$scene" --methods bdpt --seconds 0.5 --reference-render bdpt:0.5 \
  --out "$tmp/k" "${size[@]}" --threads 2
check kept-stale 0 "is of something else than the study renders (max depth 11 in the reference, 4 here): rendering it again" -- "$bin" study "$scene" \
  --methods bdpt --seconds 0.5 --reference-render bdpt:0.5 --max-depth 4 --out "$tmp/k" "${size[@]}" --threads 2
grep -q "warning: .* max depth" "$tmp/err" && { echo "FAIL kept-stale: the stale reference was used"; fail=1; }
# Method auto in a study: its pilot runs as farm jobs charged to its own budget, so its curve
# starts after the pilot's worker-seconds and ends at the same budget as bdpt's; study.json
# says what the pilot chose.
check auto 0 "auto chose " -- "$bin" study "$scene" --methods bdpt,pcbpt-k2,auto --seconds 2 --out "$tmp/a" "${size[@]}" --threads 2
if command -v python3 >/dev/null; then
  python3 - "$tmp/a/cornell-box/study.json" <<'PY' || { echo "FAIL auto json"; fail=1; }
import json, sys
d = json.load(open(sys.argv[1]))
m = {x["method"]: x for x in d["methods"]}
a, b = m["auto"], m["bdpt"]
assert m["pcbpt-k2"]["snapshots"], m["pcbpt-k2"]
assert a["auto"].startswith("chose "), a["auto"]
pilot = float(a["auto"].split("(pilot ")[1].split(" s)")[0])
assert pilot > 0, pilot
first, last = a["snapshots"][0], a["snapshots"][-1]
# every point comes after the pilot; the whole budget (pilot included) is bdpt's, within one
# upload of overrun
assert first["worker_seconds"] > pilot, (first, pilot)
assert abs(last["worker_seconds"] - b["snapshots"][-1]["worker_seconds"]) < 1.0, (last, b["snapshots"][-1])
# every candidate's job ran at least the 2 iterations its variance needs, however small its
# slice of worker-seconds (Settings.min_iterations)
its = [int(part.split(" it ")[1]) for part in a["auto"].split("; ")[1:]]
assert len(its) >= 3 and min(its) >= 2, a["auto"]
assert "; bdpt eff " in a["auto"] and "; pt eff " in a["auto"] and "; pcbpt K=1 eff " in a["auto"], a["auto"]
PY
fi
[ $fail = 0 ] && echo "ok   study with auto"
exit $fail
