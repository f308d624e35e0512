"""Fixtures of the integration suite: the bus under test, the canopen-emu program started with the devices a test
asks for, python-canopen as the master, and a capture of every frame on the bus with its time.

The bus is CO_TEST_BUS: `socketcan` (vcan0, made by tools/vcan-run: tests/integration/CMakeLists.txt runs the tests
marked socketcan so, the kernel's own behaviour) or `udp_multicast` (python-can's udp_multicast on loopback, TTL 0,
inside tests/udp/netns-run's network namespace of its own; every test not marked socketcan runs so, natively, no
User-Mode Linux). Time stamps are the kernel's on both: SocketCAN's receive time, SO_TIMESTAMPNS of the datagram."""
import os
import socket
import subprocess
import threading
import time
from pathlib import Path

import can
import can.interfaces.udp_multicast
import can.interfaces.udp_multicast.utils
import canopen
import pytest

SRC = Path(os.environ.get("CO_SOURCE_DIR", Path(__file__).resolve().parents[2]))
EMU = os.environ.get("CO_EMU", "")
SANITIZER_MARKS = ("ERROR: AddressSanitizer", "ERROR: LeakSanitizer", "runtime error:",
                   "SUMMARY: UndefinedBehaviorSanitizer")
BUS_KIND = os.environ.get("CO_TEST_BUS", "socketcan")
IFACE = os.environ.get("CO_VCAN_IFACE", "vcan0")
UDP_GROUP, UDP_PORT = "239.74.163.2", 43113  # python-can's defaults: the test's own namespace has nobody else
if BUS_KIND == "socketcan":
    BUS_NAME = IFACE                              # the bus's name in the emulator's log, events and answers
    BUS_ARG = IFACE                               # canopen-emu's -i
elif BUS_KIND == "udp_multicast":
    BUS_NAME = f"udp_multicast:{UDP_GROUP}:{UDP_PORT}"
    BUS_ARG = f"{BUS_NAME},ttl=0"
else:
    raise RuntimeError(f"CO_TEST_BUS={BUS_KIND!r}: socketcan or udp_multicast")
EDS = {"pro-ionizer": SRC / "od/pro-ionizer.eds", "sds": SRC / "od/sds.eds",
       "buerkert": SRC / "od/buerkert-flow-controller.eds"}


class Deadline:
    """A timeout for waiting on the emulator that does not count time in which this process could not run.

    A loaded CI host now and then stalls the whole User-Mode Linux guest (more than 2 s was seen); time.monotonic()
    runs on meanwhile, and a plain deadline then expires although nobody, the emulator included, got to run. A
    check that comes more than STALL_S after the previous one adds that gap to the deadline, up to MAX_EXTENSION_S
    in all, so that a wait for something that never comes still ends. Waits using it block at most POLL_S at a
    time. It only lengthens waits for things that must happen: timing is judged by frame time stamps."""

    STALL_S = 0.25
    MAX_EXTENSION_S = 30.0
    POLL_S = 0.05

    def __init__(self, seconds):
        self.seconds = seconds
        self.last = time.monotonic()
        self.end = self.last + seconds
        self.extended = 0.0

    def left(self):
        """Seconds left (0 when expired)."""
        now = time.monotonic()
        gap = now - self.last
        if gap > self.STALL_S and self.extended < self.MAX_EXTENSION_S:
            add = min(gap, self.MAX_EXTENSION_S - self.extended)
            self.end += add
            self.extended += add
        self.last = now
        return max(0.0, self.end - now)

    def expired(self):
        return self.left() <= 0.0

    def slice(self):
        """How long the next blocking step may take."""
        return min(self.left(), self.POLL_S)

    def until(self, check, step=0.01):
        """Calls check() every `step` seconds until it returns something true or the deadline has passed (checked
        once more after that); returns its last result."""
        while True:
            result = check()
            if result or self.expired():
                return result
            time.sleep(step)

    def __str__(self):
        return f"{self.seconds} s" + (f" (+{self.extended:.1f} s of stalls)" if self.extended else "")


class Capture(can.Listener):
    """Every frame seen on the bus, with the receive time."""

    def __init__(self):
        self.frames = []
        self.lock = threading.Lock()

    def on_message_received(self, msg):
        with self.lock:
            self.frames.append(msg)

    def clear(self):
        with self.lock:
            self.frames.clear()

    def matching(self, can_id, since=0.0):
        with self.lock:
            return [m for m in self.frames if m.arbitration_id == can_id and not m.is_error_frame
                    and m.timestamp >= since]

    def wait_for(self, can_id, count=1, timeout=2.0, since=0.0, data=None, prefix=None):
        """At least count frames can_id since `since` (with exactly `data`, or starting with `prefix`)."""
        def fits(m):
            return (data is None or bytes(m.data) == data) and (prefix is None or bytes(m.data).startswith(prefix))
        def enough():
            got = [m for m in self.matching(can_id, since) if fits(m)]
            return got if len(got) >= count else None
        deadline = Deadline(timeout)
        got = deadline.until(enough)
        if got:
            return got
        got = [m for m in self.matching(can_id, since) if fits(m)]
        raise AssertionError(f"expected {count} frame(s) 0x{can_id:03X}{' ' + data.hex() if data else ''} within "
                             f"{deadline}, saw {[(hex(m.arbitration_id), bytes(m.data).hex()) for m in got]}")


# SO_RCVBUFFORCE (Linux, needs CAP_NET_ADMIN) may exceed net.core.rmem_max; SO_RCVBUF is capped by it.
SO_RCVBUFFORCE = getattr(socket, "SO_RCVBUFFORCE", 33)


def deep_receive_buffer(bus, size=4 << 20):
    """A master's receive thread may stall for a second (python's GIL, a loaded CI machine, User-Mode Linux's
    single CPU) while 127 emulated nodes keep sending heartbeats: with the default buffer (~200 KiB, a few
    hundred frames) the kernel then drops frames, SDO answers among them. A real master would not lose them,
    so the test's sockets get a deeper buffer."""
    sock = bus.socket
    try:
        sock.setsockopt(socket.SOL_SOCKET, SO_RCVBUFFORCE, size)
    except OSError:
        sock.setsockopt(socket.SOL_SOCKET, socket.SO_RCVBUF, size)


class LoopbackUdpBus(can.interfaces.udp_multicast.UdpMulticastBus):
    """python-can's udp_multicast bus as a SocketCAN socket behaves: it does not receive what it sent itself.

    python-can's bus sends from the socket that receives (group port, multicast loop on) and so reads its own
    datagrams back, a frame a vcan socket never sees; a test that sends and captures on one bus would count them.
    This one sends from a socket of its own port (TTL 0: nothing leaves the machine) and drops datagrams from it."""

    def __init__(self, channel=UDP_GROUP, port=UDP_PORT, **kwargs):
        super().__init__(channel=channel, port=port, hop_limit=0, **kwargs)
        self.socket = self._multicast._socket  # for deep_receive_buffer
        self._tx = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
        self._tx.setsockopt(socket.IPPROTO_IP, socket.IP_MULTICAST_TTL, 0)
        self._tx.bind(("127.0.0.1", 0))
        self._own_port = self._tx.getsockname()[1]
        self._group = (channel, port)

    def _recv_internal(self, timeout):
        result = self._multicast.recv(timeout)
        if not result or result[1][1] == self._own_port:
            return None, False
        data, _, stamp = result
        return can.interfaces.udp_multicast.utils.unpack_message(data, replace={"timestamp": stamp},
                                                                 check=True), False

    def send(self, msg, timeout=None):
        self.send_datagram(can.interfaces.udp_multicast.utils.pack_message(msg))

    def send_datagram(self, data):
        """A datagram as it is, a malformed one too (tests of bad input)."""
        self._tx.sendto(data, self._group)

    def shutdown(self):
        super().shutdown()
        self._tx.close()


def open_bus(receive_own_messages=False):
    """A python-can bus on the bus under test."""
    if BUS_KIND == "socketcan":
        return can.Bus(channel=IFACE, interface="socketcan", receive_own_messages=receive_own_messages)
    assert not receive_own_messages, "udp_multicast: a bus does not receive its own frames"
    return LoopbackUdpBus()


def pytest_configure(config):
    config.addinivalue_line("markers", "socketcan: tests SocketCAN itself (the kernel interface): run on vcan0 only")
    names = [name for _, name in socket.if_nameindex()]
    if BUS_KIND == "udp_multicast" and names != ["lo"]:
        # multicast of a test must never reach a real network
        raise pytest.UsageError(f"CO_TEST_BUS=udp_multicast runs only inside a network namespace of its own "
                                f"(tests/udp/netns-run), not with interfaces {names}")


@pytest.fixture
def capture():
    bus = open_bus()
    deep_receive_buffer(bus)
    cap = Capture()
    notifier = can.Notifier(bus, [cap], timeout=0.05)
    yield cap
    notifier.stop()
    bus.shutdown()


class Emulator:
    def __init__(self, args, nvm_dir, control=True):
        assert EMU, "CO_EMU (path of canopen-emu) is not set"
        self.args = [EMU, "-i", BUS_ARG, "--nvm-dir", str(nvm_dir)] + (["--control", "-"] if control else []) + list(args)
        self.proc = subprocess.Popen(self.args, stdin=subprocess.PIPE if control else subprocess.DEVNULL,
                                     stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True, bufsize=1)
        self.out_lines, self.err_lines = [], []
        self._threads = [threading.Thread(target=self._pump, args=(self.proc.stdout, self.out_lines), daemon=True),
                         threading.Thread(target=self._pump, args=(self.proc.stderr, self.err_lines), daemon=True)]
        for t in self._threads:
            t.start()

    @staticmethod
    def _pump(stream, lines):
        for line in stream:
            lines.append(line.rstrip("\n"))

    def command(self, line, expect=None, timeout=2.0):
        """Sends a control command; with expect, waits for an output line containing it and returns it."""
        start = len(self.out_lines)
        self.proc.stdin.write(line + "\n")
        self.proc.stdin.flush()
        if expect is None:
            return None
        deadline = Deadline(timeout)
        found = deadline.until(lambda: next((text for text in self.out_lines[start:] if expect in text), None))
        if found is not None:
            return found
        raise AssertionError(f"no output containing {expect!r} after {line!r} within {deadline}; "
                             f"got {self.out_lines[start:]}")

    def log_contains(self, text, timeout=2.0):
        return Deadline(timeout).until(lambda: any(text in line for line in self.err_lines))

    def describe(self, lines=60):
        """For a failure report: whether the process runs, and the end of its log (the lines carry its clock)."""
        rc = self.proc.poll()
        state = "running" if rc is None else f"exited with status {rc}"
        tail = self.err_lines[-lines:]
        skipped = len(self.err_lines) - len(tail)
        return "\n".join([f"{' '.join(self.args)}", f"{state}; stderr{f' (last {lines} lines)' if skipped else ''}:"]
                         + tail)

    def wait(self, timeout=5.0):
        """Waits for the program to end by itself and for its last output lines to be read: the readers run in
        their own threads and may still hold lines when the process is gone."""
        rc = self.proc.wait(timeout=timeout)
        for t in self._threads:
            t.join(timeout=timeout)
        return rc

    def stop(self, sig=None, timeout=5.0):
        if self.proc.poll() is None:
            if sig is None:
                self.proc.terminate()
            else:
                self.proc.send_signal(sig)
        try:
            rc = self.proc.wait(timeout=timeout)
        except subprocess.TimeoutExpired:
            self.proc.kill()
            raise AssertionError("canopen-emu did not stop within %.1f s" % timeout)
        for t in self._threads:
            t.join(timeout=1.0)
        return rc


@pytest.hookimpl(hookwrapper=True)
def pytest_runtest_makereport(item, call):
    """A failed test's report shows each emulator it started, its state and its log: a CI run is seen only
    through its output, and a frame that never came is explained by what the emulator did meanwhile."""
    outcome = yield
    report = outcome.get_result()
    if report.when == "call" and report.failed:
        started = getattr(item, "emulators", [])
        for i, emu in list(enumerate(started, 1))[-3:]:  # the last ones: a test may restart hundreds of times
            report.sections.append((f"canopen-emu #{i} of {len(started)}", emu.describe()))


@pytest.fixture
def emulator(request, tmp_path):
    """emulator(args..., nvm_dir=None) starts canopen-emu; all instances are stopped at the end."""
    started = []
    request.node.emulators = started

    def start(*args, nvm_dir=None, control=True):
        emu = Emulator(args, nvm_dir or tmp_path / "nvm", control)
        started.append(emu)
        return emu

    yield start
    for emu in started:
        emu.stop()
    # the suite also runs with canopen-emu built with ASan+UBSan (tools/run-tests): a report fails the test
    for emu in started:
        reports = [line for line in emu.err_lines if any(mark in line for mark in SANITIZER_MARKS)]
        assert not reports, emu.describe(200)


@pytest.fixture
def network():
    net = canopen.Network(open_bus())
    # Its receive thread waits this long for a frame between looks at whether to stop: 1 s by default, which every
    # test paid again at its end (disconnect joins the thread). The plugin does the same (NOTIFIER_CYCLE_S).
    net.NOTIFIER_CYCLE = 0.05
    net.connect()
    deep_receive_buffer(net.bus)
    yield net
    net.disconnect()


def remote(network, device, node_id, od=None):
    """A python-canopen node for an emulated device; od: an already imported dictionary to share (parsing an
    EDS costs ~0.1 s in User-Mode Linux, too much for 127 nodes)."""
    node = canopen.RemoteNode(node_id, od if od is not None else str(EDS[device]))
    # python-canopen waits 0.3 s for an SDO answer. Inside User-Mode Linux (one virtual CPU shared by the
    # emulator, this master and a capture thread) its receive thread can lag behind a busy bus for longer
    # than that although the answer is on the wire within milliseconds, and a loaded CI host stalled the whole
    # guest for more than 2 s. A lost answer still fails, only later; answer times are the benchmarks' business.
    node.sdo.RESPONSE_TIMEOUT = 5.0
    network.add_node(node)
    return node
