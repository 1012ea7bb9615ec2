#!/usr/bin/env bash
# Every judge of docs/judging.md for one setting, in one command. Trains a database of all shared
# meshes and the proving grounds' three fold databases with the setting's training options,
# makes the judges' scene sets (once: they are kept in the work folder and reused), evaluates
# each judge with the setting's evaluation options and prints one row per judge.
#   bench/judges.sh [BUILD_DIR]
# Environment:
#   JUDGES_DIR    work folder (default: a new temporary folder, removed at the end). Scene sets
#                 and databases already there are reused, so a second setting costs only its own
#                 training (about a minute on 2 cores) and evaluation (under a minute).
#   JUDGES_NAME   the setting's name: its databases and reports go to JUDGES_DIR/NAME (default:
#                 "default"); compare two settings' reports with bench/scenes_paired.py.
#   JUDGES_TRAIN  extra `esf train` options (e.g. "--angles-weight 1.4" or "--seed 1")
#   JUDGES_EVAL   extra `esf eval` options (e.g. "--shape-weight 0.5")
#   JUDGES_FROM   evaluate the databases of that earlier setting (a name in JUDGES_DIR) instead
#                 of training (for settings of `esf eval` alone; JUDGES_TRAIN is then refused)
#   JUDGES_BASE   an earlier judged setting (a name in JUDGES_DIR): each figure is followed by its
#                 change against that setting's, in brackets
#   JUDGES_CANS   generated wide tins added to every database as can models (default 20, as the
#                 README's database: `esf generate --categories can --per-class 20 --seed 1`);
#                 0 leaves them out
# The scene sets are those of BENCHMARKS.md: proving ground (3 folds of 100 tables of held-out
# catalog groups, seed 1), sized proving ground (the same with --size-spread 0.25), household
# proving ground (--categories of the real scenes), the shared real scenes in two folds, the 229
# real views, and the pose sets (70 tables of models the database holds, seeds 6 and 5).
set -euo pipefail
bench_name=judges
source "$(dirname "$0")/bench_env.sh"
require_tools "$esf"
require_data "$data/meshes"
require_data "$data/real/scenes"
use_work_dir "${JUDGES_DIR:-}"
name="${JUDGES_NAME:-default}"
[[ "$name" =~ ^[A-Za-z0-9._-]+$ ]] || { echo "judges: JUDGES_NAME '$name' is not a plain name" >&2; exit 1; }
read -r -a train_args <<< "${JUDGES_TRAIN:-}"
read -r -a eval_args <<< "${JUDGES_EVAL:-}"
cans="${JUDGES_CANS:-20}"
meshes="$data/meshes"
household=box,can,bowl,mug,bottle,cup

base=""  # JUDGES_BASE's reports
if [[ -n "${JUDGES_BASE:-}" ]]; then
    [[ "$JUDGES_BASE" =~ ^[A-Za-z0-9._-]+$ && -f "$work/$JUDGES_BASE/views.json" ]] ||
        { echo "judges: JUDGES_BASE '$JUDGES_BASE' is no judged setting in $work" >&2; exit 1; }
    base="$work/$JUDGES_BASE"
fi

# The scene sets, each made once (a set is complete when its generate.json exists).
generate() {  # FOLDER [esf generate-scenes options...]
    local folder="$1"
    shift
    [[ -f "$work/sets/$folder/generate.json" ]] && return
    echo "== scene set $folder" >&2
    "$esf" generate-scenes "$meshes" -o "$work/sets/$folder" "$@" --json > "$work/sets/$folder.json"
    mv "$work/sets/$folder.json" "$work/sets/$folder/generate.json"
}
mkdir -p "$work/sets"
for k in 0 1 2; do
    generate "ground$k" -n 100 --seed 1 --fold "$k/3"
    generate "sized$k" -n 100 --seed 1 --fold "$k/3" --size-spread 0.25
    generate "household$k" -n 100 --seed 1 --fold "$k/3" --categories "$household"
done
generate poseB -n 70 --seed 6
generate pose -n 70 --seed 5
for k in 0 1; do
    [[ -f "$work/sets/real$k.csv" ]] ||
        "$root/scripts/mosd-scene-set.sh" --fold "$k/2" "$data" > "$work/sets/real$k.csv"
done

# The setting's databases: trained, or an earlier setting's.
databases="$work/$name"
if [[ -n "${JUDGES_FROM:-}" ]]; then
    [[ "$JUDGES_FROM" =~ ^[A-Za-z0-9._-]+$ ]] ||
        { echo "judges: JUDGES_FROM '$JUDGES_FROM' is not a plain name" >&2; exit 1; }
    databases="$work/$JUDGES_FROM"
    ((${#train_args[@]} == 0)) || { echo "judges: JUDGES_FROM and JUDGES_TRAIN together" >&2; exit 1; }
    for db in all fold0 fold1 fold2; do
        [[ -f "$databases/$db.sqlite.json" ]] ||
            { echo "judges: no trained $databases/$db.sqlite (JUDGES_FROM)" >&2; exit 1; }
    done
fi
mkdir -p "$work/$name"
train() {  # DB [esf train options...]
    local db="$1"
    shift
    [[ -f "$db.json" ]] && return
    echo "== train $db" >&2
    "$esf" train "$meshes" -o "$db" "${train_args[@]}" "$@" --json > "$db.part.json"
    add_generated_cans "$db" "$cans" "${train_args[@]}"
    mv "$db.part.json" "$db.json"
}
train "$databases/all.sqlite"
for k in 0 1 2; do train "$databases/fold$k.sqlite" --other-folds "$k/3"; done

# The evaluations, two at a time; a failed one stops the script with its status.
pids=()
evaluate() {  # REPORT DB TEST [esf eval options...]
    local report="$1" db="$2" test="$3"
    shift 3
    if ((${#pids[@]} >= 2)); then
        wait "${pids[0]}"
        pids=("${pids[@]:1}")
    fi
    "$esf" eval "$db" "$test" "$@" "${eval_args[@]}" --json > "$work/$name/$report.json" &
    pids+=("$!")
}
echo "== evaluate $name" >&2
for k in 0 1 2; do
    for set in ground sized household; do
        evaluate "$set$k" "$databases/fold$k.sqlite" --scenes "$work/sets/$set$k/scenes.csv"
    done
done
for k in 0 1; do evaluate "real$k" "$databases/all.sqlite" --scenes "$work/sets/real$k.csv"; done
for set in poseB pose; do
    evaluate "$set" "$databases/all.sqlite" --scenes "$work/sets/$set/scenes.csv"
done
evaluate views "$databases/all.sqlite" "$data/real/labels.csv"
for pid in "${pids[@]}"; do wait "$pid"; done

python3 - "$work/$name" "$name" "$base" <<'PY'
import json, sys
folder, name, base = sys.argv[1], sys.argv[2], sys.argv[3]
JUDGES = [  # judge, role, reports
    ("proving ground", "choosing", ["ground0", "ground1", "ground2"]),
    ("sized proving ground", "choosing", ["sized0", "sized1", "sized2"]),
    ("real fold 0", "choosing", ["real0"]),
    ("pose set B", "choosing (pose)", ["poseB"]),
    ("household proving ground", "reporting", ["household0", "household1", "household2"]),
    ("real fold 1", "reporting", ["real1"]),
    ("pose set", "reporting (pose)", ["pose"]),
]
def scenes(where, reports):  # objects, found, named right, ADD-S right, ADD-S judged
    total = [0, 0, 0, 0, 0]
    for r in reports:
        a = next(t for t in json.load(open(f"{where}/{r}.json"))["types"] if t["type"] == "all")
        for i, key in enumerate(("objects", "found", "correct", "pose_correct", "posed")):
            total[i] += a.get(key) or 0
    return total
def views(where):
    v = json.load(open(f"{where}/views.json"))["overall"]
    return [v["samples"], 0, v["top1_hits"], v["topk_hits"], 0]
def change(now, then):
    return f" ({now - then:+d})" if base else ""
print(f"judges of the setting '{name}' (reports in {folder})"
      + (f", changes against {base}" if base else ""))
print("| judge | role | objects | found | named right | ADD-S < 0.1 d |")
print("|---|---|---|---|---|---|")
for judge, role, reports in JUDGES + [("real views", "reporting", None)]:
    now = scenes(folder, reports) if reports else views(folder)
    then = (scenes(base, reports) if reports else views(base)) if base else now
    objects, found, right, posed, judged = now
    if reports is None:  # 1-NN, and 10-NN in brackets
        cells = ["", f"{right}{change(right, then[2])} (10-NN {now[3]}{change(now[3], then[3])})"]
    else:
        cells = [f"{found}{change(found, then[1])}", f"{right}{change(right, then[2])}"]
    pose = f"{posed}{change(posed, then[3])} of {judged}" if judged else ""
    print(f"| {judge} | {role} | {objects} | {cells[0]} | {cells[1]} | {pose} |")
PY
