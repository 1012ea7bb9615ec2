#!/usr/bin/env bash
# The speed figures that BENCHMARKS.md keeps per CPU, in one run on the machine at hand:
# - start-up: `esf --version` against `pcl_esf_describe` printing its usage line;
# - in-process ESF: build/bench/esf_bench_descriptor on milk_test.pcd and the 116 object views,
#   with the default kernels and with --kernels avx2 (what a CPU without AVX-512 runs);
# - whole processes: bench/cloud_io_batch.sh over all real clouds, the object views and the
#   scenes (`ratio:` is the batch as xargs runs it, one process per side).
# Ends with a Markdown table of the ratios (PCL time / esf time) under the CPU's name. Takes
# one to three minutes; run it on an idle machine.
#
# usage: bench/speed_summary.sh [BUILD_DIR]   (default: build; ESF_DATA as for cloud_io_batch.sh)
set -euo pipefail

bench_name=speed_summary
source "$(dirname "${BASH_SOURCE[0]}")/bench_env.sh"
bench="$build/bench/esf_bench_descriptor"
require_tools "$esf" "$pcl" "$bench"
require_data "$data/real/objects"

cpu="$(lscpu 2>/dev/null | sed -n 's/^Model name: *//p' | head -n 1)"
echo "cpu: ${cpu:-unknown}"

# Mean wall time of a command over N runs, in ms, without a subshell per run.
mean_ms() {
    local runs=$1
    shift
    local t0 t1 start
    t0=$EPOCHREALTIME
    for ((r = 0; r < runs; ++r)); do "$@" > /dev/null 2>&1 || true; done
    t1=$EPOCHREALTIME
    us "$t0"; start=$REPLY; us "$t1"
    REPLY=$(awk -v a="$start" -v b="$REPLY" -v n="$runs" 'BEGIN { printf "%.2f", (b - a) / n / 1e3 }')
}
"$esf" --version > /dev/null
"$pcl" > /dev/null 2>&1 || true
mean_ms 100 "$esf" --version
esf_start=$REPLY
mean_ms 20 "$pcl"
pcl_start=$REPLY
echo "start-up: esf --version $esf_start ms, pcl_esf_describe (usage) $pcl_start ms"

# The last "ratio: X" line of a command's output.
ratio_of() { "$@" 2>&1 | tee -a /dev/stderr | sed -n 's/^ratio: //p' | tail -n 1; }
clouds=("$data/real/pcl/milk_test.pcd" "$data"/real/objects/*.pcd)
in_best=$(ratio_of "$bench" "${clouds[@]}")
in_avx2=$(ratio_of "$bench" --kernels avx2 "${clouds[@]}")
batch_all=$(ratio_of "$root/bench/cloud_io_batch.sh" "$build" 200 real)
batch_objects=$(ratio_of "$root/bench/cloud_io_batch.sh" "$build" 200 real/objects)
batch_scenes=$(ratio_of "$root/bench/cloud_io_batch.sh" "$build" 200 real/scenes)

cat << EOF

| ${cpu:-this CPU} | figure |
|---|---|
| start-up: \`esf --version\` / \`pcl_esf_describe\` usage | $esf_start / $pcl_start ms |
| in-process ESF, default kernels | **${in_best}x** |
| in-process ESF, \`--kernels avx2\` | ${in_avx2}x |
| whole process, all real clouds | **${batch_all}x** |
| whole process, \`real/objects\` | ${batch_objects}x |
| whole process, \`real/scenes\` | ${batch_scenes}x |
EOF
