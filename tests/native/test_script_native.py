"""--script with many lines due at once: every reply reaches stdout (a file here, as a CI job keeps it), none
dropped, and the lines run a bounded number per pass, so that the nodes keep their deadlines meanwhile. Against
canopen-emu-fakecan (test_emulator_native.py), in the plain and in the ASan+UBSan build.

Environment (tests/native/CMakeLists.txt): CO_SOURCE_DIR, CO_EMU_FAKECAN (the program), CO_SANITIZED.
"""

import os
import re
import subprocess
import time  # noqa: F401

import pytest

from test_emulator_native import EMU, FakeBus

LINES = 5000


def test_a_burst_of_script_lines_loses_no_reply_and_holds_no_heartbeat(tmp_path):
    """5,000 `get` lines at 0.5 s, then quit: stdout (a file) holds 5,000 answers in order and no line says
    something was dropped; the node's 10 ms heartbeat goes on through the burst (no gap of 200 ms: before, the
    whole burst ran in one pass)."""
    if not EMU:
        pytest.fail("CO_EMU_FAKECAN is not set (the test is run by ctest: tests/native/CMakeLists.txt)", pytrace=False)
    script = tmp_path / "burst.script"
    script.write_text("@0 set 1 0x1017 10\n" + "".join(f"@500 get 1 0x1018:{1 + i % 4}\n" for i in range(LINES))
                      + "@+700 quit\n")
    bus = FakeBus(tmp_path / "bus")
    env = dict(os.environ, CO_FAKECAN_SOCKET=bus.listener.getsockname(),
               ASAN_OPTIONS="detect_leaks=1:abort_on_error=0:halt_on_error=1",
               UBSAN_OPTIONS="halt_on_error=1:print_stacktrace=1")
    out_path = tmp_path / "stdout.txt"
    with open(out_path, "wb") as out:
        proc = subprocess.Popen([EMU, "-i", "fakecan0", "--nvm-dir", str(tmp_path / "nvm"), "--script", str(script),
                                 "buerkert:1"], stdin=subprocess.DEVNULL, stdout=out, stderr=subprocess.PIPE, env=env)
        bus.proc = proc
        bus.accept()
        try:
            _, err = proc.communicate(timeout=60.0)
        finally:
            bus.close()
    heartbeats = []
    while not bus.frames.empty():
        t, can_id, data = bus.frames.get()
        if can_id == 0x701 and data == b"\x7f":
            heartbeats.append(t)
    assert proc.returncode == 0, err[-3000:]
    text = out_path.read_text(errors="replace")
    answers = [line for line in text.splitlines() if line.strip()]
    dropped = re.compile(rb"line\(s\) \(\d+ bytes\) dropped")  # emu_output.c's report of lines it dropped
    assert not dropped.search(text.encode()) and not dropped.search(err), (text[-500:], err[-500:])
    assert answers[0] == "node 1: 0x1017:00 = 10 (0xA)", answers[:2]
    gets = answers[1:]
    assert len(gets) == LINES, (len(gets), gets[-3:])
    assert all(line.startswith(f"node 1: 0x1018:0{1 + i % 4} = ") for i, line in enumerate(gets)), gets[:8]
    gaps = [b - a for a, b in zip(heartbeats, heartbeats[1:])]
    assert len(heartbeats) > 50 and max(gaps) < (1.0 if os.environ.get("CO_SANITIZED") == "ON" else 0.2), \
        (len(heartbeats), max(gaps) if gaps else None)
