# The starting inputs of each fuzz target besides its corpus: the shipped files and the
# bad-input corpus, read in place (not copied); and the committed corpus. Sourced by
# fuzz.sh and fuzz_built.sh.
fuzz_seeds() {
    case "$1" in
        graph) echo graphs tests/bad/graphs tests/bad/hostile ;;
        pass_parameters) echo graphs tests/bad/graphs ;;
        material) echo materials tests/bad/materials ;;
        scene) echo scenes tests/bad/hostile ;;
        gltf) echo tests/bad/gltf tests/bad/hostile tests/bad/hostile/models ;;
        shader) echo tests/bad/shaders shaders/common shaders/examples ;;
        sweep) echo benches/sweeps tests/bad/sweeps ;;
        *) echo "unknown fuzz target $1" >&2; return 2 ;;
    esac
}
FUZZ_TARGETS=(graph pass_parameters material scene gltf shader sweep)
# The committed corpus (TARGET/ folders at its top) into fuzz/corpus/, the first time only;
# later runs grow fuzz/corpus/ in place.
fuzz_unpack_corpus() {
    if [ ! -d fuzz/corpus ] && [ -f fuzz/corpus.tar.xz ]; then
        mkdir -p fuzz/corpus
        tar -xJf fuzz/corpus.tar.xz -C fuzz/corpus
    fi
}
