#!/usr/bin/env bash
# Instructions per RDMP step on this machine's CPU, independent of its load: callgrind counts
# `prf bench --profile-steps 2N` and `--profile-steps N`; the difference over N is one step
# (the process's start and the bench's setup cancel). Installs valgrind when missing.
# Usage: scripts/callgrind-step.sh PRF N
set -euo pipefail
prf=$1 n=$2
if ! command -v valgrind >/dev/null; then
  SUDO=""; [ "$(id -u)" -eq 0 ] || SUDO="sudo"
  $SUDO apt-get update -qq && DEBIAN_FRONTEND=noninteractive $SUDO apt-get install -y -qq valgrind >/dev/null
fi
count() {
  local f
  f=$(mktemp)
  valgrind --tool=callgrind --callgrind-out-file="$f" "$prf" bench --profile-steps "$1" >/dev/null 2>&1
  awk '/^summary:/ { print $2 }' "$f"
  rm -f "$f"
}
a=$(count "$n")
b=$(count $((2 * n)))
awk -v a="$a" -v b="$b" -v n="$n" 'BEGIN {
  printf "%d steps: %d instructions; %d steps: %d instructions\n", n, a, 2 * n, b
  printf "one RDMP step (FK, Jacobian, QR, three DMPs): %.0f instructions\n", (b - a) / n
}'
