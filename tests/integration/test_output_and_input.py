"""canopen-emu's own input and output (issue 12): command lines from stdin are taken whole or refused whole; a
terminal it reads is left as it was found."""
import fcntl
import os
import pty
import signal
import subprocess

import pytest

from conftest import EMU, IFACE, Deadline

NODE = 0x63  # 99, the sds default


def started(emulator, capture, *args):
    emu = emulator(f"sds:{NODE}", *args)
    capture.wait_for(0x700 + NODE, data=b"\x00", timeout=3)
    return emu


def test_an_overlong_stdin_line_is_refused_whole_and_its_tail_never_runs(emulator, capture):
    emu = started(emulator, capture)
    # 2047 bytes of comment, then " quit": the tail of an overlong line ran as a command and quit the emulator.
    emu.command("#" + "x" * 2046 + " quit")
    emu.command("list", expect=f"node {NODE}: sds")
    assert emu.out_lines[0] == "error: stdin line 1 is longer than 2047 bytes: ignored", emu.out_lines
    # the longest line taken: 2047 bytes
    emu.command("list" + " " * 2043, expect=f"node {NODE}: sds")
    assert emu.proc.poll() is None
    emu.command("#" + "y" * 5000 + "\nquit")
    assert emu.proc.wait(timeout=5) == 0
    assert "error: stdin line 4 is longer than 2047 bytes: ignored" in emu.out_lines


def test_a_nul_byte_refuses_its_line_only(emulator, capture):
    emu = started(emulator, capture)
    # The NUL hid the rest of the buffer from the line splitter: the lines after it were lost, or glued together.
    emu.command(f"show {NODE}\0 quit\nlist\nshow {NODE}", expect=f"node {NODE}: sds node-ID {NODE}")
    assert emu.out_lines[0] == "error: stdin line 1 holds a NUL byte: ignored", emu.out_lines
    assert emu.out_lines[1].startswith(f"node {NODE}: sds (started as {NODE})"), emu.out_lines
    assert emu.proc.poll() is None


def test_a_last_line_without_newline_runs_at_the_end_of_stdin(emulator, capture):
    emu = started(emulator, capture)
    emu.proc.stdin.write("quit")
    emu.proc.stdin.close()
    assert Deadline(5).until(lambda: emu.proc.poll() is not None) and emu.proc.returncode == 0


@pytest.mark.parametrize("end", ["quit", "SIGINT", "SIGTERM"])
def test_a_terminal_on_stdin_is_blocking_again_after_the_end(tmp_path, capture, end):
    # The emulator reads commands from a terminal without blocking; the terminal's open file is the shell's too, whose
    # next read failed with EAGAIN when the emulator left it non-blocking.
    controller, terminal = pty.openpty()
    proc = subprocess.Popen([EMU, "-i", IFACE, "--nvm-dir", str(tmp_path), f"sds:{NODE}"], stdin=terminal,
                            stdout=subprocess.PIPE, stderr=subprocess.PIPE)
    try:
        capture.wait_for(0x700 + NODE, data=b"\x00", timeout=3)
        assert Deadline(3).until(lambda: fcntl.fcntl(terminal, fcntl.F_GETFL) & os.O_NONBLOCK), \
            "the emulator did not make the terminal non-blocking: it does not read it"
        if end == "quit":
            os.write(controller, b"quit\n")
        else:
            proc.send_signal(getattr(signal, end))
        proc.communicate(timeout=5)
        assert proc.returncode == 0
        assert fcntl.fcntl(terminal, fcntl.F_GETFL) & os.O_NONBLOCK == 0, f"the terminal stayed non-blocking ({end})"
    finally:
        if proc.poll() is None:
            proc.kill()
            proc.communicate()
        os.close(controller)
        os.close(terminal)
