# k8s_manifests.sh: deploy/k8s/*.yaml validate offline against the Kubernetes API schemas
# (tests/deploy/k8s_validate.cjs with npm's kubernetes-models and yaml, which
# deploy/install-deps.sh installs under /opt/pcbpt-tools), and a broken manifest is caught.
set -euo pipefail
S=${PCBPT_SOURCE_DIR:?}
export NODE_PATH=${PCBPT_NODE_PATH:-/opt/pcbpt-tools/node_modules}
command -v node >/dev/null || { echo "SKIP: node is not installed (deploy/install-deps.sh installs it)"; exit 77; }
[ -d "$NODE_PATH/kubernetes-models" ] || { echo "SKIP: $NODE_PATH has no kubernetes-models (deploy/install-deps.sh)"; exit 77; }
node "$S/tests/deploy/k8s_validate.cjs" "$S"/deploy/k8s/*.yaml
T=$(mktemp -d /tmp/pcbpt-k8s-XXXXXX); trap 'rm -rf "$T"' EXIT
sed 's/replicas: 4/replicas: four/' "$S/deploy/k8s/workers.yaml" > "$T/bad.yaml"
if node "$S/tests/deploy/k8s_validate.cjs" "$T/bad.yaml" >/dev/null; then echo "FAIL: a non-integer replica count passed"; exit 1; fi
echo PASS
