# Shared by scripts/test and scripts/demo (sourced, not run): the Debian packages the
# project needs, and ensure_packages, which installs the missing ones.
#
# Keep this the ONE list of system dependencies. Eigen is the core library's only
# dependency, urdfdom that of the optional URDF reader; the rest serve the tests
# (GoogleTest, Orocos KDL and kdl_parser as references), benchmarks, examples (Box2D,
# MuJoCo, JSON, CLI11), plots (gnuplot), the robustness stages (valgrind, clang with
# libFuzzer) and the build itself.

INHAND_PACKAGES=(
  # build tools
  cmake
  g++
  make
  ninja-build
  pkg-config
  # the library
  libeigen3-dev
  # tests and benchmarks
  libgtest-dev
  googletest
  libbenchmark-dev
  liborocos-kdl-dev
  # examples and demos
  libbox2d-dev
  nlohmann-json3-dev
  libcli11-dev
  gnuplot-nox
  # MuJoCo (examples/mujoco, tests/mujoco): its CMake config needs OpenGL (libgl-dev,
  # libopengl-dev) and names the qhull headers' folder (libqhull-dev) as an include path
  libmujoco-dev
  libqhull-dev
  libgl-dev
  libopengl-dev
  # the URDF reader (inhand::urdf) and its tests (tests/urdf: KDL reading the same files)
  liburdfdom-dev
  libkdl-parser-dev
  # scripts/variants and scripts/gen_paper_scenarios.py, and the tests that run them
  python3
  # robustness stages of scripts/test and scripts/fuzz: memcheck, clang + libFuzzer
  valgrind
  clang-14
  libclang-rt-14-dev
)

# The CMake generator arguments for build directory DIR, one per line: "-G Ninja" for a new
# directory when ninja is installed and CMAKE_GENERATOR does not name another; nothing for
# a directory already configured (CMake refuses to change its generator) or without ninja
# (CMake's default, Makefiles). Ninja's single build graph compiles a target's files while
# the libraries it links are still being built; the Makefiles build target after target,
# so every test file waited for the shared test instances (docs/building.md).
# Use: mapfile -t gen < <(inhand_generator_args "$dir"); cmake "${gen[@]}" -S ...
inhand_generator_args() {
  local dir=$1
  if [[ -z ${CMAKE_GENERATOR:-} && ! -f $dir/CMakeCache.txt ]] && command -v ninja >/dev/null 2>&1; then
    printf '%s\n' -G Ninja
  fi
}

# Prints the packages of INHAND_PACKAGES that are not installed, one per line.
inhand_missing_packages() {
  local pkg status
  for pkg in "${INHAND_PACKAGES[@]}"; do
    status=$(dpkg-query -W -f='${Status}' "$pkg" 2>/dev/null || true)
    if [[ "$status" != "install ok installed" ]]; then
      echo "$pkg"
    fi
  done
}

# Installs whatever is missing (as root), or prints the command to run and returns 1.
ensure_packages() {
  if ! command -v dpkg-query >/dev/null 2>&1; then
    echo "ensure_packages: dpkg-query not found; this script expects Debian or Ubuntu." >&2
    echo "Install the equivalents of: ${INHAND_PACKAGES[*]}" >&2
    return 1
  fi
  local missing
  mapfile -t missing < <(inhand_missing_packages)
  if [[ ${#missing[@]} -eq 0 ]]; then
    return 0
  fi
  echo "Missing packages: ${missing[*]}"
  if [[ $(id -u) -ne 0 ]]; then
    echo "Run as root, or install them with:" >&2
    echo "  sudo apt-get install -y --no-install-recommends ${missing[*]}" >&2
    return 1
  fi
  export DEBIAN_FRONTEND=noninteractive
  apt-get update
  apt-get install -y --no-install-recommends "${missing[@]}"
}
