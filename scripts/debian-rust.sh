# Sourced by scripts/test.sh and scripts/firmware.sh: Debian's Rust toolchain (`rustc-web`,
# which cross-builds the no_std crates) new enough for the workspace. A `rustc-web` installed
# before the last `apt-get update` may be older than the crates need ("rustc 1.85.0 is not
# supported by the following packages"): `rust_new_enough` upgrades it, or stops naming both
# versions. Run from the repository's root.

# The workspace's rust-version (Cargo.toml); "older A B": version A sorts before version B.
rust_version() { sed -n 's/^rust-version *= *"\([0-9.]*\)".*/\1/p' Cargo.toml | head -1; }
older() { [ "$1" != "$2" ] && [ "$(printf '%s\n%s\n' "$1" "$2" | sort -V | head -1)" = "$1" ]; }
debian_rustc() { /usr/bin/rustc --version | awk '{ print $2 }'; }

rust_new_enough() {
  local want have
  want=$(rust_version) have=$(debian_rustc)
  older "$have" "$want" || return 0
  echo "Debian's rustc $have is older than the workspace's rust-version $want: upgrading rustc-web" >&2
  local SUDO=""; [ "$(id -u)" -eq 0 ] || SUDO="sudo"
  $SUDO apt-get update -qq
  DEBIAN_FRONTEND=noninteractive $SUDO apt-get install -y -qq --only-upgrade \
    rustc-web cargo-web rust-web-src rust-web-clippy >/dev/null
  have=$(debian_rustc)
  if older "$have" "$want"; then
    echo "error: rustc-web gives rustc $have, the workspace needs $want or newer" \
      "(apt-cache policy rustc-web: no newer version in this machine's Debian sources)" >&2
    exit 1
  fi
}
