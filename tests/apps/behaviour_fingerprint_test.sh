#!/usr/bin/env bash
# Behaviour fingerprint: for fixed seeds, the bytes of generated meshes, trained databases
# (esf-angles and esf), rendered views and `esf describe` output must not change when code is
# moved or shared (tests/apps/behaviour_fingerprints.sha256 holds their SHA-256, recorded from
# the release before the layer folders). A change that is meant to alter results records new
# fingerprints with --update and says why in its commit.
#   behaviour_fingerprint_test.sh ESF_BINARY FINGERPRINT_FILE [--update]
set -euo pipefail
esf=$1
fingerprints=$2
update=${3:-}
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
cd "$work"

"$esf" generate -o models --per-class 1 --seed 3 --categories mug,bottle,car --threads 2 >/dev/null
"$esf" train models -o angles.db --seed 5 --threads 2 >/dev/null
"$esf" train models -o esf.db --seed 5 --descriptor esf --threads 1 >/dev/null
"$esf" render models/mug/gen_mug_000.ply -o views --level 0 >/dev/null
"$esf" describe views/view_000.pcd views/view_007.pcd views/view_013.pcd --seed 9 \
    --threads 2 >describe_fast.csv
"$esf" describe views/view_000.pcd --seed 9 --sampler pcl --samples 4000 >describe_pcl.csv

sha256sum models/*/*.ply angles.db esf.db views/view_000.pcd views/view_013.pcd \
    describe_fast.csv describe_pcl.csv >actual.sha256
if [[ $update == --update ]]; then
    cp actual.sha256 "$fingerprints"
    echo "recorded $(wc -l <actual.sha256) fingerprints in $fingerprints"
    exit 0
fi
if ! diff -u "$fingerprints" actual.sha256; then
    echo "behaviour changed: the files above differ from $fingerprints" >&2
    exit 1
fi
echo "$(wc -l <actual.sha256) files byte-identical to the recorded fingerprints"
