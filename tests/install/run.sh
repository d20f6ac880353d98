#!/usr/bin/env bash
# install/find_package: `cmake --install` the build into a temporary prefix, then configure, build
# and run a separate project that finds it with find_package(tactus). Usage: run.sh BUILD_DIR
set -euo pipefail
BUILD=$1
HERE=$(cd "$(dirname "$0")" && pwd)
WORK=$(mktemp -d)
trap 'rm -rf "$WORK"' EXIT
# On failure, show the log of the step that failed.
trap 'for l in install configure build; do [ -f "$WORK/$l.log" ] && tail -20 "$WORK/$l.log"; done; rm -rf "$WORK"' ERR
# A sanitizer build's libraries need the sanitizer runtime in the consumer too.
FLAGS=""
grep -q "TACTUS_SANITIZE:BOOL=ON" "$BUILD/CMakeCache.txt" && FLAGS="-fsanitize=address,undefined"
cmake --install "$BUILD" --prefix "$WORK/prefix" > "$WORK/install.log"
test -x "$WORK/prefix/bin/tactus-solve"
test -x "$WORK/prefix/bin/tactus-sample-mesh"
test -x "$WORK/prefix/bin/tactus-post"
test -x "$WORK/prefix/bin/tactus-pipeline"
cmake -S "$HERE" -B "$WORK/consumer" -G Ninja -DCMAKE_BUILD_TYPE=Release -DCMAKE_PREFIX_PATH="$WORK/prefix" \
  -DCMAKE_CXX_FLAGS="$FLAGS" -DCMAKE_EXE_LINKER_FLAGS="$FLAGS" > "$WORK/configure.log"
cmake --build "$WORK/consumer" > "$WORK/build.log"
"$WORK/consumer/consumer"
