// k8s_validate.cjs: validates Kubernetes manifests offline against the API's OpenAPI schemas
// (npm's kubernetes-models), then checks what the schema cannot: every container states its
// resources, Services select pods that exist, volumes and the token Secret are wired up, and
// the coordinator has a liveness probe. Usage: node k8s_validate.cjs FILE.yaml...
'use strict';
const fs = require('fs');
const YAML = require('yaml');
const models = require('kubernetes-models');

const errors = [];
const objects = [];
for (const file of process.argv.slice(2)) {
  for (const doc of YAML.parseAllDocuments(fs.readFileSync(file, 'utf8'))) {
    if (doc.errors.length) { errors.push(`${file}: ${doc.errors[0].message}`); continue; }
    const obj = doc.toJS();
    if (obj) objects.push({file, obj});
  }
}
function modelOf(obj) {
  const [group, version] = obj.apiVersion.includes('/') ? obj.apiVersion.split('/') : ['', obj.apiVersion];
  const mod = group ? require(`kubernetes-models/${group}/${version}`) : require(`kubernetes-models/${version}`);
  return mod[obj.kind];
}
const podSpecs = [];
for (const {file, obj} of objects) {
  const where = `${file}: ${obj.kind}/${obj.metadata && obj.metadata.name}`;
  let Model;
  try { Model = modelOf(obj); } catch (e) { Model = undefined; }
  if (!Model) { errors.push(`${where}: unknown apiVersion/kind ${obj.apiVersion} ${obj.kind}`); continue; }
  try { new Model(obj).validate(); } catch (e) { errors.push(`${where}: ${e.message}`); continue; }
  const spec = obj.spec && obj.spec.template && obj.spec.template.spec;
  if (spec) podSpecs.push({where, obj, spec});
}
for (const {where, obj, spec} of podSpecs) {
  const labels = obj.spec.template.metadata.labels || {};
  const sel = obj.spec.selector.matchLabels || {};
  for (const k of Object.keys(sel)) if (labels[k] !== sel[k]) errors.push(`${where}: selector ${k} does not match the pod labels`);
  const vols = new Set((spec.volumes || []).map(v => v.name));
  for (const t of obj.spec.volumeClaimTemplates || []) vols.add(t.metadata.name);
  for (const c of [...(spec.initContainers || []), ...spec.containers]) {
    if (!c.resources || !c.resources.requests) { if (!(spec.initContainers || []).includes(c)) errors.push(`${where}: container ${c.name} has no resource requests`); }
    for (const m of c.volumeMounts || []) if (!vols.has(m.name)) errors.push(`${where}: container ${c.name} mounts undefined volume ${m.name}`);
  }
  const secrets = (spec.volumes || []).filter(v => v.secret).map(v => v.secret.secretName);
  if (!secrets.includes('pcbpt-token')) errors.push(`${where}: does not mount the pcbpt-token Secret`);
  if (obj.kind === 'StatefulSet' && !spec.containers.some(c => c.livenessProbe)) errors.push(`${where}: the coordinator has no liveness probe`);
}
for (const {file, obj} of objects.filter(o => o.obj.kind === 'Service')) {
  const sel = obj.spec.selector || {};
  const hit = podSpecs.some(p => Object.entries(sel).every(([k, v]) => (p.obj.spec.template.metadata.labels || {})[k] === v));
  if (!hit) errors.push(`${file}: Service/${obj.metadata.name} selects no pod of these manifests`);
}
if (errors.length) { for (const e of errors) console.log(`FAIL: ${e}`); process.exit(1); }
console.log(`PASS: ${objects.length} objects (${objects.map(o => o.obj.kind).join(', ')})`);
