# Sourced by the bench/ scripts that run the esf and PCL programs side by side: where the
# repository, the build and the data are, and the shared checks and timing helper.
# Expects $1 of the sourcing script as the build folder (default: build) and the script's name
# in $bench_name for its messages.

root="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
build="${1:-$root/build}"
data="${ESF_DATA:-$root/../shared/data}"
esf="$build/apps/esf/esf"
pcl="$build/bench/pcl_esf_describe"

# Stops with a message unless every argument is an executable built in $build.
require_tools() {
    local tool
    for tool in "$@"; do
        [[ -x "$tool" ]] || { echo "$bench_name: missing $tool (cmake --build $build)" >&2; exit 1; }
    done
}

# Sets $work to the folder $1 (created when missing), or to a new temporary folder removed when
# the script ends when $1 is empty.
use_work_dir() {
    work="$1"
    if [[ -z "$work" ]]; then
        work="$(mktemp -d)"
        trap 'rm -rf "$work"' EXIT
    fi
    mkdir -p "$work"
}

# Stops with a message unless the folder $1 exists.
require_data() {
    [[ -d "$1" ]] || { echo "$bench_name: no $1 (set ESF_DATA)" >&2; exit 1; }
}

# $EPOCHREALTIME (bash 5) as whole microseconds in REPLY. Times are read into variables: a
# command substitution would fork a subshell, whose cost would be counted on both sides.
us() { REPLY=$((10#${1/./})); }

# Adds $2 generated wide tins to the database $1 as can models, as the README's database holds
# them (`esf generate --categories can --per-class N --seed 1`, made once in $work/cans$2; then
# `esf train` resumes $1 with them and the shared meshes' catalog). Further arguments are the
# database's `esf train` options, which a resumed database must be given again. 0 tins: nothing.
add_generated_cans() {
    local db="$1" count="$2"
    shift 2
    [[ "$count" =~ ^[0-9]+$ ]] || { echo "$bench_name: '$count' tins is not a count" >&2; exit 1; }
    ((count > 0)) || return 0
    local tins="$work/cans$count"
    if [[ ! -f "$tins/generate.json" ]]; then
        "$esf" generate --categories can --per-class "$count" --seed 1 -o "$tins" --json \
            > "$tins.json"
        mv "$tins.json" "$tins/generate.json"
    fi
    "$esf" train "$tins" -o "$db" --catalog "$data/meshes/catalog.csv" "$@" --json > /dev/null
}
