#!/usr/bin/env bash
# The test command (README): installs Mesa's software Vulkan driver (lavapipe) when no
# Vulkan driver is present, then runs the whole test suite on it.
set -euo pipefail
cd "$(dirname "$0")/.."
if ! ls /usr/share/vulkan/icd.d/*.json >/dev/null 2>&1 && ! ls /etc/vulkan/icd.d/*.json >/dev/null 2>&1; then
    echo "no Vulkan driver found: installing mesa-vulkan-drivers (lavapipe)"
    SUDO=""
    [ "$(id -u)" -ne 0 ] && SUDO="sudo"
    $SUDO apt-get update -qq
    DEBIAN_FRONTEND=noninteractive $SUDO apt-get install -y -qq mesa-vulkan-drivers >/dev/null
fi
# Headless: no display server or runtime dir is needed.
export XDG_RUNTIME_DIR="${XDG_RUNTIME_DIR:-/tmp}"
cargo test --release --all-targets
