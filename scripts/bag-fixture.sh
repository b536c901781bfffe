#!/usr/bin/env bash
# Dev-only, for the ROS 2 bag tests: Foxglove's Python `mcap` and `mcap-ros2-support`, a CDR
# encoder and decoder independent of the project's.
#   scripts/bag-fixture.sh make DATASET_DIR OUT_DIR   a prf dataset as a bag + task annotation
#   scripts/bag-fixture.sh read BAG.mcap              a bag's messages, decoded, as JSON
# Sets up its own virtual environment (installing python3-venv when missing).
set -euo pipefail
usage() { echo "usage: $0 make DATASET_DIR OUT_DIR | read BAG.mcap" >&2; exit 2; }
case ${1:-} in
  make) [ $# -eq 3 ] || usage ;;
  read) [ $# -eq 2 ] || usage ;;
  *) usage ;;
esac
root="$(cd "$(dirname "$0")/.." && pwd)"
venv="$root/target/py-bag-fixture"
mkdir -p "$root/target"
# One setup at a time (tests call this in parallel); the environment counts once it is complete.
exec 9>"$venv.lock"
flock 9
if [ ! -e "$venv/.complete" ]; then
  rm -rf "$venv"
  if ! python3 -m venv "$venv" >/dev/null 2>&1; then
    rm -rf "$venv"
    SUDO=""; [ "$(id -u)" -eq 0 ] || SUDO="sudo"
    $SUDO apt-get update -qq
    DEBIAN_FRONTEND=noninteractive $SUDO apt-get install -y -qq python3-venv >/dev/null
    python3 -m venv "$venv"
  fi
  "$venv/bin/pip" install -q --disable-pip-version-check mcap==1.6.0 mcap-ros2-support==0.6.0 \
    PyYAML==6.0.4 zstandard==0.25.0 lz4==4.4.5
  touch "$venv/.complete"
fi
flock -u 9
if [ "$1" = make ]; then
  exec "$venv/bin/python" "$root/tools/bag-fixture/make_bag.py" "$2" "$3"
fi
exec "$venv/bin/python" "$root/tools/bag-fixture/read_mcap.py" "$2"
