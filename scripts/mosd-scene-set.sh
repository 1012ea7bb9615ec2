#!/usr/bin/env bash
# Writes the scene set of the shared mOSD scenes for `esf eval DB --scenes`: one row per labelled
# object (scene_file, object_id, class, scene_type) from the shared data's real/labels.csv.
#   scripts/mosd-scene-set.sh [--fold K/N | --other-folds K/N] [DATA] > scenes.csv
#   (DATA: $ESF_DATA or ../shared/data)
# Scene types follow the split's numbering: learn 0-16 isolated boxes, 17-24 stacked boxes,
# 25-32 occluded objects, 33-44 cylindric objects; test 44-54 mixed, 56-64 complex. Paths are
# absolute. --fold K/N keeps fold K of N: each type's scenes, in number order, dealt into N folds
# in turn (choose on some folds, report the others); --other-folds K/N keeps the rest. Views
# whose object id is not a number (test46's 7a and 7b: two objects under one mOSD label) have
# no row; their label still counts for segmentation.
set -euo pipefail
fold=-1
folds=0
other=0
case "${1:-}" in
    --fold | --other-folds)
        [[ "$1" == --other-folds ]] && other=1
        [[ "${2:-}" =~ ^([0-9]+)/([0-9]+)$ ]] ||
            { echo "mosd-scene-set: $1 needs K/N, got '${2:-}'" >&2; exit 1; }
        fold="${BASH_REMATCH[1]}"
        folds="${BASH_REMATCH[2]}"
        ((folds >= 2 && fold < folds)) ||
            { echo "mosd-scene-set: $1 $2: need 0 <= K < N and N >= 2" >&2; exit 1; }
        shift 2
        ;;
esac
data="${1:-${ESF_DATA:-$(cd "$(dirname "$0")/.." && pwd)/../shared/data}}"
labels="$data/real/labels.csv"
[ -f "$labels" ] || { echo "mosd-scene-set: no $labels (pass the data folder or set ESF_DATA)" >&2; exit 2; }
data="$(cd "$data" && pwd)"
echo "scene_file,object_id,class,scene_type"
# The first seven columns (file,class,shape,quality,source,scene,object_id) hold no commas.
awk -F, -v dir="$data/real/scenes" -v fold="$fold" -v folds="$folds" -v other="$other" '
function type_of(split_name, n) {
    if (split_name == "learn")
        return n <= 16 ? "isolated boxes" : n <= 24 ? "stacked boxes" : n <= 32 ? "occluded" : "cylindric"
    return n <= 54 ? "mixed" : "complex"
}
NR > 1 && $5 == "mosd" && $6 ~ /^(learn|test)[0-9]+$/ && $7 ~ /^[0-9]+$/ {
    split_name = $6 ~ /^learn/ ? "learn" : "test"
    n = substr($6, length(split_name) + 1) + 0
    type = type_of(split_name, n)
    rows[++count] = sprintf("%s/mosd_%s.pcd,%s,%s,%s", dir, $6, $7, $2, type)
    row_scene[count] = $6
    row_type[count] = type
    if (!(($6) in seen)) { seen[$6] = 1; numbers[type] = numbers[type] " " n; scene_number[$6] = n }
}
END {
    # Rank of each scene among its type by number: the fold is the rank modulo N.
    for (t in numbers) {
        k = split(numbers[t], list, " ")
        for (i = 1; i <= k; ++i) {
            rank = 0
            for (j = 1; j <= k; ++j) rank += list[j] + 0 < list[i] + 0
            rank_of[t, list[i] + 0] = rank
        }
    }
    for (i = 1; i <= count; ++i) {
        if (folds > 0) {
            in_fold = rank_of[row_type[i], scene_number[row_scene[i]]] % folds == fold
            if (in_fold == other) continue
        }
        print rows[i]
    }
}' "$labels"
