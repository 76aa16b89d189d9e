# wire_sealed.sh: confidentiality on the wire. Two workers and the client verbs reach the
# coordinator through a recording relay (relay.py) while a job renders a copy of cornell-box
# carrying a unique comment and material id. The job completes with exact counts and sums; the
# captured bytes hold the clear handshake (the capture works) but no trace of the scene (its
# marker strings, any 24-byte window of the bundle the coordinator stored) or of the film (the
# zstd magic that starts every upload, the EXR magic, any 24-byte window of the fetched image).
# The bundle travels zstd-compressed, so its windows, not the markers, are the decisive check:
# with sealing switched off this test reports both magics and every bundle and image window.
# Each worker's first connection has one bit flipped in its first sealed frame, one towards the
# coordinator, one from it: that connection alone is dropped and the worker reconnects.
# Then: a recorded AuthResponse replayed on a new connection is refused; a version-2 hello is
# refused with a clear message; a sealed frame with one flipped bit drops that connection only.
. "$(dirname "$0")/lib.inc"
start_coord
python3 "$S/tests/farm/relay.py" "$PORT" "$T/rport" "$T/cap" 2>>"$T/relay.log" &
PIDS+=("$!")
for _ in $(seq 50); do [ -s "$T/rport" ] && break; sleep 0.1; done
RPORT=$(cat "$T/rport"); HR="--host 127.0.0.1:$RPORT --token-file $T/tok"
MARK=pcbpt-unpublished-scene-7f3a9c1e; MAT=pcbpt_secret_material_7f3a9c1e
cp -r "$S/scenes/cornell-box" "$T/scene"
sed -i "s|<scene version=\"0.6.0\">|<scene version=\"0.6.0\">\n  <!-- $MARK -->|; s|<bsdf type=\"diffuse\"><rgb name=\"reflectance\" value=\"0.63, 0.065, 0.05\"/>|<bsdf type=\"diffuse\" id=\"$MAT\"><rgb name=\"reflectance\" value=\"0.63, 0.065, 0.05\"/>|" "$T/scene/scene.xml"
grep -q "$MARK" "$T/scene/scene.xml" && grep -q "$MAT" "$T/scene/scene.xml" || fail "scene markers not added"
# each worker's first connection is tampered with: wsealed1's first sealed frame to the
# coordinator and the coordinator's first sealed frame to wsealed2 have one bit flipped; each
# side drops that connection only, and the workers reconnect and render their share
for w in wsealed1 wsealed2; do
  if [ $w = wsealed1 ]; then touch "$T/cap/corrupt"; else touch "$T/cap/corrupt-s2c"; fi
  "$B/pcbpt-worker" --connect 127.0.0.1:$RPORT --token-file "$T/tok" --threads 1 --name $w --cache-dir "$T/cache-$w" >>"$T/$w.log" 2>&1 &
  PIDS+=("$!")
  for _ in $(seq 50); do [ -e "$T/cap/corrupt" ] || [ -e "$T/cap/corrupt-s2c" ] || break; sleep 0.1; done
done
for _ in $(seq 100); do
  [ "$(grep -c "connected to" "$T/wsealed1.log")" -ge 2 ] && [ "$(grep -c "connected to" "$T/wsealed2.log")" -ge 2 ] && break
  sleep 0.1
done
[ "$(grep -c "connected to" "$T/wsealed1.log")" -ge 2 ] && [ "$(grep -c "connected to" "$T/wsealed2.log")" -ge 2 ] \
  || fail "a worker did not reconnect after its tampered connection"
J=$("$B/pcbpt-coord" submit "$T/scene/scene.xml" --spp 16 --method pt --width 64 --height 64 $HR | tail -1)
timeout 60 "$B/pcbpt-coord" wait "$J" $HR >/dev/null || fail "wait"
[ "$(job_field "$J" iterations)" = 16 ] || fail "iterations $(job_field "$J" iterations) != 16"
CK=$(ls "$T/data/jobs/$J"/ckpt.* | sort -t. -k2 -n | tail -1)
"$B/tests/farm_tool" exact "$CK" "$T/scene/scene.xml" --spp 16 --method pt --width 64 --height 64 \
  || fail "the farm's sums differ from a single-process render"
"$B/pcbpt-coord" fetch "$J" --out "$T/out.exr" $HR >/dev/null || fail "fetch"
for w in wsealed1 wsealed2; do grep -q "range .* -> $w" "$T/coord.log" || fail "worker $w got no range"; done
grep -q "closing: seal: frame 0 does not authenticate" "$T/coord.log" || fail "the coordinator took wsealed1's tampered frame"
grep -q "closing: seal: frame 0 does not authenticate" "$T/wsealed2.log" || fail "wsealed2 took the coordinator's tampered frame"
python3 - "$T/cap" "$T/data/bundles" "$T/out.exr" "$MARK" "$MAT" <<'PY' || fail "capture check"
import collections, glob, os, sys
cap, bundles, exr, mark, mat = sys.argv[1:]
streams = {p: open(p, "rb").read() for p in glob.glob(cap + "/*.c2s") + glob.glob(cap + "/*.s2c")}
data = b"\0".join(streams.values())
blobs = [open(p, "rb").read() for p in glob.glob(bundles + "/*") if not os.path.basename(p).startswith(".")]
image = open(exr, "rb").read()
assert len(blobs) == 1 and len(image) > 1000, (len(blobs), len(image))
# the capture works: the clear hellos carry the workers' names, and films and bundles went by
assert b"wsealed1" in data and b"wsealed2" in data, "capture misses the clear handshake"
assert len(data) > len(blobs[0]) + len(image), ("capture too small", len(data))
def windows(b, k=24, count=64):
    step = max(1, (len(b) - k) // count)
    return [b[i:i + k] for i in range(0, len(b) - k, step)]
leaks = [("scene marker", mark.encode()), ("material id", mat.encode()),
         ("zstd magic", bytes.fromhex("28b52ffd")), ("EXR magic", bytes.fromhex("762f3101"))]
leaks += [("bundle bytes", w) for w in windows(blobs[0])] + [("image bytes", w) for w in windows(image)]
found = sorted(collections.Counter(name for name, pat in leaks if pat in data).items())
# 4-byte magics could match ciphertext by chance with probability ~ len/2^32 each
print("captured %d bytes in %d streams; bundle %d bytes, image %d bytes; %d patterns checked, leaks: %s"
      % (len(data), len(streams), len(blobs[0]), len(image), len(leaks), found or "none"))
sys.exit(1 if found else 0)
PY
python3 - "$PORT" "$T/cap" "$S/proto/wire_frame.h" <<'PY' || fail "replay / version checks"
import glob, re, socket, struct, sys
port, cap = int(sys.argv[1]), sys.argv[2]
version = int(re.search(r"PC_WIRE_PROTOCOL_VERSION (\d+)u", open(sys.argv[3]).read()).group(1))
def frames(b):
    out = []
    while len(b) >= 4:
        n = struct.unpack(">I", b[:4])[0]; out.append(b[:4 + n]); b = b[4 + n:]
    return out
def recv_frame(s):
    b = b""
    while len(b) < 4 or len(b) < 4 + struct.unpack(">I", b[:4])[0]:
        d = s.recv(1 << 16)
        if not d: return None
        b += d
    return b
# a worker's recorded hello and auth_response, replayed on a new connection
rec = next(frames(open(p, "rb").read()) for p in sorted(glob.glob(cap + "/*.c2s"))
           if b"wsealed1" in open(p, "rb").read()[:200])
assert rec[0][4] == 0x0a and rec[1][4] == 0x1a, "recorded frames are not hello, auth_response"
s = socket.create_connection(("127.0.0.1", port)); s.settimeout(10)
s.sendall(rec[0]); ch = recv_frame(s)
assert ch and ch[4] == 0x12, "no challenge to the replayed hello"
s.sendall(rec[1]); res = recv_frame(s)
assert res and res[4] == 0x22 and b"wrong token" in res, "replayed auth_response not refused: %r" % res
assert recv_frame(s) is None, "connection still open after a refused replay"
# a version-2 hello is refused with the versions named
hello = b"\x08\x02\x10\x01\x2a\x20" + bytes(32)
s = socket.create_connection(("127.0.0.1", port)); s.settimeout(10)
s.sendall(struct.pack(">I", len(hello) + 2) + b"\x0a" + bytes([len(hello)]) + hello)
err = recv_frame(s)
want = b"protocol version 2, this coordinator speaks %d" % version
assert err and want in err, "v2 hello: %r" % err
print("replay refused; v2 hello refused: %s" % want.decode())
PY
grep -q "authentication failed (wrong token)" "$T/coord.log" || fail "no log line for the replayed auth_response"
grep -q "protocol version 2, this coordinator speaks" "$T/coord.log" || fail "no log line for the v2 hello"
# one flipped bit in a sealed frame: that connection is dropped with a reason, nothing else
touch "$T/cap/corrupt"
"$B/pcbpt-coord" status "$J" $HR >/dev/null 2>&1 && fail "a corrupted sealed frame was accepted"
[ -e "$T/cap/corrupt" ] && fail "the relay did not corrupt the status connection"
[ "$(grep -c "closing: seal: frame 0 does not authenticate" "$T/coord.log")" = 2 ] || fail "no log line for the corrupted frame"
[ "$(job_field "$J" iterations)" = 16 ] || fail "the coordinator does not answer after the corrupted frame"
echo PASS
