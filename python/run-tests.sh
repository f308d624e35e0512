#!/bin/sh
# Tests of the Python package (python/tests) and of the test engineer's example suite (examples/pytest) against
# the real canopen-emu, with the package installed as a user installs it: a fresh venv, `pip install ./python[udp]`
# (not editable, no sys.path tricks), the pinned test packages, and pytest loading the plugin through its entry point.
# Two passes, on two kinds of bus, the example suite unchanged in both:
#
#   vcan  python/tests marked vcan (several SocketCAN interfaces, SocketCAN's own messages, auto finding vcan0 up)
#         and examples/pytest on vcan0
#   udp   the rest of python/tests and examples/pytest on udp_multicast, inside tests/udp/netns-run: a network
#         namespace of their own whose only interface is lo (no datagram reaches this machine's network), where
#         auto finds no vcan0 and gives the session a udp_multicast group of its own; natively, no User-Mode Linux;
#         then examples/pytest once more with --canopen-emu-bus socketcand (the master on python-can's socketcand)
#
#   CANOPEN_EMU=/path/to/canopen-emu [CO_SOURCE_DIR=/path/to/source] [CO_PYTHON_TESTS_PASSES="vcan udp"] \
#     sh python/run-tests.sh BUILD_DIR [PYTEST-ARGS]
#
# BUILD_DIR receives the venv (python-venv/), the copy of python/ it is installed from (python-src/: pip builds in
# the directory it installs from, which must not be the source tree) and the JUnit reports (python-tests.xml,
# examples-pytest.xml; the udp pass's python-tests-udp.xml, examples-pytest-udp.xml). CO_SOURCE_DIR defaults to the
# directory above this script; PYTHON (default python3) makes the venv; CO_PYTHON_TESTS_PASSES names the passes to
# run (default both; "venv": only make the venv); CO_PYTHON_TESTS_VENV=reuse takes the venv a run made before. The pinned versions of canopen, python-can, pytest and msgpack are tests/requirements.txt's.
#
# Where it runs: pip needs the package index, and tools/vcan-run's User-Mode Linux has no network. So the venv is
# made here, and the tests then run at once if vcan0 exists (a kernel with vcan, a CI runner after
# `modprobe vcan; ip link add dev vcan0 type vcan; ip link set up vcan0`), else inside tools/vcan-run, which this
# script starts itself (vcan0 and vcan1 are up there). Do not wrap the whole script in tools/vcan-run on a machine
# without CAN: the install would fail for lack of network.
#
# The udp pass needs unshare -rn (user namespaces), no root. Exit status: 0 when the suites of the passes pass, 1 when
# one fails, 2 for a usage error, 77 when every pass asked for was skipped (no vcan to be had: tools/vcan-run's
# "skip"; no user namespaces).
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

# run_suites PASS MARKS [PYTEST-ARGS...]: python/tests selected by -m MARKS, then examples/pytest as it is.
run_suites() {
  python=$venv/bin/python
  pass=$1 marks=$2
  shift 2
  suffix=$([ "$pass" = vcan ] || echo "-$pass")
  status=0
  echo "== $pass pass: python/tests -m '$marks': the canopen_emu package" \
       "($("$python" -c 'import canopen_emu; print(canopen_emu.__file__)'))"
  (cd "$src/python" && "$python" -m pytest -p no:cacheprovider -o junit_family=xunit2 -m "$marks" \
    --junitxml="$build/python-tests$suffix.xml" "$@" tests) || status=1
  echo "== $pass pass: examples/pytest: the test engineer's example suite"
  (cd "$src/examples/pytest" && "$python" -m pytest -p no:cacheprovider -o junit_family=xunit2 \
    --junitxml="$build/examples-pytest$suffix.xml" "$@") || status=1
  if [ "$pass" = udp ]; then
    echo "== $pass pass: examples/pytest again, its master on python-can's socketcand interface" \
         "(--canopen-emu-bus socketcand: a virtual bus each emulator serves on loopback)"
    (cd "$src/examples/pytest" && "$python" -m pytest -p no:cacheprovider -o junit_family=xunit2 \
      --canopen-emu-bus socketcand --junitxml="$build/examples-pytest-socketcand.xml" "$@") || status=1
  fi
  [ "$status" -eq 0 ] && echo "run-tests.sh: $pass pass: the suites passed" ||
    echo "run-tests.sh: $pass pass FAILED" >&2
  return "$status"
}

# Second stages: the venv is ready.
case ${CO_PYTHON_TESTS_STAGE:-} in
  run) run_suites vcan "vcan" "$@"; exit $? ;;   # inside tools/vcan-run, or where vcan0 is
  netns)                                              # inside tests/udp/netns-run
    # (ip asks the kernel: /sys/class/net shows the namespace sysfs was mounted in)
    links=$(ip -o link show | awk -F': ' '{print $2}')
    [ "$links" = lo ] || { echo "run-tests.sh: the udp pass runs only where lo is the only interface" \
      "(tests/udp/netns-run), not with: $(echo $links)" >&2; exit 1; }
    run_suites udp "not vcan" "$@"; exit $? ;;
esac

passes=${CO_PYTHON_TESTS_PASSES:-vcan udp}
for pass in $passes; do
  case $pass in vcan|udp|venv) ;;
    *) echo "run-tests.sh: CO_PYTHON_TESTS_PASSES takes vcan, udp and venv, not $pass" >&2; exit 2 ;;
  esac
done

pins=$(grep -E '^(canopen|python-can|pytest|msgpack)==' "$src/tests/requirements.txt" | sed 's/[[:space:]]*#.*//' || true)
[ "$(echo "$pins" | wc -l)" -eq 4 ] || {
  echo "run-tests.sh: tests/requirements.txt must pin canopen, python-can, pytest and msgpack (found: $pins)" >&2
  exit 2; }

# venv alone: make the venv and stop; a pass alone with CO_PYTHON_TESTS_VENV=reuse: use the venv made so (ctest makes
# it once, in a test of its own, for both passes: tests/integration/CMakeLists.txt)
if [ "${CO_PYTHON_TESTS_VENV:-}" = reuse ] && [ -x "$venv/bin/python" ]; then
  echo "== the venv $venv made before"
else
echo "== fresh venv $venv, pip install ./python[udp]" $pins
rm -rf "$venv" "$build/python-src"
cp -R "$src/python" "$build/python-src"
rm -rf "$build/python-src/build" "$build/python-src"/src/*.egg-info
# A venv without a pip of its own, filled by the pip of the Python that makes it (pip 22.3 and later installs into
# another environment: --python), where that pip can: ensurepip's copy of pip into the new venv was 6 of its 15 s.
# (PYTHON may itself be a venv without pip: python3's pip then)
maker=$(command -v "${PYTHON:-python3}" || echo "${PYTHON:-python3}")  # pip's --python takes a path
runner=""
for candidate in "$maker" python3; do
  if "$candidate" -m pip --python "$maker" --version >/dev/null 2>&1; then
    runner=$candidate
    break
  fi
done
if [ -n "$runner" ]; then
  "$maker" -m venv --without-pip "$venv"
  venv_pip() { "$runner" -m pip --python "$venv/bin/python" "$@"; }
else
  "$maker" -m venv "$venv"
  venv_pip() { "$venv/bin/python" -m pip "$@"; }
fi
# shellcheck disable=SC2086
if ! venv_pip install -q --disable-pip-version-check "$build/python-src[udp]" $pins; then
  echo "run-tests.sh: pip install failed; it needs the package index (tools/vcan-run's User-Mode Linux has no" \
       "network: run this script outside it, it starts tools/vcan-run itself when vcan0 is missing)" >&2
  exit 1
fi
fi
[ "$passes" != venv ] || exit 0

failed=0 ran=0
for pass in $passes; do
  status=0
  if [ "$pass" = vcan ]; then
    if [ -e /sys/class/net/vcan0 ]; then
      CO_PYTHON_TESTS_STAGE=run sh "$here/run-tests.sh" "$build" "$@" || status=$?
    else
      # CO_* and CANOPEN_EMU pass into tools/vcan-run by themselves
      CO_PYTHON_TESTS_STAGE=run "$src/tools/vcan-run" sh "$here/run-tests.sh" "$build" "$@" || status=$?
    fi
  elif ! unshare -rn true 2>/dev/null; then
    echo "run-tests.sh: udp pass skipped: unshare -rn fails here (user namespaces not allowed)" >&2
    status=77
  else
    CO_PYTHON_TESTS_STAGE=netns "$src/tests/udp/netns-run" sh "$here/run-tests.sh" "$build" "$@" || status=$?
  fi
  case $status in
    0) ran=1 ;;
    77) echo "run-tests.sh: $pass pass skipped" >&2 ;;
    *) ran=1 failed=1 ;;
  esac
done
[ "$failed" -eq 0 ] || exit 1
[ "$ran" -eq 1 ] || exit 77
exit 0
