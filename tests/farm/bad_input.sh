# bad_input.sh: wrong token, garbage, oversized and truncated frames, and a valid frame of the
# wrong type are each refused with a log line while a concurrent job still completes; a scene
# the workers would refuse is refused by submit before it reaches the farm.
. "$(dirname "$0")/lib.inc"
start_coord
start_worker w1
J=$("$B/pcbpt-coord" submit "$S/scenes/furnace/scene.xml" --spp 16 --width 64 --height 64 $H | tail -1)
echo "wrong-token-entirely" > "$T/bad"; chmod 600 "$T/bad"
"$B/pcbpt-coord" list --host 127.0.0.1:$PORT --token-file "$T/bad" 2>/dev/null && fail "wrong token accepted"
python3 - "$PORT" "$S/proto/wire_frame.h" <<'PY'
import socket, struct, sys, time, os, re
port = int(sys.argv[1])
version = int(re.search(r"PC_WIRE_PROTOCOL_VERSION (\d+)u", open(sys.argv[2]).read()).group(1))
def send(b, wait=0.3):
    s = socket.create_connection(("127.0.0.1", port)); s.sendall(b); time.sleep(wait); s.close()
def frame(b): return struct.pack(">I", len(b)) + b
# a worker that answers the challenge with a MAC made from the wrong token
s = socket.create_connection(("127.0.0.1", port))
hello = b"\x08" + bytes([version]) + b"\x10\x01\x2a\x20" + os.urandom(32)
s.sendall(frame(b"\x0a" + bytes([len(hello)]) + hello)); time.sleep(0.3); s.recv(4096)
auth = b"\x0a\x20" + os.urandom(32)
s.sendall(frame(b"\x1a" + bytes([len(auth)]) + auth)); time.sleep(0.3); s.close()
send(os.urandom(64))                                  # random bytes
send(struct.pack(">I", (1 << 20) + 1))                # over the limit
send(struct.pack(">I", 100) + b"\x0a\x02")            # truncated, then closed
send(struct.pack(">I", 2) + b"\x2a\x00")              # a valid work_request before hello
PY
# a scene the workers would refuse is refused by submit, in one line naming it, and sent nowhere
mkdir -p "$T/dark"
jobs_before=$("$B/pcbpt-coord" list $H | wc -l)
printf '<scene version="0.6.0"><sensor type="perspective"><float name="fov" value="45"/></sensor><shape type="cube"/></scene>' > "$T/dark/scene.xml"
"$B/pcbpt-coord" submit "$T/dark/scene.xml" --spp 1 $H > "$T/dark.out" 2> "$T/dark.err" && fail "a scene without an emitter was submitted"
[ "$(wc -l < "$T/dark.err")" = 1 ] && grep -q "dark/scene.xml: the scene has no emitter" "$T/dark.err" || fail "submit's refusal: $(cat "$T/dark.err")"
[ "$("$B/pcbpt-coord" list $H | wc -l)" = "$jobs_before" ] || fail "the refused scene became a job"
timeout 50 "$B/pcbpt-coord" wait "$J" $H >/dev/null || fail "job did not complete"
grep -q "wrong token" "$T/coord.log" || fail "no log line for the wrong token"
grep -q "exceeds the limit" "$T/coord.log" || fail "no log line for the oversized frame"
grep -q "expected hello, got work_request" "$T/coord.log" || fail "no log line for the wrong message type"
echo PASS
