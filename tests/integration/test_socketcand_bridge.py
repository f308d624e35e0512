"""canopen-emu as a socketcand bridge to a SocketCAN interface (-i vcan0 --socketcand 127.0.0.1:0, docs/buses.md):
a python-can socketcand client on channel vcan0 and a python-can socketcan bus on vcan0 exchange standard and
extended frames both ways, exactly, and a python-canopen master on socketcand reads a node by SDO, its frames on the
interface too. The listening port is 0 (any free one), taken from the emulator's log line."""
import re
import time

import can
import canopen
import pytest

from conftest import EDS, IFACE, Deadline, open_bus

pytestmark = [pytest.mark.socketcan]  # a kernel interface bridged

HOST = "127.0.0.1"


def serve(emulator, *devices):
    emu = emulator("--socketcand", f"{HOST}:0", *devices)
    pattern = re.compile(r"socketcand: listening on 127\.0\.0\.1:(\d+): every bus is a channel of its name")
    deadline = Deadline(5)
    port = deadline.until(lambda: next((int(m.group(1)) for m in map(pattern.search, emu.err_lines) if m), None))
    assert port, emu.describe()
    return emu, port


def receive(bus, count, ignore=(), timeout=3.0):
    """The next `count` frames a bus receives, besides those with IDs in `ignore` (heartbeats)."""
    got, deadline = [], Deadline(timeout)
    while len(got) < count and not deadline.expired():
        msg = bus.recv(deadline.slice())
        if msg is not None and msg.arbitration_id not in ignore:
            got.append(msg)
    return got


def shape(msgs):
    return [(m.arbitration_id, m.is_extended_id, m.is_remote_frame, m.dlc, bytes(m.data)) for m in msgs]


@pytest.fixture
def buses():
    opened = []
    yield opened
    for bus in opened:
        bus.shutdown()


def test_frames_cross_between_socketcand_and_the_interface(emulator, buses):
    """Standard and extended, data and remote frames, each exactly once, both ways. A client's 29-bit frame used to
    reach vcan0 as an 11-bit one of its low bits (0x1ABCDEF0 as 0x6F0; 0x1F000601 would have been an SDO request
    to node 1): the SocketCAN send dropped the format."""
    emu, port = serve(emulator, "sds:16")
    wire = open_bus()
    buses.append(wire)
    client = can.Bus(interface="socketcand", channel=IFACE, host=HOST, port=port)
    buses.append(client)
    time.sleep(0.2)  # a new rawmode client's frames wait 100 ms
    to_wire = [can.Message(arbitration_id=0x123, is_extended_id=False, data=b"\x01\x02\x03"),
               can.Message(arbitration_id=0x1ABCDEF0, is_extended_id=True, data=bytes(range(8))),
               can.Message(arbitration_id=0x7FF, is_extended_id=False, data=b""),
               can.Message(arbitration_id=0x00000005, is_extended_id=True, data=b"\xff"),
               can.Message(arbitration_id=0x1F000601, is_extended_id=True, is_remote_frame=True, dlc=2),
               can.Message(arbitration_id=0x234, is_extended_id=False, is_remote_frame=True, dlc=1)]
    for msg in to_wire:
        client.send(msg)
    assert shape(receive(wire, len(to_wire), ignore={0x710})) == shape(to_wire)
    assert receive(wire, 1, ignore={0x710}, timeout=0.3) == []  # once each

    to_client = [can.Message(arbitration_id=0x456, is_extended_id=False, data=b"\xaa\xbb"),
                 can.Message(arbitration_id=0x12345678, is_extended_id=True, data=b"\x00\x11\x22\x33\x44"),
                 can.Message(arbitration_id=0x001, is_extended_id=False, data=b"")]
    for msg in to_client:
        wire.send(msg)
    got = receive(client, len(to_client), ignore={0x710})
    assert shape(got) == shape(to_client)
    assert all(m.channel == IFACE for m in got)
    assert receive(client, 1, ignore={0x710}, timeout=0.3) == []  # once each, and not the client's own frames
    emu.stop()
    assert not [line for line in emu.err_lines if "did not reach the bus's medium" in line], emu.describe()


def test_python_canopen_on_socketcand_reads_a_node_of_the_bridged_interface(emulator, buses, capture):
    emu, port = serve(emulator, "sds:16")
    capture.wait_for(0x710, data=b"\x00", timeout=3)  # the boot-up
    network = canopen.Network()
    network.connect(interface="socketcand", channel=IFACE, host=HOST, port=port)
    try:
        node = canopen.RemoteNode(16, str(EDS["sds"]))
        node.sdo.RESPONSE_TIMEOUT = 5.0
        network.add_node(node)
        since = time.time()
        assert node.sdo.upload(0x1018, 1) == (0x24E).to_bytes(4, "little")
        assert node.sdo.upload(0x1008, 0) == b"SDS"
    finally:
        network.disconnect()
    # the master's requests went out on vcan0 and the node's answers are there as well
    requests = capture.wait_for(0x610, count=2, since=since)
    answers = capture.wait_for(0x590, count=2, since=since)
    assert [bytes(m.data) for m in requests] == [bytes([0x40, 0x18, 0x10, 0x01, 0, 0, 0, 0]),
                                                 bytes([0x40, 0x08, 0x10, 0x00, 0, 0, 0, 0])]
    assert [bytes(m.data) for m in answers] == [bytes([0x43, 0x18, 0x10, 0x01, 0x4E, 0x02, 0, 0]),
                                                bytes([0x47, 0x08, 0x10, 0x00]) + b"SDS\x00"]  # 3 bytes
    assert emu.proc.poll() is None
