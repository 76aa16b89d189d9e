# auto_farm.sh: `submit --method auto` on a two-worker farm: the pilot's candidates run as
# short jobs of their own that both workers render, the final job carries the winner's
# settings (BDPT, PT or PCBPT) and the pilot's report in `status --json` ("auto") and in the EXR
# header (pcbpt.auto). The job's iteration count is its own, and its image mixes in the films
# of the pilot's candidates rendered whatever the data says (BDPT, K = 1, K = 2, and K = 1
# with the raised MIS count; not PT's) with the weight fixed at submission: a / (a + 64), a their
# iterations over their number (pc_pilot_counted_share: they share their paths, so their mix is
# worth about one of them; coordinator/job_prior.c).
# A second job's pilot films survive a SIGKILL of the coordinator (the saved prior).
. "$(dirname "$0")/lib.inc"
start_coord
for w in w1 w2; do start_worker $w; done
J=$("$B/pcbpt-coord" submit "$S/scenes/cornell-box/scene.xml" --method auto --spp 64 --width 32 --height 32 $H 2>"$T/submit.err" | tail -1) \
  || fail "submit: $(cat "$T/submit.err")"
grep -q "auto: chose " "$T/submit.err" || fail "submit did not report the pilot's choice: $(cat "$T/submit.err")"
timeout 60 "$B/pcbpt-coord" wait "$J" $H >/dev/null || fail "wait"
"$B/pcbpt-coord" status "$J" $H --json > "$T/st.json"
python3 - "$T/st.json" <<'PY' || fail "status --json of the final job: $(cat "$T/st.json")"
import json, sys
j = json.load(open(sys.argv[1]))
assert j["auto"] and j["auto"].startswith("chose "), j
assert j["method"] in ("bdpt", "pt", "pcbpt"), j
assert j["iterations"] == 64, j
PY
"$B/pcbpt-coord" list $H --json > "$T/list.json"
python3 - "$T/list.json" "$J" <<'PY' || fail "pilot jobs: $(cat "$T/list.json")"
import json, sys
jobs = json.load(open(sys.argv[1]))
pilots = [j for j in jobs if "[auto pilot: " in j["name"]]
assert len(pilots) >= 4, pilots            # bdpt, pt, pcbpt K=1, K=2 at least
assert all(j["state"] == "done" and j["id" if "id" in j else "job"] < int(sys.argv[2]) for j in pilots), pilots
assert any(j["name"].endswith("[auto pilot: bdpt]") for j in pilots), pilots
assert any(j["name"].endswith("[auto pilot: pt]") for j in pilots), pilots
PY
for p in $(python3 -c "import json,sys; print(' '.join(str(j['job']) for j in json.load(open('$T/list.json')) if '[auto pilot' in j['name']))"); do
  grep -q "job $p: range .* -> w" "$T/coord.log" || fail "pilot job $p was not rendered by a worker"
done
"$B/pcbpt-coord" fetch "$J" --out "$T/out.exr" $H >/dev/null || fail "fetch"
grep -aq "pcbpt.auto" "$T/out.exr" || fail "no pcbpt.auto in the image header"
grep -q "job $J: --method auto chose " "$T/coord.log" || fail "the coordinator's log does not say what auto chose"
grep -q "job $J: its image includes its pilot's" "$T/coord.log" || fail "the job did not take its pilot's films"
# the pilot's weight: its amount a (pcbpt.pilot_amount), its counted iterations (3 or 4 candidates
# of at least 2 each, pcbpt.pilot_iterations) over their number, against the 64 of the job
check_weight() { # exr spp
  read -r _ w a pi it < <("$B/tests/farm_tool" exr "$1" pcbpt.pilot_weight pcbpt.pilot_amount pcbpt.pilot_iterations pcbpt.iterations)
  python3 -c "import sys; w, a, pi, n, spp = map(float, sys.argv[1:]); sys.exit(not (a >= 2 and pi in (3 * a, 4 * a) and n == spp and abs(w - a / (a + spp)) < 1e-9))" \
    "$w" "$a" "$pi" "$it" "$2" || fail "$1: pilot weight $w with amount $a, $pi pilot iterations and $it of the job's (want a/(a+$2), a = its iterations over 3 or 4)"
}
check_weight "$T/out.exr" 64
# a long job's pilot films are saved with it, so a restarted coordinator still mixes them in
J2=$("$B/pcbpt-coord" submit "$S/scenes/cornell-box/scene.xml" --method auto --spp 3000 --width 32 --height 32 $H 2>"$T/submit2.err" | tail -1) \
  || fail "submit 2: $(cat "$T/submit2.err")"
for _ in $(seq 100); do [ -f "$T/data/jobs/$J2/prior" ] && break; sleep 0.1; done
[ -f "$T/data/jobs/$J2/prior" ] || fail "job $J2 saved no prior"
[ "$(job_field "$J2" state)" = running ] || fail "job $J2 was $(job_field "$J2" state) at the kill: nothing tested"
kill -9 "$COORD"
sleep 1
start_coord "$PORT"
timeout 100 "$B/pcbpt-coord" wait "$J2" $H >/dev/null || fail "wait 2"
"$B/pcbpt-coord" fetch "$J2" --out "$T/out2.exr" $H >/dev/null || fail "fetch 2"
check_weight "$T/out2.exr" 3000
echo PASS
