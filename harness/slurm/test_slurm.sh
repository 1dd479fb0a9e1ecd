#!/usr/bin/env bash
# make test-slurm: a grid config through a real single-node Slurm cluster
# (local_cluster.sh) as `make slurm-submit` submits it, with a failure on the way:
#
#   1. the config in one process, outside Slurm: the reference rows;
#   2. make slurm-submit SHARDS=4; task 3 is cancelled (scancel) before it runs, task 0
#      once it has written its first row; tasks 1 and 2 finish, and the merge job, whose
#      afterok dependency can no longer be met, is cancelled by Slurm: no merged CSV;
#   3. the merge step submitted alone fails (exit 3), names shards 0 and 3, writes nothing;
#   4. make slurm-submit ARRAY=0,3 (only the missing shards) completes it: task 0 resumes
#      its CSV (the rows of the cancelled task kept), shards 1 and 2 are left as they were,
#      the merge job merges all four and runs the analysis (`grid`: best.yaml);
#   5. the merged CSV has every combination of the reference exactly once with the same
#      deterministic counts (nodes, prim_tests, hits);
#   6. the cluster is stopped and no Slurm or munge process of it is left (pgrep).
#
#   harness/slurm/test_slurm.sh ACCELBENCH PYTHON CONFIG.yaml
#
# Run from the project's top directory, as root (slurmd starts jobs as their user). Its
# temporary directory is removed on exit, on failure too (KEEP=1 keeps it); on failure
# the daemons' and jobs' logs are printed first.
set -euo pipefail
[ $# -eq 3 ] || { echo "usage: $0 ACCELBENCH PYTHON CONFIG.yaml" >&2; exit 2; }
accelbench=$1 python=$2 config=$3
name=$(basename "$config" .yaml)
shards=4 running=0 pending=3
here=$(cd "$(dirname "$0")" && pwd)
# shellcheck source=local_cluster.sh
source "$here/local_cluster.sh"

daemons=(slurmctld slurmd slurmstepd munged)
daemon_pids() { for d in "${daemons[@]}"; do pgrep -x "$d" || true; done | tr '\n' ' '; }
before=$(daemon_pids)
work=$(mktemp -d /tmp/accelbench-test-slurm.XXXXXX)
chmod 755 "$work"  # munged's socket below it must be reachable by every user
run=$work/run
t0=$(date +%s)

fail() { echo "test-slurm: FAIL: $*" >&2; exit 1; }
on_exit() {
    local rc=$?
    if [ "$rc" -ne 0 ]; then
        for f in "$work"/cluster/log/*.log "$run"/logs/*.log; do
            [ -f "$f" ] && { echo "---- $f (last lines)"; tail -n 15 "$f"; }
        done >&2
    fi
    cluster_stop
    if [ -n "${KEEP:-}" ]; then echo "test-slurm: kept $work" >&2; else rm -rf "$work"; fi
    exit "$rc"
}
trap on_exit EXIT
trap 'exit 130' INT TERM

# Waits until none of the jobs $@ is queued or running (5 minutes at most).
wait_jobs() {
    local t ids
    ids=$(IFS=,; echo "$*")
    for ((t = 0; t < 600; t++)); do
        [ -z "$(squeue -h -j "$ids" -o %i 2>/dev/null)" ] && return 0
        sleep 0.5
    done
    squeue -j "$ids" >&2
    fail "jobs $ids still queued after 5 minutes"
}
# A job's state; "gone" for an array task cancelled while pending (Slurm drops it from the array).
state() {
    local s
    s=$(scontrol show job "$1" 2>/dev/null | sed -n 's/.*JobState=\([A-Z_]*\).*/\1/p' | head -n 1) || true
    echo "${s:-gone}"
}
submit() { # make slurm-submit ... ; sets array_job and merge_job from what it prints
    local out
    out=$(make --no-print-directory slurm-submit CONFIG="$config" SHARDS=$shards SLURM_OUT="$run" "$@")
    echo "$out"
    array_job=$(sed -n 's/^slurm-submit: array job \([0-9]*\):.*/\1/p' <<< "$out")
    merge_job=$(sed -n 's/^slurm-submit: merge job \([0-9]*\) .*/\1/p' <<< "$out")
    [ -n "$array_job" ] && [ -n "$merge_job" ] || fail "make slurm-submit printed no job ids"
}

rows() { echo $(($(wc -l < "$1") - 1)); }  # data rows of a CSV (one line each here)

echo "== 1. $config in one process (the reference)"
"$accelbench" run --out "$work/single/$name.csv" "$config" > "$work/single.log" 2>&1 ||
    { tail -n 20 "$work/single.log" >&2; fail "the single-process run failed"; }
per_shard=()
for ((i = 0; i < shards; i++)); do
    per_shard[i]=$("$accelbench" run --dry-run --shard "$i/$shards" "$config" | sed -n 's/^\([0-9]*\) combinations in shard.*/\1/p')
done
[ "${per_shard[$running]}" -ge 2 ] || fail "shard $running has fewer than 2 combinations: nothing to cancel part way"
echo "combinations per shard: ${per_shard[*]}"

echo "== 2. a cluster, the array of $shards tasks; task $pending cancelled while pending, task $running while running"
cluster_start "$work/cluster"
submit
scancel "${array_job}_$pending"
# Task $running once it has written its first row (of ${per_shard[$running]}): a CSV left half done.
csv0=$run/shard-${running}of$shards.csv
for ((t = 0; t < 1200; t++)); do
    [ -f "$csv0" ] && [ "$(wc -l < "$csv0")" -ge 2 ] && break
    sleep 0.1
done
scancel "${array_job}_$running"
wait_jobs "$array_job" "$merge_job"
for ((i = 0; i < shards; i++)); do
    s=$(state "${array_job}_$i")
    case $i in
        "$pending") [ "$s" = CANCELLED ] || [ "$s" = gone ] || fail "task $i is $s, not CANCELLED" ;;
        "$running") [ "$s" = CANCELLED ] || fail "task $i is $s, not CANCELLED" ;;
        *) [ "$s" = COMPLETED ] || fail "task $i is $s, not COMPLETED"
           [ "$(rows "$run/shard-${i}of$shards.csv")" = "${per_shard[$i]}" ] || fail "task $i's CSV is not complete" ;;
    esac
done
kept=$(rows "$csv0")
[ "$kept" -ge 1 ] && [ "$kept" -lt "${per_shard[$running]}" ] ||
    fail "task $running was cancelled with $kept of ${per_shard[$running]} rows written (it should be part way)"
s=$(state "$merge_job")
[ "$s" = CANCELLED ] || fail "the merge job is $s; with tasks cancelled it must not run"
[ ! -e "$run/$name.csv" ] || fail "a merged CSV exists after cancelled tasks"
[ ! -e "$run/shard-${pending}of$shards.csv" ] || fail "task $pending, cancelled before it ran, left a CSV"
intact=()
for ((i = 0; i < shards; i++)); do [ "$i" = "$pending" ] || [ "$i" = "$running" ] || intact+=("$run/shard-${i}of$shards.csv"); done
sha256sum "${intact[@]}" > "$work/intact.sha256"
head -n "$((kept + 1))" "$csv0" > "$work/partial.csv"
echo "tasks: $(for ((i = 0; i < shards; i++)); do printf '%s=%s ' "$i" "$(state "${array_job}_$i")"; done)merge=$s;" \
     "task $running left $kept of ${per_shard[$running]} rows"

echo "== 3. the merge step alone names the missing shards"
rc=0
sbatch --wait --quiet --output="$run/logs/merge-alone.log" "$here/merge.sbatch" \
    "$accelbench" "$python" "$(pwd)/$config" "$shards" "$run" || rc=$?
[ "$rc" -eq 3 ] || fail "the merge of incomplete shards exited $rc, not 3"
grep -q "shard $running: " "$run/logs/merge-alone.log" && grep -q "shard $pending: " "$run/logs/merge-alone.log" &&
    grep -q -- "--array=$running,$pending)" "$run/logs/merge-alone.log" ||
    fail "the merge step's message does not name shards $running and $pending: $(cat "$run/logs/merge-alone.log")"
[ ! -e "$run/$name.csv" ] || fail "the merge step wrote a partial CSV"
grep "incomplete\|run shards" "$run/logs/merge-alone.log"

echo "== 4. only shards $running,$pending resubmitted"
submit ARRAY=$running,$pending
wait_jobs "$array_job" "$merge_job"
for i in "$running" "$pending"; do
    [ "$(state "${array_job}_$i")" = COMPLETED ] || fail "the resubmitted task $i is $(state "${array_job}_$i")"
done
[ "$(state "$merge_job")" = COMPLETED ] || fail "the merge job is $(state "$merge_job"): $(cat "$run"/logs/merge-job"$merge_job".log)"
[ -s "$run/analysis/best.yaml" ] || fail "the merge job ran no grid analysis (no $run/analysis/best.yaml)"
sha256sum --quiet -c "$work/intact.sha256" || fail "the completed shards' CSVs changed after the resubmission"
[ "$(head -n "$((kept + 1))" "$csv0")" = "$(cat "$work/partial.csv")" ] ||
    fail "the resubmitted task $running did not keep the rows the cancelled one wrote"
[ "$(rows "$csv0")" = "${per_shard[$running]}" ] || fail "shard $running is still incomplete"
tail -n 1 "$run/logs/merge-job$merge_job.log"

echo "== 5. merged = single process"
"$python" - "$work/single/$name.csv" "$run/$name.csv" <<'PY'
import csv, sys
def rows(path):
    with open(path, newline="") as f:
        r = list(csv.reader(f))
    h = r[0]
    return [dict(zip(h, x)) for x in r[1:]]
single, merged = rows(sys.argv[1]), rows(sys.argv[2])
ids = [r["combo_id"] for r in merged]
dupes = sorted({i for i in ids if ids.count(i) > 1})
assert not dupes, f"combinations merged twice: {dupes}"
want = {r["combo_id"]: r for r in single}
assert set(ids) == set(want), f"missing {sorted(set(want) - set(ids))}, extra {sorted(set(ids) - set(want))}"
for r in merged:
    w = want[r["combo_id"]]
    assert r["status"] == w["status"] == "ok", (r["combo_id"], r["status"], r["message"], w["status"])
    for col in ("nodes", "prim_tests", "hits"):
        assert r[col] != "" and r[col] == w[col], f"{r['combo_id']} {col}: merged {r[col]!r}, single {w[col]!r}"
print(f"{len(merged)} combinations, each once; nodes, prim_tests and hits equal to the single-process run")
PY

echo "== 6. stop; no daemon left"
cluster_stop
left=$(pgrep -a -f -- "$work" || true)
[ -z "$left" ] || fail "processes of the test cluster left: $left"
after=$(daemon_pids)
for pid in $after; do
    [[ " $before " == *" $pid "* ]] || fail "a ${daemons[*]} process is left: $(ps -o pid=,args= -p "$pid")"
done
echo "test-slurm: passed in $(($(date +%s) - t0)) s"
