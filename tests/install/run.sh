#!/usr/bin/env bash
# install/find_package: `cmake --install` the build into a temporary prefix, then configure, build
# and run a separate project that finds it with find_package(tactus). Usage: run.sh BUILD_DIR
set -euo pipefail
BUILD=$1
HERE=$(cd "$(dirname "$0")" && pwd)
WORK=$(mktemp -d)
trap 'rm -rf "$WORK"' EXIT
cmake --install "$BUILD" --prefix "$WORK/prefix" > "$WORK/install.log"
test -x "$WORK/prefix/bin/tactus-solve"
test -x "$WORK/prefix/bin/tactus-sample-mesh"
test -x "$WORK/prefix/bin/tactus-post"
test -x "$WORK/prefix/bin/tactus-pipeline"
cmake -S "$HERE" -B "$WORK/consumer" -G Ninja -DCMAKE_BUILD_TYPE=Release -DCMAKE_PREFIX_PATH="$WORK/prefix" > "$WORK/configure.log"
cmake --build "$WORK/consumer" > "$WORK/build.log"
"$WORK/consumer/consumer"
