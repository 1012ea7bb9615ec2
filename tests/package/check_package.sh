#!/usr/bin/env bash
# Installs a built esf into a temporary prefix and builds and runs tests/package/consumer
# against it with find_package(esf 0.1); also checks that the version file refuses esf 9.
#   tests/package/check_package.sh BUILD_DIR [CXX_FLAGS [LINKER_FLAGS]]
# CXX_FLAGS, LINKER_FLAGS: how BUILD_DIR compiled and linked its programs, for the consumer to do
# the same (the static libraries of a sanitizer build need the sanitizer runtimes); empty for a
# plain build.
set -euo pipefail
build=$(cd "$1" && pwd)
source_dir=$(cd "$(dirname "$0")/../.." && pwd)
cxx_flags="${2:-}"
linker_flags="${3:-}"
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
cmake --install "$build" --prefix "$work/prefix" > "$work/install.log"
test -x "$work/prefix/bin/esf" || { echo "check_package: esf not installed" >&2; exit 1; }
test -f "$work/prefix/lib/cmake/esf/esfConfigVersion.cmake" ||
    { echo "check_package: no esfConfigVersion.cmake" >&2; exit 1; }
"$work/prefix/bin/esf" --version
test -x "$work/prefix/lib/esf/esf_mesh_import" ||
    { echo "check_package: the mesh importer esf_mesh_import is not installed" >&2; exit 1; }
cmake -S "$source_dir/tests/package/consumer" -B "$work/consumer" -DCMAKE_BUILD_TYPE=Release \
    -DCMAKE_PREFIX_PATH="$work/prefix" -DCMAKE_CXX_FLAGS="$cxx_flags" \
    -DCMAKE_EXE_LINKER_FLAGS="$linker_flags" \
    > "$work/configure.log" ||
    { cat "$work/configure.log" >&2; exit 1; }
cmake --build "$work/consumer" > "$work/build.log" || { cat "$work/build.log" >&2; exit 1; }
# The installed mesh importer, not the build tree's (which the library also knows).
ESF_MESH_IMPORTER="$work/prefix/lib/esf/esf_mesh_import" "$work/consumer/consumer" "$work"
# A version the package is not: find_package must fail.
mkdir -p "$work/too_new"
sed 's/find_package(esf 0.1 REQUIRED)/find_package(esf 9.0 REQUIRED)/' \
    "$source_dir/tests/package/consumer/CMakeLists.txt" > "$work/too_new/CMakeLists.txt"
cp "$source_dir/tests/package/consumer/consumer.cpp" "$work/too_new/"
if cmake -S "$work/too_new" -B "$work/too_new/build" -DCMAKE_PREFIX_PATH="$work/prefix" \
        > "$work/too_new.log" 2>&1; then
    echo "check_package: find_package(esf 9.0) succeeded against esf $(\
"$work/prefix/bin/esf" --version)" >&2
    exit 1
fi
echo "check_package: ok (find_package(esf 9.0) refused)"
