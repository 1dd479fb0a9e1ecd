#!/usr/bin/env bash
# The out-of-tree route of a structure (docs/adding-a-structure.md, "As a plugin"), as a
# user takes it: install accelbench's package into a fresh prefix, build this folder's
# plugins against it with find_package(accelbench), run them in a config's `plugins:` beside
# Embree, and check their rows: measured, and no wrong answer against the double-precision
# reference. Run by ctest (plugin_out_of_tree): test_out_of_tree.sh SOURCE_DIR BUILD_DIR.
set -euo pipefail
src=$(cd "$1" && pwd)
build=$(cd "$2" && pwd)
work=$(mktemp -d "${TMPDIR:-/tmp}/accelbench-out-of-tree.XXXXXX")
trap 'rm -rf "$work"' EXIT

cmake --install "$build" --prefix "$work/prefix" >/dev/null
generator=()
command -v ninja >/dev/null && generator=(-G Ninja)
cmake -S "$src/examples/plugins" -B "$work/build" "${generator[@]}" -DCMAKE_PREFIX_PATH="$work/prefix" \
  -DCMAKE_BUILD_TYPE=Release >/dev/null
cmake --build "$work/build" >/dev/null

cat >"$work/example.yaml" <<YAML
name: example-plugin
repetitions: 1
warmup: 0
render: {width: 64, height: 48}
plugins: [build/example_bvh.so]
models:
  - {procedural: forest, triangles: 20000, seed: 1}
  - {procedural: soup, triangles: 3000, seed: 2}
accelerators:
  - {name: example_bvh, params: {bins: [8, 32]}}
  - {name: embree}
YAML
"$build/accelbench" run "$work/example.yaml" --out "$work/example.csv" >"$work/run.log" 2>&1 || {
  cat "$work/run.log"
  exit 1
}

python3 - "$work/example.csv" <<'PY'
import csv, sys
rows = list(csv.DictReader(open(sys.argv[1], newline="")))
plugin = [r for r in rows if r["accel"] == "example_bvh"]
assert len(plugin) == 4, f"{len(plugin)} example_bvh rows, expected 4 (2 models x 2 bins)"
assert len(rows) == 6, f"{len(rows)} rows, expected 6"
for r in plugin:
    what = f"{r['model']} {r['params']}"
    assert r["status"] == "ok", f"{what}: {r['status']} {r['message']}"
    for column in ("false_misses", "false_hits", "prim_mismatches", "nan_results"):
        assert r[column] == "0", f"{what}: {column} = {r[column]!r}"
    assert int(r["hits"]) > 0 and int(r["nodes"]) > 0, what
    assert r["plugin_file"].endswith("example_bvh.so") and len(r["plugin_sha256"]) == 64, what
    assert r["plugin_version"] == "example_bvh 1.0" and r["label"] == "Example BVH (plugin)", what
print(f"out-of-tree plugin: {len(plugin)} example_bvh rows ok, no wrong answers")
PY
