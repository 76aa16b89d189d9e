"""relay.py: a recording TCP relay for the farm tests: listens on an ephemeral loopback port
(written to PORT_FILE), forwards each connection to the coordinator frame by frame (the 4-byte
length prefixes travel in the clear) and appends every frame, in each direction, to
CAPTURE_DIR/<connection>.<c2s|s2c>. If CAPTURE_DIR/corrupt (or corrupt-s2c) exists when a
connection is accepted, it is removed and that connection's third frame from the client (or from
the coordinator), its first sealed one, gets one payload bit flipped on the way. An optional
fourth argument, SECONDS, holds back each frame from a client larger than 64 KiB (upload chunks)
that long: a slow uplink, so that an upload is seen in mid-transfer. If CAPTURE_DIR/cut exists
when such a frame arrives, it is removed and that connection is cut there (both sockets shut)."""
import os, socket, struct, sys, threading, time

target_port, port_file, cap = int(sys.argv[1]), sys.argv[2], sys.argv[3]
bulk_delay = float(sys.argv[4]) if len(sys.argv) > 4 else 0.0
os.makedirs(cap, exist_ok=True)


def pump(src, dst, path, corrupt_frame, delay):
    buf, frames, cut = b"", 0, False
    with open(path, "ab", buffering=0) as log:
        while not cut:
            try:
                data = src.recv(1 << 16)
            except OSError:
                data = b""
            if not data:
                break
            buf += data
            while len(buf) >= 4 and len(buf) >= 4 + struct.unpack(">I", buf[:4])[0]:
                n = 4 + struct.unpack(">I", buf[:4])[0]
                frame, buf = bytearray(buf[:n]), buf[n:]
                if frames == corrupt_frame and n > 4:
                    frame[4 + (n - 4) // 2] ^= 0x10
                frames += 1
                if delay and n > 65536:
                    time.sleep(delay)
                    try:
                        os.unlink(os.path.join(cap, "cut"))
                        cut = True
                        break
                    except FileNotFoundError:
                        pass
                log.write(frame)
                try:
                    dst.sendall(frame)
                except OSError:
                    break
    for s in (src, dst):
        try:
            s.shutdown(socket.SHUT_RDWR)
        except OSError:
            pass


lsn = socket.create_server(("127.0.0.1", 0))
with open(port_file + ".tmp", "w") as f:
    f.write(str(lsn.getsockname()[1]))
os.rename(port_file + ".tmp", port_file)
conn_id = 0
while True:
    cli, _ = lsn.accept()
    srv = socket.create_connection(("127.0.0.1", target_port))
    conn_id += 1
    corrupt = {}
    for direction in ("c2s", "s2c"):
        try:
            os.unlink(os.path.join(cap, "corrupt" if direction == "c2s" else "corrupt-s2c"))
            corrupt[direction] = 2
        except FileNotFoundError:
            pass
    base = os.path.join(cap, str(conn_id))
    threading.Thread(target=pump, args=(cli, srv, base + ".c2s", corrupt.get("c2s", -1), bulk_delay), daemon=True).start()
    threading.Thread(target=pump, args=(srv, cli, base + ".s2c", corrupt.get("s2c", -1), 0.0), daemon=True).start()
