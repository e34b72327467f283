# Sourced by every scripts/gpu_bench*.sh on the GPU machine: unpacks the Vulkan loaders
# that ../shared/gpu/prepare.sh brought in .gl/, and sets
#   $final  where results.tar.gz goes ($OUT, or results/),
#   $out    the folder the script fills (packed by gpu_pack, then removed),
#   $lg     the lightgraph binary brought in .gpu/;
# it records the GPU, its driver and its SM clock in $out/gpu.txt.
for f in .gl/*.deb; do dpkg -x "$f" /; done; ldconfig
final="${OUT:-results}"
out="$final/r"
mkdir -p "$out"
export XDG_RUNTIME_DIR=/tmp
lg=./.gpu/lightgraph
# With Bevy's binary beside it the two only fit the device tool's 64 MiB compressed:
# `xz -c .gpu/lightgraph > .gpu/lightgraph.xz` (and remove .gpu/lightgraph) before the call.
if [ ! -x "$lg" ] && [ -f .gpu/lightgraph.xz ]; then
    xz -dc .gpu/lightgraph.xz > /tmp/lightgraph && chmod +x /tmp/lightgraph
    lg=/tmp/lightgraph
fi
nvidia-smi --query-gpu=name,driver_version,clocks.sm,clocks.max.sm --format=csv > "$out/gpu.txt" 2>&1

# The device tool brings back few files: everything goes back as one archive.
gpu_pack() {
    tar -czf "$final/results.tar.gz" -C "$final" r && rm -rf "$out"
}
