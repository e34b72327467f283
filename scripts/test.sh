#!/usr/bin/env bash
# The test command (README): installs what is missing of Mesa's software Vulkan driver
# (lavapipe), Xvfb and the X11 client libraries (for the viewer's window test), then runs
# the whole test suite on whatever adapter wgpu picks.
set -euo pipefail
cd "$(dirname "$0")/.."

missing=()
# An ICD file alone does not make an adapter (a GPU driver's JSON can exist without the
# GPU), so the check is for lavapipe itself: it always works. A loop, not `ls A B`: ls
# fails when either glob matches nothing.
have_lavapipe() {
    local f
    for f in /usr/share/vulkan/icd.d/lvp_icd*.json /etc/vulkan/icd.d/lvp_icd*.json; do
        [ -e "$f" ] && return 0
    done
    return 1
}
have_lavapipe || missing+=(mesa-vulkan-drivers)
# The viewer's test opens a real window on a virtual X server; winit loads the X11
# client libraries at run time.
command -v xvfb-run >/dev/null 2>&1 || missing+=(xvfb)
command -v xauth >/dev/null 2>&1 || missing+=(xauth)
libs=$(ldconfig -p 2>/dev/null || true)
for pair in libX11-xcb.so.1:libx11-xcb1 libXcursor.so.1:libxcursor1 libXrandr.so.2:libxrandr2 \
    libXi.so.6:libxi6 libxkbcommon-x11.so.0:libxkbcommon-x11-0; do
    case "$libs" in
    *"${pair%%:*}"*) ;;
    *) missing+=("${pair#*:}") ;;
    esac
done

fail_install() {
    echo "test.sh: cannot install ${missing[*]}: $1" >&2
    echo "test.sh: install them yourself (Debian/Ubuntu: apt-get install ${missing[*]}) and rerun" >&2
    exit 1
}
if [ ${#missing[@]} -eq 0 ]; then
    echo "test.sh: lavapipe, Xvfb and the X11 libraries are installed; nothing to install"
else
    echo "test.sh: installing what is missing: ${missing[*]}"
    command -v apt-get >/dev/null 2>&1 || fail_install "no apt-get on this machine"
    if [ "$(id -u)" -eq 0 ]; then
        as_root=()
    elif ! command -v sudo >/dev/null 2>&1; then
        fail_install "not root and no sudo"
    elif [ -t 0 ]; then
        as_root=(sudo)
    else
        # No terminal to ask for a password on: fail instead of hanging.
        as_root=(sudo -n)
    fi
    "${as_root[@]}" apt-get update -qq || fail_install "apt-get update failed (no network, or not allowed?)"
    "${as_root[@]}" env DEBIAN_FRONTEND=noninteractive apt-get install -y -qq "${missing[@]}" >/dev/null ||
        fail_install "apt-get install failed"
fi
# Headless tests need no display server; the runtime dir quiets winit and Mesa.
export XDG_RUNTIME_DIR="${XDG_RUNTIME_DIR:-/tmp}"
cargo test --release --all-targets
# The crate documentation's example renders a frame; --all-targets leaves doctests out.
cargo test --release --doc
# The renderer alone, as a library user without the CLI, bench or viewer builds it. A build,
# not a check: it reuses the release artifacts of the dependencies above (same features),
# so only lightgraph itself compiles again (about a minute on two cores).
cargo build --release --lib --no-default-features
