"""canopen-emu on python-can's udp_multicast bus (-i udp_multicast[:GROUP[:PORT]], docs/buses.md), against the real
peers: python-can's own UdpMulticastBus in both directions, a python-canopen master, a second canopen-emu on the same
group; bad datagrams, CAN FD and error frames counted and harmless; IPv6; the TTL option. Runs inside a network
namespace of its own (netns-run): its datagrams never leave lo."""
import random
import socket
import struct
import time

import can
import canopen
import msgpack
import pytest
from can.interfaces.udp_multicast.utils import pack_message

from udp_support import GROUP, GROUP6, PORT, SRC, Emulator

BUS = f"udp_multicast:{GROUP}:{PORT}"
PYTHON_CAN_KEYS = ["timestamp", "arbitration_id", "is_extended_id", "is_remote_frame", "is_error_frame", "channel",
                   "dlc", "data", "is_fd", "bitrate_switch", "error_state_indicator"]
EVERY_FRAME = ["0x000/0x000", "0x00000000x/0x0"]


def start(emulators, tmp_path, *args, name="emu"):
    emu = Emulator(tmp_path, *args, name=name)
    emulators.append(emu)
    return emu


@pytest.fixture
def python_can():
    bus = can.Bus(interface="udp_multicast", channel=GROUP, port=PORT)
    yield bus
    bus.shutdown()


def listener(group=GROUP, family=socket.AF_INET):
    """A raw socket on the group: every datagram with its sender."""
    s = socket.socket(family, socket.SOCK_DGRAM)
    s.setsockopt(socket.SOL_SOCKET, socket.SO_REUSEADDR, 1)
    s.setsockopt(socket.SOL_SOCKET, socket.SO_REUSEPORT, 1)
    s.bind(("", PORT))
    if family == socket.AF_INET:
        s.setsockopt(socket.IPPROTO_IP, socket.IP_ADD_MEMBERSHIP, socket.inet_aton(group) + struct.pack("@I", 0))
    else:
        s.setsockopt(socket.IPPROTO_IPV6, socket.IPV6_JOIN_GROUP,
                     socket.inet_pton(family, group) + struct.pack("@I", socket.if_nametoindex("lo")))
    s.settimeout(0.2)
    return s


def recv_until(bus, pred, timeout=3.0):
    end = time.monotonic() + timeout
    while time.monotonic() < end:
        try:
            msg = bus.recv(0.1)
        except can.CanOperationError:  # python-can raises on a bad datagram (test_bad_datagrams_...)
            continue
        if msg is not None and pred(msg):
            return msg
    raise AssertionError("no such message within %s s" % timeout)


def sdo_upload_request(node, index, sub):
    return can.Message(arbitration_id=0x600 + node, is_extended_id=False,
                       data=[0x40, index & 0xFF, index >> 8, sub, 0, 0, 0, 0])


def test_python_can_frames_reach_the_emulator_as_sent(tmp_path, emulators, python_can):
    """Standard and extended identifiers, remote requests, DLC 0..8, from python-can's own bus: each arrives once,
    in order, with its identifier, format, DLC and data (the emulator's frame events show what it read)."""
    emu = start(emulators, tmp_path, "-i", BUS, "sds:16")
    emu.control.request("subscribe", events=["frame"], frames=EVERY_FRAME)
    sent = []
    for dlc in range(9):
        sent.append(can.Message(arbitration_id=0x123 + dlc, is_extended_id=False, data=bytes(range(0x10, 0x10 + dlc))))
    for dlc in (0, 4, 8):
        sent.append(can.Message(arbitration_id=0x1ABCDE00 + dlc, is_extended_id=True, data=bytes([0xA5] * dlc)))
    sent.append(can.Message(arbitration_id=0x7FF, is_extended_id=False, data=bytes([0xFF] * 8)))
    for dlc in (0, 5, 8):
        sent.append(can.Message(arbitration_id=0x124, is_extended_id=False, is_remote_frame=True, dlc=dlc))
    sent.append(can.Message(arbitration_id=0x18FF0001, is_extended_id=True, is_remote_frame=True, dlc=2))
    for msg in sent:
        python_can.send(msg)
    expected = [(m.arbitration_id, bool(m.is_extended_id), bool(m.is_remote_frame),
                 (bytes(m.dlc) if m.is_remote_frame else bytes(m.data)).hex().upper()) for m in sent]
    got = []
    end = time.monotonic() + 5
    while len(got) < len(expected) and time.monotonic() < end:
        for e in emu.control.drain(0.2):
            if e.get("event") == "frame" and e.get("dir") == "rx":
                got.append((e["id"], e.get("eff", False), e.get("rtr", False), e["data"]))
    got += [(e["id"], e.get("eff", False), e.get("rtr", False), e["data"]) for e in emu.control.drain(0.3)
            if e.get("event") == "frame" and e.get("dir") == "rx"]
    assert got == expected
    emu.stop()


def test_emulator_frames_are_python_can_messages(tmp_path, emulators, python_can):
    """The boot-up and an SDO answer reach python-can's bus as python-can's own messages, and each datagram is
    byte for byte what python-can's pack_message makes of that message."""
    raw = listener()
    emu = start(emulators, tmp_path, "-i", BUS, "sds:16")
    boot = recv_until(python_can, lambda m: m.arbitration_id == 0x710)
    assert (boot.is_extended_id, boot.is_remote_frame, boot.is_error_frame, boot.is_fd, boot.dlc, bytes(boot.data)) \
        == (False, False, False, False, 1, b"\x00")
    python_can.send(sdo_upload_request(16, 0x1018, 1))
    answer = recv_until(python_can, lambda m: m.arbitration_id == 0x590)
    assert answer.dlc == 8 and bytes(answer.data[:4]) == bytes([0x43, 0x18, 0x10, 0x01])
    datagrams = []
    end = time.monotonic() + 2
    while len(datagrams) < 2 and time.monotonic() < end:
        try:
            data, sender = raw.recvfrom(4096)
        except socket.timeout:
            continue
        if sender[1] != PORT:  # python-can sends from the group's port, the emulator from a port of its own
            datagrams.append(data)
    assert len(datagrams) == 2
    for data in datagrams:
        fields = msgpack.unpackb(data, raw=False)
        assert list(fields) == PYTHON_CAN_KEYS
        assert isinstance(fields["timestamp"], float) and abs(fields["timestamp"] - time.time()) < 10
        assert pack_message(can.Message(**fields)) == data
    raw.close()
    emu.stop()


def test_the_emulator_does_not_take_its_own_datagrams(tmp_path, emulators, python_can):
    """Multicast loopback is on (other processes here hear the bus), yet the emulator's own heartbeats never come
    back as frames read from the bus; a frame from python-can is read once."""
    emu = start(emulators, tmp_path, "-i", BUS, "sds:16", "buerkert:18")
    c = emu.control
    c.request("set", node=16, object="0x1017", value=100)
    c.request("subscribe", events=["frame"], frames=["0x700/0x780", "0x321"])
    python_can.send(can.Message(arbitration_id=0x321, is_extended_id=False, data=b"\x01"))
    events = c.drain(1.0)
    tx = [e for e in events if e["id"] == 0x710 and e["dir"] == "tx"]
    rx_own = [e for e in events if e["id"] in (0x710, 0x712) and e["dir"] == "rx"]
    assert len(tx) >= 7, events[:5]
    assert rx_own == []
    assert [e["data"] for e in events if e["id"] == 0x321] == ["01"]
    assert c.request("show", node="all")["heard"] == []
    emu.stop()


def test_python_canopen_master(tmp_path, emulators):
    """python-canopen on udp_multicast, unchanged: SDO expedited and segmented upload and download, NMT, heartbeat."""
    emu = start(emulators, tmp_path, "-i", BUS, "buerkert:18")
    network = canopen.Network()
    network.connect(interface="udp_multicast", channel=GROUP, port=PORT)
    try:
        node = canopen.RemoteNode(18, str(SRC / "od/buerkert-flow-controller.eds"))
        network.add_node(node)
        assert node.sdo.upload(0x1018, 1) == node.sdo[0x1018][1].raw.to_bytes(4, "little")  # expedited
        assert node.sdo.upload(0x1008, 0) == b"Buerkert MFC"                                   # segmented
        text = b"over udp mc"  # more than 4 bytes: a segmented download
        node.sdo.download(0x2002, 3, text)                                                     # segmented
        assert node.sdo.upload(0x2002, 3) == text
        assert emu.control.request("get", node=18, object="0x2002:03")["value"] == text.decode()
        node.sdo.download(0x1017, 0, (100).to_bytes(2, "little"))                             # expedited
        assert node.nmt.wait_for_heartbeat(2) == "PRE-OPERATIONAL"
        node.nmt.state = "OPERATIONAL"
        deadline = time.monotonic() + 2
        while node.nmt.wait_for_heartbeat(2) != "OPERATIONAL":
            assert time.monotonic() < deadline
        beats = []
        end = time.monotonic() + 1.0
        while time.monotonic() < end:
            node.nmt.wait_for_heartbeat(1)
            beats.append(time.monotonic())
        assert 7 <= len(beats) <= 13, beats  # 100 ms heartbeats
        assert [n["state"] for n in emu.control.request("list")["nodes"]] == ["OPERATIONAL"]
    finally:
        network.disconnect()
    emu.stop()


def test_two_emulators_on_one_group_see_each_others_nodes(tmp_path, emulators):
    a = start(emulators, tmp_path, "-i", BUS, "sds:16", name="a")
    b = start(emulators, tmp_path, "-i", BUS, "sds:17", name="b")
    a.control.request("set", node=16, object="0x1017", value=100)
    b.control.request("set", node=17, object="0x1017", value=100)
    end = time.monotonic() + 3
    while True:
        heard_a = [(h["node"], h["bus"]) for h in a.control.request("show", node="all")["heard"]]
        heard_b = [(h["node"], h["bus"]) for h in b.control.request("show", node="all")["heard"]]
        if (heard_a, heard_b) == ([(17, BUS)], [(16, BUS)]) or time.monotonic() > end:
            break
        time.sleep(0.1)
    assert (heard_a, heard_b) == ([(17, BUS)], [(16, BUS)])
    a.stop()
    b.stop()


def bad_datagrams():
    """Datagrams python-can would refuse: not msgpack, the wrong shape, wrong types, out of range, oversized."""
    rnd = random.Random(33)
    out = [bytes(rnd.randrange(256) for _ in range(rnd.randrange(1, 64))) for _ in range(40)]
    out = [d for d in out if d[0] & 0xF0 != 0x80]  # a random fixmap could happen to be valid
    good = {"timestamp": 1.0, "arbitration_id": 0x612, "is_extended_id": False, "is_remote_frame": False,
            "is_error_frame": False, "channel": None, "dlc": 1, "data": b"\x01", "is_fd": False,
            "bitrate_switch": False, "error_state_indicator": False}
    pack = lambda d: msgpack.packb(d, use_bin_type=True)  # noqa: E731
    out += [
        b"", b"\xc1", b"\xc0",
        b"\xdf\xff\xff\xff\xff",                  # a map claiming 2^32-1 entries
        b"\xdd\xff\xff\xff\xff" + b"\xc0" * 10,   # an array claiming 2^32-1 entries
        b"\xdb\xff\xff\xff\xff" + b"x" * 10,      # a string claiming 4 GiB
        b"\x91" * 2000 + b"\xc0",                 # nested 2000 deep
        pack({f"key{i}": i for i in range(300)}), # a huge map
        pack(list(good.values())),                # a list
        pack(good) + b"\x00",                     # bytes after the message
        pack(dict(good, data=b"\x00" * 4500, dlc=4500)),  # longer than python-can reads (4096)
        pack(dict(good, arbitration_id="0x612")),
        pack(dict(good, is_extended_id=1)),
        pack(dict(good, data="text")),
        pack(dict(good, dlc=9, data=b"\x00" * 9)),
        pack(dict(good, dlc=2)),
        pack(dict(good, arbitration_id=0x800)),
        pack(dict(good, arbitration_id=-1)),
        pack(dict(good, is_remote_frame=True, is_fd=True)),
        pack(dict(good, is_remote_frame=True, is_error_frame=True)),
        pack(dict(good, bitrate_switch=True)),
        pack(dict(good, unknown=1)),
        pack({1: 2}),
    ]
    return out


def test_bad_datagrams_are_counted_and_change_nothing(tmp_path, emulators, python_can):
    emu = start(emulators, tmp_path, "-i", BUS, "sds:16")
    emu.control.request("subscribe", events=["frame"], frames=EVERY_FRAME)
    sender = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
    bad = bad_datagrams()
    for d in bad:
        sender.sendto(d, (GROUP, PORT))
    python_can.send(sdo_upload_request(16, 0x1018, 1))
    recv_until(python_can, lambda m: m.arbitration_id == 0x590)  # still answering
    rx = [e for e in emu.control.drain(0.5) if e["dir"] == "rx"]
    assert [e["id"] for e in rx] == [0x610]  # nothing of the bad ones reached the nodes
    log = emu.stop()
    lines = [line for line in log.splitlines() if "not python-can messages" in line or "not a python-can message" in line]
    assert f"{len(bad)} datagram(s) not python-can messages" in log, log
    assert len(lines) <= 4, lines  # one at once, a summary a second, the exit report: not one line per datagram
    assert "from 0.0.0.0:" in lines[0] or "from 127.0.0.1:" in lines[0], lines[0]


def test_fd_and_error_frames_are_counted_not_given_to_the_nodes(tmp_path, emulators, python_can):
    emu = start(emulators, tmp_path, "-i", BUS, "sds:16")
    emu.control.request("subscribe", events=["frame"], frames=EVERY_FRAME)
    for i in range(3):
        python_can.send(can.Message(arbitration_id=0x610, is_extended_id=False, is_fd=True, data=bytes(12)))
    for i in range(2):
        python_can.send(can.Message(arbitration_id=0x610, is_error_frame=True, is_extended_id=False))
    python_can.send(sdo_upload_request(16, 0x1018, 1))
    recv_until(python_can, lambda m: m.arbitration_id == 0x590)
    rx = [e for e in emu.control.drain(0.5) if e["dir"] == "rx"]
    assert [e["data"] for e in rx] == ["4018100100000000"]
    log = emu.stop()
    assert log.count("a CAN FD frame from") == 1 and log.count("an error frame from") == 1, log
    assert "3 CAN FD and 2 error frame(s) read and not given to the nodes" in log, log


def test_ipv6_group(tmp_path, emulators):
    emu = start(emulators, tmp_path, "-i", f"udp_multicast:[{GROUP6}]:{PORT}", "sds:16")
    bus = can.Bus(interface="udp_multicast", channel=GROUP6, port=PORT)
    try:
        bus.send(sdo_upload_request(16, 0x1018, 1))
        answer = recv_until(bus, lambda m: m.arbitration_id == 0x590)
        assert bytes(answer.data[:4]) == bytes([0x43, 0x18, 0x10, 0x01])
    finally:
        bus.shutdown()
    log = emu.stop()
    assert f"group {GROUP6} port {PORT} joined on lo, hop limit 1" in log, log


IP_RECVTTL, IPV6_RECVHOPLIMIT, IPV6_HOPLIMIT = 12, 51, 52  # Linux's values


@pytest.mark.parametrize("option,ttl", [("", 1), (",ttl=4", 4)])
@pytest.mark.parametrize("family", [socket.AF_INET, socket.AF_INET6])
def test_ttl_and_hop_limit(tmp_path, emulators, family, option, ttl):
    """TTL (hop limit) 1 by default, so the datagrams stay on the link; ttl=N sets it."""
    group = GROUP if family == socket.AF_INET else GROUP6
    raw = listener(group, family)
    if family == socket.AF_INET:
        raw.setsockopt(socket.IPPROTO_IP, IP_RECVTTL, 1)
        spec = f"udp_multicast:{group}:{PORT}{option}"
    else:
        raw.setsockopt(socket.IPPROTO_IPV6, IPV6_RECVHOPLIMIT, 1)
        spec = f"udp_multicast:[{group}]:{PORT}{option}"
    emu = start(emulators, tmp_path, "-i", spec, "sds:16")
    raw.settimeout(3)
    data, ancillary, _, _ = raw.recvmsg(4096, 64)
    assert msgpack.unpackb(data)["arbitration_id"] == 0x710
    values = [struct.unpack("@i", d[:4])[0] for level, kind, d in ancillary
              if (level, kind) in ((socket.IPPROTO_IP, 2), (socket.IPPROTO_IPV6, IPV6_HOPLIMIT))]  # IP_TTL is 2
    assert values == [ttl]
    raw.close()
    emu.stop()


@pytest.mark.parametrize("spec,message", [
    ("udp_multicast:10.0.0.1", "10.0.0.1 is not an IPv4 multicast group"),
    ("udp_multicast:fe80::1", "fe80::1 is not an IPv6 multicast group"),
    ("udp_multicast:239.1.1.1:0", "the port is 1..65535, not '0'"),
    ("udp_multicast:239.1.1.1:65536", "the port is 1..65535"),
    ("udp_multicast:[ff15::1", "an IPv6 group goes in brackets"),
    ("udp_multicast:nowhere", "'nowhere' is not an IP multicast group"),
    ("udp_multicast,ttl=256", "ttl takes 0..255"),
    ("udp_multicast,colour=red", "unknown option 'colour=red'"),
    ("can:vcan0", "unknown bus kind 'can'"),
    ("virtual", "a virtual bus needs a name"),
    ("virtual:a@b", "virtual:NAME takes a name"),
    ("socketcan:", "is not a CAN interface name"),
])
def test_bad_bus_options_are_refused_with_the_reason(spec, message):
    from udp_support import EMU
    import subprocess
    done = subprocess.run([EMU, "-i", spec, "sds:16"], capture_output=True, text=True, timeout=10)
    assert done.returncode == 2 and message in done.stderr, done.stderr


@pytest.mark.parametrize("args,log", [
    (["-i", "udp_multicast"], f"{BUS}: group {GROUP} port {PORT} joined on lo, TTL 1"),
    (["-i", "udp_multicast:ff15::1"], "udp_multicast:[ff15::1]:43113: group ff15::1 port 43113 joined on lo"),
    (["-i", "udp_multicast:239.1.2.3,ttl=0,iface=lo"], "udp_multicast:239.1.2.3:43113: group 239.1.2.3 port 43113 "
                                                      "joined on lo, TTL 0"),
    (["-i", "udp_multicast", f"sds:17@{BUS}", "sds:18@udp_multicast"], "node 18 (sds) on " + BUS),
])
def test_bus_names_and_defaults(tmp_path, emulators, args, log):
    emu = start(emulators, tmp_path, *args, "sds:16")
    assert log in emu.stop()


def test_one_name_with_two_meanings_is_refused():
    from udp_support import EMU
    import subprocess
    done = subprocess.run([EMU, "-i", "udp_multicast", "-i", "udp_multicast,ttl=2", "sds:16"], capture_output=True,
                          text=True, timeout=10)
    assert done.returncode == 2 and "as another kind or with other options" in done.stderr, done.stderr
