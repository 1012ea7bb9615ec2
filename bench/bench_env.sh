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
