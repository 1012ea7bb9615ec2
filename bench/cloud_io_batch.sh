#!/usr/bin/env bash
# Whole-process batch throughput on the shared real clouds, side by side, two ways:
# - one process per file: `esf describe --threads 1 FILE` against `pcl_esf_describe FILE` (PCL's
#   loadPCDFile + ESFEstimation), alternating file by file;
# - one process for all files, as `xargs` runs a batch: `esf describe --threads 1 FILE...`
#   against `pcl_esf_describe FILE...`, five alternating rounds, best of each side.
# Every process reads its files, describes them and prints one CSV line per file, so start-up,
# reading and describing all count. Ends with "ratio per file: X" and "ratio: X" (the batch as
# xargs runs it), each PCL time / esf time.
#
# usage: bench/cloud_io_batch.sh [BUILD_DIR] [MAX_FILES] [SUBDIR]   (defaults: build, 200, real)
# The clouds are $ESF_DATA/SUBDIR/**/*.pcd (ESF_DATA defaults to ../shared/data beside the
# repository); SUBDIR real/objects takes the segmented object views only, real/scenes the
# 640 x 480 scenes.
set -euo pipefail

bench_name=cloud_io_batch
source "$(dirname "${BASH_SOURCE[0]}")/bench_env.sh"
max_files="${2:-200}"
subdir="${3:-real}"
require_tools "$esf" "$pcl"
require_data "$data/$subdir"

mapfile -t files < <(find "$data/$subdir" -name '*.pcd' -type f | sort | head -n "$max_files")
[[ ${#files[@]} -gt 0 ]] || { echo "cloud_io_batch: no .pcd files under $data/$subdir" >&2; exit 1; }

# Warm the page cache so that both sides read from memory.
cat "${files[@]}" > /dev/null

# One process per file, ours and PCL's alternating (and swapping which goes first) so that both
# meet the same machine load (times by us(), bench_env.sh).
esf_us=0
pcl_us=0
for i in "${!files[@]}"; do
    f="${files[$i]}"
    for side in $((i % 2)) $((1 - i % 2)); do
        t0=$EPOCHREALTIME
        if [[ $side == 0 ]]; then
            "$esf" describe --threads 1 "$f" > /dev/null
            t1=$EPOCHREALTIME
            us "$t1"; end=$REPLY; us "$t0"
            esf_us=$((esf_us + end - REPLY))
        else
            "$pcl" "$f" > /dev/null
            t1=$EPOCHREALTIME
            us "$t1"; end=$REPLY; us "$t0"
            pcl_us=$((pcl_us + end - REPLY))
        fi
    done
done
# All files in one process on each side (the `xargs` batch), five alternating rounds: a batch of
# ours takes a twentieth of PCL's, so on a shared machine one burst of load can cover three.
one_us=0
pcl_one_us=0
for round in 0 1 2 3 4; do
    for side in $((round % 2)) $((1 - round % 2)); do
        t0=$EPOCHREALTIME
        if [[ $side == 0 ]]; then
            "$esf" describe --threads 1 "${files[@]}" > /dev/null
        else
            "$pcl" "${files[@]}" > /dev/null
        fi
        t1=$EPOCHREALTIME
        us "$t1"; end=$REPLY; us "$t0"; took=$((end - REPLY))
        if [[ $side == 0 ]]; then
            ((one_us == 0 || took < one_us)) && one_us=$took
        else
            ((pcl_one_us == 0 || took < pcl_one_us)) && pcl_one_us=$took
        fi
    done
done

n=${#files[@]}
printf 'files: %d (%s)\n' "$n" "$data/$subdir"
awk -v n="$n" -v e="$esf_us" -v p="$pcl_us" -v o="$one_us" -v q="$pcl_one_us" 'BEGIN {
    e /= 1e6; p /= 1e6; o /= 1e6; q /= 1e6
    printf "esf describe --threads 1 FILE, one process per file: %.3f s, %.1f files/s\n", e, n / e
    printf "pcl_esf_describe FILE, one process per file:         %.3f s, %.1f files/s\n", p, n / p
    printf "ratio per file: %.2f\n", p / e
    printf "esf describe --threads 1 FILE..., one process:       %.3f s, %.1f files/s\n", o, n / o
    printf "pcl_esf_describe FILE..., one process:               %.3f s, %.1f files/s\n", q, n / q
    printf "ratio: %.2f\n", q / o
}'
