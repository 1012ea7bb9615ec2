#!/usr/bin/env bash
# The README's two set-up commands, for a fresh Debian 12 machine:
#   scripts/run.sh demo   installs missing packages, builds esf, runs `esf demo` (generated data)
#   scripts/run.sh test   installs missing packages, builds everything with warnings as errors and
#                         runs the whole test suite (ctest); CI runs exactly this
# Further arguments go to `esf demo` (e.g. scripts/run.sh demo --seed 3).
set -euo pipefail
cd "$(dirname "$0")/.."
target="${1:-}"
case "$target" in
    demo | test) shift ;;
    *)
        echo "usage: scripts/run.sh demo|test [esf demo options]" >&2
        exit 1
        ;;
esac
scripts/install-deps.sh
if [ "$target" = demo ]; then
    make --no-print-directory demo DEMO_ARGS="$*"
else
    make --no-print-directory test WERROR=ON
fi
