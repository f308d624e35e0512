#!/usr/bin/env python3
"""User-Mode Linux on hosts whose XSAVE area it cannot restore (used by tools/vcan-run).

Debian 12's User-Mode Linux (6.1) saves and restores the FPU state of its processes with
ptrace(PTRACE_GETREGSET/PTRACE_SETREGSET, NT_X86_XSTATE) and a fixed 832-byte buffer (x87, SSE, AVX).
Linux accepts a PTRACE_SETREGSET of the XSAVE area only with the host's whole size (xstateregs_set:
count != fpu_user_cfg.max_size gives EFAULT); on a CPU with AVX-512 and AMX that is about 11 KB, so UML's
first process dies ("userspace - ptrace set fp regs failed, errno = 14", "Attempted to kill init!").
When UML finds PTRACE_GETREGSET of NT_X86_XSTATE refused at start-up, it uses PTRACE_GETFPREGS and
PTRACE_SETFPREGS (the 512-byte FXSAVE area: x87 and SSE) instead, which every x86-64 host accepts.

  uml_fxsave.py --probe          exit 0 when this host refuses UML's XSAVE restore (the fallback is needed),
                                 1 when it accepts it, 2 when it cannot tell (not x86-64 Linux, no ptrace)
  uml_fxsave.py PROGRAM ARGS...  run PROGRAM with a seccomp filter under which ptrace(PTRACE_GETREGSET or
                                 PTRACE_SETREGSET, NT_X86_XSTATE) fails with EIO, so UML takes the fallback

FXSAVE does not hold the upper halves of the AVX registers: UML then cannot keep them apart between threads
of one process. tools/vcan-run therefore also tells glibc inside UML not to use AVX (GLIBC_TUNABLES), so that
the programs there keep their vector state in the SSE registers that FXSAVE holds.
"""

import ctypes
import ctypes.util
import errno
import os
import platform
import signal
import struct
import sys

PTRACE_TRACEME, PTRACE_KILL = 0, 8
PTRACE_GETREGSET, PTRACE_SETREGSET = 0x4204, 0x4205
NT_X86_XSTATE = 0x202
UML_XSTATE_SIZE = 832  # sizeof(struct _xstate) of <asm/sigcontext.h>: what UML 6.1 passes

# seccomp (linux/seccomp.h, linux/filter.h, linux/audit.h)
PR_SET_NO_NEW_PRIVS, PR_SET_SECCOMP, SECCOMP_MODE_FILTER = 38, 22, 2
SECCOMP_RET_ALLOW, SECCOMP_RET_ERRNO = 0x7FFF0000, 0x00050000
AUDIT_ARCH_X86_64 = 0xC000003E
NR_PTRACE_X86_64 = 101
BPF_LD_W_ABS, BPF_JEQ_K, BPF_RET_K = 0x20, 0x15, 0x06
# struct seccomp_data: int nr; __u32 arch; __u64 instruction_pointer; __u64 args[6]
OFF_NR, OFF_ARCH, OFF_ARG0, OFF_ARG2 = 0, 4, 16, 32


class Iovec(ctypes.Structure):
    _fields_ = [("iov_base", ctypes.c_void_p), ("iov_len", ctypes.c_size_t)]


class SockFprog(ctypes.Structure):
    _fields_ = [("len", ctypes.c_ushort), ("filter", ctypes.c_void_p)]


def libc():
    lib = ctypes.CDLL(ctypes.util.find_library("c") or "libc.so.6", use_errno=True)
    lib.ptrace.argtypes = [ctypes.c_long, ctypes.c_long, ctypes.c_void_p, ctypes.c_void_p]
    lib.ptrace.restype = ctypes.c_long
    lib.prctl.argtypes = [ctypes.c_int, ctypes.c_ulong, ctypes.c_ulong, ctypes.c_ulong, ctypes.c_ulong]
    return lib


def host_refuses_uml_xstate():
    """Does this host refuse what UML 6.1 does: PTRACE_SETREGSET of an 832-byte XSAVE area it just read?"""
    if platform.system() != "Linux" or platform.machine() != "x86_64":
        return None
    c = libc()
    pid = os.fork()
    if pid == 0:  # the tracee: stop until the parent has tried, then get killed
        try:
            c.ptrace(PTRACE_TRACEME, 0, None, None)
            os.kill(os.getpid(), signal.SIGSTOP)
        finally:
            os._exit(0)
    try:
        _, status = os.waitpid(pid, os.WUNTRACED)
        if not os.WIFSTOPPED(status):
            return None
        buf = ctypes.create_string_buffer(UML_XSTATE_SIZE)
        iov = Iovec(ctypes.cast(buf, ctypes.c_void_p), UML_XSTATE_SIZE)
        if c.ptrace(PTRACE_GETREGSET, pid, ctypes.c_void_p(NT_X86_XSTATE), ctypes.byref(iov)) != 0:
            return False  # no XSAVE regset at all: UML uses FXSAVE by itself
        iov.iov_len = UML_XSTATE_SIZE
        if c.ptrace(PTRACE_SETREGSET, pid, ctypes.c_void_p(NT_X86_XSTATE), ctypes.byref(iov)) == 0:
            return False
        return ctypes.get_errno() in (errno.EFAULT, errno.EINVAL)
    finally:
        try:
            os.kill(pid, signal.SIGKILL)
        except ProcessLookupError:
            pass
        os.waitpid(pid, 0)


def install_filter():
    """ptrace(PTRACE_GETREGSET | PTRACE_SETREGSET, pid, NT_X86_XSTATE, ...) -> -EIO; everything else allowed."""
    def stmt(code, k):
        return struct.pack("=HBBI", code, 0, 0, k)

    def jeq(k, jt, jf):
        return struct.pack("=HBBI", BPF_JEQ_K, jt, jf, k)

    prog = [
        stmt(BPF_LD_W_ABS, OFF_ARCH), jeq(AUDIT_ARCH_X86_64, 0, 8),       # other ABI: allow
        stmt(BPF_LD_W_ABS, OFF_NR), jeq(NR_PTRACE_X86_64, 0, 6),          # not ptrace: allow
        stmt(BPF_LD_W_ABS, OFF_ARG0), jeq(PTRACE_GETREGSET, 1, 0), jeq(PTRACE_SETREGSET, 0, 3),
        stmt(BPF_LD_W_ABS, OFF_ARG2), jeq(NT_X86_XSTATE, 0, 1),
        stmt(BPF_RET_K, SECCOMP_RET_ERRNO | errno.EIO),
        stmt(BPF_RET_K, SECCOMP_RET_ALLOW),
    ]
    code = b"".join(prog)
    buf = ctypes.create_string_buffer(code, len(code))
    fprog = SockFprog(len(prog), ctypes.cast(buf, ctypes.c_void_p))
    c = libc()
    if c.prctl(PR_SET_NO_NEW_PRIVS, 1, 0, 0, 0) != 0:
        raise OSError(ctypes.get_errno(), "prctl(PR_SET_NO_NEW_PRIVS)")
    if c.prctl(PR_SET_SECCOMP, SECCOMP_MODE_FILTER, ctypes.addressof(fprog), 0, 0) != 0:
        raise OSError(ctypes.get_errno(), "prctl(PR_SET_SECCOMP)")


def main(argv):
    if len(argv) < 2 or argv[1] in ("-h", "--help"):
        print(__doc__.strip())
        return 0 if len(argv) >= 2 else 2
    if argv[1] == "--probe":
        verdict = host_refuses_uml_xstate()
        return 2 if verdict is None else (0 if verdict else 1)
    install_filter()
    os.execvp(argv[1], argv[1:])
    return 127


if __name__ == "__main__":
    sys.exit(main(sys.argv))
