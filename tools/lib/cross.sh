# Shared by tools/target-tests and tools/size-report (sourced, POSIX sh): the cross toolchains and QEMU.
# Debian 12 packages: gcc-arm-none-eabi + picolibc-arm-none-eabi, gcc-riscv64-unknown-elf +
# picolibc-riscv64-unknown-elf, qemu-system-arm. Installed with apt-get when run as root.
. tools/lib/common.sh   # the sourcing scripts run from the repository root

# need_files "path:package ..." installs the packages whose file is missing (packages without a command,
# such as the C libraries).
need_files() {
  _need=""
  for _t in $1; do
    [ -e "${_t%%:*}" ] || _need="$_need ${_t#*:}"
  done
  [ -z "$_need" ] && return 0
  if [ "$(id -u)" = 0 ] && command -v apt-get >/dev/null 2>&1; then
    echo "installing$_need"
    apt-get update -qq && DEBIAN_FRONTEND=noninteractive apt-get install -y -qq $_need >/dev/null
  else
    echo "missing$_need; install them (Debian: apt-get install$_need)" >&2
    return 1
  fi
}

need_cross_arm() {
  need_tools "cmake:cmake make:make ninja:ninja-build python3:python3 arm-none-eabi-gcc:gcc-arm-none-eabi" &&
    need_files "/usr/lib/picolibc/arm-none-eabi/picolibc.specs:picolibc-arm-none-eabi"
}

need_cross_riscv() {
  need_tools "riscv64-unknown-elf-gcc:gcc-riscv64-unknown-elf" &&
    need_files "/usr/lib/picolibc/riscv64-unknown-elf/picolibc.specs:picolibc-riscv64-unknown-elf"
}

need_qemu_arm() {
  need_tools "qemu-system-arm:qemu-system-arm timeout:coreutils"
}

need_avr() {
  need_tools "avr-gcc:gcc-avr simavr:simavr timeout:coreutils" &&
    need_files "/usr/lib/avr/include/avr/io.h:avr-libc"
}
