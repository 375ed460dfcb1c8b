# Debian packages that building, testing and running ctxfuse need: the one list, sourced by
# scripts/test.sh and scripts/demo.sh (and so by .ci/run).
#
# ctxfuse_ensure_deps: when a package is missing, installs the missing ones as root
# (apt-get update once, then apt-get install -y); otherwise prints the exact apt line and
# returns 1. When all are installed it touches no network. CTXFUSE_SKIP_DEPS=1 skips the check
# (e.g. on a non-Debian machine with the tools installed another way).

CTXFUSE_DEBIAN_PACKAGES=(
  cmake ninja-build g++ clang
  libeigen3-dev libboost-dev libgtest-dev libbenchmark-dev
  libsvm-dev libsvm-tools libceres-dev gnuplot-nox
  libcli11-dev nlohmann-json3-dev
  libclang-rt-14-dev  # clang's sanitizer and libFuzzer runtimes (scripts/fuzz.sh)
)

ctxfuse_missing_packages() {
  local pkg
  for pkg in "${CTXFUSE_DEBIAN_PACKAGES[@]}"; do
    if ! dpkg-query -W -f='${Status}' "$pkg" 2>/dev/null | grep -q 'install ok installed'; then
      printf '%s\n' "$pkg"
    fi
  done
}

ctxfuse_ensure_deps() {
  if [[ "${CTXFUSE_SKIP_DEPS:-0}" == 1 ]]; then
    return 0
  fi
  if ! command -v dpkg-query >/dev/null 2>&1; then
    echo "note: dpkg-query not found (not Debian?); not checking packages. Needed: ${CTXFUSE_DEBIAN_PACKAGES[*]}" >&2
    return 0
  fi
  local missing
  mapfile -t missing < <(ctxfuse_missing_packages)
  if ((${#missing[@]} == 0)); then
    return 0
  fi
  if [[ "$(id -u)" == 0 ]]; then
    echo "installing missing packages: ${missing[*]}" >&2
    export DEBIAN_FRONTEND=noninteractive
    apt-get update && apt-get install -y --no-install-recommends "${missing[@]}"
  else
    echo "missing Debian packages: ${missing[*]}" >&2
    echo "install them with:" >&2
    echo "  sudo apt-get update && sudo apt-get install -y --no-install-recommends ${missing[*]}" >&2
    echo "(or set CTXFUSE_SKIP_DEPS=1 to try anyway)" >&2
    return 1
  fi
}

# Parallel jobs for builds and ctest: every core of the machine.
ctxfuse_jobs() {
  nproc 2>/dev/null || echo 2
}

# Configures a preset from the repository root. ctest hands tests the CTXFUSE_DATA_DIR cache
# entry, not the caller's environment, so an explicit setting must reach the cache.
ctxfuse_configure() {
  local preset="$1"
  local args=(--preset "$preset")
  if [[ -n "${CTXFUSE_DATA_DIR:-}" ]]; then
    args+=("-DCTXFUSE_DATA_DIR=$CTXFUSE_DATA_DIR")
  fi
  cmake "${args[@]}"
}
