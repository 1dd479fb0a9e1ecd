#!/bin/sh
# Cost images (where each structure spends its traversal work): for the bunny, Conference
# and the procedural forest, the shaded
# image and per-pixel node-visit / triangle-test heatmaps of the SAH BVH, the LBVH and the
# kd-tree at 640x480, then one figure per model, OUT_DIR/figures/cost-<model>.png.
#
#   harness/scripts/cost_images.sh [BUILD_DIR [PYTHON [OUT_DIR]]]
#
# Defaults: build/, .venv/bin/python, results/. Run from the project's top directory.
# Per-structure heatmaps and per-pixel CSVs go to OUT_DIR/runs/cost/ (git-ignored).
set -eu
BUILD=${1:-build}
PYTHON=${2:-.venv/bin/python}
OUT=${3:-results}
RAW="$OUT/runs/cost"
mkdir -p "$RAW"

for model in stanford-bunny conference procedural:forest; do
    name=$(echo "$model" | sed 's/^procedural://')
    "$BUILD/accelbench" render --model "$model" --accel embree --width 640 --height 480 \
        --out "$RAW/$name-shaded.png" >/dev/null
    set --
    for s in "bvh split=sah:BVH (binned SAH)" "lbvh:LBVH" "kdtree:kd-tree"; do
        spec=${s%%:*}
        label=${s#*:}
        accel=${spec%% *}
        params=""
        [ "$accel" != "$spec" ] && params="--param ${spec#* }"
        # shellcheck disable=SC2086  # $params is zero or two words
        "$BUILD/accelbench" render --model "$model" --accel "$accel" $params --width 640 --height 480 \
            --cost-out "$RAW/$name-$accel" >/dev/null
        set -- "$@" --cost "$label=$RAW/$name-$accel-cost.csv"
    done
    PYTHONPATH=analysis "$PYTHON" -m accelbench_analysis cost-images --model "$name" \
        --shaded "$RAW/$name-shaded.png" --out "$OUT" "$@"
done
