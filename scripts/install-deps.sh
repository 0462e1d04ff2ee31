#!/usr/bin/env bash
# Installs the Debian 12 packages hivecal needs (only what is missing). Idempotent.
#   scripts/install-deps.sh            everything: build, tests, cross targets, benchmarks
set -euo pipefail

packages=(
  cmake ninja-build g++ libeigen3-dev googletest          # host build and tests
  clang libclang-rt-14-dev                                # libFuzzer targets (decoder, log readers)
  clang-format                                            # the code's style, checked in CTest (code.format)
  libsqlite3-dev                                          # ROS 2 bags (rosbag2 sqlite3 storage)
  liborocos-kdl-dev libkdl-parser-dev                     # the exported URDF read by ROS's own libraries (tests/kdl)
  qemu-user qemu-system-arm                               # running cross-built tests
  g++-aarch64-linux-gnu g++-arm-linux-gnueabihf            # Linux ARM edge controllers
  gcc-arm-none-eabi libnewlib-arm-none-eabi libstdc++-arm-none-eabi-newlib  # Cortex-M
  libpagmo-dev libceres-dev                               # benchmark peers only
  valgrind hyperfine time                                 # instruction counts, timings, peak memory
  chromium                                                # the report test renders the HTML headless
)

missing=()
for p in "${packages[@]}"; do
  dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed" || missing+=("$p")
done
if [ ${#missing[@]} -eq 0 ]; then
  exit 0
fi

echo "install-deps: installing ${missing[*]}" >&2
sudo_cmd=()
if [ "$(id -u)" -ne 0 ]; then sudo_cmd=(sudo); fi
export DEBIAN_FRONTEND=noninteractive
"${sudo_cmd[@]}" apt-get update -qq
"${sudo_cmd[@]}" apt-get install -y -qq --no-install-recommends "${missing[@]}" >/dev/null
