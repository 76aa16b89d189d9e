# systemd_units.sh: deploy/systemd/*.service pass `systemd-analyze verify` with no complaint,
# in a scratch root that has the programs where the units expect them (/usr/local/bin).
set -euo pipefail
B=${PCBPT_BINARY_DIR:?}
S=${PCBPT_SOURCE_DIR:?}
command -v systemd-analyze >/dev/null || { echo "SKIP: systemd-analyze is not installed"; exit 77; }
R=$(mktemp -d /tmp/pcbpt-units-XXXXXX)
trap 'rm -rf "$R"' EXIT
mkdir -p "$R/usr/local/bin" "$R/etc/systemd/system" "$R/usr/lib"
cp "$B/pcbpt-coord" "$B/pcbpt-worker" "$R/usr/local/bin/"
cp -r /usr/lib/systemd "$R/usr/lib/"
units=()
for u in "$S"/deploy/systemd/*.service; do cp "$u" "$R/etc/systemd/system/"; units+=("$(basename "$u")"); done
[ ${#units[@]} -ge 2 ] || { echo "FAIL: no units found"; exit 1; }
out=$(systemd-analyze verify --root="$R" "${units[@]}" 2>&1) || { echo "FAIL: $out"; exit 1; }
[ -z "$out" ] || { echo "FAIL: systemd-analyze verify complains:"; echo "$out"; exit 1; }
echo "PASS: ${units[*]}"
