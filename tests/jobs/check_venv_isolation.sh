#!/bin/bash
# The virtual environment of scripts/lib.sh (kf_ensure_python) takes nothing from the system's
# site-packages, and is made from an interpreter every user can run; without a network:
#   1. a venv made by an older knotflow (--system-site-packages) is refused under
#      KNOTFLOW_NO_INSTALL=1, naming the venv, and left as it was;
#   2. without KNOTFLOW_NO_INSTALL it is made again without the system's site-packages
#      (pyvenv.cfg: include-system-site-packages = false; the system's dist-packages not on its
#      sys.path), before the pip install (which fails here: no index);
#   3. kf_python_shared: /usr/bin/python3 can be run by every user; a Python inside a directory
#      only root may enter cannot, and kf_venv_base then makes the venv from /usr/bin/python3,
#      unless KNOTFLOW_PYTHON names the interpreter.
# Usage: check_venv_isolation.sh SOURCE_DIR WORKDIR
set -uo pipefail
src="$(cd "$1" && pwd)" work="$2"
fail() { echo "FAIL: $*" >&2; exit 1; }
[ -x /usr/bin/python3 ] || { echo "SKIP: no /usr/bin/python3"; exit 77; }
/usr/bin/python3 -c 'import ensurepip' 2>/dev/null || { echo "SKIP: /usr/bin/python3 has no ensurepip (python3-venv)"; exit 77; }
rm -rf "${work}"
mkdir -p "${work}/project/tools"
# A copy of the project's set-up (lib.sh finds the project from its own place).
cp -r "${src}/scripts" "${work}/project/"
cp "${src}/tools/pyproject.toml" "${src}/tools/constraints.txt" "${work}/project/tools/"
venv="${work}/project/build/venv"
cfg_value() { sed -n 's/^include-system-site-packages *= *//p' "${venv}/pyvenv.cfg"; }

/usr/bin/python3 -m venv --system-site-packages --without-pip "${venv}" || fail "cannot make the old venv"
[[ "$(cfg_value)" == true ]] || fail "the old venv's pyvenv.cfg: $(cat "${venv}/pyvenv.cfg")"
"${venv}/bin/python" -c 'import sys; assert any(p.endswith("dist-packages") for p in sys.path), sys.path' \
  || fail "the old venv does not see the system's dist-packages (nothing to test)"

out=$(KNOTFLOW_NO_INSTALL=1 KNOTFLOW_PYTHON=/usr/bin/python3 bash -c \
  "source '${work}/project/scripts/lib.sh' && kf_ensure_python && echo DONE" 2>&1)
[[ "${out}" != *DONE* && "${out}" == *"${venv} sees the system's site-packages"* ]] \
  || fail "KNOTFLOW_NO_INSTALL=1 accepted the old venv: ${out}"
[[ "$(cfg_value)" == true ]] || fail "KNOTFLOW_NO_INSTALL=1 changed the venv"
echo "1. the old venv refused under KNOTFLOW_NO_INSTALL=1, left as it was"

out=$(PIP_NO_INDEX=1 PIP_FIND_LINKS="${work}/no-wheels" KNOTFLOW_PYTHON=/usr/bin/python3 bash -c \
  "source '${work}/project/scripts/lib.sh' && kf_ensure_python && echo DONE" 2>&1)
[[ "${out}" == *"making it again without them"* ]] || fail "the old venv was not made again: ${out}"
[[ "$(cfg_value)" == false ]] || fail "the new venv's pyvenv.cfg: $(cat "${venv}/pyvenv.cfg")"
"${venv}/bin/python" - <<'PY' || fail "the new venv sees a site directory outside itself"
import os, sys
outside = [p for p in sys.path if os.path.basename(p) in ("site-packages", "dist-packages")
           and not os.path.realpath(p).startswith(os.path.realpath(sys.prefix) + os.sep)]
assert not outside, outside
PY
echo "2. the old venv made again without the system's site-packages"

# shellcheck source=scripts/lib.sh
source "${src}/scripts/lib.sh"
kf_python_shared /usr/bin/python3 || fail "kf_python_shared: /usr/bin/python3 not usable by every user?"
mkdir -m 700 "${work}/private"
/usr/bin/python3 -m venv --copies --without-pip "${work}/private/py" || fail "cannot make the private python"
if kf_python_shared "${work}/private/py/bin/python"; then
  fail "kf_python_shared: a python under a directory of mode 700 taken as usable by every user"
fi
got="$(unset KNOTFLOW_PYTHON; kf_venv_base "${work}/private/py/bin/python" 2>/dev/null)"
[[ "${got}" == /usr/bin/python3 ]] || fail "kf_venv_base of a private python gave '${got}'"
got="$(KNOTFLOW_PYTHON="${work}/private/py/bin/python" kf_venv_base "${work}/private/py/bin/python" 2>/dev/null)"
[[ "${got}" == "${work}/private/py/bin/python" ]] || fail "KNOTFLOW_PYTHON not obeyed: '${got}'"
echo "3. a python other users cannot run is replaced by /usr/bin/python3 unless KNOTFLOW_PYTHON names it"
