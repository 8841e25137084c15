#!/usr/bin/env bash
# One whole kernel session on the Cortex-M7 (QEMU mps2-an500) compared with
# the host's `limb run`:
#   1. builds the firmware (release) and the host `limb`;
#   2. runs the session in QEMU under -icount (instruction counts are
#      deterministic) and prints what the target printed;
#   3. diffs the target's canonical digest (event lines, exact model, step
#      counts, command hash) with `limb run --digest` on the host: any
#      difference fails;
#   4. fails when the target session did not complete or its stack outgrew
#      the budget (the firmware's exit code).
# Usage: firmware/session.sh [--debug-host]   (--debug-host: use the host's
# debug `limb`, built when missing, as CI does right after `cargo test`; the
# same numbers: kernel and plant are optimised in every profile and IEEE
# arithmetic is exact)
set -euo pipefail
cd "$(dirname "$0")"
profile=release
[[ "${1:-}" == "--debug-host" ]] && profile=debug
out=target/session
mkdir -p "$out"

cargo build --release --locked --bin session
elf=target/thumbv7em-none-eabihf/release/session
if [[ $profile == release ]]; then
  (cd .. && cargo build --release --locked -p limb-cli)
elif [[ ! -x ../target/debug/limb ]]; then
  (cd .. && cargo build --locked -p limb-cli)
fi

status=0
timeout 1200 qemu-system-arm -M mps2-an500 -cpu cortex-m7 -nographic -monitor none -serial none \
  -icount shift=0 -semihosting-config enable=on,target=native -kernel "$elf" </dev/null >"$out/target.txt" || status=$?
cat "$out/target.txt"
../target/$profile/limb run --digest >"$out/host.txt"
grep -E '^(event|model|steps|command-hash) ' "$out/target.txt" >"$out/target-digest.txt" || true

echo
if ! diff -u --label host --label target "$out/host.txt" "$out/target-digest.txt"; then
  echo "host and target DIFFER (diff above)" >&2
  exit 1
fi
echo "host (limb run) and target (Cortex-M7, QEMU) agree bit for bit: $(grep -c '^event ' "$out/host.txt") events, the model, $(grep '^steps' "$out/host.txt" | cut -d' ' -f2) steps, $(grep '^command-hash' "$out/host.txt")"
if command -v arm-none-eabi-size >/dev/null 2>&1; then
  arm-none-eabi-size -A "$elf" | grep -E '^(section|\.vector_table|\.text|\.rodata|\.data|\.bss|\.uninit|Total)'
fi
if [[ $status -ne 0 ]]; then
  echo "the target session failed (exit $status)" >&2
  exit "$status"
fi
