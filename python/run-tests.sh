#!/bin/sh
# Tests of the Python package (python/tests) and of the test engineer's example suite (examples/pytest) against
# the real canopen-emu on vcan, with the package installed as a user installs it: a fresh venv,
# `pip install ./python` (not editable, no sys.path tricks), the pinned test packages, and pytest loading the
# plugin through its entry point.
#
#   CANOPEN_EMU=/path/to/canopen-emu [CO_SOURCE_DIR=/path/to/source] sh python/run-tests.sh BUILD_DIR [PYTEST-ARGS]
#
# BUILD_DIR receives the venv (python-venv/), the copy of python/ it is installed from (python-src/: pip builds in
# the directory it installs from, which must not be the source tree) and the JUnit reports (python-tests.xml,
# examples-pytest.xml). CO_SOURCE_DIR defaults to the directory above this script; PYTHON (default python3)
# makes the venv. The pinned versions of canopen, python-can and pytest are those of tests/requirements.txt.
#
# Where it runs: pip needs the package index, and tools/vcan-run's User-Mode Linux has no network. So the venv is
# made here, and the tests then run at once if vcan0 exists (a kernel with vcan, a CI runner after
# `modprobe vcan; ip link add dev vcan0 type vcan; ip link set up vcan0`), else inside tools/vcan-run, which this
# script starts itself (vcan0 and vcan1 are up there). Do not wrap the whole script in tools/vcan-run on a machine
# without CAN: the install would fail for lack of network.
#
# Exit status: 0 when both suites pass, 1 when one fails, 2 for a usage error, 77 when no vcan is to be had
# (tools/vcan-run's "skip").
set -eu

usage() {
  echo "usage: CANOPEN_EMU=PATH [CO_SOURCE_DIR=DIR] sh python/run-tests.sh BUILD_DIR [PYTEST-ARGS...]" >&2
  exit 2
}

[ $# -ge 1 ] && [ -n "$1" ] || usage
mkdir -p "$1"
build=$(cd "$1" && pwd)
shift
here=$(cd "$(dirname "$0")" && pwd)
src=$(cd "${CO_SOURCE_DIR:-$here/..}" && pwd)
venv=$build/python-venv
export CO_SOURCE_DIR="$src"
export PYTHONDONTWRITEBYTECODE=1  # no __pycache__ in the source tree

if [ -z "${CANOPEN_EMU:-}" ]; then
  CANOPEN_EMU=$(command -v canopen-emu || true)
  [ -n "$CANOPEN_EMU" ] || { echo "run-tests.sh: set CANOPEN_EMU to the canopen-emu program" >&2; usage; }
fi
case $CANOPEN_EMU in
  /*) ;;
  */*) CANOPEN_EMU=$(cd "$(dirname "$CANOPEN_EMU")" && pwd)/$(basename "$CANOPEN_EMU") ;;
  *) CANOPEN_EMU=$(command -v "$CANOPEN_EMU") ;;
esac
[ -x "$CANOPEN_EMU" ] || { echo "run-tests.sh: $CANOPEN_EMU is not an executable file" >&2; exit 2; }
export CANOPEN_EMU

run_suites() {
  python=$venv/bin/python
  status=0
  echo "== python/tests: the canopen_emu package ($("$python" -c 'import canopen_emu; print(canopen_emu.__file__)'))"
  (cd "$src/python" && "$python" -m pytest -p no:cacheprovider -o junit_family=xunit2 \
    --junitxml="$build/python-tests.xml" "$@" tests) || status=1
  echo "== examples/pytest: the test engineer's example suite"
  (cd "$src/examples/pytest" && "$python" -m pytest -p no:cacheprovider -o junit_family=xunit2 \
    --junitxml="$build/examples-pytest.xml" "$@") || status=1
  [ "$status" -eq 0 ] && echo "run-tests.sh: both suites passed" || echo "run-tests.sh: FAILED" >&2
  return "$status"
}

if [ "${CO_PYTHON_TESTS_STAGE:-}" = run ]; then
  # Second stage, inside tools/vcan-run: the venv is ready.
  run_suites "$@"
  exit $?
fi

pins=$(grep -E '^(canopen|python-can|pytest)==' "$src/tests/requirements.txt" || true)
[ "$(echo "$pins" | wc -l)" -eq 3 ] || {
  echo "run-tests.sh: tests/requirements.txt must pin canopen, python-can and pytest (found: $pins)" >&2; exit 2; }

echo "== fresh venv $venv, pip install ./python" $pins
rm -rf "$venv" "$build/python-src"
cp -R "$src/python" "$build/python-src"
rm -rf "$build/python-src/build" "$build/python-src"/src/*.egg-info
"${PYTHON:-python3}" -m venv "$venv"
# shellcheck disable=SC2086
if ! "$venv/bin/python" -m pip install -q --disable-pip-version-check "$build/python-src" $pins; then
  echo "run-tests.sh: pip install failed; it needs the package index (tools/vcan-run's User-Mode Linux has no" \
       "network: run this script outside it, it starts tools/vcan-run itself when vcan0 is missing)" >&2
  exit 1
fi

if [ -e /sys/class/net/vcan0 ]; then
  run_suites "$@"
  exit $?
fi
export CO_PYTHON_TESTS_STAGE=run  # CO_* variables pass into tools/vcan-run; CANOPEN_EMU must be named
export VCAN_RUN_PASS_ENV="${VCAN_RUN_PASS_ENV:-} CANOPEN_EMU"
exec "$src/tools/vcan-run" sh "$here/run-tests.sh" "$build" "$@"
