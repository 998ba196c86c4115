#!/usr/bin/env bash
# shellcheck disable=SC2015  # "check && check || fail": fails when either check fails, as meant
# Faults, each provoked for real and checked (loopback and temporary
# directories only):
#   1. the builder killed with SIGKILL at spread-out moments of a build, over
#      a published index: the index path always holds a whole index (the old
#      one or the new one, never part of one); a rerun completes, gives the
#      answers of an uninterrupted build and removes what the killed runs left;
#      the same for one shard of a distributed build (rows);
#   2. a full disk (a small tmpfs) and a read-only one: the builder says so
#      (exit code, "No space left on device" / "Read-only file system"), and
#      the old index stays whole; an output directory the user may not write
#      (as nobody): "Permission denied"; the geodex CLI on a full disk too
#      (at the end, once a server runs);
#   3. the server killed with SIGKILL restarts and serves the same answers;
#   4. the mmap hazard: an index replaced by rename while served changes
#      nothing until the server reloads it; one rewritten in place (same
#      size) stops being served at the next poll (UNAVAILABLE, the checksum
#      failure as the reason), never answered from; one truncated in place
#      while mapped is measured (and printed): a server that does not poll
#      dies of SIGBUS on its next read of a lost page, and its log names the
#      file. A restart refuses the damaged file with its reason, keeps serving
#      the other models, and serves the model again once a whole index is
#      renamed into place.
# Prints what it saw; exits 1 on any violation, 77 when a binary is missing.
# Part 2's full and read-only disks need a private mount namespace (unshare,
# as root or through a user namespace); without one the other checks still
# run, and the script ends SKIPPED (exit 77, which ctest reports as skipped),
# never PASSED.
#
#   faults.sh [--bin-dir DIR] [--kills N]
set -euo pipefail

KILLS=8 BIN_DIR=""
while [ $# -gt 0 ]; do
  case "$1" in
    --bin-dir) BIN_DIR="$2"; shift 2 ;;
    --kills) KILLS="$2"; shift 2 ;;
    *) echo "faults: unknown argument $1" >&2; exit 2 ;;
  esac
done
BIN_DIR="${BIN_DIR:-$(cd "$(dirname "$0")/../.." && pwd)/build}"
BIN_DIR="$(cd "$BIN_DIR" 2> /dev/null && pwd || echo "$BIN_DIR")"  # the script works in $WORK
BUILD_BIN="$BIN_DIR/core/geodex-build"
QUERY_BIN="$BIN_DIR/core/geodex-query"
SERVER_BIN="$BIN_DIR/server/geodex-server"
CLIENT_BIN="$BIN_DIR/client/geodex"
for b in "$BUILD_BIN" "$QUERY_BIN" "$SERVER_BIN" "$CLIENT_BIN"; do
  if [ ! -x "$b" ]; then echo "faults: SKIPPED: no binary $b"; exit 77; fi
done

WORK="$(mktemp -d "${TMPDIR:-/tmp}/geodex-faults.XXXXXX")"
chmod 755 "$WORK"  # part 2 runs a build as nobody inside it
SERVER_PID=""
cleanup() {
  if [ -n "$SERVER_PID" ]; then kill -9 "$SERVER_PID" 2> /dev/null || true; fi
  wait 2> /dev/null || true
  rm -rf "$WORK"
}
trap cleanup EXIT
fail() { echo "faults: FAIL: $*" >&2; exit 1; }
ok() { echo "faults: ok: $*"; }
cd "$WORK"

# --- indexes and the pairs every answer is compared on --------------------------
MESH=builtin:torus
"$BUILD_BIN" "$MESH" -o old.gdx --samples 60 --seed 1 > old.log 2>&1 || { cat old.log; fail "build old"; }
START_MS=$(date +%s%3N)
"$BUILD_BIN" "$MESH" -o ref.gdx --samples 90 --seed 2 > ref.log 2>&1 || { cat ref.log; fail "build ref"; }
BUILD_MS=$(($(date +%s%3N) - START_MS))
FACES=$("$QUERY_BIN" ref.gdx --info --format json | sed -n 's/^    "faces": \([0-9]*\),$/\1/p')
[ -n "$FACES" ] && [ "$FACES" -gt 0 ] || fail "no face count from geodex-query --info"
awk -v f="$FACES" 'BEGIN { srand(7);
  for (i = 0; i < 40; i++)
    printf "%d 0.2 0.3 0.5 %d %s\n", int(rand() * f), int(rand() * f), (i % 4 ? "0.6 0.3 0.1" : "1 0 0") }' \
  > pairs.txt
answers() { "$QUERY_BIN" "$1" --pairs pairs.txt 2> /dev/null; }
answers old.gdx > old.ans || fail "geodex-query on old.gdx"
answers ref.gdx > ref.ans || fail "geodex-query on ref.gdx"
! cmp -s old.ans ref.ans || fail "old and new indexes answer alike: the checks would prove nothing"
temporaries() { find "$1" -maxdepth 1 -name '*.tmp.*' | wc -l; }

# --- 1. the builder killed -------------------------------------------------------
mkdir pub
cp old.gdx pub/staged && mv pub/staged pub/index.gdx
KEPT_OLD=0 GOT_NEW=0
for i in $(seq 1 "$KILLS"); do
  # Spread over the whole build, from its start to just past its measured end.
  DELAY_MS=$((BUILD_MS * i / KILLS))
  "$BUILD_BIN" "$MESH" -o pub/index.gdx --samples 90 --seed 2 > /dev/null 2>&1 &
  PID=$!
  sleep "$(awk -v ms="$DELAY_MS" 'BEGIN { printf "%.3f", ms / 1000 }')"
  kill -9 "$PID" 2> /dev/null || true
  wait "$PID" 2> /dev/null || true
  answers pub/index.gdx > now.ans || fail "kill $i at ${DELAY_MS} ms: pub/index.gdx is not a whole index"
  if cmp -s now.ans old.ans; then
    KEPT_OLD=$((KEPT_OLD + 1))
  elif cmp -s now.ans ref.ans; then
    GOT_NEW=$((GOT_NEW + 1))
    cp old.gdx pub/staged && mv pub/staged pub/index.gdx  # start the next kill from the old one
  else
    fail "kill $i at ${DELAY_MS} ms: pub/index.gdx answers neither as the old index nor as the new"
  fi
done
LEFT=$(temporaries pub)
"$BUILD_BIN" "$MESH" -o pub/index.gdx --samples 90 --seed 2 > rerun.log 2>&1 ||
  { cat rerun.log; fail "the rerun after the kills"; }
answers pub/index.gdx > now.ans && cmp -s now.ans ref.ans || fail "the rerun answers unlike an uninterrupted build"
[ "$(temporaries pub)" -eq 0 ] || fail "the rerun left $(temporaries pub) temporary files"
ok "builder: $KILLS SIGKILLs over a ${BUILD_MS} ms build: the old index whole after $KEPT_OLD," \
  "the new one after $GOT_NEW (killed after its rename), never a partial one; $LEFT temporaries" \
  "left by the killed runs, removed by the rerun, whose answers equal an uninterrupted build's"

# One shard of a distributed build killed mid-way: no rows file appears; the
# rerun of the shard and the merge give the monolithic build's answers.
"$BUILD_BIN" plan "$MESH" --samples 90 --seed 2 -o work > plan.log 2>&1 || { cat plan.log; fail "plan"; }
# Killed as soon as it reports its first row (its progress on stderr), so the
# kill lands mid-shard however fast the machine is.
"$BUILD_BIN" rows work --shard 0/2 > rows0.log 2>&1 &
PID=$!
for _ in $(seq 2000); do
  grep -q '^\[rows\]' rows0.log 2> /dev/null && break
  sleep 0.005
done
kill -0 "$PID" 2> /dev/null || fail "the rows shard ended before it could be killed: $(cat rows0.log)"
kill -9 "$PID"
wait "$PID" 2> /dev/null || true
[ ! -e work/rows-00000-of-00002.bin ] ||
  fail "a rows shard killed mid-way left its rows file: $(tail -n 2 rows0.log)"
KILLED_AT="$(grep '^\[rows\]' rows0.log | tail -n 1)"
for s in 0 1; do
  "$BUILD_BIN" rows work --shard "$s/2" > rows.log 2>&1 || { cat rows.log; fail "rows $s/2"; }
done
"$BUILD_BIN" merge work -o merged.gdx > merge.log 2>&1 || { cat merge.log; fail "merge"; }
answers merged.gdx > now.ans && cmp -s now.ans ref.ans || fail "plan/rows/merge after a killed shard answers unlike the monolithic build"
[ "$(temporaries work)" -eq 0 ] || fail "the rerun of the shard left temporaries in the work directory"
ok "distributed build: a rows shard killed mid-way (its last progress: $KILLED_AT) left no rows file;" \
  "rerun and merge equal the monolithic build"

# --- 2. full and read-only disks, and a directory the user may not write ------------
UNSHARE=""
if unshare -m true 2> /dev/null; then UNSHARE="unshare -m"
elif unshare -rm true 2> /dev/null; then UNSHARE="unshare -rm"
fi
SKIPPED=""
if [ -z "$UNSHARE" ]; then
  SKIPPED="part 2's full and read-only disks and the CLI on a full disk: no private mount namespace (unshare -m / -rm)"
  echo "faults: SKIPPING $SKIPPED"
else
  mkdir disk
  OLD_KB=$(($(stat -c %s old.gdx) / 1024))
  # A tmpfs with room for the old index and not for a second one; then the
  # same filesystem read-only. Runs in a private mount namespace.
  # shellcheck disable=SC2016
  $UNSHARE sh -c '
    set -u
    mount -t tmpfs -o size="$1"k tmpfs disk || exit 90
    cp old.gdx disk/index.gdx
    "$2" "$3" -o disk/index.gdx --samples 90 --seed 2 > full.out 2> full.err
    echo "full_exit $?"
    cmp -s old.gdx disk/index.gdx && echo "full_old_whole 1" || echo "full_old_whole 0"
    echo "full_temporaries $(find disk -name "*.tmp.*" | wc -l)"
    mount -o remount,ro disk || exit 91
    "$2" "$3" -o disk/index.gdx --samples 90 --seed 2 > ro.out 2> ro.err
    echo "ro_exit $?"
    cmp -s old.gdx disk/index.gdx && echo "ro_old_whole 1" || echo "ro_old_whole 0"
  ' faults-disk "$((OLD_KB + 24))" "$BUILD_BIN" "$MESH" > disk.txt 2> disk.err || {
    cat disk.err; fail "part 2 could not mount its tmpfs (exit $?)"; }
  value() { awk -v k="$1" '$1 == k { print $2 }' disk.txt; }
  [ "$(value full_exit)" != 0 ] || fail "the builder succeeded on a full disk"
  grep -q "No space left on device" full.err || fail "the builder on a full disk did not say so: $(cat full.err)"
  [ "$(value full_old_whole)" = 1 ] || fail "a build on a full disk damaged the old index"
  [ "$(value full_temporaries)" = 0 ] || fail "a build on a full disk left its temporary file"
  [ "$(value ro_exit)" != 0 ] || fail "the builder succeeded on a read-only disk"
  grep -q "Read-only file system" ro.err || fail "the builder on a read-only disk did not say so: $(cat ro.err)"
  [ "$(value ro_old_whole)" = 1 ] || fail "a build on a read-only disk damaged the old index"
  ok "full disk: builder exit $(value full_exit), '$(grep -o 'No space left on device' full.err | head -1)'," \
    "the old index whole, no temporary left; read-only disk: exit $(value ro_exit), 'Read-only file system'"
fi
mkdir -m 555 locked
if [ "$(id -u)" -eq 0 ]; then AS_USER="setpriv --reuid=65534 --regid=65534 --clear-groups"; else AS_USER=""; fi
if $AS_USER "$BUILD_BIN" "$MESH" -o locked/index.gdx --samples 40 > locked.out 2> locked.err; then
  fail "the builder wrote into a directory it may not write"
fi
grep -q "Permission denied" locked.err || fail "the builder did not say 'Permission denied': $(cat locked.err)"
ok "unwritable output directory: the builder says '$(grep -o 'Permission denied' locked.err | head -1)'"

# --- 3. the server killed and restarted --------------------------------------------------
free_port() {
  local port
  for _ in $(seq 1 100); do
    port=$((20000 + RANDOM % 40000))
    if ! (exec 3<> "/dev/tcp/127.0.0.1/$port") 2> /dev/null; then echo "$port"; return 0; fi
  done
  return 1
}
REPO="$WORK/models"
publish() {  # FILE MODEL VERSION: staged beside the repository, then renamed
  mkdir -p "$WORK/staging" "$REPO/$2"
  rm -rf "$WORK/staging/$3" && mkdir "$WORK/staging/$3"
  cp "$1" "$WORK/staging/$3/index.gdx"
  mv -T "$WORK/staging/$3" "$REPO/$2/$3"
}
publish old.gdx torus 1
publish old.gdx other 1
ADDR="127.0.0.1:$(free_port)"
start_server() {  # MODELS_SERVING [POLL_SECONDS (default 0.2; 0: only on SIGHUP)]
  "$SERVER_BIN" --models "$REPO" --listen "$ADDR" --poll-seconds "${2:-0.2}" --log-level info \
    >> server.log 2>&1 &
  SERVER_PID=$!
  for _ in $(seq 150); do
    [ "$("$CLIENT_BIN" models --server "$ADDR" 2> /dev/null | grep -c SERVING)" -ge "$1" ] && return 0
    sleep 0.1
  done
  fail "the server did not serve $1 models: $("$CLIENT_BIN" models --server "$ADDR" 2>&1)"
}
served() { "$CLIENT_BIN" distance --server "$ADDR" --model "$1" --pairs pairs.txt 2> served.err; }
start_server 2
served torus > now.ans && cmp -s now.ans old.ans || fail "the server's answers differ from geodex-query's"
kill -9 "$SERVER_PID"
wait "$SERVER_PID" 2> /dev/null || true
start_server 2
served torus > now.ans && cmp -s now.ans old.ans || fail "the restarted server's answers differ"
ok "server: killed with SIGKILL, restarted on the same address, the same answers"

# --- 4. the mmap hazard -------------------------------------------------------------------
# Renames ref.gdx over torus version 1 and waits until the server answers
# with it (its poll reloads the model); fails after 10 s.
rename_ref_in_and_wait() {
  cp ref.gdx "$REPO/torus/1/staged" && mv "$REPO/torus/1/staged" "$REPO/torus/1/index.gdx"
  for _ in $(seq 100); do
    served torus > now.ans 2> /dev/null && cmp -s now.ans ref.ans && return 0
    sleep 0.1
  done
  return 1
}
# Replaced by rename while served: the mapping keeps the old inode; the next
# poll serves the new file.
rename_ref_in_and_wait || fail "an index replaced by rename was not picked up"
kill -0 "$SERVER_PID" || fail "the server died when an index was replaced by rename"
ok "index replaced by rename while served: no interruption, the new answers after the reload"

# Rewritten in place, same size (bytes overwritten in the middle, as a tool
# that writes into the served file would): the next poll sees the served
# file change under its mapping and stops serving it; the model is refused
# (its checksums fail), never answered from the changed bytes.
SIZE=$(stat -c %s "$REPO/torus/1/index.gdx")
dd if=/dev/zero of="$REPO/torus/1/index.gdx" bs=1 seek=$((SIZE / 2)) count=4096 conv=notrunc \
  status=none
touch -d "+2 seconds" "$REPO/torus/1/index.gdx"  # a new mtime even within one clock tick
for _ in $(seq 100); do
  "$CLIENT_BIN" models --server "$ADDR" 2> /dev/null | grep -E "^torus" | grep -q FAILED && break
  sleep 0.1
done
"$CLIENT_BIN" models --server "$ADDR" > models.txt 2>&1
grep -E "^torus" models.txt | grep -q "checksum" ||
  fail "an index rewritten in place was not refused: $(cat models.txt)"
! served torus > /dev/null || fail "the model was answered from an index rewritten in place"
grep -q "UNAVAILABLE" served.err || fail "not UNAVAILABLE after a rewrite in place: $(cat served.err)"
served other > now.ans && cmp -s now.ans old.ans || fail "the other model stopped serving"
grep -q "modified in place while mapped" server.log || fail "the server's log does not say what happened"
ok "index rewritten in place while served: no longer served at the next poll (UNAVAILABLE," \
  "'$(grep -oE 'DATA_LOSS: [^;]*checksum mismatch' models.txt | head -n 1 | sed 's|.*index.gdx: ||')'), the others serve on"

# Truncated in place while mapped (what `cp new.gdx index.gdx` does first):
# measured, not wished away. A server that does not poll (--poll-seconds 0)
# reads the lost pages on the next query.
rename_ref_in_and_wait || fail "the model was not served again after a whole index was renamed into place"
kill "$SERVER_PID"
wait "$SERVER_PID" 2> /dev/null || true
start_server 2 0
truncate -s 4096 "$REPO/torus/1/index.gdx"
TRUNC_OUTCOME="still serving"
for _ in 1 2 3; do
  served torus > /dev/null 2>&1 || true
  kill -0 "$SERVER_PID" 2> /dev/null || break
  sleep 0.2
done
if ! kill -0 "$SERVER_PID" 2> /dev/null; then
  SERVER_STATUS=0
  wait "$SERVER_PID" 2> /dev/null || SERVER_STATUS=$?
  SERVER_PID=""
  TRUNC_OUTCOME="the server died (wait status $SERVER_STATUS$( [ "$SERVER_STATUS" -eq 135 ] && echo ", SIGBUS"))"
  [ "$SERVER_STATUS" -eq 135 ] || fail "truncated in place: the server died, but not of SIGBUS (status $SERVER_STATUS)"
  grep -q "SIGBUS.*$REPO/torus/1/index.gdx" server.log ||
    fail "the server died of SIGBUS without naming the file: $(tail -n 5 server.log)"
else
  fail "an index truncated in place was served on without a SIGBUS (the check expects the hazard): $(cat served.err)"
fi
echo "faults: measured: an index truncated in place while mapped: $TRUNC_OUTCOME; its log: $(grep SIGBUS server.log | tail -n 1)"
# The restart refuses the damaged file, serves the other model, and the model
# again once a whole index is renamed into place.
start_server 1
"$CLIENT_BIN" models --server "$ADDR" > models.txt 2>&1
grep -E "^torus" models.txt | grep -q FAILED || fail "the truncated index was not refused: $(cat models.txt)"
served other > now.ans && cmp -s now.ans old.ans || fail "the other model is not served after the restart"
rename_ref_in_and_wait || fail "the model was not served again after a whole index was renamed into place"
ok "after the SIGBUS: the restart refused the truncated index ($(grep -E '^torus' models.txt | tr -s ' ' | cut -c1-60)...)," \
  "served the other model, and the model again once a whole index was renamed in"
# The CLI's outputs on a full disk: said, and no partial file left.
if [ -n "$UNSHARE" ]; then
  echo "0 0.2 0.3 0.5" > sources.txt
  # shellcheck disable=SC2016
  $UNSHARE sh -c '
    mount -t tmpfs -o size=8k tmpfs disk || exit 90
    "$1" field --server "$2" --model other --sources sources.txt --out disk/field.txt \
      > cli.out 2> cli.err
    echo "cli_exit $?"
    echo "cli_files $(find disk -type f | wc -l)"
  ' faults-cli "$CLIENT_BIN" "$ADDR" > cli.txt 2> cli.mount.err || { cat cli.mount.err; fail "mount for the CLI check"; }
  [ "$(awk '$1 == "cli_exit" { print $2 }' cli.txt)" = 1 ] || fail "geodex field on a full disk: $(cat cli.txt cli.err)"
  grep -q "No space left on device" cli.err || fail "geodex field on a full disk did not say so: $(cat cli.err)"
  [ "$(awk '$1 == "cli_files" { print $2 }' cli.txt)" = 0 ] || fail "geodex field left a partial file on a full disk"
  ok "full disk: geodex field exits 1 with '$(head -c 120 cli.err)', no partial file"
fi
if [ -n "$SKIPPED" ]; then
  echo "faults: SKIPPED (the other checks passed): $SKIPPED"
  exit 77
fi
echo "faults: PASSED"
