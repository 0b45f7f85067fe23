#!/usr/bin/env bash
# Short coverage-guided fuzz run of every codec target (seconds each), without needing
# cargo-fuzz: builds the targets with nightly and the same sanitizer-coverage flags cargo-fuzz
# uses, then runs libFuzzer. Usage: rl-drivers/fuzz/smoke.sh [seconds-per-target] (default 10).
# Exits non-zero if a target panics; crashing inputs are written to rl-drivers/fuzz/artifacts/.
set -euo pipefail
cd "$(dirname "$0")"
secs="${1:-10}"
if ! rustup toolchain list | grep -q nightly; then
  echo "SKIP: fuzz smoke run needs a nightly toolchain (rustup toolchain install nightly)"
  exit 0
fi
export CARGO_TARGET_DIR="${CARGO_TARGET_DIR:-target}"
export RUSTFLAGS="-Cpasses=sancov-module -Cllvm-args=-sanitizer-coverage-level=4 \
-Cllvm-args=-sanitizer-coverage-inline-8bit-counters -Cllvm-args=-sanitizer-coverage-pc-table \
-Cllvm-args=-sanitizer-coverage-trace-compares --cfg fuzzing -Cdebug-assertions -Coverflow-checks"
# An explicit --target keeps RUSTFLAGS away from build scripts (as cargo-fuzz does).
host="$(rustc +nightly -vV | sed -n 's/^host: //p')"
cargo +nightly build --release --bins --target "$host"
mkdir -p artifacts
for target in ${FUZZ_TARGETS:-decode_h7 decode_r3 decode_coach decode_can decode_candump decode_sdo parse_eds decode_ecat_frame decode_ecat_mailbox decode_ecat_sii decode_netft decode_modbus decode_rtde decode_ur_realtime}; do
  mkdir -p "corpus/$target"
  echo "==> fuzz $target for ${secs}s"
  status=0
  "$CARGO_TARGET_DIR/$host/release/$target" -max_total_time="$secs" -max_len=1300 \
    -artifact_prefix="artifacts/$target-" "corpus/$target" > "artifacts/$target.log" 2>&1 || status=$?
  grep -E "^Done" "artifacts/$target.log" || true
  if [ "$status" -ne 0 ]; then
    echo "FAIL: $target crashed (exit $status); input saved under rl-drivers/fuzz/artifacts/"
    tail -n 30 "artifacts/$target.log"
    exit 1
  fi
done
echo "fuzz smoke: all targets ran without a crash"
