"""canopen-emu as a whole program without CAN: its CAN channel is a test double (socketcan_unix.c) that carries
frames over a Unix socket to this test, every other part is the program's own (nodes, device models, NVM files,
control commands, main loop). In the ASan+UBSan build this is how the program, not only the core, is checked by
the sanitizers in CI (they cannot run inside User-Mode Linux, where the vcan suite runs).

Environment (tests/native/CMakeLists.txt): CO_SOURCE_DIR, CO_EMU_FAKECAN (the program), CO_SANITIZED.
"""

import configparser
import fcntl
import os
import queue
import random
import select
import socket
import struct
import subprocess
import threading
import time
from pathlib import Path

import pytest

SRC = Path(os.environ.get("CO_SOURCE_DIR") or Path(__file__).resolve().parents[2])
EMU = os.environ.get("CO_EMU_FAKECAN")
FRAME = struct.Struct("<IB3x8s")  # struct can_frame
NODES = {16: "pro-ionizer", 17: "sds", 18: "buerkert"}
EDS = {"pro-ionizer": "pro-ionizer.eds", "sds": "sds.eds", "buerkert": "buerkert-flow-controller.eds"}
SANITIZER_MARKS = ("ERROR: AddressSanitizer", "ERROR: LeakSanitizer", "runtime error:", "SUMMARY: UndefinedBehaviorSanitizer")


class FakeBus:
    """The test's end of the fake bus: frames the emulator sends arrive in a queue with their arrival time."""

    def __init__(self, path):
        self.listener = socket.socket(socket.AF_UNIX, socket.SOCK_SEQPACKET)
        self.listener.bind(str(path))
        self.listener.listen(1)
        self.conn = None
        self.frames = queue.Queue()
        self.reader = None
        self.proc = None  # the emulator: a wait that fails says whether it died, and why

    def accept(self, timeout=10.0):
        self.listener.settimeout(timeout)
        self.conn, _ = self.listener.accept()
        self.reader = threading.Thread(target=self._read, daemon=True)
        self.reader.start()

    def _read(self):
        while True:
            try:
                data = self.conn.recv(64)
            except OSError:
                return
            if not data:
                return
            can_id, dlc, payload = FRAME.unpack(data)
            self.frames.put((time.monotonic(), can_id, bytes(payload[:dlc])))

    def send(self, can_id, data):
        self.conn.send(FRAME.pack(can_id, len(data), bytes(data).ljust(8, b"\0")))

    def expect(self, pred, timeout=5.0, what="frame"):
        """The first frame for which pred(can_id, data) holds; frames before it are dropped."""
        end = time.monotonic() + timeout
        while True:
            left = end - time.monotonic()
            if left <= 0:
                if self.proc is not None and self.proc.poll() is not None:
                    raise AssertionError(f"no {what}: canopen-emu ended with status {self.proc.returncode}:\n"
                                         + self.proc.stderr.read()[-6000:])
                raise AssertionError(f"no {what} within {timeout} s")
            try:
                t, can_id, data = self.frames.get(timeout=left)
            except queue.Empty:
                continue
            if pred(can_id, data):
                return t, can_id, data

    def sdo(self, node, request, timeout=5.0):
        self.send(0x600 + node, request)
        return self.expect(lambda i, d: i == 0x580 + node and d[1:4] == bytes(request[1:4]), timeout,
                           f"SDO answer of node {node} to {bytes(request).hex()}")[2]

    def close(self):
        for s in (self.conn, self.listener):
            if s is not None:
                s.close()


def vendor_id(device):
    eds = configparser.ConfigParser(strict=False, interpolation=None)
    eds.read(SRC / "od" / EDS[device], encoding="utf-8")
    return int(eds["1018sub1"]["DefaultValue"], 0)


def upload(index, sub):
    return bytes([0x40, index & 0xFF, index >> 8, sub, 0, 0, 0, 0])


def download(index, sub, value, size):
    return bytes([0x23 | ((4 - size) << 2), index & 0xFF, index >> 8, sub]) + value.to_bytes(size, "little").ljust(4, b"\0")


def start_program(tmp_path, *args):
    """canopen-emu-fakecan with args (after -i fakecan0 --control -) on a fake bus of its own, under the sanitizers'
    options of the ASan+UBSan build: (bus, process). The caller lets the bus accept it."""
    if not EMU:
        pytest.fail("CO_EMU_FAKECAN is not set (the test is run by ctest: tests/native/CMakeLists.txt)", pytrace=False)
    bus = FakeBus(tmp_path / f"bus-{time.monotonic_ns()}")
    env = dict(os.environ, CO_FAKECAN_SOCKET=bus.listener.getsockname(),
               ASAN_OPTIONS="detect_leaks=1:abort_on_error=0:halt_on_error=1",
               UBSAN_OPTIONS="halt_on_error=1:print_stacktrace=1")
    proc = subprocess.Popen([EMU, "-i", "fakecan0", "--control", "-", *args], stdin=subprocess.PIPE,
                            stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True, env=env)
    bus.proc = proc
    return bus, proc


class Emulator:
    def __init__(self, tmp_path, nvm):
        self.bus, self.proc = start_program(tmp_path, "--nvm-dir", str(nvm),
                                            *[f"{d}:{n}" for n, d in NODES.items()])
        self.bus.accept()

    def command(self, line):
        self.proc.stdin.write(line + "\n")
        self.proc.stdin.flush()

    def quit(self, timeout=20.0):
        """quit; returns (exit status, stderr); fails on any sanitizer report."""
        self.command("quit")
        try:
            out, err = self.proc.communicate(timeout=timeout)
        except subprocess.TimeoutExpired:
            self.proc.kill()
            out, err = self.proc.communicate()
            raise AssertionError("canopen-emu did not end after quit:\n" + err[-3000:])
        finally:
            self.bus.close()
        assert not any(mark in err for mark in SANITIZER_MARKS), err[-6000:]
        return self.proc.returncode, err


def test_whole_program_runs_clean(tmp_path):
    """Three devices in one process: boot-ups, identity uploads answered with the EDS vendor IDs, a stored
    heartbeat, NMT start, an EMCY raised by a control command, 3,000 random frames to every COB-ID, and quit
    with status 0; then a second run loads the stored heartbeat. Under ASan+UBSan any report fails it."""
    nvm = tmp_path / "nvm"
    emu = Emulator(tmp_path, nvm)
    bus = emu.bus
    booted = set()
    while booted != set(NODES):
        _, can_id, data = bus.expect(lambda i, d: 0x700 < i <= 0x77F and d == b"\0", 10.0, "boot-up")
        booted.add(can_id - 0x700)
    for node, device in NODES.items():
        assert bus.sdo(node, upload(0x1018, 1)) == bytes([0x43, 0x18, 0x10, 0x01]) + struct.pack("<I", vendor_id(device))
    assert bus.sdo(16, download(0x1017, 0, 1500, 2))[0] == 0x60
    assert bus.sdo(16, download(0x1010, 1, 0x65766173, 4))[0] == 0x60  # "save"
    bus.send(0x000, bytes([0x01, 0x00]))  # NMT start all
    t1, _, d1 = bus.expect(lambda i, d: i == 0x710 and d == b"\x05", 5.0, "heartbeat of node 16 in Operational")
    t2, _, _ = bus.expect(lambda i, d: i == 0x710 and d == b"\x05", 5.0, "second heartbeat of node 16")
    assert 1.0 <= t2 - t1 <= 3.0, t2 - t1  # 1500 ms by the stored value (not the 1000 ms default); loose bounds
    emu.command("emcy 16 0x3210 0x05")
    _, _, emcy = bus.expect(lambda i, d: i == 0x090, 5.0, "EMCY of node 16")
    assert emcy[:3] == bytes([0x10, 0x32, 0x05]), emcy.hex()
    rng = random.Random(1212)
    for _ in range(3000):
        can_id = rng.randrange(0x800)
        if can_id == 0x000:
            continue  # NMT: a reset would restart the nodes (tested elsewhere), not what this run looks at
        bus.send(can_id, bytes(rng.randrange(256) for _ in range(rng.randrange(9))))
    for node, device in NODES.items():  # still answering, correctly
        assert bus.sdo(node, upload(0x1018, 1), 10.0)[4:] == struct.pack("<I", vendor_id(device))
    status, err = emu.quit()
    assert status == 0, err[-3000:]

    emu = Emulator(tmp_path, nvm)
    emu.bus.expect(lambda i, d: i == 0x710 and d == b"\0", 10.0, "boot-up of node 16 again")
    assert emu.bus.sdo(16, upload(0x1017, 0))[4:6] == struct.pack("<H", 1500)
    status, err = emu.quit()
    assert status == 0, err[-3000:]


def test_blocked_output_and_refused_input_run_clean(tmp_path):
    """The paths of the output buffers and the line reader under the sanitizers (the vcan suite holds their
    behaviour, test_output_and_input.py): -v with stdout and stderr on one pipe of one page that is not read while
    1,500 SDO requests and a help reply every 10 go through (lines dropped and counted), then read (written, and
    the drops reported); an overlong stdin line, a NUL byte, too many words; quit with status 0."""
    read_end, write_end = os.pipe()
    fcntl.fcntl(write_end, fcntl.F_SETPIPE_SZ, 4096)
    bus = FakeBus(tmp_path / "bus")
    env = dict(os.environ, CO_FAKECAN_SOCKET=bus.listener.getsockname(),
               ASAN_OPTIONS="detect_leaks=1:abort_on_error=0:halt_on_error=1",
               UBSAN_OPTIONS="halt_on_error=1:print_stacktrace=1")
    proc = subprocess.Popen([EMU, "-v", "-i", "fakecan0", "--nvm-dir", str(tmp_path / "nvm"), "--control", "-",
                             "sds:17"], stdin=subprocess.PIPE, stdout=write_end, stderr=write_end, env=env)
    os.close(write_end)
    chunks = []

    def read_for(seconds):
        end = time.monotonic() + seconds
        while time.monotonic() < end:
            ready, _, _ = select.select([read_end], [], [], 0.05)
            if ready:
                data = os.read(read_end, 1 << 16)
                if not data:
                    return
                chunks.append(data)

    try:
        bus.accept()
        bus.expect(lambda i, d: i == 0x711 and d == b"\0", 10.0, "boot-up of node 17")
        for k in range(1500):
            assert bus.sdo(17, upload(0x1018, 1))[4:] == struct.pack("<I", vendor_id("sds"))
            if k % 10 == 0:
                proc.stdin.write(b"help 17\n")
                proc.stdin.flush()
        read_for(1.0)  # the buffers drain: what follows is not dropped
        proc.stdin.write(b"#" + b"x" * 3000 + b" quit\nshow 17\0 quit\n" + b"show 17" + b" x" * 16 + b"\n")
        proc.stdin.flush()
        assert bus.sdo(17, upload(0x1018, 1))[4:] == struct.pack("<I", vendor_id("sds"))  # still running
        read_for(0.5)
        proc.stdin.write(b"quit\n")
        proc.stdin.flush()
        read_for(20.0)
        assert proc.wait(timeout=10) == 0
    finally:
        if proc.poll() is None:
            proc.kill()
            proc.wait()
        os.close(read_end)
        bus.close()
    text = b"".join(chunks).decode(errors="replace")
    assert not any(mark in text for mark in SANITIZER_MARKS), text[-6000:]
    for expected in ("dropped: output blocked (stderr was not read)", "dropped in all: output blocked",
                     "error: stdin line", "holds a NUL byte: ignored", "error: too many words (at most 16)"):
        assert expected in text, (expected, text[-3000:])


def test_sanitizers_are_on_where_they_should_be():
    """In the ASan+UBSan build the program must carry the sanitizer runtime, or the test above proves nothing."""
    if os.environ.get("CO_SANITIZED") not in ("1", "ON", "TRUE", "true"):
        pytest.skip("not the sanitizer build")
    out = subprocess.run(["nm", "-D", "--undefined-only", EMU], capture_output=True, text=True).stdout + \
        subprocess.run(["nm", EMU], capture_output=True, text=True).stdout
    assert "__asan_init" in out or "__asan_report_load" in out, "canopen-emu-fakecan is not built with ASan"


def test_control_sockets_and_faults_run_clean(tmp_path):
    """The control sockets, the JSON framing, the subscriptions and the protocol faults under the sanitizers (the vcan
    suite holds their behaviour: test_control_socket.py, test_faults.py): 20 clients with JSON and text requests,
    malformed and overlong lines, NUL bytes and random bytes, clients that vanish mid-line, one that subscribes to
    every frame and never reads until its events cut it off (its own requests wait meanwhile), faults that hold, change and drop frames while SDO traffic
    runs; quit by JSON with status 0."""
    import json
    ctl = tmp_path / "ctl.sock"
    bus = FakeBus(tmp_path / "bus")
    env = dict(os.environ, CO_FAKECAN_SOCKET=bus.listener.getsockname(),
               ASAN_OPTIONS="detect_leaks=1:abort_on_error=0:halt_on_error=1",
               UBSAN_OPTIONS="halt_on_error=1:print_stacktrace=1")
    proc = subprocess.Popen([EMU, "-i", "fakecan0", "--nvm-dir", str(tmp_path / "nvm"), "--control-socket", str(ctl),
                             "--control-tcp", "127.0.0.1:0"] + [f"{d}:{n}" for n, d in NODES.items()],
                            stdin=subprocess.DEVNULL, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True, env=env)
    bus.proc = proc
    rng = random.Random(4711)
    try:
        bus.accept()
        bus.expect(lambda i, d: i == 0x712 and d == b"\0", 10.0, "boot-up of node 18")
        deadline = time.monotonic() + 10
        while not ctl.exists() and time.monotonic() < deadline:
            time.sleep(0.01)
        greedy = socket.socket(socket.AF_UNIX)
        greedy.setsockopt(socket.SOL_SOCKET, socket.SO_RCVBUF, 4096)
        greedy.connect(str(ctl))
        greedy.sendall(b'{"cmd":"subscribe","events":["frame"],"frames":"0x000/0x000"}\n'
                       b'subscribe all\n' + b"help 16\n" * 2000)
        requests = [
            {"cmd": "hello"}, {"cmd": "list"}, {"cmd": "show", "node": "all"},
            {"cmd": "get", "node": 16, "object": "0x1018:01"}, {"cmd": "get", "node": 17, "object": "0x1008"},
            {"cmd": "set", "node": 18, "object": "0x1017", "value": 250}, {"cmd": "set", "node": 16, "object": 4119, "value": "x"},
            {"cmd": "subscribe", "events": "all", "nodes": [16, 18]}, {"cmd": "unsubscribe"},
            {"cmd": "fault", "node": 16, "args": ["sdo-delay", 30]}, {"cmd": "fault", "node": 17, "args": ["heartbeat-jitter", 20]},
            {"cmd": "fault", "node": 18, "args": ["tpdo-freeze", 1]}, {"cmd": "fault", "node": 17, "args": ["emcy-burst", 10]},
            {"cmd": "fault", "node": 18, "args": ["bus-off", 50]}, {"cmd": "fault", "node": 16, "args": ["sdo-ignore", "50%", 3]},
            {"cmd": "fault", "node": 17, "args": ["reboot"]}, {"cmd": "faults", "node": 16},
            {"cmd": "fault-clear", "node": "all"}, {"cmd": "emcy", "node": 16, "args": ["0x3210", 5]},
            {"cmd": "power-cycle", "node": 18}, {"cmd": "status", "node": 16},
        ]
        clients = []
        for k in range(20):
            c = socket.socket(socket.AF_UNIX)
            c.connect(str(ctl))
            clients.append(c)
        for round_ in range(3):
            for k, c in enumerate(clients):
                lines = [json.dumps(rng.choice(requests)).encode() for _ in range(5)]
                lines.append(bytes(rng.randrange(1, 256) for _ in range(rng.randrange(1, 300))).replace(b"\n", b" "))
                lines += [b"{bad json", b'{"cmd":"get","node":16,"object":"0x1017","x":' + b"1" * 5000 + b"}",
                          b'{"cmd":"li\0st"}', b"get 16 0x1017", b"fault 16 weather", b"list"]
                rng.shuffle(lines)
                c.sendall(b"\n".join(lines) + b"\n")
            for node in NODES:
                bus.send(0x600 + node, upload(0x1018, 1))
            time.sleep(0.2)
        # the greedy client's "help" lines wait while its answers wait unread (they cost no work); the frame events
        # it subscribed to (text lines of some 50 bytes since its `subscribe all`) pile up until it is cut off
        for k in range(60000):
            bus.send(0x7E0, k.to_bytes(4, "little"))
        watch = select.poll()  # the emulator closes it: its end of the socket hangs up (nothing of it is read here)
        watch.register(greedy, select.POLLRDHUP)
        assert watch.poll(20000), "the greedy client was not cut off"
        clients[0].sendall(b'{"cmd":"set","node":16,"object":"0x1017","va')  # vanishes mid-line
        clients[0].close()
        for c in clients[1:]:
            c.setblocking(False)
            try:
                while c.recv(1 << 16):
                    pass
            except BlockingIOError:
                pass
        quitter = socket.socket(socket.AF_UNIX)
        quitter.connect(str(ctl))
        quitter.sendall(b'{"id":"bye","cmd":"quit"}\n')
        out, err = proc.communicate(timeout=30)
        quitter.close()
        greedy.close()
        for c in clients[1:]:
            c.close()
    finally:
        if proc.poll() is None:
            proc.kill()
            proc.communicate()
        bus.close()
    assert not any(mark in err for mark in SANITIZER_MARKS), err[-6000:]
    assert proc.returncode == 0, err[-3000:]
    assert "disconnected: it left more than 1048576 bytes unread" in err, err[-3000:]
    assert not ctl.exists()
