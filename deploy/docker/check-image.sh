#!/usr/bin/env bash
# Builds the image of deploy/docker/Dockerfile with podman on a machine that
# reaches Debian's package mirrors but no container registry, and runs it:
#
#   1. installs podman and debootstrap (Debian packages) if they are missing;
#   2. the base image localhost/debian:12: reused if podman has it, else
#      imported from the cached root filesystem tar
#      ($XDG_CACHE_HOME/geodex-image, default ~/.cache/geodex-image), else made
#      with `debootstrap --variant=minbase bookworm` (with the host's Debian
#      apt sources, so that the image gets bookworm-updates and -security),
#      cached, and imported;
#   3. `podman build --isolation chroot --network host` of the targets server,
#      builder and cli (BASE_IMAGE=RUNTIME_IMAGE=localhost/debian:12);
#   4. exports the server image's root filesystem (podman create + podman
#      export) and checks with ldd inside it that every library of the four
#      binaries resolves, and that the image runs as a non-root user;
#   5. builds a small index of builtin:torus with the image's geodex-build,
#      published atomically into a model repository on the host that is
#      bind-mounted on /models;
#   6. starts the image's ENTRYPOINT + CMD (geodex-server --models /models
#      --listen 0.0.0.0:50051 ...) under chroot, as the image's user, in a
#      mount namespace of its own (the repository, /proc and /dev mounted) and
#      a network namespace of its own (loopback only), asks it for distances
#      with the image's `geodex` CLI, checks that the answers equal the image's
#      offline `geodex-query` on the same index, as text, and stops it
#      (SIGTERM: it must exit 0).
#
# `podman run` is not used: on these machines the OCI runtime refuses to
# start containers (crun: setrlimit RLIMIT_NOFILE; with default_ulimits = []:
# cgroups in hybrid mode not supported), so the image's root filesystem is
# run under chroot. Every podman command here runs with CONTAINERS_CONF
# pointing at a file with `[containers]` / `default_ulimits = []` (written
# by this script), as these machines want.
#
#   deploy/docker/check-image.sh [--jobs N] [--samples M] [--base-only]
#                                [--rebuild-base] [--keep]
#
# --jobs: parallel compile jobs in the build stage (default 2). --samples: m
# of the torus index (default 60). --base-only: stop after step 2.
# --rebuild-base: make the base image anew (debootstrap), replacing the cache.
# --keep: keep the work directory (logs, exported filesystem, repository).
# Needs root (podman rootful, chroot, mount namespaces). The images stay in
# podman's storage (localhost/geodex:VERSION, localhost/geodex-builder:VERSION,
# localhost/geodex-cli:VERSION) and make the next build incremental.
# Exit codes: 0 every check passed; 1 a check failed; 2 bad usage.
set -euo pipefail

SCRIPT_DIR="$(cd "$(dirname "${BASH_SOURCE[0]}")" && pwd)"
ROOT="$(cd "$SCRIPT_DIR/../.." && pwd)"
DOCKERFILE="$SCRIPT_DIR/Dockerfile"
IGNOREFILE="$SCRIPT_DIR/Dockerfile.dockerignore"
BASE_IMAGE="localhost/debian:12"
CACHE_DIR="${XDG_CACHE_HOME:-$HOME/.cache}/geodex-image"
BASE_TAR="$CACHE_DIR/debian-12-minbase.tar"
JOBS=2
SAMPLES=60
BASE_ONLY=0
REBUILD_BASE=0
KEEP=0
MODEL=torus

usage() { sed -n '/^#   deploy\/docker/,/^# Exit codes/p' "$0" | sed 's/^# \{0,1\}//' >&2; exit 2; }
die() { echo "check-image: FAILED: $*" >&2; exit 1; }
log() { echo "check-image: $*"; }

while [ $# -gt 0 ]; do
  case "$1" in
    --jobs) JOBS="${2:?--jobs needs a value}"; shift 2 ;;
    --samples) SAMPLES="${2:?--samples needs a value}"; shift 2 ;;
    --base-only) BASE_ONLY=1; shift ;;
    --rebuild-base) REBUILD_BASE=1; shift ;;
    --keep) KEEP=1; shift ;;
    -h|--help) usage ;;
    *) echo "check-image: unknown argument $1" >&2; usage ;;
  esac
done
[[ "$JOBS" =~ ^[1-9][0-9]*$ ]] || { echo "check-image: --jobs must be a positive integer" >&2; exit 2; }
[[ "$SAMPLES" =~ ^[1-9][0-9]*$ ]] || { echo "check-image: --samples must be a positive integer" >&2; exit 2; }
[ "$(id -u)" -eq 0 ] || { echo "check-image: needs root (rootful podman, chroot, mount namespaces)" >&2; exit 2; }

VERSION="$(sed -n 's/^project(geodex VERSION \([0-9.]*\).*/\1/p' "$ROOT/CMakeLists.txt")"
[ -n "$VERSION" ] || die "cannot read the project version from $ROOT/CMakeLists.txt"
IMAGE_SERVER="localhost/geodex:$VERSION"
IMAGE_BUILDER="localhost/geodex-builder:$VERSION"
IMAGE_CLI="localhost/geodex-cli:$VERSION"

WORK="$(mktemp -d "${TMPDIR:-/tmp}/geodex-check-image.XXXXXX")"
ROOTFS="$WORK/rootfs"
MODELS="$WORK/models"
NETNS="$WORK/netns"
CONTAINER=""
SERVER_PID=""
DEBOOTSTRAP_DIR=""

cleanup() {
  local status=$?
  if [ -n "$SERVER_PID" ] && kill -0 "$SERVER_PID" 2>/dev/null; then
    kill -KILL "$SERVER_PID" 2>/dev/null || true
    wait "$SERVER_PID" 2>/dev/null || true
  fi
  if [ -n "$CONTAINER" ]; then podman rm -f "$CONTAINER" > /dev/null 2>&1 || true; fi
  if mountpoint -q "$NETNS" 2>/dev/null; then umount "$NETNS" || true; fi
  if [ -n "$DEBOOTSTRAP_DIR" ] && [ -d "$DEBOOTSTRAP_DIR" ]; then rm -rf "$DEBOOTSTRAP_DIR"; fi
  if [ "$KEEP" -eq 1 ]; then
    echo "check-image: work directory kept: $WORK" >&2
  else
    rm -rf "$WORK"
  fi
  exit "$status"
}
trap cleanup EXIT
trap 'exit 130' INT
trap 'exit 143' TERM

# podman's default ulimits cannot be set on these machines; no other setting changes.
cat > "$WORK/containers.conf" <<'EOF'
[containers]
default_ulimits = []
EOF
export CONTAINERS_CONF="$WORK/containers.conf"

# --- 1: tools ------------------------------------------------------------------
missing=()
for p in podman debootstrap; do
  dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed" || missing+=("$p")
done
if [ "${#missing[@]}" -gt 0 ]; then
  log "installing ${missing[*]}"
  export DEBIAN_FRONTEND=noninteractive
  apt-get update -qq
  apt-get install -y -qq --no-install-recommends "${missing[@]}" > "$WORK/apt.log" 2>&1 ||
    { tail -20 "$WORK/apt.log" >&2; die "apt-get install ${missing[*]}"; }
fi
log "$(podman --version), $(debootstrap --version)"

# --- 2: the base image ---------------------------------------------------------
# host_bookworm_mirror: the URI of the host's apt source for bookworm (deb822
# or one-line format), so that debootstrap uses the mirror apt uses; empty if
# none (debootstrap's default then).
host_bookworm_mirror() {
  local f
  for f in /etc/apt/sources.list.d/*.sources; do
    [ -f "$f" ] || continue
    awk 'BEGIN { RS = "" }
         /(^|\n)Types:[^\n]*deb([ \t]|\n|$)/ && /(^|\n)Suites:[^\n]*[ \t]bookworm([ \t]|\n|$)/ {
           if (match($0, /(^|\n)URIs:[ \t]*[^ \t\n]+/)) {
             s = substr($0, RSTART, RLENGTH); sub(/^\n?URIs:[ \t]*/, "", s); print s; exit
           }
         }' "$f"
  done | head -1
  if [ -f /etc/apt/sources.list ]; then
    awk '$1 == "deb" && $3 == "bookworm" { print $2; exit }' /etc/apt/sources.list
  fi
}

make_base_tar() {
  local mirror
  mirror="${GEODEX_DEBIAN_MIRROR:-$(host_bookworm_mirror | head -1)}"
  mkdir -p "$CACHE_DIR"
  DEBOOTSTRAP_DIR="$(mktemp -d "$CACHE_DIR/rootfs.XXXXXX")"
  log "base: debootstrap --variant=minbase bookworm ${mirror:-(default mirror)} (a few minutes)"
  # shellcheck disable=SC2086  # $mirror: one word, or none
  debootstrap --variant=minbase bookworm "$DEBOOTSTRAP_DIR" $mirror > "$WORK/debootstrap.log" 2>&1 ||
    { tail -20 "$WORK/debootstrap.log" >&2; die "debootstrap (log above)"; }
  # The host's Debian sources (bookworm, -updates, -security, as in Debian's
  # own images) replace debootstrap's single line, when the host has them.
  if [ -f /etc/apt/sources.list.d/debian.sources ] &&
     grep -qE '^Suites:.*[[:space:]]bookworm([[:space:]]|$)' /etc/apt/sources.list.d/debian.sources; then
    cp /etc/apt/sources.list.d/debian.sources "$DEBOOTSTRAP_DIR/etc/apt/sources.list.d/debian.sources"
    rm -f "$DEBOOTSTRAP_DIR/etc/apt/sources.list"
  fi
  rm -rf "$DEBOOTSTRAP_DIR"/var/cache/apt/archives/*.deb "$DEBOOTSTRAP_DIR"/var/lib/apt/lists/*
  tar -C "$DEBOOTSTRAP_DIR" -c . > "$BASE_TAR.tmp"
  mv -f "$BASE_TAR.tmp" "$BASE_TAR"
  rm -rf "$DEBOOTSTRAP_DIR"
  DEBOOTSTRAP_DIR=""
  log "base: cached $BASE_TAR ($(du -m "$BASE_TAR" | cut -f1) MiB)"
}

if [ "$REBUILD_BASE" -eq 1 ]; then
  podman rmi "$BASE_IMAGE" > /dev/null 2>&1 || true
  rm -f "$BASE_TAR"
fi
if podman image exists "$BASE_IMAGE"; then
  log "base: $BASE_IMAGE present, reused"
else
  if [ -s "$BASE_TAR" ]; then
    log "base: importing the cached $BASE_TAR"
  else
    make_base_tar
  fi
  podman import --quiet --change 'CMD ["/bin/bash"]' "$BASE_TAR" "$BASE_IMAGE" > /dev/null ||
    die "podman import of $BASE_TAR"
  log "base: imported $BASE_IMAGE"
fi
if [ "$BASE_ONLY" -eq 1 ]; then
  log "PASSED (--base-only): $BASE_IMAGE ready"
  exit 0
fi

# --- 3: build the three targets --------------------------------------------------
SECONDS=0
for target in server builder cli; do
  case "$target" in
    server) tag="$IMAGE_SERVER" ;;
    builder) tag="$IMAGE_BUILDER" ;;
    cli) tag="$IMAGE_CLI" ;;
  esac
  log "build: podman build --target $target -t $tag (JOBS=$JOBS; log $WORK/build-$target.log)"
  start=$SECONDS
  if ! podman build --isolation chroot --network host --layers \
      -f "$DOCKERFILE" --ignorefile "$IGNOREFILE" \
      --build-arg BASE_IMAGE="$BASE_IMAGE" --build-arg RUNTIME_IMAGE="$BASE_IMAGE" \
      --build-arg JOBS="$JOBS" --target "$target" -t "$tag" "$ROOT" > "$WORK/build-$target.log" 2>&1; then
    tail -40 "$WORK/build-$target.log" >&2
    die "podman build --target $target (log above)"
  fi
  log "build: $tag in $((SECONDS - start)) s"
done
BUILD_SECONDS=$SECONDS
log "build: all targets in $BUILD_SECONDS s"

# Image sizes, users and entrypoints, as podman records them.
image_field() { podman image inspect --format "$2" "$1"; }
for tag in "$IMAGE_SERVER" "$IMAGE_BUILDER" "$IMAGE_CLI"; do
  size="$(image_field "$tag" '{{.Size}}')"
  user="$(image_field "$tag" '{{.Config.User}}')"
  entrypoint="$(image_field "$tag" '{{join .Config.Entrypoint " "}}')"
  log "image: $tag $((size / 1024 / 1024)) MiB, user $user, entrypoint $entrypoint"
  case "$user" in ""|0|0:*|root|root:*) die "$tag runs as root (user '$user')" ;; esac
done
[ "$(image_field "$IMAGE_BUILDER" '{{join .Config.Entrypoint " "}}')" = /usr/local/bin/geodex-build ] ||
  die "the builder target's entrypoint is not geodex-build"
[ "$(image_field "$IMAGE_CLI" '{{join .Config.Entrypoint " "}}')" = /usr/local/bin/geodex ] ||
  die "the cli target's entrypoint is not geodex"
# builder and cli only change the entrypoint: the same layers as the server.
LAYERS="$(image_field "$IMAGE_SERVER" '{{.RootFS.Layers}}')"
for tag in "$IMAGE_BUILDER" "$IMAGE_CLI"; do
  [ "$(image_field "$tag" '{{.RootFS.Layers}}')" = "$LAYERS" ] ||
    die "$tag does not share the server image's layers (the runtime stage)"
done
log "image: the three targets share one filesystem ($(image_field "$IMAGE_SERVER" '{{len .RootFS.Layers}}') layers)"
BASE_SIZE="$(image_field "$BASE_IMAGE" '{{.Size}}')"
log "image: base $BASE_IMAGE $((BASE_SIZE / 1024 / 1024)) MiB"

# --- 4: the server image's root filesystem -------------------------------------------
USERSPEC="$(image_field "$IMAGE_SERVER" '{{.Config.User}}')"
mapfile -t IMAGE_ENV < <(image_field "$IMAGE_SERVER" '{{range .Config.Env}}{{println .}}{{end}}' | sed '/^$/d')
mapfile -t ENTRYPOINT < <(image_field "$IMAGE_SERVER" '{{range .Config.Entrypoint}}{{println .}}{{end}}' | sed '/^$/d')
mapfile -t CMD < <(image_field "$IMAGE_SERVER" '{{range .Config.Cmd}}{{println .}}{{end}}' | sed '/^$/d')
[ "${#ENTRYPOINT[@]}" -gt 0 ] || die "$IMAGE_SERVER has no entrypoint"

CONTAINER="$(podman create "$IMAGE_SERVER")" || die "podman create $IMAGE_SERVER"
mkdir -p "$ROOTFS"
podman export "$CONTAINER" | tar -C "$ROOTFS" -x || die "podman export | tar -x"
podman rm "$CONTAINER" > /dev/null
CONTAINER=""
log "rootfs: exported $IMAGE_SERVER ($(du -sm "$ROOTFS" | cut -f1) MiB)"

BINARIES=(geodex-server geodex-build geodex-query geodex)
for b in "${BINARIES[@]}"; do
  [ -x "$ROOTFS/usr/local/bin/$b" ] || die "no /usr/local/bin/$b in the image"
  chroot "$ROOTFS" /usr/bin/ldd "/usr/local/bin/$b" > "$WORK/ldd-$b.txt" 2>&1 ||
    { cat "$WORK/ldd-$b.txt" >&2; die "ldd /usr/local/bin/$b in the image"; }
  if grep -q 'not found' "$WORK/ldd-$b.txt"; then
    grep 'not found' "$WORK/ldd-$b.txt" >&2
    die "$b: libraries missing from the image (above)"
  fi
  log "ldd: $b: $(grep -c '=> /' "$WORK/ldd-$b.txt") libraries, all resolved"
done

# --- 5 + 6: run it -------------------------------------------------------------------
# A network namespace with only loopback, as a container's, kept by a bind
# mount on $NETNS until cleanup.
touch "$NETNS"
unshare --net="$NETNS" true || die "unshare --net"
nsenter --net="$NETNS" ip link set lo up || die "ip link set lo up in the network namespace"

# IN_IMAGE ARGV...: runs ARGV under chroot in the image's root filesystem as
# the image's user and with the image's environment only, in the network
# namespace above and a private mount namespace where the repository is
# bind-mounted on /models and /proc, /dev are mounted (gone when it exits).
# Every step execs the next: the pid of "${IN_IMAGE[@]}" ... & is ARGV's.
# shellcheck disable=SC2016  # expanded by the inner bash, not here
IN_IMAGE=(nsenter --net="$NETNS" unshare --mount --propagation private -- /bin/bash -c '
    set -e
    rootfs="$1" models="$2" userspec="$3"; shift 3
    mount --bind "$models" "$rootfs/models"
    mount -t proc proc "$rootfs/proc"
    mount --rbind /dev "$rootfs/dev"
    exec chroot --userspec="$userspec" "$rootfs" /usr/bin/env -i "$@"'
  _ "$ROOTFS" "$MODELS" "$USERSPEC" "${IMAGE_ENV[@]}")
in_image() { "${IN_IMAGE[@]}" "$@"; }

# The repository on the host, writable by the image's user (a volume).
mkdir -p "$MODELS"
chown "$USERSPEC" "$MODELS"
log "model: geodex-build builtin:$MODEL --samples $SAMPLES in the image, published as /models/$MODEL/1/index.gdx"
start=$SECONDS
# Built to a temporary name in the version directory, then renamed: the
# server ignores a version directory without index.gdx.
in_image /bin/sh -c "set -e
  mkdir -p /models/$MODEL/1
  /usr/local/bin/geodex-build builtin:$MODEL -o /models/$MODEL/1/.index.gdx.partial --samples $SAMPLES --threads $JOBS
  mv -f /models/$MODEL/1/.index.gdx.partial /models/$MODEL/1/index.gdx" > "$WORK/builder.log" 2>&1 ||
  { tail -20 "$WORK/builder.log" >&2; die "geodex-build in the image"; }
[ -s "$MODELS/$MODEL/1/index.gdx" ] || die "no $MODEL/1/index.gdx in the repository"
log "model: $(du -k "$MODELS/$MODEL/1/index.gdx" | cut -f1) KiB in $((SECONDS - start)) s, owned by $(stat -c %u:%g "$MODELS/$MODEL/1/index.gdx")"

FACES="$(in_image /usr/local/bin/geodex-query "/models/$MODEL/1/index.gdx" --info --format json |
  sed -n 's/^    "faces": \([0-9]*\),$/\1/p')" ||
  die "geodex-query --info in the image"
[[ "$FACES" =~ ^[1-9][0-9]*$ ]] || die "geodex-query --info in the image gave no face count"
# Pairs inside faces and at vertices, spread over the mesh (fixed seed).
awk -v f="$FACES" 'BEGIN { srand(20);
  for (i = 0; i < 16; i++)
    printf "%d 0.2 0.3 0.5 %d %s\n", int(rand() * f), int(rand() * f), (i % 4 ? "0.6 0.3 0.1" : "1 0 0") }' \
  > "$ROOTFS/tmp/pairs.txt"
chmod 0644 "$ROOTFS/tmp/pairs.txt"

log "server: ${ENTRYPOINT[*]} ${CMD[*]} (the image's entrypoint and command, as $USERSPEC)"
"${IN_IMAGE[@]}" "${ENTRYPOINT[@]}" "${CMD[@]}" > "$WORK/server.out" 2> "$WORK/server.log" &
SERVER_PID=$!
PORT=""
for _ in $(seq 1 150); do
  PORT="$(sed -n 's/^listening on port \([0-9]*\)$/\1/p' "$WORK/server.out")"
  [ -n "$PORT" ] && break
  kill -0 "$SERVER_PID" 2>/dev/null || { cat "$WORK/server.log" >&2; die "geodex-server exited at start"; }
  sleep 0.2
done
[ -n "$PORT" ] || { cat "$WORK/server.log" >&2; die "geodex-server did not listen within 30 s"; }
SERVER_UID="$(awk '/^Uid:/ { print $2 }' "/proc/$SERVER_PID/status")"
log "server: pid $SERVER_PID, uid $SERVER_UID, listening on port $PORT"
[ "$SERVER_UID" = "${USERSPEC%%:*}" ] || die "the server runs as uid $SERVER_UID, not the image's user $USERSPEC"

ADDR="127.0.0.1:$PORT"
served=""
for _ in $(seq 1 150); do
  served="$(in_image /usr/local/bin/geodex info --server "$ADDR" --model "$MODEL" --format json --attempts 1 --timeout 2 2>/dev/null |
    sed -n 's/^  "version": \([0-9]*\),$/\1/p')" || true
  [ "$served" = 1 ] && break
  kill -0 "$SERVER_PID" 2>/dev/null || { cat "$WORK/server.log" >&2; die "geodex-server exited"; }
  sleep 0.2
done
[ "$served" = 1 ] || { cat "$WORK/server.log" >&2; die "the server does not serve $MODEL version 1 after 30 s"; }
in_image /usr/local/bin/geodex models --server "$ADDR" > "$WORK/models.txt" 2>&1 ||
  { cat "$WORK/models.txt" >&2; die "geodex models"; }
sed 's/^/check-image: geodex models: /' "$WORK/models.txt"

in_image /usr/local/bin/geodex distance --server "$ADDR" --model "$MODEL" --pairs /tmp/pairs.txt \
  > "$WORK/answers.txt" 2> "$WORK/answers.err" || { cat "$WORK/answers.err" >&2; die "geodex distance"; }
in_image /usr/local/bin/geodex-query "/models/$MODEL/1/index.gdx" --pairs /tmp/pairs.txt \
  > "$WORK/expected.txt" 2> "$WORK/expected.err" || { cat "$WORK/expected.err" >&2; die "geodex-query"; }
[ "$(wc -l < "$WORK/expected.txt")" -eq 16 ] || die "geodex-query gave $(wc -l < "$WORK/expected.txt") answers for 16 pairs"
if ! cmp -s "$WORK/answers.txt" "$WORK/expected.txt"; then
  diff "$WORK/answers.txt" "$WORK/expected.txt" | head -10 >&2
  die "the server's distances differ from geodex-query's (above: server <, offline >)"
fi
log "distance: pair 1 '$(head -1 "$ROOTFS/tmp/pairs.txt")': server $(head -1 "$WORK/answers.txt"), geodex-query $(head -1 "$WORK/expected.txt")"
log "distance: all 16 answers of the server equal geodex-query's, as text"

kill -TERM "$SERVER_PID"
server_status=0
wait "$SERVER_PID" || server_status=$?
SERVER_PID=""
[ "$server_status" -eq 0 ] || { tail -20 "$WORK/server.log" >&2; die "geodex-server exited $server_status on SIGTERM"; }
log "server: stopped by SIGTERM, exit 0"

# docker-compose.yml cannot be run here (no compose run, no podman run):
# checked offline with Python's yaml module where it is installed (Debian's
# python3-yaml, a dependency of podman-compose): it parses; the services'
# build targets are stages of the Dockerfile; the server waits for the
# builder and polls; the builder publishes by rename; no `$` is left for
# compose to interpolate from the host's environment (the shell's are `$$`).
# (podman-compose 1.0.3 has no `config`, and its --dry-run creates volumes.)
if python3 -c 'import yaml' 2> /dev/null; then
  python3 - "$SCRIPT_DIR/docker-compose.yml" "$DOCKERFILE" > "$WORK/compose.txt" 2>&1 <<'PY' ||
import re, sys, yaml
compose_path, dockerfile_path = sys.argv[1], sys.argv[2]
text = open(compose_path).read()
doc = yaml.safe_load(text)
stages = set(re.findall(r"^FROM\s+\S+\s+AS\s+(\S+)", open(dockerfile_path).read(), re.M | re.I))
services = doc["services"]
assert {"server", "builder"} <= set(services), "services server and builder"
for name, svc in services.items():
    target = svc["build"]["target"]
    assert target in stages, f"{name}: target {target} is no stage of the Dockerfile ({sorted(stages)})"
    assert svc["build"]["dockerfile"] == "deploy/docker/Dockerfile", f"{name}: dockerfile"
server, builder = services["server"], services["builder"]
assert server["depends_on"]["builder"]["condition"] == "service_completed_successfully", "server waits for builder"
assert "--poll-seconds" in server["command"], "server polls the repository"
assert any(v.startswith("models:/models") for v in server["volumes"]), "server mounts the models volume"
assert any(v == "models:/models" for v in builder["volumes"]), "builder mounts the models volume read-write"
assert "models" in doc["volumes"], "volume models declared"
script = "\n".join(builder["command"])
assert re.search(r"\bmv\b.*\.index\.gdx\.partial.*index\.gdx", script), "builder renames the index into place"
for m in re.finditer(r"\$+", text):
    assert len(m.group()) % 2 == 0, f"unescaped $ at offset {m.start()}: compose would interpolate it"
print(f"services {sorted(services)}, targets {sorted(s['build']['target'] for s in services.values())}")
PY
    { cat "$WORK/compose.txt" >&2; die "docker-compose.yml (above)"; }
  log "compose: docker-compose.yml parses and is consistent: $(cat "$WORK/compose.txt") (not run)"
else
  log "compose: docker-compose.yml not checked (no python3-yaml)"
fi

log "PASSED: $IMAGE_SERVER, $IMAGE_BUILDER, $IMAGE_CLI built in $BUILD_SECONDS s; the image's server answered as geodex-query"
