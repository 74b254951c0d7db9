# shellcheck shell=bash
# Shared helpers of scripts/test.sh and scripts/run.sh (sourced, not run).
# Everything is idempotent: packages are installed only when missing, builds are incremental.
#
# Environment:
#   KNOTFLOW_JOBS      parallel build/test jobs (default 2)
#   KNOTFLOW_PYTHON    Python interpreter to use (default: python3 on PATH)
#   KNOTFLOW_NO_INSTALL=1  never install anything (only check and report what is missing)
#   KNOTFLOW_NO_OPTIONAL=1 skip the optional system packages (ffmpeg, chromium, SLURM, shellcheck)
#   KNOTFLOW_NO_APT=1  the compilers and libraries come from environment modules (or elsewhere):
#                      never call dpkg or apt-get, only check that the tools are on PATH
#   KNOTFLOW_BUILD_DIR the Release build directory of build.sh and reproduce.sh, and the home of
#                      the Python virtual environment (<dir>/venv); default build

KF_ROOT="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
KF_JOBS="${KNOTFLOW_JOBS:-2}"
KF_BUILD_DIR="${KNOTFLOW_BUILD_DIR:-$KF_ROOT/build}"
case "$KF_BUILD_DIR" in /*) ;; *) KF_BUILD_DIR="$KF_ROOT/$KF_BUILD_DIR" ;; esac
export DEBIAN_FRONTEND=noninteractive
# One thread per MPI rank: every rank runs one serial case, and idle OpenBLAS threads spin
# (sched_yield) and steal the cores the other ranks need. Set them yourself to override.
export OPENBLAS_NUM_THREADS="${OPENBLAS_NUM_THREADS:-1}" OMP_NUM_THREADS="${OMP_NUM_THREADS:-1}"
# OpenBLAS's kernels chosen by the CPU's instruction sets unless OPENBLAS_CORETYPE is set.
# shellcheck source=scripts/blas_env.sh
source "$KF_ROOT/scripts/blas_env.sh"
kf_openblas_environment

kf_log() { printf '==> %s\n' "$*"; }
kf_die() { printf 'ERROR: %s\n' "$*" >&2; exit 1; }

# Run a command as root (directly, or through non-interactive sudo).
kf_as_root() {
  if [ "$(id -u)" -eq 0 ]; then
    "$@"
  elif command -v sudo >/dev/null 2>&1 && sudo -n true 2>/dev/null; then
    sudo -n "$@"
  else
    return 1
  fi
}

# System packages (Debian 12 names).  Installed with apt-get only when dpkg says missing.
KF_APT_PACKAGES=(gcc gfortran cmake make git pkg-config openssh-client libopenmpi-dev openmpi-bin libhdf5-dev
                 libopenblas-dev liblapack-dev libfftw3-dev python3 python3-pip python3-venv)

# Optional system packages: ffmpeg (MP4 movies; without it GIFs), chromium (the browser test
# of the report's 3-D viewer), a single-node SLURM with munge (the scheduler test of the job
# scripts, tests/jobs, whose jobs run as another user: their Python tools use the system's
# numpy, h5py and matplotlib), shellcheck (the lint tests) and strace (the kill-at-every-write
# test; without it only random kills); those tests are skipped without them. Installed when
# missing; a failure is only a warning.
KF_APT_OPTIONAL=(ffmpeg chromium munge slurmctld slurmd slurm-client python3-numpy python3-h5py
                 python3-matplotlib python3-setuptools shellcheck strace)

kf_ensure_optional_packages() {
  [ "${KNOTFLOW_NO_OPTIONAL:-0}" = 1 ] && return 0
  command -v dpkg >/dev/null 2>&1 || return 0
  [ "${KNOTFLOW_NO_APT:-0}" = 1 ] && return 0
  local missing=() pkg
  for pkg in "${KF_APT_OPTIONAL[@]}"; do
    dpkg -s "$pkg" >/dev/null 2>&1 || missing+=("$pkg")
  done
  [ "${#missing[@]}" -eq 0 ] && return 0
  if [ "${KNOTFLOW_NO_INSTALL:-0}" = 1 ]; then
    kf_log "optional packages missing (movies as GIF, browser test skipped): ${missing[*]}"
    return 0
  fi
  kf_log "installing optional packages: ${missing[*]}"
  { kf_as_root apt-get update -q </dev/null \
      && kf_as_root apt-get install -y -q --no-install-recommends "${missing[@]}" </dev/null; } \
    || kf_log "WARNING: could not install ${missing[*]} (movies as GIF; browser, SLURM, lint tests skipped)"
  return 0
}

kf_ensure_system_packages() {
  if [ "${KNOTFLOW_NO_APT:-0}" = 1 ] || ! command -v dpkg >/dev/null 2>&1; then
    kf_log "KNOTFLOW_NO_APT=1 or no dpkg: no system packages installed; checking the tools instead"
    local tool
    for tool in gfortran cmake make mpirun python3; do
      command -v "$tool" >/dev/null 2>&1 || kf_die "'$tool' not found; install it first"
    done
    return 0
  fi
  local missing=() pkg
  for pkg in "${KF_APT_PACKAGES[@]}"; do
    dpkg -s "$pkg" >/dev/null 2>&1 || missing+=("$pkg")
  done
  if [ "${#missing[@]}" -eq 0 ]; then
    kf_log "system packages: all present"
    kf_ensure_optional_packages
    return 0
  fi
  [ "${KNOTFLOW_NO_INSTALL:-0}" = 1 ] && kf_die "missing system packages: ${missing[*]}"
  kf_log "installing system packages: ${missing[*]}"
  kf_as_root apt-get update -q </dev/null \
    || kf_die "apt-get update failed (need root or passwordless sudo); missing: ${missing[*]}"
  kf_as_root apt-get install -y -q --no-install-recommends "${missing[@]}" </dev/null \
    || kf_die "apt-get install failed for: ${missing[*]}"
  kf_ensure_optional_packages
}

# Python: the tools package (tools/pyproject.toml, editable, with its [test] extra and its
# [fortran] extra: fypp, which the build needs, findent and FORD) or, before
# it exists, numpy h5py matplotlib pytest.  Installs go into a virtual environment of this
# checkout, build/venv, isolated from the system's site-packages: every package the tools use
# comes from PyPI with the versions of tools/constraints.txt, never from the base Python (whose
# packages, e.g. Debian's python3-matplotlib installed for the scheduler jobs, would shadow the
# pinned ones: its mpl_toolkits broke the pinned matplotlib's 3-D axes).  Nothing is installed
# into the base Python (which may be shared with other checkouts, or refuse pip installs under
# PEP 668 as Debian's /usr/bin/python3 does).  A venv made by an older knotflow with
# --system-site-packages (pyvenv.cfg: include-system-site-packages = true) is made again.
# The venv is made from an interpreter every user can run (its executable and standard library
# readable by others), so that the tools in build/venv also run for other users (e.g. the jobs of
# a scheduler): python3 on PATH when it is such an interpreter, else /usr/bin/python3 (>= 3.11)
# when it is, else python3 on PATH with a warning.  KNOTFLOW_PYTHON chooses it outright.
# An interpreter that already runs inside a virtual environment is used as it is.
# Sets KF_PY to the interpreter to use and puts its bin/ first on PATH.

# The Python requirement of the tools (requires-python = ">=3.11" in tools/pyproject.toml).
KF_PYTHON_MIN="3.11"

# kf_python_shared PY: exit status 0 when PY's executable and standard library can be read and
# run by every user (every directory above them searchable by others), 1 otherwise.
kf_python_shared() {
  "$1" - <<'PY' 2>/dev/null
import os, stat, sys, sysconfig

def shared(path):
    path = os.path.realpath(path)
    if not os.stat(path).st_mode & stat.S_IROTH:
        return False
    d = path if os.path.isdir(path) else os.path.dirname(path)
    while True:
        if not os.stat(d).st_mode & stat.S_IXOTH:
            return False
        if d == os.path.dirname(d):
            return True
        d = os.path.dirname(d)

sys.exit(0 if shared(sys.executable) and shared(sysconfig.get_paths()["stdlib"]) else 1)
PY
}

# kf_python_version_ok PY: exit status 0 when PY is at least KF_PYTHON_MIN.
kf_python_version_ok() {
  "$1" -c "import sys; sys.exit(0 if sys.version_info >= tuple(map(int, '$KF_PYTHON_MIN'.split('.'))) else 1)" 2>/dev/null
}

# kf_venv_base PY: the interpreter to make the venv from (see above); printed.
kf_venv_base() {
  local py="$1" real
  if [ -n "${KNOTFLOW_PYTHON:-}" ] || kf_python_shared "$py"; then
    printf '%s\n' "$py"
    return 0
  fi
  real="$("$py" -c 'import sys; print(sys.executable)' 2>/dev/null || printf '%s' "$py")"
  if [ -x /usr/bin/python3 ] && kf_python_version_ok /usr/bin/python3 && kf_python_shared /usr/bin/python3; then
    kf_log "python: $real cannot be run by other users; the venv is made from /usr/bin/python3" >&2
    printf '%s\n' /usr/bin/python3
  else
    kf_log "WARNING: python: $real cannot be run by other users: neither can the tools in the venv" >&2
    printf '%s\n' "$py"
  fi
}

kf_ensure_python() {
  local py="${KNOTFLOW_PYTHON:-python3}"
  command -v "$py" >/dev/null 2>&1 || kf_die "python interpreter '$py' not found"
  py="$(command -v "$py")"
  local in_venv venv="$KF_BUILD_DIR/venv" base
  in_venv="$("$py" -c 'import sys; print(int(sys.prefix != sys.base_prefix))')" \
    || kf_die "cannot run $py"
  # this checkout's own venv (activated in the shell) is checked like any other time
  if [ "$in_venv" = 1 ] && [ -d "$venv" ] \
     && [ "$("$py" -c 'import os, sys; print(os.path.realpath(sys.prefix))')" = "$(cd "$venv" && pwd -P)" ]; then
    py="$("$py" -c 'import sys; print(getattr(sys, "_base_executable", "") or sys.executable)')"
    in_venv=0
  fi
  if [ "$in_venv" = 0 ]; then
    if [ -f "$venv/pyvenv.cfg" ] \
       && grep -qiE '^[[:space:]]*include-system-site-packages[[:space:]]*=[[:space:]]*true' "$venv/pyvenv.cfg"; then
      [ "${KNOTFLOW_NO_INSTALL:-0}" = 1 ] \
        && kf_die "the virtual environment $venv sees the system's site-packages (made by an older knotflow); run without KNOTFLOW_NO_INSTALL=1 to make it again"
      kf_log "the virtual environment $venv sees the system's site-packages (made by an older knotflow): making it again without them"
      rm -rf "$venv"
    elif [ -e "$venv" ] && ! "$venv/bin/python" -c '' 2>/dev/null; then
      [ "${KNOTFLOW_NO_INSTALL:-0}" = 1 ] && kf_die "the virtual environment $venv is broken (its python does not run)"
      kf_log "the virtual environment $venv is broken (its python does not run): making it again"
      rm -rf "$venv"
    fi
    if [ ! -x "$venv/bin/python" ]; then
      base="$(kf_venv_base "$py")"
      kf_python_version_ok "$base" || kf_die "$base is older than Python $KF_PYTHON_MIN (set KNOTFLOW_PYTHON)"
      kf_log "creating the virtual environment $venv from $base (without the system's site-packages)"
      mkdir -p "$KF_BUILD_DIR"
      "$base" -m venv "$venv" </dev/null \
        || kf_die "$base -m venv failed (Debian: apt-get install python3-venv)"
    fi
    py="$venv/bin/python"
  fi
  KF_PY="$py"
  PATH="$(dirname "$KF_PY"):$PATH"
  export PATH

  if [ -f "$KF_ROOT/tools/pyproject.toml" ]; then
    # Installed with the tested versions of tools/constraints.txt.  A stamp in the environment
    # (sha256 of pyproject.toml + constraints.txt) tells whether it is up to date: a changed
    # dependency list or pin reinstalls (tools/tests/test_constraints.py reads the stamp).
    local name location prefix stamp digest constraints=()
    [ -f "$KF_ROOT/tools/constraints.txt" ] && constraints=(-c "$KF_ROOT/tools/constraints.txt")
    digest="$(cat "$KF_ROOT/tools/pyproject.toml" "${constraints[@]:1}" | sha256sum | cut -d' ' -f1)"
    prefix="$("$KF_PY" -c 'import sys; print(sys.prefix)')"
    stamp="$prefix/knotflow-tools.stamp"
    name="$("$KF_PY" -c 'import sys, tomllib; print(tomllib.load(open(sys.argv[1], "rb"))["project"]["name"])' \
            "$KF_ROOT/tools/pyproject.toml" 2>/dev/null || true)"
    location=""
    if [ -n "$name" ]; then
      location="$("$KF_PY" -m pip show "$name" 2>/dev/null \
                  | sed -n 's/^Editable project location: //p' || true)"
    fi
    if [ -n "$location" ] && [ "$(cd "$location" 2>/dev/null && pwd)" = "$KF_ROOT/tools" ] \
       && "$KF_PY" -c 'import pytest' 2>/dev/null \
       && [ "$(cut -d' ' -f1 "$stamp" 2>/dev/null)" = "$digest" ]; then
      kf_log "python: $name already installed (editable) from tools/, constraints up to date"
    else
      [ "${KNOTFLOW_NO_INSTALL:-0}" = 1 ] && kf_die "python package in tools/ not installed (or outdated)"
      kf_log "python: pip install ${constraints[*]} -e tools[test,fortran]"
      "$KF_PY" -m pip install -q --disable-pip-version-check "${constraints[@]}" \
               -e "$KF_ROOT/tools[test,fortran]" </dev/null \
        || kf_die "pip install -e tools[test,fortran] failed"
      printf '%s pyproject.toml+constraints.txt\n' "$digest" >"$stamp" \
        || kf_log "WARNING: cannot write $stamp"
    fi
  else
    local missing=() mod
    for mod in numpy h5py matplotlib pytest; do
      "$KF_PY" -c "import $mod" 2>/dev/null || missing+=("$mod")
    done
    if [ "${#missing[@]}" -eq 0 ]; then
      kf_log "python: numpy h5py matplotlib pytest present"
    else
      [ "${KNOTFLOW_NO_INSTALL:-0}" = 1 ] && kf_die "missing python packages: ${missing[*]}"
      kf_log "python: pip install ${missing[*]}"
      "$KF_PY" -m pip install -q --disable-pip-version-check "${missing[@]}" </dev/null \
        || kf_die "pip install ${missing[*]} failed"
    fi
  fi
}

# kf_build <build dir> <build type> [targets...]: configure (if needed) and build.
kf_build() {
  local dir="$1" type="$2"
  shift 2
  kf_log "configuring $type build in $dir"
  mkdir -p "$dir"
  cmake -S "$KF_ROOT" -B "$dir" -DCMAKE_BUILD_TYPE="$type" -DKNOTFLOW_PYTHON3="$KF_PY" \
        >"$dir/configure.log" 2>&1 \
    || { cat "$dir/configure.log"; kf_die "CMake configuration ($type) failed"; }
  grep -E '^-- Tests:' "$dir/configure.log" || true
  local target_args=() t
  for t in "$@"; do target_args+=(--target "$t"); done
  kf_log "building $type (-j$KF_JOBS) ${*:-all}"
  cmake --build "$dir" -j "$KF_JOBS" "${target_args[@]}" || kf_die "$type build failed"
  [ "$type" = Release ] && kf_link_python_library "$dir"
  return 0
}

# kf_link_python_library <build dir>: make the build's C interface (lib/libknotflow_capi.so,
# src/capi) the one the Python package `knotflow` of KF_PY's environment loads: a symbolic link
# <sys.prefix>/lib/knotflow/libknotflow_capi.so (tools/src/knotflow/_library.py looks there),
# so that `import knotflow` works without LD_LIBRARY_PATH or KNOTFLOW_LIBRARY. Release builds
# only (a Debug library traps floating-point exceptions, which would end the interpreter).
kf_link_python_library() {
  local lib="$1/lib/libknotflow_capi.so" prefix
  [ -e "$lib" ] && [ -n "${KF_PY:-}" ] || return 0
  prefix="$("$KF_PY" -c 'import sys; print(sys.prefix)')" || return 0
  if mkdir -p "$prefix/lib/knotflow" && ln -sfn "$lib" "$prefix/lib/knotflow/libknotflow_capi.so"; then
    kf_log "python: knotflow loads $lib (link in $prefix/lib/knotflow)"
  else
    kf_log "WARNING: cannot link $lib into $prefix/lib/knotflow (set KNOTFLOW_LIBRARY instead)"
  fi
}

# The number of MPI ranks of the run scripts: KNOTFLOW_NP (default 2), checked; printed.
kf_ranks() {
  local np="${KNOTFLOW_NP:-2}"
  [[ "$np" =~ ^[1-9][0-9]*$ ]] || kf_die "KNOTFLOW_NP must be a positive integer (got '$np')"
  printf '%s\n' "$np"
}

# mpirun flags: --oversubscribe for Open MPI, plus --allow-run-as-root when root.
kf_mpirun_flags() {
  KF_MPIRUN_FLAGS=()
  if mpirun --version 2>/dev/null | grep -qE 'Open MPI|OpenRTE'; then
    KF_MPIRUN_FLAGS+=(--oversubscribe)
    [ "$(id -u)" -eq 0 ] && KF_MPIRUN_FLAGS+=(--allow-run-as-root)
  fi
  return 0
}
