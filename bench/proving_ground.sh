#!/usr/bin/env bash
# The proving ground: recognition judged on generated table scenes of model groups that the
# database does not hold. For each fold K of N, trains on the other folds' groups
# (`esf train --other-folds K/N`), generates scenes of fold K's groups
# (`esf generate-scenes --fold K/N`) and evaluates them end to end (`esf eval --scenes`); then
# prints per scene type: objects, found as one cluster, found and named right, over all folds.
#   bench/proving_ground.sh [BUILD_DIR] [SCENES_PER_FOLD] [FOLDS] [SEED]
# Defaults: build, 100 scenes a fold, 3 folds (300 scenes), seed 1. Work files go to
# $PROVING_GROUND_DIR (default: a new temporary folder, removed at the end); scenes and databases
# already there are reused. Extra `esf eval` options come from $PROVING_GROUND_EVAL (e.g.
# "--no-verify", or "--verify-meshes {meshes}" for databases trained before surfaces were
# stored); {meshes} in it stands for the mesh folder. $PROVING_GROUND_SIZE_SPREAD (default 0)
# makes the objects other than their models' sizes (`esf generate-scenes --size-spread`; the
# sized proving ground of BENCHMARKS.md uses 0.25); its scenes are kept apart from the others.
# $PROVING_GROUND_CATEGORIES (comma-separated) generates scenes of those categories only
# (`esf generate-scenes --categories`; the household proving ground of BENCHMARKS.md uses
# box,can,bowl,mug,bottle,cup, the classes of the real scenes); the databases are the same.
# Each database holds $PROVING_GROUND_CANS generated wide tins as can models, as the README's
# does (default 20; 0: none).
set -euo pipefail
bench_name=proving_ground
source "$(dirname "$0")/bench_env.sh"
scenes="${2:-100}"
folds="${3:-3}"
seed="${4:-1}"
require_tools "$esf"
require_data "$data/meshes"
use_work_dir "${PROVING_GROUND_DIR:-}"
eval_args="${PROVING_GROUND_EVAL:-}"
size_spread="${PROVING_GROUND_SIZE_SPREAD:-0}"
categories="${PROVING_GROUND_CATEGORIES:-}"
sized=""
[[ "$size_spread" == 0 ]] || sized="_size$size_spread"
category_args=()
if [[ -n "$categories" ]]; then
    sized="${sized}_${categories//,/-}"
    category_args=(--categories "$categories")
fi
for ((k = 0; k < folds; k++)); do
    echo "== fold $k/$folds: train on the other folds, $scenes scenes of this fold's groups" >&2
    if [[ ! -f "$work/train$k.json" ]]; then
        "$esf" train "$data/meshes" -o "$work/fold$k.sqlite" --other-folds "$k/$folds" --json \
            > "$work/train$k.part.json"
        add_generated_cans "$work/fold$k.sqlite" "${PROVING_GROUND_CANS:-20}"
        mv "$work/train$k.part.json" "$work/train$k.json"
    fi
    [[ -f "$work/generate$k$sized.json" ]] ||
        "$esf" generate-scenes "$data/meshes" -o "$work/scenes$k$sized" -n "$scenes" --seed "$seed" \
            --fold "$k/$folds" --size-spread "$size_spread" "${category_args[@]}" --json \
            > "$work/generate$k$sized.json"
    # shellcheck disable=SC2086
    "$esf" eval "$work/fold$k.sqlite" --scenes "$work/scenes$k$sized/scenes.csv" --json \
        ${eval_args//\{meshes\}/$data/meshes} > "$work/eval$k.json"
done
python3 - "$work" "$folds" <<'PY'
import json, sys, collections
work, folds = sys.argv[1], int(sys.argv[2])
rows = collections.OrderedDict()
classes = {}
ms = []
failures = 0
for k in range(folds):
    report = json.load(open(f"{work}/eval{k}.json"))
    for t in report["types"]:
        r = rows.setdefault(t["type"], collections.Counter())
        for key in ("scenes", "objects", "found", "labelled", "correct"):
            r[key] += t[key]
    for o in report["objects"]:
        c = classes.setdefault(o["class"], collections.Counter())
        c["objects"] += 1
        c["found"] += o["outcome"] == "found"
        c["correct"] += bool(o["correct"])
    ms.append(report["timings"]["segment_ms_per_frame"] + report["timings"]["recognize_ms_per_frame"])
    failures += len(report["failures"])
print("| scene type | scenes | objects | found as one cluster | named right (of labelled) |")
print("|---|---|---|---|---|")
order = [t for t in rows if t != "all"] + ["all"]
for t in order:
    r = rows[t]
    found = 100.0 * r["found"] / max(r["objects"], 1)
    right = 100.0 * r["correct"] / max(r["labelled"], 1)
    print(f"| {t} | {r['scenes']} | {r['objects']} | {found:.1f} % | {right:.1f} % |")
print("\n| class | objects | found | named right |")
print("|---|---|---|---|")
for name in sorted(classes, key=lambda n: -classes[n]["objects"]):
    c = classes[name]
    print(f"| {name} | {c['objects']} | {100.0 * c['found'] / c['objects']:.1f} % | "
          f"{100.0 * c['correct'] / c['objects']:.1f} % |")
print(f"\nscenes that failed to evaluate: {failures}")
print(f"\nmean frame time (segment + recognise), per fold: " +
      ", ".join(f"{m:.1f} ms" for m in ms))
PY
