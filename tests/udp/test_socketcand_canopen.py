"""A python-canopen master on python-can's stock socketcand interface against canopen-emu's socketcand server
(--socketcand, docs/buses.md), for the services test_socketcand.py leaves out: SDO block transfer both ways, PDOs
(the TPDO configuration read by SDO, a TPDO carrying the value the emulator has, an RPDO written into the node),
the heartbeat consumer's EMCY for a producer that is a socketcand client, two clients on one channel (frames
exactly once, SDO answers to one client's requests seen by the other's master), and a watching client that sees
each request before its answer, from another client or from the bus's medium. Runs inside a network namespace of
its own (netns-run): nothing leaves lo."""
import struct
import threading
import time

import can
import canopen
import pytest

from udp_support import GROUP, PORT, SRC, Emulator

HOST = "127.0.0.1"
SCD_PORT = 29537
SERVE = f"{HOST}:{SCD_PORT}"
BUERKERT = SRC / "od/buerkert-flow-controller.eds"
ALL_TYPES = SRC / "tests/eds/files/all-types.eds"


@pytest.fixture
def master():
    """master() connects a python-canopen master to the socketcand channel "plant" (once the emulator runs)."""
    opened = []

    def connect():
        net = canopen.Network()
        net.connect(interface="socketcand", channel="plant", host=HOST, port=SCD_PORT)
        opened.append(net)
        return net

    yield connect
    for net in opened:
        net.disconnect()


def start(emulators, tmp_path, *args):
    emu = Emulator(tmp_path, "--socketcand", SERVE, "-i", "virtual:plant", *args)
    emulators.append(emu)
    return emu


def scd_bus(buses):
    bus = can.Bus(interface="socketcand", channel="plant", host=HOST, port=SCD_PORT)
    buses.append(bus)
    return bus


def remote(network, node_id, eds):
    node = canopen.RemoteNode(node_id, str(eds))
    node.sdo.RESPONSE_TIMEOUT = 5.0  # a lost answer still fails, later; a loaded machine may lag 0.3 s
    network.add_node(node)
    return node


def until(check, timeout=10.0, what="condition"):
    end = time.monotonic() + timeout
    while True:
        result = check()
        if result:
            return result
        assert time.monotonic() < end, f"no {what} within {timeout} s"
        time.sleep(0.02)


def collect(bus, ids, marker_id, timeout=5.0):
    """The frames with IDs in `ids` a bus receives until the frame `marker_id` (which the test sends last)."""
    got = []
    end = time.monotonic() + timeout
    while time.monotonic() < end:
        msg = bus.recv(0.1)
        if msg is None:
            continue
        if msg.arbitration_id == marker_id:
            return got
        if msg.arbitration_id in ids:
            got.append(msg)
    raise AssertionError(f"no marker 0x{marker_id:X} within {timeout} s; have {[str(m) for m in got]}")


def get(emu, node_id, obj):
    return emu.control.request("get", node=node_id, object=obj)["value"]


def test_sdo_block_download_and_upload_with_crc(tmp_path, emulators, buses, master):
    """python-canopen's block client (CRC on) writes and reads the Bürkert's 0x2002:01 and a 64-byte DOMAIN of a
    device from an EDS through the socketcand server; a second client watching the channel sees the CiA 301 block
    protocol (not a segmented fall-back): the initiates C6/A4, the segments 01..85, the ends."""
    emu = start(emulators, tmp_path, "buerkert:18", f"{ALL_TYPES}:33")
    network = master()
    watcher = scd_bus(buses)
    time.sleep(0.2)  # the server holds a new rawmode client's frames for 100 ms
    node = remote(network, 18, BUERKERT)
    name = b"flow controller, line 7, bay 3"  # 30 bytes: five segments, 5 unused bytes in the last
    with node.sdo.open(0x2002, 1, "wb", block_transfer=True, size=len(name)) as stream:
        stream.write(name)
    assert get(emu, 18, "0x2002:01") == name.decode()
    with node.sdo.open(0x2002, 1, "rb", block_transfer=True) as stream:
        assert stream.read() == name  # python-canopen checks the server's CRC
    network.send_message(0x7EE, b"")  # the watcher's marker: every frame before it has been relayed
    frames = [(m.arbitration_id, bytes(m.data)) for m in collect(watcher, {0x612, 0x592}, 0x7EE)]
    assert frames[0] == (0x612, bytes([0xC6, 0x02, 0x20, 0x01, 30, 0, 0, 0]))   # block download, CRC, size
    assert frames[1] == (0x592, bytes([0xA4, 0x02, 0x20, 0x01, 10, 0, 0, 0]))   # CRC, blksize 10
    assert [f for f in frames[2:7]] == [(0x612, bytes([seq]) + name[i:i + 7].ljust(7, b"\0"))
                                       for seq, i in ((1, 0), (2, 7), (3, 14), (4, 21), (0x85, 28))]
    assert frames[7] == (0x592, bytes([0xA2, 5, 10, 0, 0, 0, 0, 0]))
    assert frames[8][0] == 0x612 and frames[8][1][0] == 0xC1 | (5 << 2)
    assert frames[9] == (0x592, bytes([0xA1, 0, 0, 0, 0, 0, 0, 0]))
    assert frames[10][0] == 0x612 and frames[10][1][:4] == bytes([0xA4, 0x02, 0x20, 0x01])  # block upload
    assert frames[11] == (0x592, bytes([0xC6, 0x02, 0x20, 0x01, 30, 0, 0, 0]))
    assert [f for f in frames[13:18]] == [(0x592, bytes([seq]) + name[i:i + 7].ljust(7, b"\0"))
                                         for seq, i in ((1, 0), (2, 7), (3, 14), (4, 21), (0x85, 28))]
    assert len(frames) == 21, frames  # + A2 confirmation, C1|5<<2 end, A1

    blob = bytes(range(7, 7 + 64))  # the whole 64-byte domain: ten segments, the last with 1 byte
    other = remote(network, 33, ALL_TYPES)
    with other.sdo.open(0x200D, 0, "rb", block_transfer=True) as stream:
        assert stream.read() == bytes.fromhex("DEADBEEF")  # its default, with its length (4 bytes, not 64)
    with other.sdo.open(0x200D, 0, "wb", block_transfer=True, size=len(blob)) as stream:
        stream.write(blob)
    assert get(emu, 33, "0x200D") == blob.hex().upper()
    with other.sdo.open(0x200D, 0, "rb", block_transfer=True) as stream:
        assert stream.read() == blob
    assert other.sdo.upload(0x200D, 0) == blob  # and segmented
    assert "socketcand" not in emu.stop().replace("socketcand: listening", "")  # nothing refused, nothing lost


def test_tpdo_and_rpdo(tmp_path, emulators, master):
    """The master reads the Bürkert's PDO configuration by SDO, starts the node, and its TPDO1 (0x2500:01, the flow)
    brings the flow the emulator has once it has followed a set-point the control socket wrote (12.5 exactly: the
    model reports the flow rounded to 0.01); the master's RPDO1 then writes 0x2540:01 (the set-point), and TPDO1
    follows to it."""
    emu = start(emulators, tmp_path, "buerkert:18")
    network = master()
    node = remote(network, 18, BUERKERT)
    node.tpdo.read()
    node.rpdo.read()
    tpdo, rpdo = node.tpdo[1], node.rpdo[1]
    assert (tpdo.enabled, tpdo.cob_id, tpdo.trans_type, tpdo.inhibit_time, tpdo.event_timer) == \
           (True, 0x192, 0xFE, 5000, 1000)
    assert [(v.index, v.subindex, v.length) for v in tpdo.map] == [(0x2500, 1, 32)]
    assert (rpdo.enabled, rpdo.cob_id) == (True, 0x212)
    assert [(v.index, v.subindex, v.length) for v in rpdo.map] == [(0x2540, 1, 32)]
    assert not [p for p in list(node.tpdo.map.values())[1:] if p.enabled]  # TPDO2..4 are off

    emu.control.request("set", node=18, object="0x2540:01", value=12.5)
    node.nmt.state = "OPERATIONAL"
    values = []

    def flow_is(value):
        def check():
            if tpdo.wait_for_reception(2.0):  # None on a timeout
                values.append(tpdo.map[0].raw)
            return values and values[-1] == value
        return check

    until(flow_is(12.5), timeout=15, what="TPDO1 with 12.5")
    assert bytes(tpdo.data) == struct.pack("<f", 12.5)
    assert get(emu, 18, "0x2500:01") == 12.5
    assert all(0.0 <= v <= 12.5 for v in values), values  # rising towards the set-point, not past it

    rpdo.map[0].raw = 33.25
    rpdo.transmit()
    until(lambda: get(emu, 18, "0x2540:01") == 33.25, timeout=5, what="set-point 33.25 from RPDO1")
    until(flow_is(33.25), timeout=15, what="TPDO1 with 33.25")
    assert get(emu, 18, "0x2500:01") == 33.25
    assert [n["state"] for n in emu.control.request("list")["nodes"]] == ["OPERATIONAL"]


def test_heartbeat_consumer_emcy_for_a_producer_on_socketcand(tmp_path, emulators, buses, master):
    """The master sets the Bürkert's heartbeat consumer (0x1016:01) to watch node 0x25 with 1000 ms by SDO over
    socketcand; another socketcand client is node 0x25, sending heartbeats every 100 ms for a while, then none:
    the consumer's EMCY 0x8130 (register 0x11, msef source 2 and the node-ID: decisions.md, EMCY) reaches the
    master, not before 1000 ms after the last heartbeat by the server's own time stamps, once, 0x1001 shows it; the
    next heartbeat clears it (EMCY 0000)."""
    emu = start(emulators, tmp_path, "buerkert:18")
    network = master()
    node = remote(network, 18, BUERKERT)
    beats = []
    network.subscribe(0x725, lambda can_id, data, stamp: beats.append((bytes(data), stamp)))
    producer = scd_bus(buses)
    node.sdo.download(0x1016, 1, struct.pack("<I", (0x25 << 16) | 1000))
    assert get(emu, 18, "0x1016:01") == (0x25 << 16) | 1000
    time.sleep(0.2)  # the producer's frames reach the others 100 ms after its rawmode's ok at the earliest
    for _ in range(10):
        producer.send(can.Message(arbitration_id=0x725, is_extended_id=False, data=b"\x05"))
        time.sleep(0.1)
    emcy = node.emcy.wait(0x8130, timeout=5)
    assert emcy is not None, [str(e) for e in node.emcy.log]
    assert (emcy.code, emcy.register, emcy.data) == (0x8130, 0x11, bytes([0x02, 0x25, 0, 0, 0]))
    until(lambda: len(beats) == 10, timeout=2, what="the 10 heartbeats at the master")
    assert [d for d, _ in beats] == [b"\x05"] * 10
    assert emcy.timestamp - beats[-1][1] >= 0.99, (emcy.timestamp, beats[-1][1])
    assert get(emu, 18, "0x1001") == 0x11  # the error register (the Buerkert has no 0x1003 history)
    time.sleep(1.5)
    assert [e.code for e in node.emcy.log] == [0x8130]  # once: no heartbeat, no new timeout
    # a heartbeat again: monitoring resumes, the error is cleared (EMCY 0000 with register 0)
    producer.send(can.Message(arbitration_id=0x725, is_extended_id=False, data=b"\x05"))
    until(lambda: len(node.emcy.log) == 2, timeout=3, what="the error reset")
    reset = node.emcy.log[1]
    assert (reset.code, reset.register) == (0x0000, 0x00), str(reset)
    assert get(emu, 18, "0x1001") == 0


def test_two_clients_frames_exactly_once_and_sdo_answers_seen_by_the_other(tmp_path, emulators, buses, master):
    """Client A's frames reach client B once each and in order (and never A); an SDO request A sends reaches the
    node, whose answer reaches both A and B's python-canopen master; B's master's SDO transfer is seen by A."""
    start(emulators, tmp_path, "buerkert:18")
    a, b = scd_bus(buses), scd_bus(buses)
    network = master()
    time.sleep(0.2)
    sent = [can.Message(arbitration_id=0x300 + i, is_extended_id=False, data=bytes([i] * (i % 9))) for i in range(40)]
    sent += [can.Message(arbitration_id=0x10000000 + i, is_extended_id=True, data=bytes([i])) for i in range(10)]
    for msg in sent:
        a.send(msg)
    a.send(can.Message(arbitration_id=0x7EE, is_extended_id=False, data=b""))
    ids = {m.arbitration_id for m in sent}
    got = collect(b, ids, 0x7EE)
    assert [(m.arbitration_id, m.is_extended_id, bytes(m.data)) for m in got] == \
           [(m.arbitration_id, m.is_extended_id, bytes(m.data)) for m in sent]
    assert [m for m in (b.recv(0.3),) if m is not None and m.arbitration_id in ids] == []
    assert [m for m in (a.recv(0.1),) if m is not None and m.arbitration_id in ids | {0x7EE}] == []

    answers = []
    network.subscribe(0x592, lambda can_id, data, stamp: answers.append(bytes(data)))
    node = remote(network, 18, BUERKERT)  # B's master; its SDO client also subscribes 0x592
    vendor = node.sdo.upload(0x1018, 1)
    until(lambda: answers, timeout=3, what="B's own answer")
    answers.clear()
    a.send(can.Message(arbitration_id=0x612, is_extended_id=False, data=[0x40, 0x18, 0x10, 0x01, 0, 0, 0, 0]))
    seen_by_a = collect_one(a, 0x592)
    assert bytes(seen_by_a.data) == bytes([0x43, 0x18, 0x10, 0x01]) + vendor
    until(lambda: answers, timeout=3, what="the answer to A's request at B's master")
    time.sleep(0.3)
    assert answers == [bytes([0x43, 0x18, 0x10, 0x01]) + vendor]  # exactly once
    # and A sees B's master's transfer, each request before its answer
    network.send_message(0x7EE, b"")
    collect(a, set(), 0x7EE)  # what A had before
    assert node.sdo.upload(0x1008, 0) == b"Buerkert MFC"
    network.send_message(0x7EF, b"")
    frames = [(m.arbitration_id, bytes(m.data)) for m in collect(a, {0x612, 0x592}, 0x7EF)]
    assert frames[0] == (0x612, bytes([0x40, 0x08, 0x10, 0x00, 0, 0, 0, 0]))
    assert frames[1] == (0x592, bytes([0x41, 0x08, 0x10, 0x00, 12, 0, 0, 0]))
    assert [f[0] for f in frames] == [0x612, 0x592] * 3, frames


def collect_one(bus, can_id, timeout=3.0):
    end = time.monotonic() + timeout
    while time.monotonic() < end:
        msg = bus.recv(0.1)
        if msg is not None and msg.arbitration_id == can_id:
            return msg
    raise AssertionError(f"no 0x{can_id:X} within {timeout} s")


def test_a_watching_client_sees_each_request_before_its_answer(tmp_path, emulators, buses):
    """A frame from the bus's medium (a udp_multicast group) or from another client reaches a watching client before
    the node's answer to it, as on the wire (the server used to relay it after the nodes had answered: a trace of
    the watcher showed every SDO answer ahead of its request)."""
    bus_name = f"udp_multicast:{GROUP}:{PORT}"
    emu = Emulator(tmp_path, "--socketcand", SERVE, "-i", bus_name, "buerkert:18")
    emulators.append(emu)
    group = can.Bus(interface="udp_multicast", channel=GROUP, port=PORT)
    buses.append(group)
    watcher = can.Bus(interface="socketcand", channel=bus_name, host=HOST, port=SCD_PORT)
    buses.append(watcher)
    client = can.Bus(interface="socketcand", channel=bus_name, host=HOST, port=SCD_PORT)
    buses.append(client)
    time.sleep(0.2)
    request = [0x40, 0x18, 0x10, 0x01, 0, 0, 0, 0]
    answer = bytes([0x43, 0x18, 0x10, 0x01]) + struct.pack("<I", 0x39)  # the Bürkert EDS's vendor-ID
    for sender in (group, client, group, client):  # one at a time: the request, then its answer
        sender.send(can.Message(arbitration_id=0x612, is_extended_id=False, data=request))
        assert until_answer(watcher) == [(0x612, bytes(request)), (0x592, answer)]
    # and all four again, back to back: however the server interleaves them, no answer comes before its request
    for sender in (group, client, group, client):
        sender.send(can.Message(arbitration_id=0x612, is_extended_id=False, data=request))
    frames = until_answer(watcher, answers=4)
    assert sorted(frames) == [(0x592, answer)] * 4 + [(0x612, bytes(request))] * 4, frames
    for k in range(1, len(frames) + 1):
        ids = [i for i, _ in frames[:k]]
        assert ids.count(0x592) <= ids.count(0x612), frames


def until_answer(bus, answers=1, timeout=5.0):
    """The 0x612 and 0x592 frames a bus receives until it has `answers` 0x592 ones."""
    frames = []
    end = time.monotonic() + timeout
    while sum(1 for i, _ in frames if i == 0x592) < answers:
        assert time.monotonic() < end, frames
        msg = bus.recv(0.1)
        if msg is not None and msg.arbitration_id in (0x612, 0x592):
            frames.append((msg.arbitration_id, bytes(msg.data)))
    return frames
