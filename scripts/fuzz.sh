#!/usr/bin/env bash
# Runs the libFuzzer targets built in build-fuzz (issue 18; see README "Reliability").
#   scripts/fuzz.sh smoke [RUNS]     what `make test` runs: the regression inputs in fuzz/corpus/TARGET once
#                                    each, then RUNS (default 300) generated inputs per target
#   scripts/fuzz.sh run [SECONDS]    what `make fuzz` runs: SECONDS (default 60) of fuzzing per target
# Seeds: fuzz/corpus/TARGET (regression inputs of fixed findings), the files of scenes/ and tests/ each
# target reads, and inputs made by the real encoders (PATHFARM_FUZZ_SEEDS). The working corpus grows in
# build-fuzz/corpus/TARGET. Prints executions and coverage (libFuzzer's cov: edges, ft: features) per
# target; exits non-zero on the first crash, leak, timeout or sanitizer report (the reproducer is saved
# in build-fuzz/artifacts/).
set -euo pipefail
cd "$(dirname "$0")/.."
MODE=${1:-smoke}
BUILD=${FUZZ_BUILD:-build-fuzz}
TARGETS=${FUZZ_TARGETS:-"fuzz_scene_xml fuzz_mesh fuzz_image fuzz_bundle fuzz_master_requests"}
case "$MODE" in
  smoke) LIMIT=(-runs="${2:-300}" -max_total_time=60) ;;
  run) LIMIT=(-max_total_time="${2:-60}") ;;
  *) echo "usage: $0 smoke [RUNS] | run [SECONDS]" >&2; exit 2 ;;
esac
export ASAN_OPTIONS=${ASAN_OPTIONS:-detect_leaks=1:allocator_may_return_null=1}
export UBSAN_OPTIONS=${UBSAN_OPTIONS:-print_stacktrace=1:halt_on_error=1}
mkdir -p "$BUILD/artifacts"
# The targets write their inputs as files (fuzz/fuzz_util.h): into a directory of the build, emptied per target.
export TMPDIR="$PWD/$BUILD/tmp"

# Seeds from the repository: the files whose format the target reads, with its selector byte.
seed() {  # seed TARGET CORPUS
  local t=$1 dir=$2 f
  case "$t" in
    fuzz_scene_xml)
      for f in tests/bad_scenes/*.xml tests/warning_scenes/*.xml scenes/*/scene.xml; do
        cp "$f" "$dir/repo-$(echo "$f" | tr / _)"; done ;;
    fuzz_mesh)
      for f in tests/bad_scenes/assets/*.ply; do { printf '\x00'; cat "$f"; } > "$dir/repo-$(basename "$f")"; done
      for f in tests/bad_scenes/assets/*.obj scenes/veach-bidir/models/Mesh00[0-4].obj; do
        { printf '\x01'; cat "$f"; } > "$dir/repo-$(echo "$f" | tr / _)"; done ;;
    fuzz_image)
      for f in tests/bad_scenes/assets/*.png; do { printf '\x01'; cat "$f"; } > "$dir/repo-$(basename "$f")"; done ;;
  esac
}

printf '%-22s %10s %8s %8s %8s %s\n' target executions exec/s cov ft corpus
for t in $TARGETS; do
  bin="$BUILD/$t"
  [ -x "$bin" ] || { echo "$bin is not built (make fuzz builds it)" >&2; exit 1; }
  rm -rf "$TMPDIR" && mkdir -p "$TMPDIR"
  corpus="$BUILD/corpus/$t"
  mkdir -p "$corpus" "fuzz/corpus/$t"
  seed "$t" "$corpus"
  PATHFARM_FUZZ_SEEDS="$corpus" "$bin" -runs=0 > /dev/null 2>&1 || true
  log="$BUILD/$t.log"
  # The regression inputs first, once each: a fixed finding must stay fixed.
  if compgen -G "fuzz/corpus/$t/*" > /dev/null; then
    "$bin" -timeout=10 -rss_limit_mb=2048 "fuzz/corpus/$t"/* > "$log.regression" 2>&1 ||
      { cat "$log.regression"; echo "$t: a regression input fails" >&2; exit 1; }
  fi
  if ! "$bin" "${LIMIT[@]}" -timeout=10 -rss_limit_mb=2048 -print_final_stats=1 \
      -artifact_prefix="$BUILD/artifacts/$t-" "$corpus" "fuzz/corpus/$t" > "$log" 2>&1; then
    tail -60 "$log"; echo "$t: FAILED (log: $log)" >&2; exit 1
  fi
  execs=$(grep -o 'stat::number_of_executed_units: *[0-9]*' "$log" | grep -o '[0-9]*$' || echo 0)
  rate=$(grep -o 'stat::average_exec_per_sec: *[0-9]*' "$log" | grep -o '[0-9]*$' || echo 0)
  cov=$(grep -o 'cov: [0-9]*' "$log" | tail -1 | grep -o '[0-9]*$' || echo 0)
  ft=$(grep -o 'ft: [0-9]*' "$log" | tail -1 | grep -o '[0-9]*$' || echo 0)
  printf '%-22s %10s %8s %8s %8s %s\n' "$t" "$execs" "$rate" "$cov" "$ft" "$(ls "$corpus" | wc -l)"
done
