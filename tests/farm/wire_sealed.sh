# wire_sealed.sh: confidentiality on the wire. Two workers and the client verbs reach the
# coordinator through a recording relay (relay.py) while a job renders a copy of cornell-box
# carrying a unique comment and material id. The job completes with exact counts and sums; the
# captured bytes hold the job's traffic (the clear handshake, frames as large as the submitted
# and distributed bundle, at least one per merged upload, the fetched image; the film is large
# enough that uploads and the fetch take several sealed chunks) but no trace of the scene (its
# marker strings, any 24-byte window of the bundle the coordinator stored) or of the film (the
# zstd magic that starts every upload, seen twice or more; the EXR magic with its version field;
# any 24-byte window of the fetched image).
# The bundle travels zstd-compressed, so its windows, not the markers, are the decisive check:
# with sealing switched off (and the tampering skipped) this test reports both magics and every
# bundle and image window.
# Each worker's first connection has one bit flipped in its first sealed frame, one towards the
# coordinator, one from it: that connection alone is dropped and the worker reconnects.
# Then the handshake is replay-proof: a recorded hello and AuthResponse replayed on a new
# connection are refused (while an honest handshake computed by the test from the token is
# accepted), a sealed frame recorded on one connection is refused on another, and a client and a
# worker refuse an impostor that replays a recorded Challenge. A hello of the previous protocol
# version (unsealed) is refused with a clear message; a sealed frame with one flipped bit drops
# that connection only.
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
J=$("$B/pcbpt-coord" submit "$T/scene/scene.xml" --spp 16 --method pt --width 160 --height 160 $HR | tail -1)
timeout 60 "$B/pcbpt-coord" wait "$J" $HR >/dev/null || fail "wait"
[ "$(job_field "$J" iterations)" = 16 ] || fail "iterations $(job_field "$J" iterations) != 16"
CK=$(ls "$T/data/jobs/$J"/ckpt.* | sort -t. -k2 -n | tail -1)
"$B/tests/farm_tool" exact "$CK" "$T/scene/scene.xml" --spp 16 --method pt --width 160 --height 160 \
  || fail "the farm's sums differ from a single-process render"
"$B/pcbpt-coord" fetch "$J" --out "$T/out.exr" $HR >/dev/null || fail "fetch"
for w in wsealed1 wsealed2; do grep -q "range .* -> $w" "$T/coord.log" || fail "worker $w got no range"; done
grep -q "closing: seal: frame 0 does not authenticate" "$T/coord.log" || fail "the coordinator took wsealed1's tampered frame"
grep -q "closing: seal: frame 0 does not authenticate" "$T/wsealed2.log" || fail "wsealed2 took the coordinator's tampered frame"
UPLOADS=$(sed -n "s/.*job $J: done, .*(\([0-9]*\) uploads merged.*/\1/p" "$T/coord.log")
[ "${UPLOADS:-0}" -ge 2 ] || fail "the coordinator merged ${UPLOADS:-no} uploads"
python3 - "$T/cap" "$T/data/bundles" "$T/out.exr" "$MARK" "$MAT" "$UPLOADS" <<'PY' || fail "capture check"
import collections, glob, os, struct, sys
cap, bundles, exr, mark, mat, uploads = sys.argv[1:]
streams = {p: open(p, "rb").read() for p in glob.glob(cap + "/*.c2s") + glob.glob(cap + "/*.s2c")}
data = b"\0".join(streams.values())
blobs = [open(p, "rb").read() for p in glob.glob(bundles + "/*") if not os.path.basename(p).startswith(".")]
image = open(exr, "rb").read()
assert len(blobs) == 1 and len(image) > 1000, (len(blobs), len(image))
# The capture holds the job's traffic, or finding nothing in it would prove nothing: the clear
# hellos carry the workers' names, and frames at least as large as what they carry show that
# the scene went up with the submit and down to a worker, every upload the coordinator merged
# came from a worker, and the image came down with the fetch.
assert b"wsealed1" in data and b"wsealed2" in data, "capture misses the clear handshake"
def frames(b):
    out = []
    while len(b) >= 4:
        n = struct.unpack(">I", b[:4])[0]; out.append(b[4:4 + n]); b = b[4 + n:]
    return out
conns = collections.defaultdict(dict)
for p, b in streams.items():
    conn, way = os.path.basename(p).split(".")
    conns[conn][way] = frames(b)
worker = {c for c, f in conns.items() if f.get("c2s") and b"wsealed" in f["c2s"][0]}
client = set(conns) - worker
big = lambda cs, way, n: [len(f) for c in cs for f in conns[c].get(way, [])[2:] if len(f) >= n]
# an upload of a 160x160 film (zstd-compressed sums) is several 256 KiB chunks, the image two;
# control messages are < 200 B
assert len(big(worker, "c2s", 4096)) >= int(uploads), ("uploads captured", big(worker, "c2s", 4096), uploads)
assert big(client, "c2s", len(blobs[0])), "the submitted bundle is not in the capture"
assert big(worker, "s2c", len(blobs[0])), "the bundle sent to the workers is not in the capture"
assert max(sum(big([c], "s2c", 0)) for c in client) >= len(image), "the fetched image is not in the capture"
def windows(b, k=24, count=64):
    step = max(1, (len(b) - k) // count)
    return [b[i:i + k] for i in range(0, len(b) - k, step)]
# A 4-byte magic matches ciphertext by chance with probability ~ len/2^32 (~0.15% per run for
# this capture), so a single zstd magic proves nothing; clear uploads would show it once per
# upload, and two chance matches are ~1e-6. The image's magic is checked with its version field,
# its first 8 bytes as fetched.
zstd_magic = bytes.fromhex("28b52ffd")
assert image[:4] == bytes.fromhex("762f3101"), "the fetched image is not an EXR"
leaks = [("scene marker", mark.encode()), ("material id", mat.encode()), ("EXR magic and version", image[:8])]
leaks += [("bundle bytes", w) for w in windows(blobs[0])] + [("image bytes", w) for w in windows(image)]
found = collections.Counter(name for name, pat in leaks if pat in data)
if data.count(zstd_magic) >= 2:
    found["zstd magic"] = data.count(zstd_magic)
found = sorted(found.items())
print("captured %d bytes in %d streams (%d upload frames of %s bytes); bundle %d bytes, image %d bytes; %d patterns checked, leaks: %s"
      % (len(data), len(streams), len(big(worker, "c2s", 4096)), big(worker, "c2s", 4096), len(blobs[0]), len(image),
         len(leaks), found or "none"))
sys.exit(1 if found else 0)
PY
python3 - "$PORT" "$T/cap" "$S/proto/wire_frame.h" "$T/tok" "$B" "$T" <<'PY' || fail "replay / version checks"
import glob, hashlib, re, socket, struct, subprocess, sys, threading, time
port, cap, hdr, tokf, bindir, tmp = int(sys.argv[1]), sys.argv[2], sys.argv[3], sys.argv[4], sys.argv[5], sys.argv[6]
version = int(re.search(r"PC_WIRE_PROTOCOL_VERSION (\d+)u", open(hdr).read()).group(1))
# the handshake as auth.c computes it, so this script can also be an honest client
key = hashlib.blake2b(open(tokf, "rb").read().rstrip(b" \t\r\n"), key=b"pcbpt-token-v1", digest_size=32).digest()
mac = lambda label, n1, n2: hashlib.blake2b(label + n1 + n2, key=key, digest_size=32).digest()
def frames(b):
    out = []
    while len(b) >= 4:
        n = struct.unpack(">I", b[:4])[0]; out.append(b[:4 + n]); b = b[4 + n:]
    return out
def field(tag, b):  # a length-delimited protobuf field (lengths < 128 here)
    return bytes([tag, len(b)]) + b
def parse(m):  # a message's fields, for varints and short length-delimited fields
    out, i = {}, 0
    while i < len(m):
        k, i = m[i], i + 1
        if k & 7 == 0:
            v = s = 0
            while True:
                v |= (m[i] & 0x7f) << s; s += 7; i += 1
                if not m[i - 1] & 0x80: break
            out[k >> 3] = v
        else:
            n = m[i]; out[k >> 3] = m[i + 1:i + 1 + n]; i += 1 + n
    return out
def frame(tag, body): return struct.pack(">I", len(body) + 2) + field(tag, body)
class Conn:
    def __init__(self, s): self.s, self.buf = s, b""; s.settimeout(10)
    def recv(self):
        while len(self.buf) < 4 or len(self.buf) < 4 + struct.unpack(">I", self.buf[:4])[0]:
            d = self.s.recv(1 << 16)
            if not d: return None
            self.buf += d
        n = 4 + struct.unpack(">I", self.buf[:4])[0]; f, self.buf = self.buf[:n], self.buf[n:]
        return f
def dial(): return Conn(socket.create_connection(("127.0.0.1", port)))
def hello(nonce, name=b"replay-test", v=version):
    return frame(0x0a, b"\x08" + bytes([v]) + b"\x10\x02" + field(0x1a, name) + field(0x2a, nonce))
recorded = [frames(open(p, "rb").read()) for p in sorted(glob.glob(cap + "/*.c2s"))]
recorded = [f for f in recorded if f and b"wsealed1" in f[0]]
s2c = [frames(open(p[:-4] + ".s2c", "rb").read()) for p in sorted(glob.glob(cap + "/*.c2s"))
       if b"wsealed1" in open(p, "rb").read()[:200]]
rec = max(recorded, key=len)   # the connection that rendered: its frames from 2 on are sealed
assert rec[0][4] == 0x0a and rec[1][4] == 0x1a and len(rec) > 4, "recorded frames are not hello, auth_response, ..."

# 1. a worker's recorded hello and auth_response, replayed on a new connection: the
# coordinator's nonce is new, so the recorded MAC does not answer it
c = dial()
c.s.sendall(rec[0]); ch = c.recv()
assert ch and ch[4] == 0x12, "no challenge to the replayed hello"
c.s.sendall(rec[1]); res = c.recv()
assert res and res[4] == 0x22 and b"wrong token" in res, "replayed auth_response not refused: %r" % res
assert c.recv() is None, "connection still open after a refused replay"

# 2. the control: the same exchange with fresh values and the token is accepted, so the refusal
# above was the replay's; then a sealed frame recorded on another connection, sent as this
# connection's first, does not open under this connection's keys: dropped
cn = bytes(range(32))
c = dial()
c.s.sendall(hello(cn)); ch = c.recv()
f = parse(parse(ch[4:])[2])
assert f[2] == mac(b"pcbpt-auth-server-v1", cn, f[1]), "the coordinator's proof differs from this script's"
c.s.sendall(frame(0x1a, field(0x0a, mac(b"pcbpt-auth-client-v1", f[1], cn)))); res = c.recv()
assert res and parse(parse(res[4:])[4]).get(1) == 1, "an honest handshake was refused: %r" % res
c.s.sendall(rec[2])
assert c.recv() is None, "a sealed frame replayed from another connection was accepted"

# 3. an impostor coordinator that replays a recorded challenge (nonce and proof) to every hello:
# the client verbs and a worker refuse it and send it nothing more, as the proof does not cover
# their fresh nonces
challenge = s2c[0][0]
assert challenge[4] == 0x12, "recorded s2c frame 0 is not a challenge"
lsn = socket.create_server(("127.0.0.1", 0)); after_hello = []
def impostor():
    while True:
        c = Conn(lsn.accept()[0])
        if c.recv() is None: continue
        c.s.sendall(challenge)
        try: after_hello.append(c.recv())
        except OSError as e: after_hello.append(e)
threading.Thread(target=impostor, daemon=True).start()
fake = "127.0.0.1:%d" % lsn.getsockname()[1]
r = subprocess.run([bindir + "/pcbpt-coord", "status", "--host", fake, "--token-file", tokf],
                   capture_output=True, text=True, timeout=30)
assert r.returncode != 0 and "holds a different token" in r.stderr, "client took a replayed challenge: %r" % r.stderr
with open(tmp + "/wimpostor.log", "w") as log:
    r = subprocess.run([bindir + "/pcbpt-worker", "--connect", fake, "--token-file", tokf, "--threads", "1", "--name",
                        "wimpostor", "--cache-dir", tmp + "/cache-wimpostor"], stdout=log, stderr=log, timeout=30)
assert r.returncode != 0 and "holds a different token" in open(tmp + "/wimpostor.log").read(), \
    "worker took a replayed challenge (exit %d)" % r.returncode
# the impostor's thread records a connection's end after the process has exited: wait for it
deadline = time.time() + 10
while len(after_hello) < 2 and time.time() < deadline: time.sleep(0.01)
assert after_hello == [None, None], "a peer answered a replayed challenge: %r" % after_hello

# 4. a hello of the previous version (whose frames travel in the clear) is refused with the
# versions named
c = dial()
c.s.sendall(hello(bytes(32), v=version - 1))
err = c.recv()
want = b"protocol version %d, this coordinator speaks %d" % (version - 1, version)
assert err and want in err, "older hello: %r" % err
print("replayed handshake refused (an honest one accepted); a sealed frame from another connection dropped; "
      "client and worker refuse a replayed challenge; older hello refused: %s" % want.decode())
PY
grep -q "authentication failed (wrong token)" "$T/coord.log" || fail "no log line for the replayed auth_response"
grep -q "closing: protocol version [0-9]*, this coordinator speaks" "$T/coord.log" || fail "no log line for the older hello"
# one flipped bit in a sealed frame: that connection is dropped with a reason, nothing else
touch "$T/cap/corrupt"
"$B/pcbpt-coord" status "$J" $HR >/dev/null 2>&1 && fail "a corrupted sealed frame was accepted"
[ -e "$T/cap/corrupt" ] && fail "the relay did not corrupt the status connection"
[ "$(grep -c "closing: seal: frame 0 does not authenticate" "$T/coord.log")" = 3 ] \
  || fail "not one log line each for the tampered worker frame, the frame from another connection and the corrupted one"
[ "$(job_field "$J" iterations)" = 16 ] || fail "the coordinator does not answer after the corrupted frame"
echo PASS
