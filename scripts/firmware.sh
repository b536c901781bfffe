#!/usr/bin/env bash
# Builds the cell-controller firmware (runtime/firmware, thumbv7em-none-eabihf, Cortex-M7) and
# runs it under QEMU mps2-an500 with a blob and a task block flashed into their regions.
# Usage: scripts/firmware.sh CELL.BLOB TASK.BIN   (TASK.BIN from `prf plan … --task-block`)
# Work in progress (issue 7): not yet part of scripts/test.sh.
set -euo pipefail
cd "$(dirname "$0")/.."
blob=${1:?usage: scripts/firmware.sh CELL.BLOB TASK.BIN}
task=${2:?usage: scripts/firmware.sh CELL.BLOB TASK.BIN}

need=()
for p in rustc-web cargo-web rust-web-src qemu-system-arm binutils-arm-none-eabi; do
  dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q 'install ok installed' || need+=("$p")
done
if [ ${#need[@]} -gt 0 ]; then
  SUDO=""; [ "$(id -u)" -eq 0 ] || SUDO="sudo"
  $SUDO apt-get update -qq
  DEBIAN_FRONTEND=noninteractive $SUDO apt-get install -y -qq "${need[@]}" >/dev/null
fi

(cd runtime/firmware && PATH="/usr/bin:$PATH" RUSTC=/usr/bin/rustc RUSTC_BOOTSTRAP=1 \
  /usr/bin/cargo build --release -q)
elf=runtime/firmware/target/thumbv7em-none-eabihf/release/prf-firmware
# QEMU 7.2 hangs silently without enable=on; -icount shift=0 makes SysTick deterministic.
timeout 300 qemu-system-arm -machine mps2-an500 -cpu cortex-m7 -nographic \
  -semihosting-config enable=on,target=native -icount shift=0 -kernel "$elf" \
  -device loader,file="$blob",addr=0x00300000 -device loader,file="$task",addr=0x003F0000
