#!/usr/bin/env bash
# Writes the scene set of the mOSD learn scenes for `esf eval DB --scenes`: one row per labelled
# object (scene_file, object_id, class, scene_type) from the shared data's real/labels.csv.
#   scripts/mosd-scene-set.sh [DATA] > scenes.csv      (DATA: $ESF_DATA or ../shared/data)
# Scene types follow the split's numbering: 0-16 isolated boxes, 17-24 stacked boxes,
# 25-32 occluded objects, 33-44 cylindric objects. Paths are absolute.
set -euo pipefail
data="${1:-${ESF_DATA:-$(cd "$(dirname "$0")/.." && pwd)/../shared/data}}"
labels="$data/real/labels.csv"
[ -f "$labels" ] || { echo "mosd-scene-set: no $labels (pass the data folder or set ESF_DATA)" >&2; exit 2; }
data="$(cd "$data" && pwd)"
echo "scene_file,object_id,class,scene_type"
# The first seven columns (file,class,shape,quality,source,scene,object_id) hold no commas.
awk -F, -v dir="$data/real/scenes" 'NR > 1 && $5 == "mosd" && $6 ~ /^learn[0-9]+$/ {
    n = substr($6, 6) + 0
    type = n <= 16 ? "isolated boxes" : n <= 24 ? "stacked boxes" : n <= 32 ? "occluded" : "cylindric"
    printf "%s/mosd_%s.pcd,%s,%s,%s\n", dir, $6, $7, $2, type
}' "$labels"
