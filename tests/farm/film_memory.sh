# film_memory.sh: a job whose film is larger than the coordinator may hold (--max-film-mb, by
# default the machine's memory) is refused at submit in one line and never becomes a job; a
# worker whose films for a job would be larger than it may make fails the job's ranges with
# that reason (and is not killed making them), so the job fails naming it; and jobs whose films
# do not fit together run as films are freed: a study's three interleaved 256x256 jobs under
# --max-film-mb 20 (two films at a time) all reach their budgets.
. "$(dirname "$0")/lib.inc"
COORD_ARGS="--max-film-mb 20" start_coord
jobs_before=$("$B/pcbpt-coord" list $H | wc -l)
# 512x512: six layers of 6 MiB, 36 MiB
"$B/pcbpt-coord" submit "$S/scenes/furnace/scene.xml" --spp 4 --width 512 --height 512 $H >"$T/big.out" 2>"$T/big.err" &&
  fail "a 512x512 job was accepted under --max-film-mb 20"
[ "$(wc -l <"$T/big.err")" = 1 ] && grep -q "the film of a 512x512 job takes 36 MB on the coordinator, more than its 20 MB" "$T/big.err" ||
  fail "submit's refusal: $(cat "$T/big.err")"
[ "$("$B/pcbpt-coord" list $H | wc -l)" = "$jobs_before" ] || fail "the refused job was listed"
# 256x256: 9 MiB on the coordinator; on a worker of one thread 9 MiB pending, 6 MiB of scratch
# and 1.5 MiB of splats, over its 10 MB
J=$("$B/pcbpt-coord" submit "$S/scenes/furnace/scene.xml" --spp 4 --width 256 --height 256 $H | tail -1)
"$B/pcbpt-worker" --connect 127.0.0.1:$PORT --token-file "$T/tok" --threads 1 --name small --cache-dir "$T/cache-small" \
  --max-film-mb 10 >>"$T/w-small.log" 2>&1 &
PIDS+=("$!")
for _ in $(seq 150); do [ "$(job_field "$J" state)" = failed ] && break; sleep 0.1; done
[ "$(job_field "$J" state)" = failed ] || fail "job $(job_field "$J" state) on a worker that cannot hold its films"
job_field "$J" error | grep -q "the films of a 256x256 render on 1 thread take 17 MB, more than this worker's 10 MB" ||
  fail "job error: $(job_field "$J" error)"
kill -0 "${PIDS[-1]}" 2>/dev/null || fail "the worker exited"
kill "${PIDS[-1]}"
start_worker w1
"$B/pcbpt-coord" study "$S/scenes/furnace/scene.xml" --methods pt,bdpt,lt --seconds 0.5 --width 256 --height 256 \
  --out "$T/study" $H >"$T/study.out" 2>&1 || fail "study: $(tail -3 "$T/study.out")"
grep -q "waits for memory: its film takes 9 MB, and the running jobs' hold 18 of 20 MB" "$T/coord.log" ||
  fail "no job waited for memory"
for m in pt bdpt lt; do grep -q "^$m," "$T/study/furnace/study.csv" || fail "no $m row in study.csv"; done
echo PASS
