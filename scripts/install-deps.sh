#!/usr/bin/env bash
# Installs the Debian packages the build, tests and demo need. Idempotent: does nothing when
# everything is present, so every entry command can call it first.
set -euo pipefail

PACKAGES=(
  build-essential cmake ninja-build pkg-config clang-format
  libeigen3-dev libspdlog-dev libfmt-dev libyaml-cpp-dev libgtest-dev libgmock-dev libbenchmark-dev
  iceoryx libiceoryx-posh-dev libiceoryx-hoofs-dev libiceoryx-introspection-dev
  libfastrtps-dev libfastcdr-dev fastddsgen fastdds-tools
  libcli11-dev libsystemd-dev libbullet-dev libboost-dev nlohmann-json3-dev libssl-dev
  can-utils rt-tests gnuplot-nox procps openssl help2man man-db bsdextrautils
  qemu-system-x86 busybox-static iproute2 xz-utils clang
)

missing=()
for package in "${PACKAGES[@]}"; do
  if ! dpkg-query -W -f='${Status}' "$package" 2>/dev/null | grep -q "install ok installed"; then
    missing+=("$package")
  fi
done

if ((${#missing[@]} == 0)); then
  exit 0
fi

echo "install-deps: installing ${missing[*]}" >&2
SUDO=""
if [[ $(id -u) -ne 0 ]]; then
  SUDO="sudo"
fi
export DEBIAN_FRONTEND=noninteractive
$SUDO apt-get update -qq
$SUDO apt-get install -y -qq --no-install-recommends "${missing[@]}"
