"""What canopen-emu shows as text: values and names with bytes a terminal would act on (ESC[2J clears the screen,
a C1 CSI does the same on terminals that take 8-bit controls) are escaped wherever they are shown (the text `get`,
the log, events' text lines, and in JSON events as \\u escapes), and a command with a wrong number of arguments says
what it takes instead of "unknown command". Against canopen-emu-fakecan (test_emulator_native.py), in the plain and
in the ASan+UBSan build.

Environment (tests/native/CMakeLists.txt): CO_SOURCE_DIR, CO_EMU_FAKECAN (the program), CO_SANITIZED.
"""

import json
import os
import shutil
import subprocess
import time

import pytest

from test_emulator_native import EMU, SANITIZER_MARKS, SRC, FakeBus

# Bytes that must never reach a terminal raw: C0 controls but the line end, DEL, and the UTF-8 C1 controls.
RAW_CONTROLS = [bytes([c]) for c in range(0x20) if c != 0x0A] + [b"\x7f"] + [bytes([0xC2, c]) for c in range(0x80, 0xA0)]


def raw_controls_in(data):
    return [c for c in RAW_CONTROLS if c in data]


class TextEmulator:
    """canopen-emu-fakecan with --control - and binary pipes: its output is checked byte by byte (bytes that are
    not UTF-8 must not break the test's decoding of them)."""

    def __init__(self, tmp_path, *args):
        if not EMU:
            pytest.fail("CO_EMU_FAKECAN is not set (the test is run by ctest: tests/native/CMakeLists.txt)",
                        pytrace=False)
        self.bus = FakeBus(tmp_path / f"bus-{time.monotonic_ns()}")
        env = dict(os.environ, CO_FAKECAN_SOCKET=self.bus.listener.getsockname(),
                   ASAN_OPTIONS="detect_leaks=1:abort_on_error=0:halt_on_error=1",
                   UBSAN_OPTIONS="halt_on_error=1:print_stacktrace=1")
        self.proc = subprocess.Popen([EMU, "-i", "fakecan0", "--control", "-", "--nvm-dir", str(tmp_path / "nvm"),
                                      *args], stdin=subprocess.PIPE, stdout=subprocess.PIPE, stderr=subprocess.PIPE,
                                     env=env)
        self.bus.proc = self.proc
        self.bus.accept()

    def command(self, line):
        self.proc.stdin.write(line.encode() + b"\n")
        self.proc.stdin.flush()

    def quit(self):
        """quit; returns (stdout, stderr) as bytes; fails on a sanitizer report or a status other than 0."""
        self.command("quit")
        try:
            out, err = self.proc.communicate(timeout=20.0)
        except subprocess.TimeoutExpired:
            self.proc.kill()
            out, err = self.proc.communicate()
            raise AssertionError("canopen-emu did not end after quit:\n" + err[-3000:].decode(errors="replace"))
        finally:
            self.bus.close()
        text = err.decode(errors="replace")
        assert not any(mark in text for mark in SANITIZER_MARKS), text[-6000:]
        assert self.proc.returncode == 0, text[-3000:]
        return out, err


def sdo_download(bus, node, index, sub, value):
    """A VISIBLE_STRING written as an SDO client would: expedited up to 4 bytes, else segmented."""
    mux = bytes([index & 0xFF, index >> 8, sub])
    if len(value) <= 4:
        answer = bus.sdo(node, bytes([0x23 | ((4 - len(value)) << 2)]) + mux + value.ljust(4, b"\0"))
        assert answer[0] == 0x60, answer.hex()
        return
    answer = bus.sdo(node, bytes([0x21]) + mux + len(value).to_bytes(4, "little"))
    assert answer[0] == 0x60, answer.hex()
    toggle = 0
    for at in range(0, len(value), 7):
        part = value[at:at + 7]
        last = at + 7 >= len(value)
        bus.send(0x600 + node, bytes([(toggle << 4) | ((7 - len(part)) << 1) | int(last)]) + part.ljust(7, b"\0"))
        _, _, answer = bus.expect(lambda i, d: i == 0x580 + node, 5.0, "SDO segment answer")
        assert answer[0] == 0x20 | (toggle << 4), answer.hex()
        toggle ^= 1


def test_get_shows_a_string_written_over_sdo_escaped(tmp_path):
    """ESC[2J written into the Buerkert's 0x2002:03 (VISIBLE_STRING) by an SDO client: the text `get` shows it as
    "\\x1b[2J", never the raw ESC that clears the operator's screen; a longer value with a backslash, a quote, a line
    break, DEL, a UTF-8 C1 control and a byte that is no UTF-8 is shown as a C string, every byte recoverable. JSON
    `get` keeps the value itself (jansson writes the ESC as \\u001b)."""
    emu = TextEmulator(tmp_path, "buerkert:18")
    emu.bus.expect(lambda i, d: i == 0x712 and d == b"\0", 10.0, "boot-up of node 18")
    sdo_download(emu.bus, 18, 0x2002, 3, b"\x1b[2J")
    emu.command("get 18 0x2002:03")
    emu.command('{"id":1,"cmd":"get","node":18,"object":"0x2002:03"}')
    time.sleep(0.3)  # the answers above come before the next value is written
    sdo_download(emu.bus, 18, 0x2002, 3, b'a\\b"c\nd\x7f\xc2\x9b\xff')
    emu.command("get 18 0x2002:03")
    time.sleep(0.3)
    sdo_download(emu.bus, 18, 0x2002, 3, b"x\xc2\x9b2Jy")  # valid UTF-8 holding a C1 CSI (U+009B)
    emu.command('{"id":3,"cmd":"get","node":18,"object":"0x2002:03"}')
    out, _ = emu.quit()
    lines = out.split(b"\n")
    c1 = next(line for line in lines if line.startswith(b'{"id":3'))
    assert b'"value":"x\\u009B2Jy"' in c1, c1  # JSON answers are ASCII: no raw C1 control either
    assert json.loads(c1)["value"] == "x\u009b2Jy"
    assert b'node 18: 0x2002:03 = "\\x1b[2J"' in lines, out
    assert b'node 18: 0x2002:03 = "a\\\\b\\"c\\x0ad\\x7f\\xc2\\x9b\\xff"' in lines, out
    answer = next(json.loads(line) for line in lines if line.startswith(b'{"id":1'))
    assert answer["value"] == "\x1b[2J", answer
    assert raw_controls_in(out) == [], out


def test_log_and_events_escape_what_they_show(tmp_path):
    """A device read from an EDS takes its name from the file's: one named with ESC[2J and a C1 CSI (U+009B) appears
    in the log (stderr), in the text events (`subscribe nmt`) and in the JSON events. The log and the text lines show
    both as \\x escapes; JSON shows them as \\u escapes (ASCII only), so a terminal that shows a raw event stream does
    not act on them either."""
    name = "evil\x1b[2J\u009b.eds"
    eds = tmp_path / name
    shutil.copyfile(SRC / "od" / "buerkert-flow-controller.eds", eds)
    # A second one: UTF-8 of a printable character stays (ü), bytes that are no UTF-8 are escaped one by one (0xFF,
    # the overlong C0 80, the surrogate ED A0 80), and so are a CR and a TAB.
    odd = tmp_path / os.fsdecode(b"m\xc3\xbcnchen\xff\xc0\x80\xed\xa0\x80\r\t.eds")
    shutil.copyfile(eds, odd)
    emu = TextEmulator(tmp_path, f"{eds}:5", f"{os.fsdecode(odd)}:6")
    emu.bus.expect(lambda i, d: i == 0x705 and d == b"\0", 10.0, "boot-up of node 5")
    emu.command("subscribe nmt")
    time.sleep(0.3)
    emu.bus.send(0x000, bytes([0x01, 0x05]))  # NMT start node 5: an event and a log line
    emu.bus.expect(lambda i, d: i == 0x705 and d == b"\x05", 5.0, "heartbeat of node 5 in Operational")
    emu.command('{"id":2,"cmd":"subscribe","events":["nmt"]}')
    time.sleep(0.3)
    emu.bus.send(0x000, bytes([0x80, 0x05]))  # to Pre-operational: a JSON event
    emu.bus.expect(lambda i, d: i == 0x705 and d == b"\x7f", 5.0, "heartbeat of node 5 in Pre-operational")
    time.sleep(0.3)
    out, err = emu.quit()
    shown = b"evil\\x1b[2J\\xc2\\x9b.eds"
    assert b"node 5 (" + shown + b"): NMT PRE-OPERATIONAL -> OPERATIONAL" in err, err
    assert b"node 6 (m\xc3\xbcnchen\\xff\\xc0\\x80\\xed\\xa0\\x80\\x0d\\x09.eds): NMT INITIALISING" in err, err
    assert raw_controls_in(err) == [], err
    text_events = [line for line in out.split(b"\n") if line.startswith(b"event nmt ")]
    assert text_events and all(b"(" + shown + b"): NMT" in line for line in text_events), out
    json_events = [line for line in out.split(b"\n") if line.startswith(b'{"event":"nmt"')]
    assert json_events, out
    assert all(b'"device":"evil\\u001B[2J\\u009B.eds"' in line for line in json_events), json_events
    assert json.loads(json_events[-1])["device"] == name
    assert raw_controls_in(out) == [], out


def test_wrong_number_of_arguments_says_what_the_command_takes(tmp_path):
    """D15: a command the node knows, with too few or too many words, is answered with what it takes (the usage of
    the command table or the device's help), not "unknown command"; a word that is no command still is unknown."""
    emu = TextEmulator(tmp_path, "buerkert:18")
    emu.bus.expect(lambda i, d: i == 0x712 and d == b"\0", 10.0, "boot-up of node 18")
    for line in ("get 18", "set 18 0x1017", "show 18 extra", "get 18 0x1017 extra", "emcy 18", "power-cycle 18 now",
                 "mode 18", "status 18 all", "supply 18", "flow-fault 18 on now", "get", "set", "frobnicate 18"):
        emu.command(line)
    out, _ = emu.quit()
    lines = out.decode().splitlines()
    for expected in ("node 18: error: get takes INDEX[:SUB]",
                     "node 18: error: set takes INDEX[:SUB] VALUE",
                     "node 18: error: show takes no arguments",
                     "node 18: error: emcy takes CODE [REGISTER [B0..B4]]",
                     "node 18: error: power-cycle takes no arguments",
                     "node 18: error: mode takes auto|hand|flashing",  # the Buerkert's own help
                     "node 18: error: status takes no arguments",
                     "node 18: error: supply takes VOLTS",
                     "node 18: error: flow-fault takes on|off",
                     "error: get takes NODE INDEX[:SUB]",  # the command table's usage when even NODE is missing
                     "error: set takes NODE INDEX[:SUB] VALUE",
                     "node 18: error: unknown command 'frobnicate' (try help 18)"):
        assert expected in lines, (expected, lines)
    assert lines.count("node 18: error: get takes INDEX[:SUB]") == 2, lines  # too few and too many
    assert not any("unknown command" in line for line in lines if "frobnicate" not in line), lines
