#!/usr/bin/env bash
# The test command (README): installs Mesa's software Vulkan driver (lavapipe) when it is
# missing, then runs the whole test suite on whatever adapter wgpu picks.
set -euo pipefail
cd "$(dirname "$0")/.."
# An ICD file alone does not make an adapter (a GPU driver's JSON can exist without the
# GPU), so the check is for lavapipe itself: it always works.
if ! ls /usr/share/vulkan/icd.d/lvp_icd*.json /etc/vulkan/icd.d/lvp_icd*.json >/dev/null 2>&1; then
    echo "no lavapipe Vulkan driver found: installing mesa-vulkan-drivers"
    SUDO=""
    [ "$(id -u)" -ne 0 ] && SUDO="sudo"
    $SUDO apt-get update -qq
    DEBIAN_FRONTEND=noninteractive $SUDO apt-get install -y -qq mesa-vulkan-drivers >/dev/null
fi
# The viewer's test opens a real window on a virtual X server; winit loads the X11
# client libraries at run time.
need_x11=""
command -v xvfb-run >/dev/null 2>&1 || need_x11=1
for lib in libX11-xcb.so.1 libXcursor.so.1 libXrandr.so.2 libXi.so.6 libxkbcommon-x11.so.0; do
    ldconfig -p | grep "$lib" >/dev/null || need_x11=1
done
if [ -n "$need_x11" ]; then
    echo "installing Xvfb and the X11 client libraries (for the viewer's window test)"
    SUDO=""
    [ "$(id -u)" -ne 0 ] && SUDO="sudo"
    $SUDO apt-get update -qq
    DEBIAN_FRONTEND=noninteractive $SUDO apt-get install -y -qq xvfb xauth libx11-xcb1 \
        libxcursor1 libxrandr2 libxi6 libxkbcommon-x11-0 >/dev/null
fi
# Headless tests need no display server; the runtime dir quiets winit and Mesa.
export XDG_RUNTIME_DIR="${XDG_RUNTIME_DIR:-/tmp}"
cargo test --release --all-targets
