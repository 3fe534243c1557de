#!/usr/bin/env bash
# Installs a built vobb into a fresh prefix and builds two projects against it through
# find_package(vobb):
# - core_consumer, configured with OpenGL/EGL, FCL, PNG, assimp and nlohmann-json hidden from
#   CMake (CMAKE_DISABLE_FIND_PACKAGE_<Name>) and ODE hidden from pkg-config (an empty
#   PKG_CONFIG_LIBDIR: ODE has no CMake package, and CMake's FindOpenSSL needs pkg-config
#   itself), so that it can only succeed if the core needs none of them. It builds and certifies a tree; the installed `vobb build` must write the same bytes
#   for the same options and `vobb certify` the same exact e (rationals compared as text).
# - README.md's C++ example, built the same way (it is not run: it reads dino).
# - full_consumer, with every component (GL, collision, assimp), which checks their results.
# Fails when the installed CMake files or headers refer back into the source or build tree.
#   install_test.sh BUILD_DIR TESTS_INSTALL_DIR PROJECT_SOURCE_DIR
set -euo pipefail
build=$(cd "$1" && pwd)
here=$2
source_dir=$(cd "$3" && pwd)
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT

cmake --install "$build" --prefix "$work/prefix" >"$work/install.log"
if grep -rlF -e "$source_dir" -e "$build" "$work/prefix/lib/cmake" "$work/prefix/include"; then
  echo "install_test: the installed files above name the source or build tree" >&2
  exit 1
fi
configure() {  # configure NAME [cmake args...]
  local name=$1
  shift
  cmake -S "$work/src/$name" -B "$work/$name" -G Ninja -DCMAKE_BUILD_TYPE=Release -DCMAKE_PREFIX_PATH="$work/prefix" \
        "$@" >"$work/$name.configure.log" 2>&1 || { cat "$work/$name.configure.log" >&2; exit 1; }
  cmake --build "$work/$name" >"$work/$name.build.log" 2>&1 || { cat "$work/$name.build.log" >&2; exit 1; }
}
mkdir "$work/src"
cp -r "$here/core_consumer" "$here/full_consumer" "$here/readme_example" "$work/src/"
sed -n '/^```cpp$/,/^```$/p' "$source_dir/README.md" | sed '1d;$d' >"$work/src/readme_example/main.cpp"
[ -s "$work/src/readme_example/main.cpp" ] || { echo "install_test: README.md has no C++ example" >&2; exit 1; }
hidden=()
for pkg in OpenGL fcl PNG assimp nlohmann_json; do hidden+=("-DCMAKE_DISABLE_FIND_PACKAGE_$pkg=ON"); done
mkdir "$work/no-pkg-config"
PKG_CONFIG_LIBDIR="$work/no-pkg-config" PKG_CONFIG_PATH= configure core_consumer "${hidden[@]}"
PKG_CONFIG_LIBDIR="$work/no-pkg-config" PKG_CONFIG_PATH= configure readme_example "${hidden[@]}"
configure full_consumer

mkdir "$work/run"
"$work/prefix/bin/vobb-make-analytic" "$work/run" >/dev/null
mesh="$work/run/polygonal_torus.off"
"$work/core_consumer/vobb_core_consumer" "$mesh" "$work/run/lib_tree.json" >"$work/core.txt"
e_lib=$(sed -n 's/^e //p' "$work/core.txt")
"$work/prefix/bin/vobb" build "$mesh" -o "$work/run/cli_tree.json" --depth 4 --m 8 --quiet 2>/dev/null
if ! cmp -s "$work/run/lib_tree.json" "$work/run/cli_tree.json"; then
  echo "install_test: the library's tree differs from the installed vobb build's" >&2
  exit 1
fi
"$work/prefix/bin/vobb" certify "$mesh" "$work/run/lib_tree.json" --json --rational --quiet >"$work/cert.json"
e_cli=$(grep -o '"weighted_error_rational": *"[^"]*"' "$work/cert.json" | sed 's/.*: *"//; s/"$//')
if [ -z "$e_lib" ] || [ "$e_lib" != "$e_cli" ]; then
  echo "install_test: e from the library (${e_lib:0:40}...) != e from the installed vobb (${e_cli:0:40}...)" >&2
  exit 1
fi
"$work/full_consumer/vobb_full_consumer" "$mesh" "$work/run/lib_tree.json" "$work/run/figure.png"
echo "install_test: both consumers built and ran against $work/prefix; tree and e agree (${#e_lib} characters)"
