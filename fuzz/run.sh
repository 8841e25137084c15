#!/usr/bin/env bash
# Runs every fuzz target (cargo-fuzz, libFuzzer) one after another and
# writes benchmarks/fuzz.md: executions, exec/s, coverage (edges) and
# features, corpus size, crashes.
#
#   fuzz/run.sh --time S            each target for S seconds
#   fuzz/run.sh --runs N [--kernel-runs M]
#                                   each decoder target for N executions,
#                                   kernel_sequence for M (default N / 10)
#   options: --targets "a b"        only these targets
#            --report FILE          write the table there (default
#                                   benchmarks/fuzz.md; `-` for none: the
#                                   run leaves the recorded rows alone)
#
# The table has one row per target: its latest run (fuzz/logs/<target>.row),
# so targets run separately, with different limits, share one report.
#
# Needs the pinned nightly toolchain only (nightly-2026-03-01): the targets are built with exactly the
# flags of `cargo fuzz build -s none` (cargo-fuzz 0.13), so `cargo fuzz run
# <target>` uses the same binaries and CI need not install cargo-fuzz.
# No sanitizer: every target is safe Rust (the crates forbid unsafe), so
# AddressSanitizer would find nothing the overflow checks and assertions
# do not, at half the speed. Release build with debug assertions and
# overflow checks (cargo-fuzz's default).
# The working corpus grows in fuzz/corpus/<target> (not committed),
# starting from the committed seeds in fuzz/seeds/<target>; a crash is
# written to fuzz/artifacts/<target>/ and fails the script.
set -euo pipefail
cd "$(dirname "$0")"

ALL_TARGETS="fri_datagram fri_session arebo_stream zenoh_command zenoh_estop zenoh_heartbeat plant_log drive_log kernel_config kernel_sequence"
targets=$ALL_TARGETS
time_s=""
runs=""
kernel_runs=""
report=../benchmarks/fuzz.md
while [ $# -gt 0 ]; do
  case "$1" in
    --time) time_s=$2; shift 2 ;;
    --runs) runs=$2; shift 2 ;;
    --kernel-runs) kernel_runs=$2; shift 2 ;;
    --targets) targets=$2; shift 2 ;;
    --report) report=$2; shift 2 ;;
    *) echo "usage: fuzz/run.sh (--time S | --runs N [--kernel-runs M]) [--targets \"a b\"] [--report FILE]" >&2; exit 2 ;;
  esac
done
if [ -z "$time_s" ] && [ -z "$runs" ]; then
  echo "fuzz/run.sh: give --time S or --runs N" >&2; exit 2
fi
if [ -n "$runs" ] && [ -z "$kernel_runs" ]; then
  kernel_runs=$((runs / 10))
fi

# The project's one pinned nightly (the one Kani 0.67 pins too); another
# with FUZZ_TOOLCHAIN.
toolchain=${FUZZ_TOOLCHAIN:-nightly-2026-03-01}
host=$(rustc "+$toolchain" -vV | sed -n 's/^host: //p')
RUSTFLAGS="-Cpasses=sancov-module -Cllvm-args=-sanitizer-coverage-level=4"
RUSTFLAGS+=" -Cllvm-args=-sanitizer-coverage-inline-8bit-counters"
RUSTFLAGS+=" -Cllvm-args=-sanitizer-coverage-pc-table"
RUSTFLAGS+=" -Cllvm-args=-sanitizer-coverage-trace-compares --cfg fuzzing"
RUSTFLAGS+=" -Cllvm-args=-simplifycfg-branch-fold-threshold=0"
RUSTFLAGS+=" -Cllvm-args=-sanitizer-coverage-stack-depth -Cdebug-assertions -Ccodegen-units=1"
RUSTFLAGS="$RUSTFLAGS" cargo "+$toolchain" build --locked --target "$host" --release \
  --config 'profile.release.debug="line-tables-only"' --bins
bin="target/$host/release"
mkdir -p logs
failed=""
for target in $targets; do
  mkdir -p "corpus/$target" "artifacts/$target"
  limit=()
  if [ -n "$time_s" ]; then
    limit+=("-max_total_time=$time_s")
  elif [ "$target" = kernel_sequence ]; then
    limit+=("-runs=$kernel_runs")
  else
    limit+=("-runs=$runs")
  fi
  case "$target" in
    plant_log|drive_log) max_len=8192 ;;
    *) max_len=4096 ;;
  esac
  log="logs/$target.log"
  echo "==> $target (${limit[*]})"
  start=$(date +%s)
  status=0
  "$bin/$target" "corpus/$target" "seeds/$target" \
    "${limit[@]}" -max_len=$max_len -timeout=10 -rss_limit_mb=2048 \
    -print_final_stats=1 -artifact_prefix="artifacts/$target/" >"$log" 2>&1 || status=$?
  seconds=$(( $(date +%s) - start ))
  stat() { sed -n "s/^stat::$1: *//p" "$log" | tail -1; }
  executions=$(stat number_of_executed_units)
  rate=$(stat average_exec_per_sec)
  # The last status line: "#N  DONE/pulse  cov: C ft: F corp: U/SIZE ..."
  last=$(grep -E '^#[0-9]+' "$log" | tail -1)
  cov=$(sed -nE 's/.* cov: ([0-9]+).*/\1/p' <<<"$last")
  ft=$(sed -nE 's/.* ft: ([0-9]+).*/\1/p' <<<"$last")
  corp=$(sed -nE 's/.* corp: ([0-9]+\/[0-9]+[a-zA-Z]*).*/\1/p' <<<"$last")
  crashes=$(find "artifacts/$target" -type f | wc -l)
  if [ "$status" -ne 0 ] || [ "$crashes" -ne 0 ]; then
    failed="$failed $target"
    tail -30 "$log"
  fi
  echo "    ${executions:-?} executions, ${rate:-?}/s, cov ${cov:-?}, ft ${ft:-?}, corpus ${corp:-?}, crashes $crashes"
  [ "$report" = - ] || echo "| \`$target\` | ${executions:-?} | ${rate:-?} | ${cov:-?} | ${ft:-?} | ${corp:-?} | $crashes | $seconds | \`${limit[*]}\` | $(date -u +%Y-%m-%d) |" >"logs/$target.row"
done

if [ "$report" != - ]; then
  {
    echo "# Fuzzing"
    echo
    echo "Coverage-guided fuzzing (cargo-fuzz, libFuzzer) of every decoder and of"
    echo "the kernel; targets and their properties: \`fuzz/README.md\`."
    echo
    echo "Each row is a target's latest run of \`fuzz/run.sh\` (limit in the"
    echo "row), on $(nproc) cores shared with other builds, $(rustc "+$toolchain" --version),"
    echo "libFuzzer of libfuzzer-sys, cargo-fuzz's flags without a sanitizer"
    echo "(release with debug assertions and overflow checks). Executions and exec/s are libFuzzer's"
    echo "final figures; cov is the number of instrumented edges reached, ft"
    echo "libFuzzer's features (edges × hit-count buckets, comparisons); corpus"
    echo "is units/bytes after the run, grown from the committed seeds in"
    echo "\`fuzz/seeds/\`; crashes counts the artifacts left by the run."
    echo
    echo "| target | executions | exec/s | cov | ft | corpus | crashes | time [s] | limit | date |"
    echo "|---|---:|---:|---:|---:|---:|---:|---:|---|---|"
    for target in $ALL_TARGETS; do
      if [ -f "logs/$target.row" ]; then cat "logs/$target.row"
      else echo "| \`$target\` | not run | | | | | | | | |"; fi
    done
    echo
    cat findings.md
  } >"$report"
  echo "wrote $report"
fi
if [ -n "$failed" ]; then
  echo "fuzz/run.sh: crashes or failures in:$failed (fuzz/artifacts/, fuzz/logs/)" >&2
  exit 1
fi
