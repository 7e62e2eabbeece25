#!/usr/bin/env bash
# Prepares the one device run of scripts/device/gpu-measure.sh: builds the release `raybench`
# binary and the GPU criterion bench binary here (the device has no Rust toolchain), strips
# them into .device/bin, copies the meshes the runs need into .device/scenes (from
# RAYBENCH_ASSETS, default ../shared/scenes), downloads the Vulkan loader packages into
# .device/gl (as ../.library/device/README.md says), and packs the three into
# .device/pack.tar.gz, which gpu-measure.sh unpacks. `.device/` is git-ignored and never
# committed: the pack travels with `carry: [".device/pack.tar.gz"]`, and it and the
# checkout's tracked files must stay under the 64 MiB a device call carries.
#
#   scripts/device/prep.sh            # release builds (the device run)
#   scripts/device/prep.sh --debug    # debug builds, for a dry run here on lavapipe
set -euo pipefail
cd "$(git rev-parse --show-toplevel)"

profile=release
case "${1:-}" in
    --debug) profile=debug ;;
    "") ;;
    *) echo "error: scripts/device/prep.sh: unknown option '$1' (known: --debug)" >&2; exit 2 ;;
esac

assets=${RAYBENCH_ASSETS:-../shared/scenes}
dir=.device
mkdir -p "$dir/bin" "$dir/scenes" "$dir/gl"

# The binaries. `--message-format=json` names the bench executable cargo built.
if [ "$profile" = release ]; then
    cargo build --locked --release -p raybench
    raybench_bin=${CARGO_TARGET_DIR:-target}/release/raybench
    bench_flags=(bench --locked -p raybench-tests --bench gpu --no-run)
else
    cargo build --locked -p raybench
    raybench_bin=${CARGO_TARGET_DIR:-target}/debug/raybench
    bench_flags=(test --locked -p raybench-tests --bench gpu --no-run)
fi
bench_bin=$(cargo "${bench_flags[@]}" --message-format=json \
    | grep '"executable":"[^"]*/gpu-[0-9a-f]*"' \
    | sed 's/.*"executable":"\([^"]*\)".*/\1/' | tail -n 1)
if [ -z "$bench_bin" ] || [ ! -x "$bench_bin" ]; then
    echo "error: scripts/device/prep.sh: cargo named no GPU bench executable" >&2
    exit 1
fi
strip -o "$dir/bin/raybench" "$raybench_bin"
strip -o "$dir/bin/gpu-bench" "$bench_bin"

# The meshes of bunny, dabrovic-sponza, bunny-field (bunnies and teapots around Sponza) and the
# bench's quick scenes (terrain and spheres are generated).
for scene in bunny sponza-dabrovic teapot cornell-box; do
    if [ ! -d "$assets/$scene" ]; then
        echo "error: scripts/device/prep.sh: $assets/$scene: no such scene folder (set RAYBENCH_ASSETS)" >&2
        exit 1
    fi
    rm -rf "${dir:?}/scenes/$scene"
    cp -r "$assets/$scene" "$dir/scenes/$scene"
    chmod -R u+w "$dir/scenes/$scene"
done

# The Vulkan loader and GL dispatch libraries for the device (its base image has none).
if ! ls "$dir"/gl/libvulkan1_*.deb >/dev/null 2>&1; then
    o='-oAPT::Architecture=amd64 -oAPT::Architectures=amd64 -oDir::State::Lists=/tmp/amd64'
    mkdir -p /tmp/amd64/partial
    # shellcheck disable=SC2086
    apt-get $o update >/dev/null
    # shellcheck disable=SC2086
    (cd "$dir/gl" && apt-get $o download libvulkan1 libegl1 libglvnd0 libopengl0 libgl1 libglx0 libgles2)
fi

du -sh "$dir"/bin/* "$dir/scenes" "$dir/gl"
if [ "$profile" = debug ]; then
    echo "ready: $dir (debug builds: for a dry run here, too large to carry)"
    exit 0
fi
tar -czf "$dir/pack.tar.gz" -C "$dir" bin scenes gl
pack=$(stat -c %s "$dir/pack.tar.gz")
tracked=$(git ls-files -z | xargs -0 stat -c %s 2>/dev/null | awk '{ s += $1 } END { print s + 0 }')
limit=$((64 * 1024 * 1024))
echo "pack: $pack bytes; tracked files: $tracked bytes; a device call carries at most $limit"
if [ $((pack + tracked)) -gt "$limit" ]; then
    echo "error: scripts/device/prep.sh: the pack and the tracked files come to $((pack + tracked)) bytes, more than the $limit a device call carries" >&2
    exit 1
fi
echo "ready: $dir/pack.tar.gz; run scripts/device/gpu-measure.sh on the device with carry [\"$dir/pack.tar.gz\"]"
