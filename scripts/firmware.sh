#!/usr/bin/env bash
# The cell-controller firmware (runtime/firmware: thumbv7em-none-eabihf, Cortex-M7) under QEMU
# mps2-an500. Installs what it needs when missing (Debian's Rust toolchain with std sources,
# its clippy, qemu-system-arm, binutils-arm-none-eabi for the linker, gcc-arm-none-eabi and
# libstdc++-arm-none-eabi-newlib for Ruckig's C++ core in the output stage), and upgrades a
# rustc-web older than the workspace's rust-version (scripts/debian-rust.sh).
#
#   scripts/firmware.sh build                       build; prints the ELF's path
#   scripts/firmware.sh run CELL.BLOB TASK.BIN [--stream FILE] [--figures FILE]
#                                                   flash the blob at 0x00300000 and the task
#                                                   block (`prf plan … --task-block`) at
#                                                   0x003F0000, run; --stream writes every
#                                                   setpoint to FILE (prf_runtime::stream),
#                                                   --figures the measured figures
#                                                   (prf_runtime::figures)
#   scripts/firmware.sh image CELL.BLOB TASK.BIN   build a self-contained image with both
#                                                   linked in (feature embed); prints its path
#   scripts/firmware.sh run-image ELF [--blob F] [--task F] [--stream FILE] [--figures FILE]
#                                                   [--fault-test]
#                                                   (--fault-test: executes an undefined
#                                                   instruction, to show the HardFault exit)
#   scripts/firmware.sh clippy                      clippy -D warnings on the firmware crate
#
# QEMU runs with -icount shift=0,sleep=off: every instruction takes 1 ns of virtual time, so the
# SysTick counts the firmware reports are deterministic instruction counts, and idle time (WFI
# until the next 1 kHz tick) is skipped. Every QEMU run is limited by `timeout`
# (PRF_QEMU_TIMEOUT seconds, default 300): a hang ends as a failure.
set -euo pipefail
caller=$PWD
# Paths given relative to where the script was called from.
abs() { case $1 in /*) echo "$1" ;; *) echo "$caller/$1" ;; esac; }
cd "$(dirname "$0")/.."
usage() { awk 'NR > 1 && /^#/ { sub(/^# ?/, ""); print; next } NR > 1 { exit }' "$0" >&2; exit 2; }
# shellcheck source=scripts/debian-rust.sh
. scripts/debian-rust.sh

install_missing() {
  local need=()
  for p in rustc-web cargo-web rust-web-src rust-web-clippy qemu-system-arm binutils-arm-none-eabi \
    gcc-arm-none-eabi libstdc++-arm-none-eabi-newlib; do
    dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q 'install ok installed' || need+=("$p")
  done
  if [ ${#need[@]} -gt 0 ]; then
    echo "installing Debian packages: ${need[*]}" >&2
    local SUDO=""; [ "$(id -u)" -eq 0 ] || SUDO="sudo"
    $SUDO apt-get update -qq
    DEBIAN_FRONTEND=noninteractive $SUDO apt-get install -y -qq "${need[@]}" >/dev/null
  fi
  rust_new_enough
}

# Debian's toolchain (rustup cannot add targets here) with -Zbuild-std (.cargo/config.toml).
debian_cargo() {
  (cd runtime/firmware && PATH="/usr/bin:$PATH" RUSTC=/usr/bin/rustc RUSTC_BOOTSTRAP=1 \
    /usr/bin/cargo "$@")
}

qemu() {
  local elf=$1; shift
  local semi="enable=on,target=native,arg=prf-firmware"
  local loaders=()
  while [ $# -gt 0 ]; do
    case $1 in
      --stream) semi+=",arg=--stream,arg=$(abs "${2:?--stream needs a file}")"; shift 2 ;;
      --figures) semi+=",arg=--figures,arg=$(abs "${2:?--figures needs a file}")"; shift 2 ;;
      --fault-test) semi+=",arg=--fault-test"; shift ;;
      --blob) loaders+=(-device "loader,file=$(abs "$2"),addr=0x00300000"); shift 2 ;;
      --task) loaders+=(-device "loader,file=$(abs "$2"),addr=0x003F0000"); shift 2 ;;
      *) usage ;;
    esac
  done
  # QEMU 7.2 hangs silently without semihosting enable=on.
  timeout "${PRF_QEMU_TIMEOUT:-300}" qemu-system-arm -machine mps2-an500 -cpu cortex-m7 \
    -nographic -monitor none -serial none -semihosting-config "$semi" \
    -icount shift=0,sleep=off -kernel "$elf" "${loaders[@]}"
}

elf=runtime/firmware/target/thumbv7em-none-eabihf/release/prf-firmware
image_dir=runtime/firmware/target/image
case ${1:-} in
  build)
    install_missing
    debian_cargo build --release -q --locked
    echo "$elf"
    ;;
  run)
    [ $# -ge 3 ] || usage
    install_missing
    debian_cargo build --release -q --locked
    blob=$2 task=$3; shift 3
    qemu "$elf" --blob "$blob" --task "$task" "$@"
    ;;
  image)
    [ $# -eq 3 ] || usage
    install_missing
    PRF_EMBED_BLOB=$(abs "$2") PRF_EMBED_TASK=$(abs "$3") \
      debian_cargo build --release -q --locked --features embed --target-dir target/image
    echo "$image_dir/thumbv7em-none-eabihf/release/prf-firmware"
    ;;
  run-image)
    [ $# -ge 2 ] || usage
    image=$(abs "$2"); shift 2
    qemu "$image" "$@"
    ;;
  clippy)
    install_missing
    debian_cargo clippy --release -q --locked -- -D warnings
    # The embedded files only need to exist for the lint.
    empty=$(mktemp)
    PRF_EMBED_BLOB=$empty PRF_EMBED_TASK=$empty debian_cargo clippy --release -q --locked \
      --features embed --target-dir target/image -- -D warnings
    rm -f "$empty"
    ;;
  *) usage ;;
esac
