#!/usr/bin/env bash
# The report pages in a real browser: makes every kind of page esf writes (esf demo --report,
# esf scene --report, esf eval --report with its gallery of misclassified views) from the
# demo's generated models, then tests/report/page_check.py opens each one in headless Chromium,
# offline, and checks that it loads without console messages, embeds all its pictures, and
# shows them. Skips (exit 77) when Chromium is not installed.
#
# Usage: browser_pages_test.sh ESF_BINARY [DATA_DIR]   (ESF_DATA, else DATA_DIR: the shared data,
# for a real mOSD scene too). ESF_KEEP_PAGES=DIR keeps the pages there for a person to look at.
set -euo pipefail
esf=$1
data=${ESF_DATA:-${2:-}}
chromium=$(command -v chromium || command -v chromium-browser || true)
if [ -z "$chromium" ]; then
    echo "SKIPPED: no chromium on the PATH (Debian: apt-get install chromium)"
    exit 77
fi
here=$(cd "$(dirname "$0")" && pwd)
work=$(mktemp -d "${TMPDIR:-/tmp}/esf-browser-XXXXXX")
trap 'rm -rf "$work"' EXIT
cd "$work"

# The demo: its evaluation page and its scene page; it keeps its models and database.
"$esf" demo --per-class 1 --level 0 --query-models 1 --query-views 3 --scene-objects 4 \
    --threads 2 --report demo --work models > demo.log
db=$(ls models/demo_*.db)
root=$(ls -d models/train_*)

# Scene pages: the demo's depth frame, and a real scene when the shared data is there.
scenes=(demo/scene_depth.png)
if [ -n "$data" ] && [ -f "$data/real/scenes/mosd_learn0.pcd" ]; then
    scenes+=("$data/real/scenes/mosd_learn0.pcd")
else
    echo "note: no shared data at '${data}': the real scene is left out"
fi
"$esf" scene "$db" "${scenes[@]}" --report scene --meshes "$root" > scene.log

# An evaluation with a gallery: views of the training models, each labelled with the next
# class, so that most are misclassified (a query nearest to a view of its label's class is
# counted right and left out of the gallery).
classes=($(cd "$root" && ls -d */ | tr -d /))
echo "file,class" > test.csv
for n in "${!classes[@]}"; do
    mesh=$(ls "$root/${classes[$n]}"/* | head -1)
    "$esf" render "$mesh" -o "views/${classes[$n]}" --level 0 --distance 1.0 --seed 7 > /dev/null
    label=${classes[$(((n + 1) % ${#classes[@]}))]}
    for view in $(ls "views/${classes[$n]}"/*.pcd | head -2); do
        echo "$work/$view,$label" >> test.csv
    done
done
"$esf" eval "$db" test.csv --report eval --meshes "$root" -k 3 > eval.log

# The gallery holds every misclassified query, each with its three pictures.
wrong=$(python3 -c "
import json; r = json.load(open('eval/report.json'))
print(sum(q['predicted'] != q['class'] for q in r['queries']))")
shown=$(grep -o '<div class="entry">' eval/index.html | wc -l)
if [ "$wrong" -lt 1 ] || [ "$shown" -ne "$wrong" ]; then
    echo "FAILED: $wrong misclassified queries, $shown in the gallery"
    exit 1
fi
echo "gallery: $shown misclassified queries"

if [ -n "${ESF_KEEP_PAGES:-}" ]; then
    mkdir -p "$ESF_KEEP_PAGES" && cp -r demo scene eval "$ESF_KEEP_PAGES"/
fi

pages=(demo/index.html demo/scene.html scene/index.html scene/scene_*.html eval/index.html)
python3 "$here/page_check.py" "$chromium" "$work" "${pages[@]}"
