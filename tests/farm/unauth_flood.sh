# unauth_flood.sh: 300 unauthenticated connections each sending most of a 1 MiB frame (issue
# 10, failure 5) grow the coordinator by little (frames before authentication are bounded to
# a few KiB, and so is the number of peers authenticating at once), a client still gets its
# status during and after, and the memory is returned when they go.
. "$(dirname "$0")/lib.inc"
start_coord
rss() { awk '/^VmRSS/ { print int($2 / 1024) }' "/proc/$COORD/status"; }
BASE=$(rss)
python3 - "$PORT" "$COORD" "$B/pcbpt-coord" "$T/tok" <<'PY' || fail "flood"
import socket, struct, sys, time, subprocess
port, pid, coord, tok = int(sys.argv[1]), sys.argv[2], sys.argv[3], sys.argv[4]
def rss():
    for l in open(f"/proc/{pid}/status"):
        if l.startswith("VmRSS"): return int(l.split()[1]) // 1024
conns, payload = [], b"\x0a" * (400 << 10)
for _ in range(300):
    try:
        s = socket.create_connection(("127.0.0.1", port)); s.setblocking(False)
        conns.append(s)
        s.send(struct.pack(">I", (1 << 20) - 16))
        try: s.send(payload)
        except (BlockingIOError, ConnectionError): pass
    except OSError: pass
time.sleep(1)
peak = rss()
print(f"{len(conns)} connections sent {len(payload) >> 10} KiB each; coordinator RSS {peak} MB")
st = subprocess.run([coord, "list", "--host", f"127.0.0.1:{port}", "--token-file", tok], capture_output=True, text=True)
if st.returncode != 0: print("status during the flood failed:", st.stderr); sys.exit(1)
for s in conns: s.close()
open(sys.argv[4] + ".peak", "w").write(str(peak))
PY
PEAK=$(cat "$T/tok.peak")
sleep 1
AFTER=$(rss)
echo "coordinator RSS: $BASE MB before, $PEAK MB during, $AFTER MB after"
[ $((PEAK - BASE)) -lt 40 ] || fail "the coordinator grew by $((PEAK - BASE)) MB for unauthenticated peers"
[ $((AFTER - BASE)) -lt 20 ] || fail "the coordinator kept $((AFTER - BASE)) MB after they left"
"$B/pcbpt-coord" list $H >/dev/null || fail "status after the flood"
echo PASS
