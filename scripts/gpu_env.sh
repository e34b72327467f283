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

# The device tool brings back few files: everything goes back as one archive. `pack`
# after every stage, so a cut-off run still brings back what it finished; `gpu_pack` at
# the end.
pack() { tar -czf "$final/results.tar.gz" -C "$final" r; }
gpu_pack() {
    pack && rm -rf "$out"
}

# run_sweep LABEL SWEEP LIMIT_S [ROOT] [ENV]: benches/sweeps/SWEEP.ron into $out/LABEL
# under the shader root folder ROOT (none where empty: graphs named ../benches/graphs/...
# are found from the graphs/ folder, which a root moves), with ENV (NAME=value) set;
# prints its tables and packs.
run_sweep() {
    local label=$1 sweep=$2 limit=$3 root=${4:-} vars=${5:-}
    env $vars timeout "$limit" $lg ${root:+--root $root} bench --sweep "benches/sweeps/$sweep.ron" --out "$out/$label" > "$out/$label.log" 2>&1
    echo "== $label (rc $?) $vars"; tail -n 1 "$out/$label.log"
    sed -n '/^| scene | technique | params | lights | size/,/^$/p' "$out/$label/results.md" | cut -c1-220
    grep -A12 '^Per-pass GPU time' "$out/$label/results.md" | grep '^|' | cut -c1-200
    pack
}
