#!/usr/bin/env bash
# Runs a raybench report on a Slurm cluster: submits the shards as one array job
# (report.sbatch, one shard per task) and the merge (merge.sbatch) to run after every shard
# succeeded. This is the command a user runs, from the folder that holds the raybench
# build (the repository root):
#
#   scripts/slurm/submit.sh N [report options...]
#
# for example `scripts/slurm/submit.sh 8 --quick`. N is the shard count: at most the plan's
# unit count (the matrix's scenes plus the scaling experiments). The merged report appears
# in RAYBENCH_SLURM_OUT/report (default target/raybench-slurm/report), the shards in
# RAYBENCH_SLURM_OUT/shards/1..N; the job ids are printed.
#
# Environment: RAYBENCH_BIN, RAYBENCH_ASSETS and RAYBENCH_SLURM_OUT as report.sbatch reads
# them (made absolute here); RAYBENCH_SBATCH_OPTIONS, sbatch options for both jobs (split on
# white space; for example "--partition=bench --cpus-per-task=8 --exclusive"), and
# RAYBENCH_MERGE_OPTIONS, options of the merge (for example --allow-mixed-machines).
set -euo pipefail

here=$(cd "$(dirname "$0")" && pwd)
n=${1:-}
if ! [[ "${n}" =~ ^[1-9][0-9]*$ ]]; then
    echo "usage: $0 N [report options...] (N: the shard count, 1 or more)" >&2
    exit 2
fi
shift
command -v sbatch >/dev/null || {
    echo "error: sbatch not found: run this on a Slurm login node" >&2
    exit 2
}
absolute() { case "$1" in /*) echo "$1" ;; *) echo "${PWD}/$1" ;; esac; }
export RAYBENCH_SLURM_OUT
RAYBENCH_SLURM_OUT=$(absolute "${RAYBENCH_SLURM_OUT:-target/raybench-slurm}")
if [ -n "${RAYBENCH_BIN:-}" ] && [[ "${RAYBENCH_BIN}" == */* ]]; then
    export RAYBENCH_BIN
    RAYBENCH_BIN=$(absolute "${RAYBENCH_BIN}")
fi
if [ -n "${RAYBENCH_ASSETS:-}" ]; then
    export RAYBENCH_ASSETS
    RAYBENCH_ASSETS=$(absolute "${RAYBENCH_ASSETS}")
fi
# Shards of an earlier run would be merged with this one's.
if [ -e "${RAYBENCH_SLURM_OUT}/shards" ] || [ -e "${RAYBENCH_SLURM_OUT}/report" ]; then
    echo "error: ${RAYBENCH_SLURM_OUT} holds an earlier run; remove it or set RAYBENCH_SLURM_OUT" >&2
    exit 2
fi
mkdir -p "${RAYBENCH_SLURM_OUT}"
read -r -a sbatch_options <<<"${RAYBENCH_SBATCH_OPTIONS:-}"
read -r -a merge_options <<<"${RAYBENCH_MERGE_OPTIONS:-}"
array=$(sbatch --parsable --array="1-${n}" \
    --output="${RAYBENCH_SLURM_OUT}/report-%a.out" \
    ${sbatch_options[@]+"${sbatch_options[@]}"} "${here}/report.sbatch" "$@")
array=${array%%;*}
merge=$(sbatch --parsable --dependency="afterok:${array}" --kill-on-invalid-dep=yes \
    --output="${RAYBENCH_SLURM_OUT}/merge.out" \
    ${sbatch_options[@]+"${sbatch_options[@]}"} "${here}/merge.sbatch" "${n}" \
    ${merge_options[@]+"${merge_options[@]}"})
merge=${merge%%;*}
echo "shards: array job ${array} (${n} tasks) -> ${RAYBENCH_SLURM_OUT}/shards"
echo "merge: job ${merge} after ${array} -> ${RAYBENCH_SLURM_OUT}/report"
