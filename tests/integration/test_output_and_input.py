"""canopen-emu's own input and output (issue 12): output nobody reads never stops the nodes; command lines from stdin
are taken whole or refused whole; a terminal it reads is left as it was found."""
import fcntl
import os
import pty
import re
import select
import signal
import subprocess
import time

import pytest

from conftest import BUS_ARG, EMU, Deadline
from test_bus_faults import HB_MS, RawCan, odv, set_heartbeats, starved_heartbeats, upload, upload_answer, \
    wait_bootups

NODE = 0x63  # 99, the sds default


def started(emulator, capture, *args):
    emu = emulator(f"sds:{NODE}", *args)
    capture.wait_for(0x700 + NODE, data=b"\x00", timeout=3)
    return emu


def read_some(fd, chunks, wait):
    """Appends what fd has within `wait` seconds to chunks; False at its end."""
    ready, _, _ = select.select([fd], [], [], wait)
    if not ready:
        return True
    data = os.read(fd, 1 << 16)
    chunks.append(data)
    return bool(data)


# What canopen-emu writes, line by line: log lines with their time, fatal messages, replies and the lines of a
# multi-line reply (help). A line cut in two would match none.
WHOLE_LINE = re.compile(r"^(\[ *\d+\.\d{3}\] \S|canopen-emu: |node \d+|  \S)")


def test_output_nobody_reads_never_stops_the_nodes(tmp_path):
    # stdout and stderr to one pipe that is not read, as `canopen-emu ... 2>&1 | less` left alone. The pipe holds one
    # page here, so it is full after a few dozen lines of -v; the emulator then blocked in write(2) and neither
    # answered nor sent heartbeats any more.
    read_end, write_end = os.pipe()
    fcntl.fcntl(write_end, fcntl.F_SETPIPE_SZ, 4096)
    recorder = RawCan((0x700 + NODE, 0x580 + NODE))  # every heartbeat and answer, with kernel time stamps
    client = RawCan((0x700 + NODE, 0x580 + NODE))
    proc = subprocess.Popen([EMU, "-v", "-i", BUS_ARG, "--nvm-dir", str(tmp_path), "--control", "-", f"sds:{NODE}"],
                            stdin=subprocess.PIPE, stdout=write_end, stderr=write_end)
    os.close(write_end)
    try:
        wait_bootups(client, [NODE])
        set_heartbeats(client, [NODE], HB_MS)
        request, answer = upload(0x1018, 1), upload_answer(0x1018, 1, odv("sds", 0x1018, 1), 4)
        # Closed loop for 5 s and at least 2,000 requests (each logs two lines: 64 KiB of log buffer overflow after
        # about 1,000), and a help reply (about 1 KiB) every 10 requests, which overflows the 64 KiB of stdout.
        since = time.time()
        requests = 0
        while (time.time() - since < 5.0 or requests < 2000) and time.time() - since < 60.0:
            client.transact(NODE, request, answer)  # fails when a request is not answered within 2 s
            requests += 1
            if requests % 10 == 0:
                proc.stdin.write(f"help {NODE}\n".encode())
                proc.stdin.flush()
        until = time.time()
        assert proc.poll() is None
        frames = recorder.drain(wait=0.3)
        heartbeats = [ts for ts, can_id, _ in frames if can_id == 0x700 + NODE and since <= ts <= until]
        assert len(heartbeats) >= 10, f"{len(heartbeats)} heartbeats in {until - since:.1f} s"
        starved = starved_heartbeats(frames, NODE, since, until)
        assert not starved, starved

        # Now read: the emulator writes what it buffered, and says what it had to drop.
        chunks = []
        deadline = Deadline(10)
        deadline.until(lambda: read_some(read_end, chunks, 0.05) and b"dropped: output blocked" in b"".join(chunks)
                       and b"(stdout was not read)" in b"".join(chunks))
        proc.send_signal(signal.SIGTERM)
        deadline = Deadline(10)
        deadline.until(lambda: not read_some(read_end, chunks, 0.05))
        assert proc.wait(timeout=5) == 0
    finally:
        if proc.poll() is None:
            proc.kill()
            proc.wait()
        os.close(read_end)
        recorder.close()
        client.close()
    text = b"".join(chunks).decode()
    lines = text.splitlines()
    assert text.endswith("\n") and all(WHOLE_LINE.match(line) for line in lines), \
        [line for line in lines if not WHOLE_LINE.match(line)][:5]
    log_gaps = [re.search(r"\] (\d+) log line\(s\) \((\d+) bytes\) dropped: output blocked \(stderr was not read\)$",
                          line) for line in lines]
    log_gaps = [(int(m[1]), int(m[2])) for m in log_gaps if m]
    reply_gaps = [re.search(r"\] (\d+) reply line\(s\) \((\d+) bytes\) dropped: output blocked \(stdout was not "
                            r"read\)$", line) for line in lines]
    reply_gaps = [(int(m[1]), int(m[2])) for m in reply_gaps if m]
    assert log_gaps and reply_gaps, [line for line in lines if "dropped" in line]
    totals = [re.search(r"\] (\d+) log line\(s\) \((\d+) bytes\) and (\d+) reply line\(s\) \((\d+) bytes\) dropped in "
                        r"all: output blocked$", line) for line in lines]
    totals = [tuple(int(g) for g in m.groups()) for m in totals if m]
    assert len(totals) == 1, lines[-20:]
    # Each gap in the log was reported where it is, and the reports add up to the total (a report of dropped replies
    # goes to the log and may itself be dropped there: those add up to at most the total).
    assert totals[0][:2] == (sum(n for n, _ in log_gaps), sum(b for _, b in log_gaps)), (totals, log_gaps)
    assert 0 < sum(n for n, _ in reply_gaps) <= totals[0][2], (totals, reply_gaps)
    assert sum(1 for line in lines if "frame(s) sent" in line) == 1  # the exit summary came through


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
    assert emu.wait(timeout=5) == 0
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
    proc = subprocess.Popen([EMU, "-i", BUS_ARG, "--nvm-dir", str(tmp_path), f"sds:{NODE}"], stdin=terminal,
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


def test_a_command_of_too_many_words_says_so(emulator, capture):
    emu = started(emulator, capture)
    bytes13 = " ".join(str(i) for i in range(1, 14))
    # 16 words reach the command, whose own check refuses 13 bytes; 17 were cut to 16 and the command then
    # called unknown, whatever it was
    emu.command(f"emcy {NODE} 0x5000 {bytes13}", expect=f"node {NODE}: error: usage: emcy")
    emu.command(f"emcy {NODE} 0x5000 {bytes13} 14", expect="error: too many words (at most 16)")
    emu.command(f"show {NODE} " + "x " * 15, expect="error: too many words (at most 16)")
    assert not any("unknown command" in line for line in emu.out_lines), emu.out_lines


def test_the_exit_waits_for_output_nobody_reads_a_bounded_time(tmp_path):
    # Never read at all: the exit writes what it can and waits at most OUTPUT_EXIT_WAIT_MS (1 s) for the rest.
    read_end, write_end = os.pipe()
    fcntl.fcntl(write_end, fcntl.F_SETPIPE_SZ, 4096)
    client = RawCan((0x700 + NODE, 0x580 + NODE))
    proc = subprocess.Popen([EMU, "-v", "-i", BUS_ARG, "--nvm-dir", str(tmp_path), f"sds:{NODE}"],
                            stdin=subprocess.DEVNULL, stdout=write_end, stderr=write_end)
    os.close(write_end)
    try:
        wait_bootups(client, [NODE])
        request, answer = upload(0x1018, 1), upload_answer(0x1018, 1, odv("sds", 0x1018, 1), 4)
        for _ in range(200):  # 400 lines of -v: the pipe is full, the buffer holds the rest
            client.transact(NODE, request, answer)
        start = time.monotonic()
        proc.send_signal(signal.SIGTERM)
        assert proc.wait(timeout=10) == 0
        assert time.monotonic() - start < 5.0  # 1 s of waiting, the rest is slack for a loaded machine
    finally:
        if proc.poll() is None:
            proc.kill()
            proc.wait()
        os.close(read_end)
        client.close()
