#!/usr/bin/env bash
# Checks scripts/k8s-render.yaml (run by scripts/test.sh): against the Kubernetes API schemas
# (kubernetes-validate --strict, from PyPI, in .venv-k8s/ made by scripts/setup-debian.sh), then
# the fields the farm depends on (Indexed completions, N in agreement, the shared volume), then
# runs both Jobs' shell commands here with a stand-in `illum` to check the arguments each part
# and the merge get, and that the merge names missing parts.
set -euo pipefail
cd "$(dirname "$0")/.."
venv=.venv-k8s
manifest=scripts/k8s-render.yaml
[ -x "$venv/bin/kubernetes-validate" ] || {
  echo "test-k8s: error: $venv/bin/kubernetes-validate not found: run scripts/setup-debian.sh" >&2
  exit 1
}
"$venv/bin/kubernetes-validate" --strict --quiet "$manifest"

"$venv/bin/python" - "$manifest" <<'EOF'
import os, subprocess, sys, tempfile, yaml

path = sys.argv[1]
docs = [d for d in yaml.safe_load_all(open(path)) if d]
def fail(msg):
    sys.exit(f"test-k8s: {path}: {msg}")
by_name = {(d["kind"], d["metadata"]["name"]): d for d in docs}
for key in [("PersistentVolumeClaim", "illum-farm"), ("Job", "illum-render"), ("Job", "illum-merge")]:
    if key not in by_name:
        fail(f"no {key[0]} {key[1]}")
render, merge = by_name["Job", "illum-render"], by_name["Job", "illum-merge"]
pvc = by_name["PersistentVolumeClaim", "illum-farm"]
if "ReadWriteMany" not in pvc["spec"]["accessModes"]:
    fail("the parts volume must be ReadWriteMany: every node writes its part there")
rs = render["spec"]
if rs.get("completionMode") != "Indexed":
    fail(f"job/illum-render spec.completionMode is {rs.get('completionMode')!r}, not Indexed")
n = rs["completions"]
if not 1 <= rs.get("parallelism", 1) <= n:
    fail(f"job/illum-render spec.parallelism {rs.get('parallelism')} is not 1..completions ({n})")

def container(job):
    spec = job["spec"]["template"]["spec"]
    if spec.get("restartPolicy") != "Never":
        fail(f"job/{job['metadata']['name']}: restartPolicy must be Never (a part is retried by the Job)")
    c = spec["containers"][0]
    env = {e["name"]: e.get("value") for e in c.get("env", [])}
    mounts = {m["name"]: m["mountPath"] for m in c.get("volumeMounts", [])}
    claims = {v["name"]: v.get("persistentVolumeClaim", {}).get("claimName") for v in spec.get("volumes", [])}
    if mounts.get("farm") != "/farm" or claims.get("farm") != "illum-farm":
        fail(f"job/{job['metadata']['name']}: volume farm (claim illum-farm) must be mounted at /farm")
    return c, env

for job in (render, merge):
    c, env = container(job)
    if env.get("PARTS") != str(n):
        fail(f"job/{job['metadata']['name']} env PARTS={env.get('PARTS')!r} but job/illum-render "
             f"spec.completions is {n}: N must agree")

# Run both commands with a stand-in illum that prints its arguments.
with tempfile.TemporaryDirectory() as tmp:
    stub = os.path.join(tmp, "illum")
    with open(stub, "w") as f:
        f.write('#!/bin/sh\nprintf "%s\\n" "$@"\n')
    os.chmod(stub, 0o755)
    def run(job, extra_env, farm):
        c, env = container(job)
        cmd = [a.replace("/farm", farm) for a in c["command"]]
        e = dict(os.environ, PATH=f"{tmp}:{os.environ['PATH']}", **env, **extra_env)
        return subprocess.run(cmd, env=e, capture_output=True, text=True)
    r = run(render, {"JOB_COMPLETION_INDEX": "2"}, "/farm")
    args = r.stdout.split("\n")
    want = ["render", "/farm/scene.json", "--part", f"2/{n}"]
    if r.returncode != 0 or args[:4] != want or args[args.index("-o") + 1] != "/farm/parts/part-2.exr":
        fail(f"index 2 ran illum {args} (rc {r.returncode}, {r.stderr!r}); want {want} … -o /farm/parts/part-2.exr")
    farm = os.path.join(tmp, "farm")
    os.makedirs(os.path.join(farm, "parts"))
    for k in range(n):
        if k != 1:
            open(os.path.join(farm, "parts", f"part-{k}.exr"), "w").close()
    r = run(merge, {}, farm)
    if r.returncode == 0 or f"missing part(s) 1 of {n}" not in r.stderr:
        fail(f"the merge with part 1 missing: rc {r.returncode}, {r.stderr!r}")
    open(os.path.join(farm, "parts", "part-1.exr"), "w").close()
    r = run(merge, {}, farm)
    want = ["merge"] + [os.path.join(farm, "parts", f"part-{k}.exr") for k in range(n)] + ["-o", os.path.join(farm, "out.exr")]
    if r.returncode != 0 or r.stdout.split("\n")[:-1] != want:
        fail(f"the merge ran illum {r.stdout.split()} (rc {r.returncode}, {r.stderr!r}); want {want}")
print(f"test-k8s: {path}: schema-valid; Indexed Job of {n} parts and merge Job agree; commands checked")
EOF
