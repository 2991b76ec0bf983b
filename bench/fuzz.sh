#!/usr/bin/env bash
# Runs every fuzz target (tests/fuzz/) for SECONDS each (default 600, issue 17's
# bench figure), one after the other, from the seed corpus plus what earlier runs
# found (build/fuzz/corpus/), and prints libFuzzer's final stats. A crash, leak
# or timeout stops the script with its input in build/fuzz/<target>-*.
#   bash bench/fuzz.sh [SECONDS]
set -euo pipefail
cd "$(dirname "$0")/.."
seconds="${1:-600}"
cmake --preset fuzz >/dev/null
cmake --build --preset fuzz
for t in garment_obj body feature_file resize; do
  echo "== fuzz_$t, $seconds s"
  mkdir -p "build/fuzz/corpus/$t"
  rc=0
  "build/fuzz/tests/fuzz/fuzz_$t" -max_total_time="$seconds" -timeout=10 -rss_limit_mb=2048 \
    -artifact_prefix="build/fuzz/$t-" -print_final_stats=1 "build/fuzz/corpus/$t" "tests/fuzz/seeds/$t" \
    > "build/fuzz/$t.log" 2>&1 || rc=$?
  grep -E "^(stat::number_of_executed_units|stat::peak_rss_mb|==[0-9]+==ERROR|SUMMARY|Done)" "build/fuzz/$t.log" || true
  if [ "$rc" -ne 0 ]; then echo "fuzz_$t failed (exit $rc): build/fuzz/$t.log"; exit 1; fi
done
