#!/usr/bin/env bash
# The project's test command (README, "Two commands"): installs what it needs, then runs every check
# CI runs. Usage: scripts/test.sh
set -euo pipefail
cd "$(dirname "$0")/.."

# After each step, how long it took (CI gives the whole command 40 minutes).
last=$SECONDS
step() {
  [ -z "${current:-}" ] || printf '    (%s: %d s)\n' "$current" $((SECONDS - last))
  current=${*%% (*}; last=$SECONDS
  printf '\n==> %s\n' "$*"
}
timing() { printf '    (%s: %d s)\ntotal %d s\n' "${current:-set-up}" $((SECONDS - last)) "$SECONDS"; }
trap timing EXIT

# Debian's Rust (rustc/cargo 1.96 with matching std sources) cross-builds the no_std crates for
# the Cortex-M7 cell controller; rustup cannot add targets on these machines. Ruckig's C++ core
# (prf-ruckig) is cross-compiled with Debian's arm-none-eabi-g++ and newlib.
# Charts (SVG and PNG) set their text in DejaVu Sans.
APT_PACKAGES=(rustc-web cargo-web rust-web-src gcc-arm-none-eabi libstdc++-arm-none-eabi-newlib
  fonts-dejavu-core)
missing=()
for p in "${APT_PACKAGES[@]}"; do
  dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q 'install ok installed' || missing+=("$p")
done
if [ ${#missing[@]} -gt 0 ]; then
  step "installing Debian packages: ${missing[*]}"
  SUDO=""; [ "$(id -u)" -eq 0 ] || SUDO="sudo"
  $SUDO apt-get update -qq
  DEBIAN_FRONTEND=noninteractive $SUDO apt-get install -y -qq "${missing[@]}" >/dev/null
fi
# shellcheck source=scripts/debian-rust.sh
. scripts/debian-rust.sh
rust_new_enough

step "cargo fmt --check"
cargo fmt --all -- --check
cargo fmt --manifest-path fuzz/libfuzzer/Cargo.toml -- --check

step "cargo clippy -D warnings"
cargo clippy --workspace --all-targets --locked -q -- -D warnings

step "cargo doc -D warnings (intra-doc links resolve, none to private items from public ones)"
RUSTDOCFLAGS="-D warnings" cargo doc --workspace --no-deps --locked -q

# The firmware is the no_std proof: it builds prf-shared, prf-runtime and prf-ruckig for
# thumbv7em-none-eabihf with -Zbuild-std=core (runtime/firmware/.cargo/config.toml), so none of
# them can use std or alloc.
step "firmware (Cortex-M7; the no_std proof of prf-shared, prf-runtime, prf-ruckig): fmt, clippy -D warnings, build (installs qemu-system-arm, binutils-arm-none-eabi)"
(cd runtime/firmware && cargo fmt -- --check)
scripts/firmware.sh clippy
scripts/firmware.sh build

step "main job smoke run: prf demo --task 1 (dataset, blob, firmware-sim, one task in real time)"
cargo run --locked -q -p prf-offline --bin prf -- demo --task 1 >/tmp/prf-demo.$$ || { cat /tmp/prf-demo.$$; exit 1; }
tail -n 4 /tmp/prf-demo.$$; rm -f /tmp/prf-demo.$$

step "CLI smoke run: prf rdmp-demo (kinematics and RDMP on the built-in robot)"
cargo run --locked -q -p prf-offline --bin prf -- rdmp-demo | tail -n 2

step "CLI smoke run: prf gen (4 demonstrations) + prf check-dataset against the ground truth"
smoke=target/smoke-dataset
rm -rf "$smoke"
cargo run --locked -q -p prf-offline --bin prf -- gen --only 0-1,20,60 -o "$smoke" --quiet
cargo run --locked -q -p prf-offline --bin prf -- check-dataset "$smoke" --world example | tail -n 2

step "CLI smoke run: prf learn (those 4) + prf inspect"
cargo run --locked -q -p prf-offline --bin prf -- learn "$smoke" -o "$smoke/cell.blob" --quiet
cargo run --locked -q -p prf-offline --bin prf -- inspect "$smoke/cell.blob" | tail -n 4

step "CLI smoke run: prf plan (every task on that blob, one program exported at 1 kHz)"
cargo run --locked -q -p prf-offline --bin prf -- plan "$smoke/cell.blob" --all | tail -n 1
cargo run --locked -q -p prf-offline --bin prf -- plan "$smoke/cell.blob" --part Part1 --from CNC1 \
  --to Table1 --export "$smoke/program.csv" | tail -n 1

step "CLI smoke run: prf envelope (the nominal part pose and 10 mm around it, one yaw)"
cargo run --locked -q -p prf-offline --bin prf -- envelope "$smoke/cell.blob" --part Part1 --from CNC1 \
  --to Table1 --range-mm 10 --step-mm 10 --yaw-deg 0 --budget-steps 20000 -o "$smoke/envelope" | tail -n 1

step "CLI smoke run: prf view, prf export-mcap and prf field-error (the tour's viewers and the field against the exact Ω+)"
cargo run --locked -q -p prf-offline --bin prf -- view "$smoke/cell.blob" --part Part1 --from CNC1 \
  --to Table1 -o "$smoke/view" | tail -n 1
cargo run --locked -q -p prf-offline --bin prf -- export-mcap --blob "$smoke/cell.blob" \
  -o "$smoke/knowledge.mcap" | tail -n 1
cargo run --locked -q -p prf-offline --bin prf -- field-error "$smoke" --points 200 | tail -n 4

step "CLI smoke run: prf bench-learn (the plant, archives of 1 and 2 programs each taught its own way, every task planned on each)"
cargo run --locked -q -p prf-offline --bin prf -- bench-learn --world plant --vary --n 1,2 \
  -o "$smoke/learn-scale" --quiet | tail -n 2

step "fuzzing, short: every target 5 s from the committed seeds (scripts/fuzz.sh all 5; installs cargo-fuzz)"
scripts/fuzz.sh all 5

step "cargo test (workspace)"
log=$(mktemp)
trap 'rm -f "$log"; timing' EXIT
cargo test --workspace --locked 2>&1 | tee "$log"
# One closing line over all test binaries (cargo's last line is often a crate with 0 doc-tests).
awk '/^test result:/ { for (i = 1; i <= NF; i++) { if ($i ~ /^passed/) p += $(i-1); if ($i ~ /^failed/) f += $(i-1) } }
     END { printf "\nsummary: %d passed, %d failed\n", p, f; exit (f > 0 || p == 0) }' "$log"
