#!/usr/bin/env bash
# The GPU measurement on the device (an NVIDIA H200 lent for a few minutes; see docs/gpu.md,
# "GPU"): the BVH2 kernels (`wgpu`) against the CWBVH kernels (`wgpu-cwbvh`) with
# `raybench compare` on bunny, dabrovic-sponza, bunny-field (12.6 million triangles, instanced) and
# terrain:708 (primary, incoherent and shadow rays, path tracing at 1 spp), then the GPU
# criterion suite on the same scenes with short measurement times. A run that fails or
# outlasts its time is recorded with its error and the others go on; the whole run ends
# within 540 s (300 s for the compare runs, the rest for the criterion suite). Runs
# from what scripts/device/prep.sh put in .device/ (stripped binaries, meshes, the Vulkan
# loader packages, unpacked from .device/pack.tar.gz when only the pack travelled); needs no
# Rust toolchain. Writes under $OUT (default .device/out), at
# most 8 files: log.txt, adapter.txt, nvidia-smi.txt, backends.json, compare.json,
# bench.json, summary.txt.
#
# It fails loudly unless the adapter wgpu opens is an NVIDIA GPU; `--allow-software`
# accepts Mesa's lavapipe for a dry run here, with `--size N` (default 1024) and `--quick`
# (fewer scenes and repetitions) to keep that short.
#
#   device:  bash scripts/device/gpu-measure.sh          (carry [".device/pack.tar.gz"])
#   here:    scripts/device/prep.sh --debug && \
#            OUT=/tmp/gpu-dry bash scripts/device/gpu-measure.sh --allow-software --size 64 --quick
set -euo pipefail
cd "$(dirname "$0")/../.."

allow_software=0
size=1024
quick=0
while [ $# -gt 0 ]; do
    case "$1" in
        --allow-software) allow_software=1 ;;
        --quick) quick=1 ;;
        --size)
            shift
            size=${1:-}
            case "$size" in
                '' | *[!0-9]*)
                    echo "error: gpu-measure.sh: --size needs a number of pixels, got '$size'" >&2
                    exit 2
                    ;;
            esac
            ;;
        *)
            echo "error: gpu-measure.sh: unknown option '$1' (known: --allow-software, --size N, --quick)" >&2
            exit 2
            ;;
    esac
    shift
done

dir=.device
OUT=${OUT:-$PWD/.device/out}
mkdir -p "$OUT"
exec > >(tee "$OUT/log.txt") 2>&1
if [ ! -x "$dir/bin/raybench" ] && [ -f "$dir/pack.tar.gz" ]; then
    tar -xzf "$dir/pack.tar.gz" -C "$dir"
fi
for f in "$dir/bin/raybench" "$dir/bin/gpu-bench"; do
    if [ ! -x "$f" ]; then
        echo "error: gpu-measure.sh: $f missing: run scripts/device/prep.sh first and carry .device" >&2
        exit 1
    fi
done

# The Vulkan loader (../.library/device/README.md): unpacked from the carried packages when
# the machine has none; the NVIDIA driver's manifests named when they exist.
if ! ldconfig -p | grep -q 'libvulkan\.so\.1'; then
    for f in "$dir"/gl/*.deb; do
        dpkg -x "$f" /
    done
    ldconfig
fi
if [ -e /usr/local/nvidia/share/vulkan/icd.d/nvidia_icd.json ] && [ -z "${VK_DRIVER_FILES:-}" ]; then
    export VK_DRIVER_FILES=/usr/local/nvidia/share/vulkan/icd.d/nvidia_icd.json
    export __EGL_VENDOR_LIBRARY_FILENAMES=/usr/local/nvidia/share/glvnd/egl_vendor.d/10_nvidia.json
fi
export WGPU_BACKEND=${WGPU_BACKEND:-vulkan}
export RAYBENCH_ASSETS=$PWD/$dir/scenes
export CRITERION_HOME=${CRITERION_HOME:-/tmp/raybench-criterion}

if command -v nvidia-smi >/dev/null; then
    nvidia-smi --query-gpu=name,driver_version,memory.total,clocks.max.sm --format=csv \
        >"$OUT/nvidia-smi.txt" 2>&1 || true
fi
"$dir/bin/raybench" --version
"$dir/bin/raybench" backends --json >"$OUT/backends.json"
# The first device string is the first GPU backend's (CPU backends have none).
adapter=$(grep -o '"device": "[^"]*"' "$OUT/backends.json" | head -n 1 | sed 's/"device": "\(.*\)"/\1/')
echo "$adapter" >"$OUT/adapter.txt"
if [ -z "$adapter" ]; then
    echo "error: gpu-measure.sh: wgpu opened no adapter (see $OUT/backends.json for the reason)" >&2
    exit 1
fi
echo "adapter: $adapter"
case "$adapter" in
    *NVIDIA* | *nvidia*) ;;
    *)
        if [ "$allow_software" = 1 ]; then
            echo "warning: not an NVIDIA adapter; a dry run (--allow-software): figures mean nothing"
        else
            echo "error: gpu-measure.sh: the adapter is '$adapter', not the NVIDIA GPU (Vulkan loader or driver manifest missing?); --allow-software runs anyway" >&2
            exit 1
        fi
        ;;
esac

scenes=(bunny dabrovic-sponza bunny-field terrain:708)
repeat=3
if [ "$quick" = 1 ]; then
    scenes=(bunny terrain:708)
    repeat=1
fi
workloads=("primary|--rays primary" "incoherent|--rays incoherent" "shadow|--rays shadow" "path|--mode path --spp 1")

# compare.json: one array of {scene, workload, runs}, runs being `compare --json`'s array.
compare=$OUT/compare.json
echo "[" >"$compare"
first=1
for scene in "${scenes[@]}"; do
    for w in "${workloads[@]}"; do
        name=${w%%|*}
        # shellcheck disable=SC2086
        set -- ${w#*|}
        echo "== compare $scene $name ($size x $size)"
        [ "$first" = 1 ] || echo "," >>"$compare"
        first=0
        # The compare runs get 300 s of the budget in all, the criterion suite the rest.
        if [ "$SECONDS" -ge 300 ]; then
            echo "warning: compare $scene $name skipped: the compare runs' 300 s are spent"
            printf '{"scene": "%s", "workload": "%s", "size": %s, "error": "skipped: out of time"}\n' \
                "$scene" "$name" "$size" >>"$compare"
            continue
        fi
        if runs=$(timeout 60 "$dir/bin/raybench" compare "$scene" --backends wgpu,wgpu-cwbvh \
            --width "$size" --height "$size" "$@" --repeat "$repeat" --json); then
            printf '{"scene": "%s", "workload": "%s", "size": %s, "runs": %s}\n' \
                "$scene" "$name" "$size" "$runs" >>"$compare"
        else
            status=$?
            echo "warning: compare $scene $name failed (exit $status); going on"
            printf '{"scene": "%s", "workload": "%s", "size": %s, "error": "exit %s"}\n' \
                "$scene" "$name" "$size" "$status" >>"$compare"
        fi
    done
done
echo "]" >>"$compare"

echo "== criterion GPU suite"
bench_scenes=$(IFS=,; echo "${scenes[*]}")
if [ "$quick" = 1 ]; then
    bench_scenes="terrain:708"
fi
RAYBENCH_GPU_SIZE=$size RAYBENCH_GPU_RAYS=$((size * size)) RAYBENCH_GPU_SCENES=$bench_scenes RAYBENCH_GPU_JSON=$OUT/bench.json \
    timeout $((SECONDS < 480 ? 540 - SECONDS : 60)) "$dir/bin/gpu-bench" --bench --warm-up-time 0.5 --measurement-time 1 --noplot \
    || echo "warning: the criterion GPU suite failed or ran out of time (exit $?); its figures so far are in bench.json"

# summary.txt: Mrays/s per backend and workload, from the criterion figures.
{
    echo "adapter: $adapter"
    grep -o '"id": "[^"]*"\|"mrays_per_s": [0-9.e+-]*' "$OUT/bench.json" | paste - - \
        | sed 's/"id": "\([^"]*\)"\t"mrays_per_s": \(.*\)/\1 \2 Mrays\/s/'
} >"$OUT/summary.txt"
cat "$OUT/summary.txt"
echo "done: $(ls "$OUT" | tr '\n' ' ')"
