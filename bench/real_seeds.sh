#!/usr/bin/env bash
# The real judges over several training seeds: the training seed alone moves the real scene
# folds and views by up to 5 objects (BENCHMARKS.md, "How far the training seed alone moves the
# judges"), as much as most rules do, so a rule is judged on the real data by its mean over seeds.
# For each seed, trains a database of all shared meshes (`esf train --seed S` and the extra
# training options), then evaluates the 229 real views (`esf eval DB real/labels.csv`) and the
# two folds of the shared real scenes (`scripts/mosd-scene-set.sh --fold K/2`, `esf eval
# --scenes`) with the extra evaluation options; prints one row per seed and the mean.
#   bench/real_seeds.sh [BUILD_DIR] [SEEDS]
# Defaults: build, "0 1 2". Extra options: $REAL_SEEDS_TRAIN (esf train), $REAL_SEEDS_EVAL (esf
# eval). Work files go to $REAL_SEEDS_DIR (default: a new temporary folder, removed at the end);
# databases already there are reused. Each database holds $REAL_SEEDS_CANS generated wide tins
# as can models, as the README's does (default 20; 0: none).
set -euo pipefail
bench_name=real_seeds
source "$(dirname "$0")/bench_env.sh"
seeds="${2:-0 1 2}"
require_tools "$esf"
require_data "$data/meshes"
require_data "$data/real"
use_work_dir "${REAL_SEEDS_DIR:-}"
read -r -a train_args <<< "${REAL_SEEDS_TRAIN:-}"
read -r -a eval_args <<< "${REAL_SEEDS_EVAL:-}"
for k in 0 1; do
    [[ -f "$work/real_$k.csv" ]] ||
        "$root/scripts/mosd-scene-set.sh" --fold "$k/2" "$data" > "$work/real_$k.csv"
done
for seed in $seeds; do
    echo "== seed $seed: train, then the real views and both scene folds" >&2
    if [[ ! -f "$work/train_$seed.json" ]]; then
        "$esf" train "$data/meshes" -o "$work/seed_$seed.sqlite" --seed "$seed" \
            "${train_args[@]}" --json > "$work/train_$seed.part.json"
        add_generated_cans "$work/seed_$seed.sqlite" "${REAL_SEEDS_CANS:-20}" --seed "$seed" \
            "${train_args[@]}"
        mv "$work/train_$seed.part.json" "$work/train_$seed.json"
    fi
    "$esf" eval "$work/seed_$seed.sqlite" "$data/real/labels.csv" --json "${eval_args[@]}" \
        > "$work/views_$seed.json"
    for k in 0 1; do
        "$esf" eval "$work/seed_$seed.sqlite" --scenes "$work/real_$k.csv" --json \
            "${eval_args[@]}" > "$work/scenes_${k}_$seed.json"
    done
done
# shellcheck disable=SC2086  # the seeds, one argument each
python3 - "$work" $seeds <<'PY'
import json, sys
work, seeds = sys.argv[1], sys.argv[2:]
rows = []
for seed in seeds:
    views = json.load(open(f"{work}/views_{seed}.json"))["overall"]
    row = [seed, views["top1_hits"], views["samples"]]
    for k in (0, 1):
        scenes = json.load(open(f"{work}/scenes_{k}_{seed}.json"))
        total = next(t for t in scenes["types"] if t["type"] == "all")
        row += [total["found"], total["correct"], total["objects"]]
    rows.append(row)
print("| seed | views named right | fold 0: found / named right | fold 1: found / named right |")
print("|---|---|---|---|")
for r in rows:
    print(f"| {r[0]} | {r[1]} of {r[2]} | {r[3]} / {r[4]} of {r[5]} | {r[6]} / {r[7]} of {r[8]} |")
mean = lambda i: sum(r[i] for r in rows) / len(rows)
spread = lambda i: max(r[i] for r in rows) - min(r[i] for r in rows)
print(f"| mean (spread) | {mean(1):.1f} ({spread(1)}) | {mean(3):.1f} / {mean(4):.1f} ({spread(4)}) "
      f"| {mean(6):.1f} / {mean(7):.1f} ({spread(7)}) |")
PY
