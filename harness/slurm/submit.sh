#!/usr/bin/env bash
# Submits a config as a Slurm array job plus its merge job; `make slurm-submit`
# calls it with the Makefile's variables:
#
#   harness/slurm/submit.sh ACCELBENCH PYTHON CONFIG.yaml SHARDS OUT_DIR [ARRAY]
#
# The array's task i runs shard i of SHARDS (shard.sbatch) into OUT_DIR/shard-<i>ofN.csv;
# the merge job (merge.sbatch), submitted with --dependency=afterok on the array, joins
# them into OUT_DIR/<config>.csv and runs the analysis into OUT_DIR/analysis/. ARRAY
# (default 0-<SHARDS-1>) takes sbatch's --array syntax, e.g. 3 or 1,3 to run only the
# shards a cancelled or failed submission left missing; the new merge job then merges all
# SHARDS CSVs. If a task fails the merge job is cancelled (--kill-on-invalid-dep) rather
# than left pending forever.
#
# Site settings, from the environment (the Makefile sets them; empty means the site's
# default): PARTITION, TIME_LIMIT and MERGE_TIME_LIMIT (sbatch --time), CPUS_PER_TASK,
# MEM_PER_TASK (--mem), ACCOUNT, SBATCH_ARGS (more sbatch options for both jobs, split
# on spaces). Logs: OUT_DIR/logs/. Prints the two job ids.
set -euo pipefail
[ $# -ge 5 ] && [ $# -le 6 ] || { echo "usage: $0 ACCELBENCH PYTHON CONFIG.yaml SHARDS OUT_DIR [ARRAY]" >&2; exit 2; }
accelbench=$1 python=$2 config=$3 shards=$4 out_dir=$5
[[ $shards =~ ^[1-9][0-9]*$ ]] || { echo "slurm-submit: SHARDS must be a count > 0, got '$shards'" >&2; exit 2; }
array=${6:-0-$((shards - 1))}
[ -f "$config" ] || { echo "slurm-submit: no config '$config' (CONFIG=configs/NAME.yaml)" >&2; exit 2; }
here=$(cd "$(dirname "$0")" && pwd)

# Every task id must name a shard: sbatch accepts --array=7 with SHARDS=4, the task would not.
for id in $(echo "${array%%%*}" | tr ',' ' '); do
    for bound in ${id//-/ }; do
        [[ $bound =~ ^[0-9]+$ ]] && [ "$bound" -lt "$shards" ] ||
            { echo "slurm-submit: ARRAY=$array: '$id' is not within shards 0-$((shards - 1))" >&2; exit 2; }
    done
done
# A wrong config fails here, once, rather than in every task.
"$accelbench" run --dry-run "$config" > /dev/null

mkdir -p "$out_dir/logs"
out_dir=$(cd "$out_dir" && pwd)
config=$(cd "$(dirname "$config")" && pwd)/$(basename "$config")
name=$(basename "$config" .yaml)
site=()
[ -n "${PARTITION:-}" ] && site+=(--partition="$PARTITION")
[ -n "${ACCOUNT:-}" ] && site+=(--account="$ACCOUNT")
# shellcheck disable=SC2206  # SBATCH_ARGS is a list of options
[ -n "${SBATCH_ARGS:-}" ] && site+=($SBATCH_ARGS)
task=(--cpus-per-task="${CPUS_PER_TASK:-1}")
[ -n "${TIME_LIMIT:-}" ] && task+=(--time="$TIME_LIMIT")
[ -n "${MEM_PER_TASK:-}" ] && task+=(--mem="$MEM_PER_TASK")
merge=()
[ -n "${MERGE_TIME_LIMIT:-}" ] && merge+=(--time="$MERGE_TIME_LIMIT")

array_job=$(sbatch --parsable --job-name="$name" --array="$array" --chdir="$PWD" \
    --output="$out_dir/logs/shard-%a-job%A.log" "${site[@]}" "${task[@]}" \
    "$here/shard.sbatch" "$accelbench" "$config" "$shards" "$out_dir")
array_job=${array_job%%;*}  # "id;cluster" on a multi-cluster site
merge_job=$(sbatch --parsable --job-name="$name-merge" --dependency="afterok:$array_job" --kill-on-invalid-dep=yes \
    --chdir="$PWD" --output="$out_dir/logs/merge-job%j.log" --ntasks=1 "${site[@]}" "${merge[@]}" \
    "$here/merge.sbatch" "$accelbench" "$python" "$config" "$shards" "$out_dir")
merge_job=${merge_job%%;*}
echo "slurm-submit: array job $array_job: $config, tasks $array of $shards shards -> $out_dir/shard-<i>of$shards.csv"
echo "slurm-submit: merge job $merge_job (after every task of $array_job succeeded) -> $out_dir/$name.csv, $out_dir/analysis/"
echo "slurm-submit: logs in $out_dir/logs/; watch with: squeue -j $array_job,$merge_job"
