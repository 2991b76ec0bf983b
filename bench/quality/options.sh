#!/usr/bin/env bash
# Every resize option that changes the method, measured by the quality suite:
# one summary row (worst / median over the 16 cases) per option, against the
# default. About 4 minutes. Usage (from the repository root):
#   bash bench/quality/options.sh [build/release/tools/refit] > bench/quality/options.md
set -euo pipefail
refit="${1:-build/release/tools/refit}"
here="$(cd "$(dirname "$0")" && pwd)"
variants=("" "--method paper" "--no-collision" "--symmetry none" "--clearance 0.5" "--feature-zone 0"
          "--feature-zone 3" "--epsilon 0.5" "--epsilon 2" "--no-layers" "--encode-on-warped" "--paper-closeness" "--ordered-features"
          "--paper-surface" "--plain-sweeps" "--v-cycles" "--max-triangles 8" "--agents 5000")
echo "| option | flipped | inside v / faces | near-body change cm | mirror - warp's cm | height ratio / warp's | features vs warp (least) | between vs warp (least) | feature gap cm |"
echo "|---|---:|---:|---:|---:|---:|---:|---:|---:|"
for v in "${variants[@]}"; do
  row=$(/usr/bin/python3 "$here/run.py" --refit "$refit" --methods warp refit --refit-args="$v" |
        grep '^| refit | [0-9]' || true)
  echo "| ${v:-(default)} ${row#| refit }"
done
