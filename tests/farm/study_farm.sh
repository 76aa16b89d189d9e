# study_farm.sh: equal-time studies on a 2-worker loopback farm (docs/farm-study.md), on
# cornell-box at 64x64 with pt and bdpt for 1 s per method:
# 1. --reference-render bdpt:2 --runs 2 --workers 1,2 --snapshots 6: the reference is rendered
#    on the farm and kept; every output exists (scene folder, scaling chart, report); study.csv
#    holds both runs of both farm sizes; the jobs of a group were interleaved (their ranges
#    alternate in the coordinator's log) and on 2 workers rotated (each worker served both
#    methods); on 1 worker the group never had two workers at once (its jobs' wall time covers
#    the summed worker-seconds); every job halted at its budget of worker-seconds; the report's
#    images all load in a headless browser (or, without one, decode as PNG/SVG data URIs).
# 2. A second study reuses the reference; one worker is killed mid-study: the study finishes
#    on the other, every job still reaches its worker-seconds, and a range the dead worker held
#    unacknowledged is re-run (counted in study.json and said in the output).
# 3. The coordinator is killed mid-study and restarted: the study reconnects, the jobs resume
#    with their worker-seconds (stored) and their curves stay monotonic.
. "$(dirname "$0")/lib.inc"
start_coord
start_worker w1
start_worker w2
W2=$LAST
scene="$S/scenes/cornell-box/scene.xml"
wait_workers() { # n
  for _ in $(seq 100); do
    [ "$("$B/pcbpt-coord" workers $H 2>/dev/null | grep -c 'w[12]')" -ge "$1" ] && return 0
    sleep 0.1
  done
  fail "the workers did not connect"
}
wait_workers 2
common=(--methods pt,bdpt --seconds 1 --width 64 --height 64 --snapshots 6 --out "$T/s" $H)

timeout 240 "$B/pcbpt-coord" study "$scene" "${common[@]}" --reference-render bdpt:2 --runs 2 --workers 1,2 \
  >"$T/study1.out" 2>&1 || { cat "$T/study1.out"; fail "study 1"; }
d="$T/s/cornell-box"
for f in "$T/s/report.html" "$d/reference-bdpt-2s.exr" "$d/pt.exr" "$d/pt.png" "$d/bdpt.exr" "$d/bdpt.png" "$d/study.csv" \
  "$d/study.json" "$d/study_beauty.png" "$d/study_beauty.svg" "$d/study_inner.svg" "$d/study_scaling.png" \
  "$d/study_scaling.svg" "$d/crop_pt.png" "$d/reference.png"; do
  [ -s "$f" ] || fail "study 1: $f missing"
done
grep -q "rendering the reference" "$T/study1.out" || fail "study 1: no reference render"
grep -q "^scaling" "$T/study1.out" && grep -q "2 workers: .* speed-up .* workers busy" "$T/study1.out" || { cat "$T/study1.out"; fail "study 1: no scaling table"; }
grep -q "over 2 runs on 2 workers" "$T/study1.out" || { cat "$T/study1.out"; fail "study 1: no spread table"; }
python3 - "$d/study.json" "$T/coord.log" <<'EOF' || fail "study 1: the figures"
import collections, json, re, sys
d = json.load(open(sys.argv[1]))
runs = d["methods"]
got = sorted((r["workers"], r["run"], r["method"]) for r in runs)
want = sorted((w, k, m) for w in (1, 2) for k in (1, 2) for m in ("pt", "bdpt"))
assert got == want, got
for r in runs:
    s = r["snapshots"]
    assert 2 <= len(s) <= 6, (r["method"], len(s))
    ws = [p["worker_seconds"] for p in s]
    assert ws == sorted(ws), ws
    # halted at its budget (1 s on the farm = workers worker-seconds), late by at most what
    # each worker rendered since its last upload: an upload interval (2 s) and a batch
    assert r["workers"] <= ws[-1] < r["workers"] * (1 + 2.5), (r["workers"], ws[-1])
    assert all(p["layers"]["beauty"]["relmse"] is not None for p in s)
# on 1 worker the group never had two workers at once: its wall time covers both jobs' work
# (within 10%); on 2 workers the same line rejects it, so the check can tell. (The 2-worker
# groups' wall is 0.55-0.62 of their worker-seconds on an idle machine and was 0.805 under CI's
# load, where an earlier line at 0.8 failed: the group's wall includes its start, the polls'
# quarter-seconds and the last uploads, which a 1 s budget does not amortise.)
for w in (1, 2):
    for k in (1, 2):
        one = [r for r in runs if r["workers"] == w and r["run"] == k]
        total = sum(r["snapshots"][-1]["worker_seconds"] for r in one)
        wall = one[0]["group_wall_seconds"]
        print("%d worker(s), run %d: %.2f worker-seconds in %.2f s" % (w, k, total, wall))
        assert (wall >= 0.9 * total) if w == 1 else (wall < 0.9 * total), (w, k, total, wall)
# interleaving: per group, the ranges handed out alternate between its jobs, and with 2
# workers each worker renders both methods
log = open(sys.argv[2]).read()
names = {}
for m in re.finditer(r"job (\d+): submitted by \S+: '[^']*' (\w+)", log):
    names[int(m.group(1))] = m.group(2)
seq = [(int(m.group(1)), m.group(2)) for m in re.finditer(r"job (\d+): range \d+ \[\d+,\+\d+\) -> (w\d)", log)]
jobs = sorted(names)
groups = [jobs[i:i + 2] for i in range(1, len(jobs), 2)]  # job 1 is the reference
assert len(groups) == 4, jobs
for gi, g in enumerate(groups):
    order = [j for j, w in seq if j in g]
    switches = sum(1 for a, b in zip(order, order[1:]) if a != b)
    assert switches >= 3, (g, order)
    if gi >= 2:  # the 2-worker runs
        for w in ("w1", "w2"):
            served = {names[j] for j, ww in seq if j in g and ww == w}
            assert served == {"pt", "bdpt"}, (g, w, served)
EOF
# the worker alternated the group's jobs range by range over kept renderers (worker/render.c):
# the bdpt job of the first run on 1 worker is still exactly a single process's render of its
# iterations
read -r BJ BSEED BN < <(python3 - "$d/study.json" "$T/coord.log" <<'EOF'
import json, re, sys
d = json.load(open(sys.argv[1]))
r = [r for r in d["methods"] if r["method"] == "bdpt" and r["workers"] == 1 and r["run"] == 1][0]
jobs = [int(m.group(1)) for m in re.finditer(r"job (\d+): submitted by \S+: '[^']*' bdpt", open(sys.argv[2]).read())]
print(jobs[1], r["seed"], r["iterations"])  # job 1 is the reference
EOF
)
CK=$(ls "$T/data/jobs/$BJ"/ckpt.* | sort -t. -k2 -n | tail -1)
"$B/tests/farm_tool" exact "$CK" "$scene" --method bdpt --seed "$BSEED" --spp "$BN" --width 64 --height 64 >"$T/exact.out" ||
  { cat "$T/exact.out"; fail "study job $BJ (bdpt, seed $BSEED, $BN iterations) is not a single process's render"; }
grep -q "^trace $BN/$BN iterations, identical" "$T/exact.out" || { cat "$T/exact.out"; fail "study job $BJ: trace"; }
# a study job's snapshots are fetchable by any client (job 2: the first run's pt)
[ "$(job_field 2 snapshots)" -ge 1 ] || fail "job 2 kept no snapshot"
"$B/pcbpt-coord" fetch 2 --snapshot 1 --out "$T/snap1.exr" $H >/dev/null && [ -s "$T/snap1.exr" ] || fail "fetch --snapshot 1"
! "$B/pcbpt-coord" fetch 2 --snapshot 99 --out "$T/snap99.exr" $H 2>"$T/fetch.err" && grep -q "snapshots" "$T/fetch.err" ||
  fail "fetch of a snapshot the job does not have: $(cat "$T/fetch.err")"
python3 - "$T/s/report.html" <<'EOF' || fail "report: images"
import base64, html.parser, sys
class P(html.parser.HTMLParser):
    imgs = []
    def handle_starttag(self, tag, attrs):
        if tag == "img": self.imgs.append(dict(attrs)["src"])
p = P(); p.feed(open(sys.argv[1]).read())
# charts beauty, inner, scaling, strategy shares, per-iteration errors; pt, bdpt, reference;
# crops of pt, bdpt, reference
assert len(p.imgs) == 11, len(p.imgs)
for src in p.imgs:
    head, data = src.split(",", 1)
    raw = base64.b64decode(data)
    assert (head == "data:image/png;base64" and raw[:8] == b"\x89PNG\r\n\x1a\n") or \
           (head == "data:image/svg+xml;base64" and b"<svg" in raw[:400]), head
EOF
if command -v chromium-headless-shell >/dev/null; then
  # a copy with a script that records, once loaded, how many images the browser decoded
  cp "$T/s/report.html" "$T/probe.html"
  echo "<script>addEventListener('load',()=>{let ok=0,bad=0;for(const i of document.images)(i.complete&&i.naturalWidth>0)?ok++:bad++;document.body.dataset.images=ok+'/'+bad})</script>" >>"$T/probe.html"
  timeout 60 chromium-headless-shell --no-sandbox --disable-gpu --virtual-time-budget=5000 --dump-dom "file://$T/probe.html" \
    2>/dev/null | grep -q 'data-images="11/0"' || fail "report: the browser did not show its 11 images"
else
  echo "no chromium-headless-shell: the report was checked with an HTML parser only"
fi

# 2: the reference is reused; a worker dies mid-study
# (the reference is in place before the study starts: copied after, it raced the study's look)
mkdir -p "$T/k/cornell-box" && cp "$d/reference-bdpt-2s.exr" "$T/k/cornell-box/"
"$B/pcbpt-coord" study "$scene" "${common[@]}" --seconds 3 --reference-render bdpt:2 --out "$T/k" >"$T/study2.out" 2>&1 &
STUDY=$!; PIDS+=("$STUDY")
for _ in $(seq 100); do grep -q "snap" <(ls "$T/data/jobs"/*/ 2>/dev/null) && break; sleep 0.1; done
n0=$(grep -c "submitted" "$T/coord.log")
sleep 1.5
kill -9 "$W2"
wait "$STUDY" || { cat "$T/study2.out"; fail "study 2 (a worker killed) failed"; }
grep -q "reusing the reference" "$T/study2.out" || fail "study 2 rendered its reference again"
python3 - "$T/k/cornell-box/study.json" "$T/coord.log" "$T/study2.out" <<'EOF' || fail "study 2: the figures"
import json, re, sys
d = json.load(open(sys.argv[1]))
log = open(sys.argv[2]).read()
out = open(sys.argv[3]).read()
for r in d["methods"]:
    assert r["snapshots"][-1]["worker_seconds"] >= 2 * 3.0, r["snapshots"][-1]
lost = [m for m in re.finditer(r"job (\d+): range \d+ orphaned \(w2 gone\), (\d+) of (\d+) iterations", log)
        if int(m.group(2)) < int(m.group(3))]
rerun = sum(r["ranges_rerun"] for r in d["methods"])
print("ranges orphaned with work left:", len(lost), "re-run:", rerun)
assert not lost or rerun >= 1, (lost, rerun)
assert not rerun or "re-run after a worker went away" in out
EOF

# 3: the coordinator is killed mid-study and restarted: the study reconnects and finishes, and
# the jobs' worker-seconds carry on from their checkpoints (stored), not from zero
# (one worker is left: the budget is 3 worker-seconds)
last=$(ls "$T/data/jobs" | sort -n | tail -1)
"$B/pcbpt-coord" study "$scene" "${common[@]}" --seconds 3 --out "$T/r" >"$T/study3.out" 2>&1 &
STUDY=$!; PIDS+=("$STUDY")
for _ in $(seq 300); do [ -e "$T/data/jobs/$((last + 1))/snap.2.exr" ] && break; sleep 0.1; done
[ -e "$T/data/jobs/$((last + 1))/snap.2.exr" ] || fail "study 3 kept no second snapshot"
kill -9 "$COORD"
sleep 1
start_coord "$PORT"
wait "$STUDY" || { cat "$T/study3.out"; fail "study 3 (the coordinator restarted) failed"; }
grep -q "reconnecting" "$T/study3.out" || fail "study 3 did not see the coordinator go"
grep -q "resumed" "$T/coord.log" || fail "study 3: no job resumed"
python3 - "$T/r/cornell-box/study.json" <<'EOF' || fail "study 3: the figures"
import json, sys
for r in json.load(open(sys.argv[1]))["methods"]:
    ws = [p["worker_seconds"] for p in r["snapshots"]]
    it = [p["iterations"] for p in r["snapshots"]]
    assert ws == sorted(ws) and it == sorted(it), (ws, it)
    assert 3.0 <= ws[-1] < 3 + 2.5, ws
EOF
echo PASS
