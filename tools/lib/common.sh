# Shared by tools/run-tests, tools/profile-tests and tools/demo (sourced, POSIX sh): Debian packages, the Python venv,
# the CMake generator.

# need_tools "cmd:package ..." [APT-OPTION...] installs the packages whose command is missing (as root, with
# apt-get); an absolute path instead of a command is a file the package gives (a library's header). The options go
# to apt-get install: --no-install-recommends keeps a package's recommends out (chromium's: some 100 packages,
# systemd among them, that a headless browser under test never uses).
need_tools() {
  _need=""
  _list=$1
  shift
  for _t in $_list; do
    case ${_t%%:*} in
      /*) [ -e "${_t%%:*}" ] || _need="$_need ${_t#*:}" ;;
      *) command -v "${_t%%:*}" >/dev/null 2>&1 || _need="$_need ${_t#*:}" ;;
    esac
  done
  [ -z "$_need" ] && return 0
  if [ "$(id -u)" = 0 ] && command -v apt-get >/dev/null 2>&1; then
    echo "installing$_need"
    apt-get update -qq && DEBIAN_FRONTEND=noninteractive apt-get install -y -qq "$@" $_need >/dev/null
  else
    echo "missing$_need; install them (Debian: apt-get install${1:+ $*}$_need)" >&2
    return 1
  fi
}

# make_venv DIR: a venv with tests/requirements.txt, made once and refreshed when the file changes.
make_venv() {
  if ! python3 -c 'import ensurepip, venv' >/dev/null 2>&1; then
    if [ "$(id -u)" = 0 ] && command -v apt-get >/dev/null 2>&1; then
      apt-get update -qq && DEBIAN_FRONTEND=noninteractive apt-get install -y -qq python3-venv >/dev/null
    else
      echo "python3 cannot make a venv (Debian: apt-get install python3-venv)" >&2; return 1
    fi
  fi
  if ! cmp -s tests/requirements.txt "$1/requirements.txt" 2>/dev/null; then
    echo "== python venv ($1)"
    # Without a pip of its own where python3's pip can fill it (pip 22.3 and later: --python): ensurepip's copy of
    # pip into the venv is 6 s. The venv's pip is not used later (python/run-tests.sh brings its own).
    if python3 -m pip --python "$(command -v python3)" --version >/dev/null 2>&1; then
      python3 -m venv --without-pip "$1" &&
        python3 -m pip --python "$1/bin/python" install -q --disable-pip-version-check -r tests/requirements.txt
    else
      python3 -m venv "$1" && "$1/bin/pip" install -q --disable-pip-version-check -r tests/requirements.txt
    fi && cp tests/requirements.txt "$1/requirements.txt" || { echo "pip install failed" >&2; return 1; }
  fi
}

# cmake_generator DIR: "-G Ninja" where ninja is installed and DIR is a new build tree or already Ninja's (cmake
# cannot switch a tree's generator), else nothing (cmake's default, make). Ninja schedules across targets where make
# recurses per target: the plain build in 32 s instead of 40.
cmake_generator() {
  command -v ninja >/dev/null 2>&1 || return 0
  if [ ! -f "$1/CMakeCache.txt" ] || grep -q '^CMAKE_GENERATOR:INTERNAL=Ninja$' "$1/CMakeCache.txt"; then
    echo "-G Ninja"
  fi
}
