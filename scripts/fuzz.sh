#!/usr/bin/env bash
# Coverage-guided fuzzing (libFuzzer through cargo fuzz) of every reader of outside bytes; the
# harnesses are in fuzz/src (crate prf-fuzz), the targets in fuzz/libfuzzer.
#
#   scripts/fuzz.sh build                 build every target (coverage-instrumented, debug
#                                         assertions on: an integer overflow is a crash)
#   scripts/fuzz.sh run TARGET SECONDS    fuzz one target (its corpus grows in
#                                         fuzz/libfuzzer/corpus/TARGET, seeded from fuzz/seeds)
#   scripts/fuzz.sh all SECONDS           every target for SECONDS each, one after the other;
#                                         prints executions, time and crashes per target
#   scripts/fuzz.sh seeds                 learn the smoke blob again and rewrite fuzz/data and
#                                         fuzz/seeds (after a blob or message format change)
#
# A crash stops the run and leaves its input in fuzz/libfuzzer/artifacts/TARGET/; copy it to
# fuzz/regressions/TARGET/ (the tests replay every file there) once it is fixed.
# Targets: blob task_block setpoints joint_states dataset world robot kb.
set -euo pipefail
cd "$(dirname "$0")/.."

TARGETS=(blob task_block setpoints joint_states dataset world robot kb)
DIR=fuzz/libfuzzer
BIN=$DIR/target/x86_64-unknown-linux-gnu/release

# The machine's stable toolchain takes the sanitizer-coverage flags with RUSTC_BOOTSTRAP=1.
ensure_cargo_fuzz() {
  command -v cargo-fuzz >/dev/null || cargo install --locked -q cargo-fuzz@0.13.2
}

build() {
  ensure_cargo_fuzz
  RUSTC_BOOTSTRAP=1 cargo fuzz build --fuzz-dir "$DIR" -O -a -s none
}

# run TARGET SECONDS: one campaign; prints "TARGET: N executions in S s, C crashes".
run() {
  local t=$1 secs=$2 log
  mkdir -p "$DIR/corpus/$t" "$DIR/artifacts/$t"
  log=$(mktemp)
  set +e
  "$BIN/$t" "$DIR/corpus/$t" "fuzz/seeds/$t" -max_total_time="$secs" -timeout=10 \
    -rss_limit_mb=1024 -print_final_stats=1 -artifact_prefix="$DIR/artifacts/$t/" \
    >"$log" 2>&1
  local rc=$?
  set -e
  local runs
  runs=$(awk '/stat::number_of_executed_units/ { print $2 }' "$log")
  local crashes
  crashes=$(find "$DIR/artifacts/$t" -type f | wc -l)
  printf '%-13s %12s executions in %5s s, exit %d, %d crash inputs in %s\n' \
    "$t" "${runs:-?}" "$secs" "$rc" "$crashes" "$DIR/artifacts/$t"
  if [ $rc -ne 0 ]; then
    grep -E "panicked|ERROR: libFuzzer|SUMMARY" "$log" | head -n 5
    rm -f "$log"
    return 1
  fi
  rm -f "$log"
}

case "${1:-}" in
  build) build ;;
  run) build >/dev/null 2>&1 || build; run "$2" "$3" ;;
  all)
    build >/dev/null 2>&1 || build
    failed=0
    for t in "${TARGETS[@]}"; do run "$t" "$2" || failed=1; done
    exit $failed
    ;;
  seeds)
    smoke=target/smoke-dataset
    rm -rf "$smoke"
    cargo run --locked -q --release -p prf-offline --bin prf -- gen --only 0-1,20,60 -o "$smoke" --quiet
    cargo run --locked -q --release -p prf-offline --bin prf -- learn "$smoke" -o "$smoke/cell.blob" --quiet
    cp "$smoke/cell.blob" fuzz/data/smoke.blob
    mkdir -p fuzz/seeds/dataset
    { printf '\0'; cat "$smoke/manifest.json"; } >fuzz/seeds/dataset/manifest.bin
    cargo run --locked -q --release -p prf-fuzz --bin prf-fuzz-seeds -- --dataset "$smoke" -o fuzz
    ;;
  *) sed -n '2,16p' "$0"; exit 2 ;;
esac
