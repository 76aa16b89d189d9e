# bad_bundle.sh: scene bundles a worker must refuse to unpack (a "../" path, an absolute path,
# no scene file, a duplicate file, a file/directory clash, not protobuf) fail their ranges, so
# each job fails after three such ranges with the reason in `status`, instead of the worker
# reconnecting forever and starving every later job (issue 10, failure 4); so does a job whose
# bundle is gone from the coordinator's data dir; a good job then completes.
. "$(dirname "$0")/lib.inc"
start_coord
J0=$("$B/pcbpt-coord" submit "$S/scenes/cornell-box/scene.xml" --method pt --spp 40 --width 16 --height 16 $H | tail -1)
rm "$T/data/bundles/"*
start_worker w1
start_worker w2
JOBS=()
for kind in dotdot absolute noscene dup clash notproto; do
  JOBS+=("$("$B/tests/farm_tool" badbundle 127.0.0.1:$PORT "$T/tok" $kind)") || fail "badbundle $kind"
done
for J in "${JOBS[@]}"; do
  for _ in $(seq 100); do [ "$(job_field "$J" state)" = failed ] && break; sleep 0.1; done
  [ "$(job_field "$J" state)" = failed ] || fail "job $J on a bad bundle is $(job_field "$J" state)"
  echo "job $J: $(job_field "$J" error)"
  job_field "$J" error | grep -q "scene bundle refused" || fail "job $J: no reason in status"
done
for _ in $(seq 100); do [ "$(job_field "$J0" state)" = failed ] && break; sleep 0.1; done
job_field "$J0" error | grep -q "cannot be read from the data dir" || fail "job $J0 without its bundle: $(job_field "$J0" state) $(job_field "$J0" error)"
J=$("$B/pcbpt-coord" submit "$S/scenes/furnace/scene.xml" --method pt --spp 40 --width 32 --height 32 $H | tail -1)
timeout 20 "$B/pcbpt-coord" wait "$J" $H >/dev/null || fail "the good job did not complete"
[ "$(job_field "$J" iterations)" = 40 ] || fail "iterations $(job_field "$J" iterations) != 40"
grep -q "closing: bad scene bundle" "$T/coord.log" "$T/w1.log" "$T/w2.log" && fail "the worker still drops its connection"
echo PASS
