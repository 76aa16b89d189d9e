# disk_full.sh: the data dir's filesystem (a 4 MB tmpfs; needs root to mount, else the test
# is skipped with a message) fills up mid-job (issue 10, failure 2). A full disk pauses the
# job instead of failing it: it stays running with the reason in `status` and its workers
# keep their unacknowledged uploads; the coordinator is killed while the disk is full and
# restarted once space is freed, and the job (--time 4) resumes from its last good
# checkpoint and ends with an image exactly that of the iterations it counts; a second job then completes (no worker is wedged).
. "$(dirname "$0")/lib.inc"
mkdir -p "$T/mnt"
if ! mount -t tmpfs -o size=4m tmpfs "$T/mnt" 2>"$T/mount.err"; then
  echo "SKIP: cannot mount a small tmpfs here ($(cat "$T/mount.err")); run as root to test a full data dir"
  exit 77
fi
CLEANUP+=("umount '$T/mnt'")
DATA="$T/mnt/data"
start_coord
start_worker w1
SC="$S/scenes/furnace/scene.xml"
J=$("$B/pcbpt-coord" submit "$SC" --method pt --time 4 --width 48 --height 48 $H | tail -1)
for _ in $(seq 50); do [ "$(job_field "$J" iterations)" -gt 0 ] && break; sleep 0.1; done
dd if=/dev/zero of="$T/mnt/fill" bs=1M 2>/dev/null || true
# The next checkpoint finds the disk full; on a busy machine that may take a few seconds.
for _ in $(seq 150); do job_field "$J" error | grep -q "waiting for the data dir" && break; sleep 0.1; done
# running, or stopping if its 4 s ran out meanwhile: paused either way, not failed
case $(job_field "$J" state) in running|stopping) ;; *) fail "job $(job_field "$J" state) on a full disk: $(job_field "$J" error)" ;; esac
job_field "$J" error | grep -q "waiting for the data dir" || fail "no reason in status: '$(job_field "$J" error)'"
echo "full disk: job $J $(job_field "$J" state) at $(job_field "$J" iterations) iterations: $(job_field "$J" error)"
kill -9 "$COORD"
rm -f "$T/mnt/fill"
sleep 0.5
start_coord "$PORT"
timeout 40 "$B/pcbpt-coord" wait "$J" $H >/dev/null || fail "the job did not complete after space came back"
N=$(job_field "$J" iterations)
CK=$(ls "$DATA/jobs/$J"/ckpt.* | sort -t. -k2 -n | tail -1)
"$B/tests/farm_tool" exact "$CK" "$SC" --method pt --spp "$N" --width 48 --height 48 >"$T/exact.out" || { cat "$T/exact.out"; fail "image not exact"; }
J2=$("$B/pcbpt-coord" submit "$SC" --method pt --spp 30 --width 16 --height 16 $H | tail -1)
timeout 20 "$B/pcbpt-coord" wait "$J2" $H >/dev/null || fail "a worker is wedged: the next job did not complete"
grep -E "paused until|writable again" "$T/coord.log"
echo PASS
