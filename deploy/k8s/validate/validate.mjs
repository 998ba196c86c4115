// Checks rendered manifests (multi-document YAML files, one per overlay)
// offline, in two ways:
//   1. every object against the Kubernetes OpenAPI schema of its kind
//      (kubernetes-models: types, required fields, enums, formats; it does
//      not reject unknown fields, which is what some of the checks below
//      are for);
//   2. what a schema cannot see: references between objects and the rules
//      of this deployment (shard counts that agree, podFailurePolicy with
//      restartPolicy Never, probes, requests, services that select pods).
// References (ConfigMaps, PersistentVolumeClaims) are resolved across all the
// files given, per namespace, because a build overlay uses the volumes its
// environment's server overlay declares. Secrets may live outside (created
// out of band), and are listed as such.
//
//   node validate.mjs [--scripts DIR] RENDERED.yaml...
//
// --scripts DIR writes every container's `sh -c` script to DIR (one file
// each, with a #!/bin/sh line) for shellcheck.
// Exit status: 0 all good, 1 any problem (each printed as FILE: kind/name: what).

import { mkdirSync, readFileSync, writeFileSync } from "node:fs";
import { parseAllDocuments } from "yaml";

const problems = [];
const notes = [];
const objects = [];  // {file, obj}

const argv = process.argv.slice(2);
let scriptsDir = null;
if (argv[0] === "--scripts") { scriptsDir = argv[1]; argv.splice(0, 2); }

for (const file of argv) {
  const docs = parseAllDocuments(readFileSync(file, "utf8"));
  for (const doc of docs) {
    if (doc.errors.length) {
      problems.push(`${file}: YAML: ${doc.errors.map((e) => e.message).join("; ")}`);
      continue;
    }
    const obj = doc.toJS();
    if (obj) objects.push({ file, obj });
  }
  if (!docs.length) problems.push(`${file}: no objects`);
}
if (!objects.length) problems.push("no objects at all");

const id = ({ obj }) => `${obj.kind}/${obj.metadata?.name}`;
const bad = (o, what) => problems.push(`${o.file}: ${id(o)}: ${what}`);
const ns = (o) => o.obj.metadata?.namespace ?? "default";

// --- 1. schemas ---------------------------------------------------------------
for (const o of objects) {
  const { apiVersion, kind } = o.obj;
  if (!apiVersion || !kind) { bad(o, "no apiVersion or kind"); continue; }
  // kubernetes-models lays its classes out as <group>/<version>/<Kind>, the
  // core group as <version>/<Kind>.
  let Model;
  try {
    Model = (await import(`kubernetes-models/${apiVersion}/${kind}`))[kind];
  } catch {
    bad(o, `no schema for ${apiVersion} ${kind}`);
    continue;
  }
  try {
    new Model(o.obj).validate();
  } catch (e) {
    bad(o, `schema: ${e.message}`);
  }
}

// --- 2. references and rules ----------------------------------------------------
const byKind = (kind) => objects.filter((o) => o.obj.kind === kind);
const find = (kind, name, namespace) =>
  objects.find((o) => o.obj.kind === kind && o.obj.metadata?.name === name && ns(o) === namespace);
const podSpecOf = (o) =>
  ["Deployment", "Job", "StatefulSet", "DaemonSet"].includes(o.obj.kind) ? o.obj.spec?.template?.spec : null;
const matches = (selector, labels) =>
  Object.entries(selector ?? {}).every(([k, v]) => (labels ?? {})[k] === v);

for (const o of objects) {
  const pod = podSpecOf(o);
  if (!pod) continue;
  const containers = [...(pod.initContainers ?? []), ...(pod.containers ?? [])];
  const volumes = new Map((pod.volumes ?? []).map((v) => [v.name, v]));
  for (const c of containers) {
    if (!c.image || /:latest$/.test(c.image) || !c.image.includes(":")) {
      bad(o, `container ${c.name}: image '${c.image}' has no pinned tag`);
    }
    // $(VAR) in command/args is expanded by the kubelet only for defined
    // variables; an undefined one is passed on literally.
    const defined = new Set((c.env ?? []).map((e) => e.name));
    const fromMaps = (c.envFrom ?? []).map((e) => e.configMapRef?.name).filter(Boolean);
    const mapKeys = new Set(fromMaps.flatMap((name) => Object.keys(find("ConfigMap", name, ns(o))?.obj.data ?? {})));
    for (const word of [...(c.command ?? []), ...(c.args ?? [])]) {
      for (const [, v] of String(word).matchAll(/\$\(([A-Za-z_][A-Za-z0-9_]*)\)/g)) {
        if (!defined.has(v) && !mapKeys.has(v)) bad(o, `container ${c.name}: $(${v}) is not defined`);
      }
    }
    for (const name of fromMaps) {
      if (!find("ConfigMap", name, ns(o))) bad(o, `container ${c.name}: no ConfigMap ${name} in ${ns(o)}`);
    }
    for (const m of c.volumeMounts ?? []) {
      if (!volumes.has(m.name)) bad(o, `container ${c.name}: mounts undeclared volume ${m.name}`);
    }
    if (!pod.initContainers?.includes(c) && !c.resources?.requests?.cpu) {
      bad(o, `container ${c.name}: no CPU request (the HPA and the scheduler need one)`);
    }
    if (!pod.initContainers?.includes(c) && !c.resources?.requests?.memory) {
      bad(o, `container ${c.name}: no memory request`);
    }
  }
  for (const v of volumes.values()) {
    const claim = v.persistentVolumeClaim?.claimName;
    if (claim && !find("PersistentVolumeClaim", claim, ns(o))) {
      bad(o, `volume ${v.name}: no PersistentVolumeClaim ${claim} in namespace ${ns(o)}`);
    }
    const secret = v.secret?.secretName;
    if (secret && !find("Secret", secret, ns(o))) notes.push(`${o.file}: ${id(o)}: Secret ${secret} is created out of band`);
  }
}

for (const o of byKind("Deployment")) {
  const spec = o.obj.spec ?? {};
  const tpl = spec.template ?? {};
  if (!matches(spec.selector?.matchLabels, tpl.metadata?.labels)) bad(o, "selector does not select its own pods");
  for (const c of tpl.spec?.containers ?? []) {
    for (const p of ["startupProbe", "readinessProbe", "livenessProbe"]) {
      if (!c[p]) bad(o, `container ${c.name}: no ${p}`);
    }
    // The kubelet must wait for the drain (and the preStop pause) before SIGKILL.
    const drain = (c.args ?? []).map((a) => /^--drain-seconds=(\d+(\.\d+)?)$/.exec(a)).find(Boolean);
    const pause = c.lifecycle?.preStop?.sleep?.seconds ?? 0;
    const grace = tpl.spec?.terminationGracePeriodSeconds ?? 30;
    if (drain && Number(drain[1]) + pause >= grace) {
      bad(o, `terminationGracePeriodSeconds ${grace} <= drain ${drain[1]} s + preStop ${pause} s`);
    }
    const tls = (c.args ?? []).some((a) => a.startsWith("--tls-cert"));
    if (tls && ["startupProbe", "readinessProbe", "livenessProbe"].some((p) => c[p]?.grpc)) {
      bad(o, `container ${c.name}: gRPC probes cannot speak TLS; use exec probes with --tls-cert`);
    }
  }
}

for (const o of byKind("Service")) {
  const pods = byKind("Deployment").filter(
    (d) => ns(d) === ns(o) && matches(o.obj.spec?.selector, d.obj.spec?.template?.metadata?.labels));
  if (!pods.length) { bad(o, "selects no Deployment's pods"); continue; }
  for (const port of o.obj.spec?.ports ?? []) {
    const named = pods.some((d) => (d.obj.spec.template.spec.containers ?? []).some(
      (c) => (c.ports ?? []).some((p) => p.name === port.targetPort || p.containerPort === port.targetPort)));
    if (!named) bad(o, `port ${port.name}: targetPort ${port.targetPort} is no container port`);
  }
}
for (const o of byKind("PodDisruptionBudget")) {
  const pods = byKind("Deployment").filter(
    (d) => ns(d) === ns(o) && matches(o.obj.spec?.selector?.matchLabels, d.obj.spec?.template?.metadata?.labels));
  if (!pods.length) bad(o, "covers no Deployment's pods");
}
for (const o of byKind("HorizontalPodAutoscaler")) {
  const ref = o.obj.spec?.scaleTargetRef ?? {};
  if (!find(ref.kind, ref.name, ns(o))) bad(o, `scales ${ref.kind}/${ref.name}, which is not there`);
  if ((o.obj.spec?.minReplicas ?? 1) > o.obj.spec?.maxReplicas) bad(o, "minReplicas > maxReplicas");
}
// Both Service flavours per namespace that has the server.
for (const d of byKind("Deployment")) {
  const svcs = byKind("Service").filter((s) => ns(s) === ns(d));
  if (!svcs.some((s) => s.obj.spec?.clusterIP === "None")) bad(d, "no headless Service (client-side round-robin)");
  if (!svcs.some((s) => s.obj.spec?.clusterIP !== "None")) bad(d, "no ClusterIP Service");
}

for (const o of byKind("Job")) {
  const spec = o.obj.spec ?? {};
  const pod = spec.template?.spec ?? {};
  const names = new Set([...(pod.initContainers ?? []), ...(pod.containers ?? [])].map((c) => c.name));
  if (spec.podFailurePolicy) {
    if (pod.restartPolicy !== "Never") bad(o, "podFailurePolicy needs restartPolicy Never");
    for (const r of spec.podFailurePolicy.rules ?? []) {
      const c = r.onExitCodes?.containerName;
      if (c && !names.has(c)) bad(o, `podFailurePolicy names container ${c}, which is not there`);
      if (r.action === "FailIndex" && spec.backoffLimitPerIndex === undefined) bad(o, "FailIndex needs backoffLimitPerIndex");
    }
  }
  if (spec.backoffLimitPerIndex !== undefined && spec.completionMode !== "Indexed") {
    bad(o, "backoffLimitPerIndex needs completionMode Indexed");
  }
}
// The shard count N: the rows Job's completions, GEODEX_SHARDS in its pods
// and in the merge Job's wait, per file (one build per overlay).
const shardsEnv = (o, container) => {
  const pod = o.obj.spec?.template?.spec ?? {};
  const c = [...(pod.initContainers ?? []), ...(pod.containers ?? [])].find((x) => x.name === container);
  return c?.env?.find((e) => e.name === "GEODEX_SHARDS")?.value;
};
for (const rows of byKind("Job").filter((o) => o.obj.spec?.completionMode === "Indexed")) {
  const n = rows.obj.spec.completions;
  if (!(n >= 1)) bad(rows, "an Indexed Job needs completions >= 1");
  if (shardsEnv(rows, "rows") !== String(n)) bad(rows, `GEODEX_SHARDS ${shardsEnv(rows, "rows")} != completions ${n}`);
  if ((rows.obj.spec.parallelism ?? 1) > n) bad(rows, "parallelism > completions");
  const merges = byKind("Job").filter((m) => m.file === rows.file && shardsEnv(m, "wait-for-rows") !== undefined);
  if (!merges.length) bad(rows, "no merge Job waits for these rows");
  for (const m of merges) {
    if (shardsEnv(m, "wait-for-rows") !== String(n)) {
      bad(m, `waits for ${shardsEnv(m, "wait-for-rows")} shards, the rows Job makes ${n}`);
    }
  }
}

if (scriptsDir) {
  mkdirSync(scriptsDir, { recursive: true });
  let count = 0;
  for (const o of objects) {
    const pod = podSpecOf(o);
    for (const c of [...(pod?.initContainers ?? []), ...(pod?.containers ?? [])]) {
      const cmd = c.command ?? [];
      if (cmd[0] === "sh" && cmd[1] === "-c" && cmd.length >= 3) {
        writeFileSync(`${scriptsDir}/${o.obj.metadata.name}.${c.name}.sh`, `#!/bin/sh\n${cmd[2]}\n`);
        count++;
      }
    }
  }
  console.log(`validate: ${count} inline sh scripts written to ${scriptsDir}`);
}

for (const n of [...new Set(notes)]) console.log(`note: ${n}`);
for (const p of problems) console.error(`FAIL ${p}`);
console.log(`validate: ${objects.length} objects in ${argv.length} files, ${problems.length} problems`);
process.exit(problems.length ? 1 : 0);
