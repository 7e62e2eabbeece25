#!/usr/bin/env bash
# The path tracer against an analytic reference, at full size (outside CI; the CI test at
# a small size is tests/tests/furnace.rs): the Cornell box's geometry as a furnace
# (scripts/cornell-furnace.toml: every surface albedo 0.5 and emission 0.5, the background
# 1.0, so the exact radiance is 1.0 on every pixel), path traced at 256 x 256 with
# --max-depth 64 and written as OpenEXR, once per seed. The mean of each image, read back
# from the EXR by `raybench diff`, is one independent estimate; their spread gives the
# standard error. The script fails unless the grand mean is within 1 % of 1.0, and prints
# the deviation in standard errors too.
#
# Usage: scripts/cornell-furnace.sh [RAYBENCH] (default target/release/raybench; needs
# the shared Cornell box: RAYBENCH_ASSETS or --assets, as for every scene). SEEDS and SPP
# may be set in the environment (default 8 seeds of 16 samples per pixel: about a minute
# on two cores).
set -euo pipefail
cd "$(dirname "$0")/.."
bin=${1:-target/release/raybench}
seeds=${SEEDS:-8}
spp=${SPP:-16}
out=target/cornell-furnace
mkdir -p "$out"
means=()
for ((s = 0; s < seeds; s++)); do
    "$bin" render scripts/cornell-furnace.toml --mode path --width 256 --height 256 \
        --max-depth 64 --spp "$spp" --seed "$s" --out "$out/seed-$s.exr" 2>/dev/null
    json=$("$bin" diff "$out/seed-0.exr" "$out/seed-$s.exr" --json)
    mean=$(python3 -c 'import json, sys; print(json.loads(sys.argv[1])["mean_b"])' "$json")
    echo "seed $s: image mean $mean"
    means+=("$mean")
done
python3 - "${means[@]}" <<'PY'
import math, sys
m = [float(x) for x in sys.argv[1:]]
n = len(m)
mean = sum(m) / n
se = math.sqrt(sum((x - mean) ** 2 for x in m) / (n - 1) / n) if n > 1 else float("nan")
print(f"grand mean {mean:.5f}, standard error {se:.5f} over {n} seeds; exact 1.0 "
      f"(deviation {100 * (mean - 1.0):+.3f} %, {(mean - 1.0) / se:+.1f} standard errors)")
ok = abs(mean - 1.0) <= 0.01
print("agrees with the analytic radiance within 1 %" if ok else "DISAGREES with the analytic radiance")
sys.exit(0 if ok else 1)
PY
