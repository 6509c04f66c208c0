#!/usr/bin/env bash
# Builds the libFuzzer targets (tests/fuzz) with clang in their own tree and runs each
# for a while on a copy of its seed corpus (tests/fuzz/corpus/<target>, never grown).
#
#   tools/fuzz.sh [SECONDS] [TARGET...]     default: 30 s each, every target
#
# FUZZ_BUILD_DIR (default: build-fuzz) may be set. Prints each target's executions,
# speed, coverage and corpus size; exits 1 when any target crashed (its log, grown
# corpus and the input that did it are kept under $FUZZ_BUILD_DIR/out/), 2 on a build or
# usage error. Runs at the same time (ctest, a developer) share the build, nothing else.
set -euo pipefail
cd "$(dirname "$0")/.."

seconds=${1:-30}
shift || true
# (0 would be libFuzzer's "no limit".)
[[ "$seconds" =~ ^[1-9][0-9]*$ ]] || { echo "usage: tools/fuzz.sh [SECONDS] [TARGET...]" >&2; exit 2; }
targets=("$@")
if ((${#targets[@]} == 0)); then
  for f in tests/fuzz/*_fuzzer.cc; do targets+=("$(basename "$f" .cc)"); done
fi

build_dir=${FUZZ_BUILD_DIR:-build-fuzz}
mkdir -p "$build_dir/out"
(
  flock 9  # one build at a time in the tree
  if [ ! -f "$build_dir/CMakeCache.txt" ]; then
    cmake -S . -B "$build_dir" -DCMAKE_BUILD_TYPE=RelWithDebInfo -DFLOORPOSE_FUZZ=ON \
      -DCMAKE_C_COMPILER=clang -DCMAKE_CXX_COMPILER=clang++ >/dev/null
  else
    cmake "$build_dir" >/dev/null  # a target added since the tree was configured
  fi
  cmake --build "$build_dir" -j"$(nproc)" --target "${targets[@]}" >/dev/null
) 9>"$build_dir/out/build.lock" || exit 2

failed=0
for t in "${targets[@]}"; do
  work=$(mktemp -d "$build_dir/out/$t.XXXXXX")
  mkdir "$work/corpus"
  cp tests/fuzz/corpus/"$t"/* "$work/corpus/"
  seeds=$(ls "$work/corpus" | wc -l)
  # Each input gets 10 s (a hang is a failure too); the fuzzer's own output goes to the log.
  if "$build_dir/tests/fuzz/$t" -max_total_time="$seconds" -timeout=10 -print_final_stats=1 \
    -artifact_prefix="$work/" "$work/corpus" >"$work/log" 2>&1; then
    status=ok
  else
    status=FAILED
    failed=1
  fi
  execs=$(sed -n 's/^stat::number_of_executed_units: *//p' "$work/log")
  speed=$(sed -n 's/^stat::average_exec_per_sec: *//p' "$work/log")
  last=$(grep -E '^#[0-9]+' "$work/log" | tail -n 1 || true)
  cov=$(sed -n 's/.* cov: \([0-9]*\).*/\1/p' <<<"$last")
  ft=$(sed -n 's/.* ft: \([0-9]*\).*/\1/p' <<<"$last")
  echo "$t: $status, ${execs:-?} executions (${speed:-?}/s), cov ${cov:-?}, ft ${ft:-?}," \
    "corpus $seeds seeds -> $(ls "$work/corpus" | wc -l)"
  if [ "$status" = ok ]; then
    rm -rf "$work"
  else
    grep -E '^(==[0-9]+==ERROR|SUMMARY|.*runtime error|.*broken promise|artifact_prefix|Test unit)' \
      "$work/log" | head -n 20 | sed 's/^/  /'
    echo "  kept: $work (log, corpus, crash input)"
  fi
done
exit "$failed"
