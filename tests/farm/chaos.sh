# chaos.sh: random faults (issue 10). Each trial renders one job on a coordinator and two
# workers while 3 random events strike: SIGKILL of the coordinator (restarted on its port) or
# of a worker (restarted), or SIGSTOP of either for 0.5-6 s (longer than --heartbeat-timeout
# 5, so a stopped worker is dropped and its range re-assigned). Every trial must end done with
# exactly the requested iterations and an image exactly that of a single-process render of
# them. CHAOS_TRIALS (3) trials; CHAOS_SEED fixes the random events (printed for a rerun).
. "$(dirname "$0")/lib.inc"
TRIALS=${CHAOS_TRIALS:-3}
SEED=${CHAOS_SEED:-$(( $(date +%s) % 100000 ))}
RANDOM=$SEED
SPP=${CHAOS_SPP:-800}
SC="$S/scenes/furnace/scene.xml"
echo "chaos: $TRIALS trials, seed $SEED, furnace pt 32x32, $SPP iterations"
pause() { sleep "$(( $1 / 10 )).$(( $1 % 10 ))"; } # tenths of a second
for trial in $(seq "$TRIALS"); do
  DATA="$T/data-$trial"
  : >"$T/coord.log"
  start_coord
  start_worker w1; W[1]=$LAST
  start_worker w2; W[2]=$LAST
  t0=$(date +%s.%N)
  J=$("$B/pcbpt-coord" submit "$SC" --method pt --spp "$SPP" --width 32 --height 32 $H | tail -1)
  events=""
  for _ in 1 2 3; do
    pause $(( 2 + RANDOM % 5 ))
    [ "$(job_field "$J" state 2>/dev/null || echo running)" = done ] && break
    target=$(( RANDOM % 3 )) kind=$(( RANDOM % 2 )) len=$(( 5 + RANDOM % 56 ))
    if [ "$target" = 0 ]; then
      if [ "$kind" = 0 ]; then
        kill -9 "$COORD"; wait "$COORD" 2>/dev/null || true; pause 3; start_coord "$PORT"; events+=" kill-coord"
      else
        kill -STOP "$COORD"; pause "$len"; kill -CONT "$COORD"; events+=" stop-coord-${len}ds"
      fi
    else
      if [ "$kind" = 0 ]; then
        kill -9 "${W[$target]}"; wait "${W[$target]}" 2>/dev/null || true; start_worker "w$target"; W[$target]=$LAST
        events+=" kill-w$target"
      else
        kill -STOP "${W[$target]}"; pause "$len"; kill -CONT "${W[$target]}"; events+=" stop-w$target-${len}ds"
      fi
    fi
  done
  timeout 90 "$B/pcbpt-coord" wait "$J" $H >/dev/null 2>"$T/wait.err" || fail "trial $trial (seed $SEED, events:$events): job did not complete"
  N=$(job_field "$J" iterations)
  [ "$N" = "$SPP" ] || fail "trial $trial (seed $SEED, events:$events): $N iterations != $SPP"
  CK=$(ls "$DATA/jobs/$J"/ckpt.* | sort -t. -k2 -n | tail -1)
  "$B/tests/farm_tool" exact "$CK" "$SC" --method pt --spp "$SPP" --width 32 --height 32 >"$T/exact.out" \
    || { cat "$T/exact.out"; fail "trial $trial (seed $SEED, events:$events): image not exact"; }
  echo "trial $trial: exact, $SPP iterations in $(echo "$(date +%s.%N) - $t0" | bc | cut -c1-5) s; events:$events"
  kill -9 "$COORD" "${W[1]}" "${W[2]}" 2>/dev/null || true
  wait "$COORD" "${W[1]}" "${W[2]}" 2>/dev/null || true
done
echo PASS
