#!/usr/bin/env bash
# Dev-only: writes a prf dataset as a ROS 2 bag (MCAP + task annotation) with Foxglove's Python
# `mcap` and `mcap-ros2-support`, an encoder independent of the project's reader, for
# `prf import-bag`'s tests. Sets up its own virtual environment (installing python3-venv when
# missing). Usage: scripts/bag-fixture.sh DATASET_DIR OUT_DIR
set -euo pipefail
[ $# -eq 2 ] || { echo "usage: $0 DATASET_DIR OUT_DIR" >&2; exit 2; }
root="$(cd "$(dirname "$0")/.." && pwd)"
venv="$root/target/py-bag-fixture"
if [ ! -x "$venv/bin/python" ]; then
  if ! python3 -m venv "$venv" >/dev/null 2>&1; then
    rm -rf "$venv"
    SUDO=""; [ "$(id -u)" -eq 0 ] || SUDO="sudo"
    $SUDO apt-get update -qq
    DEBIAN_FRONTEND=noninteractive $SUDO apt-get install -y -qq python3-venv >/dev/null
    python3 -m venv "$venv"
  fi
  "$venv/bin/pip" install -q --disable-pip-version-check mcap==1.6.0 mcap-ros2-support==0.6.0 \
    PyYAML==6.0.4 zstandard==0.25.0 lz4==4.4.5
fi
exec "$venv/bin/python" "$root/tools/bag-fixture/make_bag.py" "$1" "$2"
