# shellcheck shell=bash
# Shared by the tests of the study's scripts (sourced; defines functions only):
#   kf_project_copy SRC BUILD WORK   a copy of the project in WORK/project (scripts, the Python
#                                    tools, links to BUILD's knotflow, knotflow-analyze and
#                                    C-interface library (lib/libknotflow_capi.so), and
#                                    build/venv with this checkout's tools, without a network);
#                                    sets `proj`; exits 77 (ctest: skipped) when the system's
#                                    python3 lacks numpy/h5py/matplotlib for the tools
#   kf_small_sweep SWEEP CHAIN SWEEP_LINE T_END
#                                    writes inputs/SWEEP.nml in the current directory: RPY +
#                                    excluded volume (seconds), output in results/SWEEP, a frame
#                                    and a progress line per time unit
kf_project_copy() {
  local src="$1" build="$2" work="$3"
  proj="${work}/project"
  mkdir -p "${proj}/build/bin" "${proj}/inputs" "${proj}/tools"
  cp -r "${src}/scripts" "${proj}/"
  cp -r "${src}/tools/pyproject.toml" "${src}/tools/src" "${proj}/tools/"
  ln -s "${build}/bin/knotflow" "${proj}/build/bin/knotflow"
  ln -s "${build}/bin/knotflow-analyze" "${proj}/build/bin/knotflow-analyze"
  # the library's C interface, which the tools call for knots and shape (the package `knotflow`
  # finds it in the checkout's build/lib)
  mkdir -p "${proj}/build/lib"
  ln -s "${build}/lib/libknotflow_capi.so" "${proj}/build/lib/libknotflow_capi.so"
  # The Python tools of this checkout in build/venv (as tests/jobs/check_slurm_jobs.sh)
  if ! { /usr/bin/python3 -m venv --system-site-packages "${proj}/build/venv" \
         && "${proj}/build/venv/bin/python" -m pip install -q --no-deps --no-build-isolation --no-index -e "${proj}/tools" \
         && "${proj}/build/venv/bin/knotflow-study" --help; } >"${work}/venv.log" 2>&1; then
    echo "SKIP: no Python tools (system python3 without numpy/h5py/matplotlib?): $(tail -n 2 "${work}/venv.log")"
    exit 77
  fi
}

kf_small_sweep() {
  cat >"inputs/$1.nml" <<NML
&chain $2 /
&forces excluded_volume = .true. /
&integrator t_end = $4 /
&output directory = 'results/$1', frame_interval = 1.0, progress_interval = 0.0 /
$3
NML
}
