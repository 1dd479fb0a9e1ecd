#!/bin/sh
# Cost images (where each structure spends its traversal work): for the bunny, Conference
# and the procedural forest, the shaded
# image and per-pixel node-visit / triangle-test heatmaps of every registered structure that
# counts its traversal (`accelbench list --structures`), each at its defaults, at 640x480,
# then one figure per model, OUT_DIR/figures/cost-<model>.png. A structure that refuses a
# model (brute force above its triangle limit) is left out of that model's figure.
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
    structures=$("$BUILD/accelbench" list --structures)
    tab=$(printf '\t')
    while IFS="$tab" read -r accel label counts; do
        [ "$counts" = yes ] || continue
        if "$BUILD/accelbench" render --model "$model" --accel "$accel" --width 640 --height 480 \
            --cost-out "$RAW/$name-$accel" >/dev/null 2>"$RAW/$name-$accel.err"; then
            set -- "$@" --cost "$label=$RAW/$name-$accel-cost.csv"
        else
            echo "cost_images: $accel left out of $name: $(tail -n 1 "$RAW/$name-$accel.err")" >&2
        fi
    done <<EOF
$structures
EOF
    PYTHONPATH=analysis "$PYTHON" -m accelbench_analysis cost-images --model "$name" \
        --shaded "$RAW/$name-shaded.png" --out "$OUT" "$@"
done
