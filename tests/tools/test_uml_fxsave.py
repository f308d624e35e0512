"""tools/lib/uml_fxsave.py, which lets User-Mode Linux run on hosts whose XSAVE area it cannot restore
(docs/vcan.md). Its seccomp filter must refuse exactly ptrace(PTRACE_GETREGSET/PTRACE_SETREGSET,
NT_X86_XSTATE) with EIO and let every other ptrace request through; a wrong offset in the filter would
either leave UML dying on such hosts or break its other ptrace calls."""

import os
import platform
import subprocess
import sys
from pathlib import Path

import pytest

REPO = Path(os.environ.get("CO_SOURCE_DIR") or Path(__file__).resolve().parents[2])
TOOL = REPO / "tools" / "lib" / "uml_fxsave.py"

pytestmark = pytest.mark.skipif(platform.system() != "Linux" or platform.machine() != "x86_64",
                                reason="the filter is for x86-64 Linux hosts")

# Run as a child under the filter (or without it): ptrace calls on a stopped tracee, one result per line.
PROBE = r"""
import ctypes, os, signal, sys
sys.path.insert(0, sys.argv[1])
import uml_fxsave as u
c = u.libc()
pid = os.fork()
if pid == 0:
    c.ptrace(u.PTRACE_TRACEME, 0, None, None)
    os.kill(os.getpid(), signal.SIGSTOP)
    os._exit(0)
os.waitpid(pid, os.WUNTRACED)
def call(req, addr, size):
    buf = ctypes.create_string_buffer(size)
    iov = u.Iovec(ctypes.cast(buf, ctypes.c_void_p), size)
    data = ctypes.byref(iov) if req in (u.PTRACE_GETREGSET, u.PTRACE_SETREGSET) else buf
    r = c.ptrace(req, pid, ctypes.c_void_p(addr), data)
    return "ok" if r == 0 else "errno %d" % ctypes.get_errno()
NT_PRSTATUS, PTRACE_GETREGS, PTRACE_GETFPREGS = 1, 12, 14
print("xstate-get", call(u.PTRACE_GETREGSET, u.NT_X86_XSTATE, 4096))
print("prstatus-get", call(u.PTRACE_GETREGSET, NT_PRSTATUS, 27 * 8))
print("getregs", call(PTRACE_GETREGS, 0, 27 * 8))
print("getfpregs", call(PTRACE_GETFPREGS, 0, 512))
os.kill(pid, signal.SIGKILL)
os.waitpid(pid, 0)
"""


def probe(under_filter):
    cmd = [sys.executable, "-c", PROBE, str(TOOL.parent)]
    if under_filter:
        cmd = [sys.executable, str(TOOL)] + cmd
    out = subprocess.run(cmd, capture_output=True, text=True, timeout=60)
    assert out.returncode == 0, out.stderr
    return dict(line.split(" ", 1) for line in out.stdout.strip().split("\n"))


def test_filter_refuses_only_the_xsave_regset():
    plain = probe(under_filter=False)
    if plain["xstate-get"] != "ok":
        pytest.skip("this host has no XSAVE regset: %s" % plain["xstate-get"])
    filtered = probe(under_filter=True)
    assert filtered["xstate-get"] == "errno 5"  # EIO: UML then takes PTRACE_GETFPREGS
    for other in ("prstatus-get", "getregs", "getfpregs"):
        assert filtered[other] == "ok", (other, filtered)


def test_probe_answers_and_the_filter_hides_the_problem():
    direct = subprocess.run([sys.executable, str(TOOL), "--probe"], timeout=60).returncode
    assert direct in (0, 1)
    # Under the filter UML's start-up check fails, so nothing is left to refuse: the probe says "not needed".
    wrapped = subprocess.run([sys.executable, str(TOOL), sys.executable, str(TOOL), "--probe"], timeout=60)
    assert wrapped.returncode == 1


def test_program_runs_with_its_arguments_and_exit_status():
    r = subprocess.run([sys.executable, str(TOOL), "sh", "-c", "echo \"$0 $1\"; exit 7", "a b", "c"],
                       capture_output=True, text=True, timeout=60)
    assert (r.returncode, r.stdout) == (7, "a b c\n")
