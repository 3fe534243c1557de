#!/usr/bin/env bash
# Installs a built vobb into a fresh prefix, builds tests/install/consumer against it through
# find_package(vobb), runs it, and checks that the installed `vobb certify` gives the consumer's
# exact e for the tree it wrote (the same rational, compared as text). Fails when the installed
# CMake files or headers refer back into the source or build tree (the archives may: __FILE__).
#   install_test.sh BUILD_DIR CONSUMER_SOURCE_DIR PROJECT_SOURCE_DIR
set -euo pipefail
build=$(cd "$1" && pwd)
consumer=$2
source_dir=$(cd "$3" && pwd)
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT

cmake --install "$build" --prefix "$work/prefix" >"$work/install.log"
if grep -rlF -e "$source_dir" -e "$build" "$work/prefix/lib/cmake" "$work/prefix/include"; then
  echo "install_test: the installed files above name the source or build tree" >&2
  exit 1
fi
cmake -S "$consumer" -B "$work/build" -G Ninja -DCMAKE_BUILD_TYPE=Release \
      -DCMAKE_PREFIX_PATH="$work/prefix" >"$work/configure.log" || { cat "$work/configure.log" >&2; exit 1; }
cmake --build "$work/build" >"$work/build.log" || { cat "$work/build.log" >&2; exit 1; }

mkdir "$work/run"
"$work/build/vobb_consumer" "$work/run" >"$work/consumer.txt"
e_lib=$(sed -n 's/^e //p' "$work/consumer.txt")
"$work/prefix/bin/vobb" certify "$work/run/torus.off" "$work/run/tree.json" --json --rational --quiet >"$work/cert.json"
e_cli=$(grep -o '"weighted_error_rational": *"[^"]*"' "$work/cert.json" | sed 's/.*: *"//; s/"$//')
if [ -z "$e_lib" ] || [ "$e_lib" != "$e_cli" ]; then
  echo "install_test: e from the library (${e_lib:0:40}...) != e from the installed vobb (${e_cli:0:40}...)" >&2
  exit 1
fi
echo "install_test: consumer built and ran against $work/prefix; e agrees (${#e_lib} characters)"
