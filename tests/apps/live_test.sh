#!/usr/bin/env bash
# esf live on recordings: read directly (--recording) and, when Debian's libfreenect-bin is
# installed and esf links libfreenect, through fakenect as a Kinect. Checks the JSON lines, the
# exit status and the summary at --frames, at the end of a recording, on Ctrl-C, for a missing
# or broken recording and without a device; every run is bounded by `timeout`.
#   live_test.sh ESF_BINARY recording|fakenect
# Exit 77 (skipped) in fakenect mode when fakenect or libfreenect is missing.
set -euo pipefail
esf=$1
mode=$2
here=$(cd "$(dirname "$0")" && pwd)
check() { python3 "$here/live_check.py" "$@"; }
fail() { echo "FAIL: $*" >&2; exit 1; }

if [[ $mode == fakenect ]]; then
    command -v fakenect >/dev/null || { echo "fakenect not installed (libfreenect-bin)"; exit 77; }
    # grep reads all of ldd's output: with -q it may stop early, and pipefail would take the
    # SIGPIPE that ldd gets then for a missing library.
    ldd "$esf" | grep libfreenect >/dev/null || { echo "esf built without libfreenect"; exit 77; }
fi
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
cd "$work"

"$esf" generate -o models --per-class 1 --seed 3 --categories mug,bottle,bowl --threads 2 >/dev/null
"$esf" train models -o db.sqlite --level 0 --threads 2 >/dev/null
"$esf" record-scenes models -o rec -n 1 --frames 6 --seed 1 --types isolated --threads 2 >/dev/null
[[ -f rec/sequence_000/INDEX.txt && -f rec/sequences.json ]] || fail "no recording written"
[[ $(grep -c '^d-' rec/sequence_000/INDEX.txt) == 6 ]] || fail "6 depth frames expected"

if [[ $mode == recording ]]; then
    # The whole recording: 6 frames, nothing skipped, exit 0, the end in the summary.
    timeout 60 "$esf" live db.sqlite --recording rec/sequence_000 --threads 1 >out.jsonl 2>err.txt
    check out.jsonl --lines 6 || fail "JSON lines"
    grep -q '^esf live: 6 frames processed, 0 skipped, .*: the recording ended$' err.txt ||
        fail "summary: $(cat err.txt)"
    # Tracks carry over: some track was seen in several frames.
    python3 -c "import json,sys; l=[json.loads(x) for x in open('out.jsonl')];
sys.exit(0 if any(t['frames'] >= 3 for t in l[-1]['tracks']) else 1)" ||
        fail "no track lasted 3 frames: $(tail -1 out.jsonl)"
    # Verification: objects carry their fitted model's pose and tracks their last fit.
    python3 -c "import json,sys; l=[json.loads(x) for x in open('out.jsonl')];
sys.exit(0 if any('fit' in t for t in l[-1]['tracks']) and
         any(o.get('verified') for f in l for o in f['objects']) else 1)" ||
        fail "no verified fit: $(tail -1 out.jsonl)"
    # A named track names its class's best model (generated models are gen_CLASS_NNN).
    python3 -c "import json,sys; l=[json.loads(x) for x in open('out.jsonl')];
named=[t for f in l for t in f['tracks'] if t['class']];
sys.exit(0 if named and all(t['model'].startswith('gen_' + t['class'] + '_') for t in named) else 1)" ||
        fail "tracks without their class's model: $(tail -1 out.jsonl)"
    # --frames stops early; --report keeps the latest frame's page.
    timeout 60 "$esf" live db.sqlite --recording rec/sequence_000 --frames 2 --report page \
        >out2.jsonl 2>err2.txt
    check out2.jsonl --lines 2 || fail "--frames 2"
    grep -q ': --frames reached$' err2.txt || fail "summary: $(cat err2.txt)"
    grep -q 'http-equiv="refresh"' page/index.html || fail "no refreshing page"
    # A broken recording is one error line, exit 2.
    cp -r rec/sequence_000 broken
    first=$(grep -m1 '^d-' broken/INDEX.txt)
    head -c 1000 "broken/$first" >broken/tmp && mv broken/tmp "broken/$first"
    set +e
    timeout 60 "$esf" live db.sqlite --recording broken >out3.jsonl 2>err3.txt
    status=$?
    set -e
    [[ $status == 2 ]] || fail "broken recording: exit $status"
    grep -q "^esf: error: .*$first: truncated" err3.txt || fail "error line: $(cat err3.txt)"
    # The real scenes' recordings: a cloud of the wrong size is refused by name.
    "$esf" record-scenes --cloud models/mug/gen_mug_000.ply -o clouds 2>err4.txt && fail "ply taken"
    grep -q "^esf: error: .*gen_mug_000.ply: a recording needs an organised 640 x 480" err4.txt ||
        fail "cloud error: $(cat err4.txt)"
    echo "esf live on recordings: ok"
    exit 0
fi

# Under fakenect: --frames, then the end of the recording (nothing hangs: fakenect neither loops
# nor exits there), with stdout holding JSON only. fakenect plays at the recording's clock and esf
# live skips the frames it cannot keep up with, so the --frames run plays a recording at 2 frames
# a second: a slow build (sanitizers) then still processes every frame. The same slow recording
# is interrupted below.
"$esf" record-scenes models -o slow -n 1 --frames 20 --frame-rate 2 --seed 1 --types isolated \
    --threads 2 >/dev/null
timeout 60 fakenect slow/sequence_000 "$esf" live db.sqlite --frames 3 --threads 1 \
    >out.jsonl 2>err.txt || fail "fakenect --frames 3: $(cat err.txt)"
check out.jsonl --lines 3 || fail "JSON lines under fakenect"
grep -q '^esf live: 3 frames processed, .*fakenect recording .*: --frames reached$' err.txt ||
    fail "summary: $(cat err.txt)"
timeout 60 fakenect rec/sequence_000 "$esf" live db.sqlite --threads 1 >out.jsonl 2>err.txt ||
    fail "fakenect to the end: $(cat err.txt)"
check out.jsonl --at-most 6 || fail "JSON lines at the end"
summary=$(grep '^esf live: ' err.txt) || fail "no summary: $(cat err.txt)"
[[ $summary =~ ([0-9]+)\ frames\ processed,\ ([0-9]+)\ skipped ]] || fail "summary: $summary"
(( BASH_REMATCH[1] + BASH_REMATCH[2] == 6 )) || fail "processed + skipped != 6: $summary"
[[ $summary == *": the recording ended" ]] || fail "summary: $summary"
grep -q 'No more lines' err.txt || fail "fakenect's warning should be on stderr"

# Ctrl-C: the slow recording (2 frames a second), interrupted after 3 s: exit 130.
set +e
timeout --preserve-status -s INT 3 fakenect slow/sequence_000 "$esf" live db.sqlite >out.jsonl 2>err.txt
status=$?
set -e
[[ $status == 130 ]] || fail "Ctrl-C: exit $status: $(cat err.txt)"
grep -q ': interrupted$' err.txt || fail "summary after Ctrl-C: $(cat err.txt)"

# A missing recording: one error line naming it, exit 2, before fakenect could exit(1).
set +e
fakenect_lib=$(grep 'export LD_LIBRARY_PATH' "$(command -v fakenect)" | grep -o '/[^":]*/fakenect/')
FAKENECT_PATH="$work/nowhere" LD_LIBRARY_PATH="$fakenect_lib" timeout 60 "$esf" live db.sqlite >out.jsonl 2>err.txt
status=$?
set -e
[[ $status == 2 ]] || fail "missing recording: exit $status: $(cat err.txt)"
grep -q '^esf: error: .*nowhere/INDEX.txt: no such file' err.txt || fail "$(cat err.txt)"
[[ ! -s out.jsonl ]] || fail "stdout not empty"

# No fakenect, no Kinect: one error line, exit 2.
set +e
timeout 60 "$esf" live db.sqlite --timeout 2 >out.jsonl 2>err.txt
status=$?
set -e
[[ $status == 2 ]] || fail "no device: exit $status: $(cat err.txt)"
[[ $(grep -c '^esf: error: ' err.txt) == 1 ]] || fail "no device: $(cat err.txt)"
echo "esf live under fakenect: ok"
