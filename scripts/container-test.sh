#!/usr/bin/env bash
# make container-test: the farm in real containers (issue 8). Builds the image from deploy/Dockerfile with
# podman, starts a master and two workers on a podman network, runs `pathfarm compare` of path and bdpt on
# a small Cornell box from a client container, checks the report, and tears everything down.
# Needs root (apt-get, rootful podman). Settings for this sandbox: ../shared/docs/CONTAINERS.md.
# Environment: PATHFARM_IMAGE (default localhost/pathfarm:latest), KEEP_REPORT=DIR copies the report there.
set -euo pipefail
cd "$(dirname "$0")/.."

start=$(date +%s)
IMAGE=${PATHFARM_IMAGE:-localhost/pathfarm:latest}
BASE=docker.io/library/debian:bookworm
# crun fails on this machine's hybrid cgroups; runc works (CONTAINERS.md).
podman() { command podman --runtime runc "$@"; }
say() { echo "container-test [$(($(date +%s) - start)) s]: $*"; }
fail() {
    echo "container-test: FAILED: $*" >&2
    exit 1
}

# ---- prerequisites ----
if ! command -v podman >/dev/null || ! command -v runc >/dev/null || ! command -v debootstrap >/dev/null; then
    say "installing podman, runc, debootstrap"
    apt-get update -qq
    DEBIAN_FRONTEND=noninteractive apt-get install -y -qq podman runc debootstrap
fi
# Without this, containers fail with "setrlimit RLIMIT_NOFILE: Operation not permitted" here.
if [ ! -e /etc/containers/containers.conf ]; then
    say "writing /etc/containers/containers.conf (default_ulimits = [])"
    mkdir -p /etc/containers
    printf '[containers]\ndefault_ulimits = []\n' >/etc/containers/containers.conf
fi

python3 deploy/check-manifests.py || fail "deploy/compose.yaml or deploy/k8s/ are inconsistent"

RUN=pfct-$$
WORK=$(mktemp -d /tmp/pathfarm-container-test.XXXXXX)
cleanup() {
    status=$?
    if [ $status -ne 0 ]; then
        [ -s "$WORK/podman.log" ] && { echo "---- podman.log ----" >&2; tail -20 "$WORK/podman.log" >&2; }
        for c in master worker1 worker2; do
            echo "---- logs of $RUN-$c (last 20 lines) ----" >&2
            podman logs --tail 20 "$RUN-$c" >&2 2>&1 || true
        done
    fi
    podman rm -f -v -t 5 "$RUN-master" "$RUN-worker1" "$RUN-worker2" >/dev/null 2>&1 || true
    podman network rm -f "$RUN" >/dev/null 2>&1 || true
    podman volume rm -f "$RUN-data" >/dev/null 2>&1 || true
    rm -rf "$WORK"
    echo "container-test: $([ $status -eq 0 ] && echo passed || echo failed) in $(($(date +%s) - start)) s"
}
trap cleanup EXIT

# ---- base image: no registry here, so Debian's archive through debootstrap, under the name the
# Dockerfile uses (built once, then cached by podman) ----
if ! podman image exists "$BASE"; then
    say "building $BASE with debootstrap (about 5 minutes)"
    debootstrap --variant=minbase bookworm "$WORK/rootfs" >"$WORK/debootstrap.log" 2>&1 ||
        fail "debootstrap (log: $(tail -5 "$WORK/debootstrap.log"))"
    tar -C "$WORK/rootfs" -c . | podman import - "$BASE" >/dev/null
    rm -rf "$WORK/rootfs"
fi
podman image exists "$BASE-slim" || podman tag "$BASE" "$BASE-slim"

# ---- the image (docker format: the OCI format drops HEALTHCHECK) ----
say "building $IMAGE from deploy/Dockerfile"
build_start=$(date +%s)
podman build --pull=never --format docker -t "$IMAGE" -f deploy/Dockerfile . >"$WORK/build.log" 2>&1 ||
    fail "image build (last lines: $(tail -20 "$WORK/build.log"))"
say "image built in $(($(date +%s) - build_start)) s ($(podman image inspect --format '{{.Size}}' "$IMAGE" | awk '{printf "%.0f MB", $1 / 1e6}'))"

# ---- tokens, network, volume ----
deploy/make-tokens.sh "$WORK/secrets"
mkdir -p "$WORK/scene" "$WORK/report"
chown 10001:10001 "$WORK/report"  # the image's unprivileged user writes the report
podman network create "$RUN" >/dev/null
podman volume create "$RUN-data" >/dev/null
secret() { echo "--volume=$WORK/secrets/$1:/run/secrets/$1:ro"; }

# ---- the farm: the image's default command is the master; each worker is held to one CPU, and its
# --threads is left to the default so that the CPU quota reader (worker/cpu_quota.h) decides. Podman runs
# health checks on systemd timers, which this machine lacks: the timers are off and wait_healthy runs
# the image's check itself (podman still complains about the timers: that goes to podman.log) ----
podman run -d --name "$RUN-master" --network "$RUN" --network-alias master --volume "$RUN-data:/var/lib/pathfarm" \
    --health-interval disable "$(secret client_token)" "$(secret worker_token)" "$IMAGE" >/dev/null 2>>"$WORK/podman.log"
for w in worker1 worker2; do
    podman run -d --name "$RUN-$w" --network "$RUN" --cpus 1 --env PATHFARM_HEALTH_ADDR=127.0.0.1:7701 \
        --health-interval disable \
        "$(secret worker_token)" "$IMAGE" pathfarm-worker --master master:7700 \
        --token-file /run/secrets/worker_token --health-listen 0.0.0.0:7701 --cache /tmp/pathfarm-cache --name "$w" \
        >/dev/null 2>>"$WORK/podman.log"
done

# The image's HEALTHCHECK (`pathfarm health` against the gRPC health service), run by podman.
wait_healthy() {
    for _ in $(seq 60); do
        podman healthcheck run "$1" >/dev/null 2>&1 && return 0
        sleep 1
    done
    fail "$1 did not become healthy in 60 s"
}
for c in master worker1 worker2; do wait_healthy "$RUN-$c"; done
say "master and two workers healthy"

client() {
    podman run --rm --no-healthcheck --network "$RUN" "$(secret client_token)" --volume "$WORK/scene:/scene:ro" \
        --volume "$WORK/report:/report" "$IMAGE" "$@"
}
# The master's HTTP probes, as Kubernetes calls them (deploy/k8s/master.yaml); bash's /dev/tcp, since the
# slim image has no HTTP client.
for probe in livez readyz; do
    reply=$(client bash -c "exec 3<>/dev/tcp/master/8080 && printf 'GET /$probe HTTP/1.0\r\n\r\n' >&3 && head -1 <&3")
    [[ $reply == *" 200 "* ]] || fail "master /$probe answered: $reply"
done
workers=$(client pathfarm workers --master master:7700 --token-file /run/secrets/client_token)
echo "$workers"
for w in worker1 worker2; do grep -qw "$w" <<<"$workers" || fail "the master does not list $w"; done
for w in worker1 worker2; do
    podman logs "$RUN-$w" 2>&1 | grep -q "registered with master:7700, 1 threads" ||
        fail "$w did not derive 1 thread from its --cpus 1 quota: $(podman logs "$RUN-$w" 2>&1 | grep registered)"
done
say "both workers registered with 1 thread (--cpus 1)"

# ---- the comparison: the Cornell box at 128 x 128, path against bdpt for 5 s each, against a BDPT
# reference rendered on the same farm first ----
cp -r scenes/cornell-box/. "$WORK/scene/"
sed -i -e 's/name="width" value="[0-9]*"/name="width" value="128"/' \
    -e 's/name="height" value="[0-9]*"/name="height" value="128"/' "$WORK/scene/scene.xml"
say "running pathfarm compare (path, bdpt; 5 s each) across the containers"
compare_start=$(date +%s)
client pathfarm compare /scene/scene.xml --integrators path,bdpt --time 5 --reference-spp 128 --snapshots 4 \
    --master master:7700 --token-file /run/secrets/client_token --cache-dir /report/.cache -o /report/cornell ||
    fail "pathfarm compare"
say "compare took $(($(date +%s) - compare_start)) s"

# ---- the report ----
R=$WORK/report/cornell
for f in index.html report.json reference.exr reference.png; do [ -s "$R/$f" ] || fail "report lacks $f"; done
for integrator in path bdpt; do
    ls "$R"/*"$integrator"*.exr >/dev/null 2>&1 || fail "no EXR of $integrator in the report"
done
python3 - "$R" <<'EOF' || fail "report.json does not describe the two runs on the two workers"
import json, math, os, sys
d = sys.argv[1]
r = json.load(open(os.path.join(d, "report.json")))
assert r["integrators"] == ["path", "bdpt"], r["integrators"]
assert r["farm"]["master"] == "master:7700" and not r["farm"]["embedded"], r["farm"]
# Both containers took part, each with the one thread its --cpus 1 quota allows.
assert [w["threads"] for w in r["farm"]["workers"]] == [1, 1], r["farm"]["workers"]
assert sorted(run["integrator"] for run in r["runs"]) == ["bdpt", "path"], [run["integrator"] for run in r["runs"]]
print(f'{"integrator":<10} {"spp":>6} {"time (s)":>9} {"relMSE":>10} {"RMSE":>10}')
for run in r["runs"]:
    m = run["metrics"]
    for f in (run["exr"], run["png"], run["errorPng"]):
        assert os.path.getsize(os.path.join(d, f)) > 0, f
    # A 5 s render of a 128 x 128 image is neither empty nor equal to its reference.
    assert run["spp"] > 0 and run["renderSeconds"] > 0, run
    assert math.isfinite(m["relmse"]) and 0 < m["relmse"] < 1, m
    print(f'{run["integrator"]:<10} {run["spp"]:>6} {run["renderSeconds"]:>9.2f} {m["relmse"]:>10.4g} {m["rmse"]:>10.4g}')
EOF
grep -q "<table" "$R/index.html" && grep -q "<svg" "$R/index.html" || fail "index.html lacks the table or the plot"
if [ -n "${KEEP_REPORT:-}" ]; then
    mkdir -p "$KEEP_REPORT" && cp -r "$R/." "$KEEP_REPORT/" && say "report copied to $KEEP_REPORT"
fi
say "report checked: index.html, report.json, reference and run EXRs"
