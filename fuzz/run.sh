#!/usr/bin/env bash
# Runs every fuzz target (or those named) for N seconds each; not part of CI.
#
#   cargo install cargo-fuzz --locked          # once
#   fuzz/run.sh [SECONDS] [TARGET...]          # default: 60 s, every target
#
# Targets (fuzz/fuzz_targets/<name>.rs): the scene file and mesh loaders scene_toml obj gltf
# ply bpt raw_volume; mtl (the material library of a fixed OBJ), env_map and texture (the
# first byte chooses the map's format, OpenEXR or Radiance HDR, or the texture's wrap
# modes; the rest is the image), rays_file (the registry crate's ray file reader). cargo fuzz
# needs nightly flags (-Zsanitizer): on the stable toolchain they are unlocked with
# RUSTC_BOOTSTRAP=1. One target by hand:
#
#   cd fuzz && RUSTC_BOOTSTRAP=1 cargo fuzz run obj -- -max_total_time=60 -rss_limit_mb=2048 -timeout=5
#
# Each run starts from the committed seeds (fuzz/seeds/<name>/, tiny handwritten samples)
# plus the working corpus fuzz/corpus/<name>/ (ignored by git). To seed from the shared
# assets locally, copy a few small files into the corpus first, e.g.
#   cp ../shared/scenes/<some>.obj fuzz/corpus/obj/
# Crashes, hangs (-timeout) and excessive allocations (-rss_limit_mb, -malloc_limit_mb)
# are written to fuzz/artifacts/<name>/; reproduce one with
#   RUSTC_BOOTSTRAP=1 cargo fuzz run <name> fuzz/artifacts/<name>/<file>
# then fix the loader and add the input to crates/scene/tests/fuzz_regressions.rs (ray
# files: the tests of crates/registry/src/rays_file.rs).
set -euo pipefail
cd "$(dirname "$0")"
secs=${1:-60}
shift || true
targets=("$@")
if [ ${#targets[@]} -eq 0 ]; then
    targets=(scene_toml obj gltf ply bpt raw_volume mtl env_map texture rays_file)
fi
export RUSTC_BOOTSTRAP=1
cargo fuzz build
for t in "${targets[@]}"; do
    mkdir -p "corpus/$t"
    echo "== $t: ${secs}s"
    cargo fuzz run "$t" "corpus/$t" "seeds/$t" -- \
        -max_total_time="$secs" -rss_limit_mb=2048 -malloc_limit_mb=1024 -timeout=5 \
        -print_final_stats=1
done
