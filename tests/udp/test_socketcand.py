"""canopen-emu's socketcand server (--socketcand HOST:PORT, docs/buses.md) against the real peers: python-can's own
socketcand Bus both ways, a python-canopen master on it, two clients on one channel, a bridge to a udp_multicast
bus; and hostile clients: an HTTP request, garbage, a client that never reads, too many clients. Runs inside a network
namespace of its own (netns-run): nothing leaves lo."""
import socket
import threading
import time

import can
import canopen
import pytest

from udp_support import GROUP, PORT, SRC, Emulator

HOST = "127.0.0.1"
SCD_PORT = 29536
SERVE = f"{HOST}:{SCD_PORT}"


def start(emulators, tmp_path, *args, name="emu"):
    emu = Emulator(tmp_path, "--socketcand", SERVE, *args, name=name)
    emulators.append(emu)
    return emu


def scd_bus(buses, channel="plant"):
    bus = can.Bus(interface="socketcand", channel=channel, host=HOST, port=SCD_PORT)
    buses.append(bus)
    return bus


class Raw:
    """A socketcand client at the byte level."""

    def __init__(self, rcvbuf=None):
        self.sock = socket.socket(socket.AF_INET, socket.SOCK_STREAM)
        if rcvbuf is not None:
            self.sock.setsockopt(socket.SOL_SOCKET, socket.SO_RCVBUF, rcvbuf)
        self.sock.connect((HOST, SCD_PORT))
        self.buf = b""

    def send(self, data):
        self.sock.sendall(data if isinstance(data, bytes) else data.encode())

    def item(self, timeout=3.0):
        """The next '< ... >' the server wrote."""
        end = time.monotonic() + timeout
        while b">" not in self.buf:
            left = end - time.monotonic()
            if left <= 0:
                raise AssertionError(f"nothing within {timeout} s; have {self.buf[:200]!r}")
            self.sock.settimeout(left)
            try:
                chunk = self.sock.recv(65536)
            except socket.timeout:
                continue
            if not chunk:
                raise ConnectionError(f"closed; have {self.buf!r}")
            self.buf += chunk
        text, self.buf = self.buf.split(b">", 1)
        return (text + b">").decode().strip()

    def items_for(self, seconds):
        out = []
        end = time.monotonic() + seconds
        while time.monotonic() < end:
            try:
                out.append(self.item(end - time.monotonic()))
            except AssertionError:
                break
        return out

    def closed(self, timeout=3.0):
        """Whether the server closes the connection within timeout (what it wrote meanwhile is kept in buf)."""
        end = time.monotonic() + timeout
        while time.monotonic() < end:
            self.sock.settimeout(max(0.01, end - time.monotonic()))
            try:
                chunk = self.sock.recv(65536)
            except socket.timeout:
                continue
            except ConnectionResetError:
                return True
            if not chunk:
                return True
            self.buf += chunk
        return False

    def open_raw(self, channel="plant"):
        assert self.item() == "< hi >"
        self.send(f"< open {channel} >")
        assert self.item() == "< ok >"
        self.send("< rawmode >")
        assert self.item() == "< ok >"

    def close(self):
        self.sock.close()


def recv_until(bus, pred, timeout=3.0):
    end = time.monotonic() + timeout
    while time.monotonic() < end:
        msg = bus.recv(0.1)
        if msg is not None and pred(msg):
            return msg
    raise AssertionError("no such message within %s s" % timeout)


def frames_of_every_kind():
    out = []
    for n in range(9):
        out.append(can.Message(arbitration_id=0x123 + n, is_extended_id=False, data=bytes(range(0xF0, 0xF0 + n))))
        out.append(can.Message(arbitration_id=0x1ABCDE00 + n, is_extended_id=True, data=bytes(range(n))))
    out.append(can.Message(arbitration_id=0x7FF, is_extended_id=False, data=b"\x00\xff"))
    out.append(can.Message(arbitration_id=0x00000005, is_extended_id=True, data=b""))  # 8 digits, small value
    return out


def test_python_can_clients_exchange_frames_exactly(tmp_path, emulators, buses):
    """Standard and extended IDs, DLC 0..8, from one python-can socketcand Bus to another through the emulator."""
    start(emulators, tmp_path, "-i", "virtual:plant", "sds:16")
    a, b = scd_bus(buses), scd_bus(buses)
    time.sleep(0.2)  # the server holds frames for 100 ms after rawmode's ok
    sent = frames_of_every_kind()
    for msg in sent:
        a.send(msg)
    got = []
    end = time.monotonic() + 5
    while len(got) < len(sent) and time.monotonic() < end:
        msg = b.recv(0.2)
        if msg is not None and msg.arbitration_id != 0x710:
            got.append(msg)
    assert [(m.arbitration_id, m.is_extended_id, bytes(m.data), m.dlc) for m in got] == \
           [(m.arbitration_id, m.is_extended_id, bytes(m.data), m.dlc) for m in sent]
    assert all(abs(m.timestamp - time.time()) < 5 for m in got), [m.timestamp for m in got]  # wall clock, as socketcand
    assert a.recv(0.3) is None  # a client does not get its own frames back


def test_the_nodes_answer_python_can_including_remote_frames(tmp_path, emulators, buses):
    """An SDO request reaches the node and its answer the client; python-can's remote frame (send with DLC and no
    bytes) is a remote frame to the node: node guarding answers it."""
    emu = start(emulators, tmp_path, "-i", "virtual:plant", "buerkert:18")
    emu.control.request("set", node=18, object="0x1017", value=0)  # node guarding works without a heartbeat only
    bus = scd_bus(buses)
    bus.send(can.Message(arbitration_id=0x612, is_extended_id=False, data=[0x40, 0x18, 0x10, 0x01, 0, 0, 0, 0]))
    answer = recv_until(bus, lambda m: m.arbitration_id == 0x592)
    assert answer.data[:4] == bytes([0x43, 0x18, 0x10, 0x01])
    # an extended 0x612 is not the node's SDO request: nothing answers it
    bus.send(can.Message(arbitration_id=0x612, is_extended_id=True, data=[0x40, 0x18, 0x10, 0x01, 0, 0, 0, 0]))
    with pytest.raises(AssertionError):
        recv_until(bus, lambda m: m.arbitration_id == 0x592, timeout=0.5)
    bus.send(can.Message(arbitration_id=0x712, is_extended_id=False, is_remote_frame=True, dlc=1))
    guard = recv_until(bus, lambda m: m.arbitration_id == 0x712)
    assert guard.dlc == 1 and guard.data[0] & 0x7F == 0x7F  # pre-operational


def test_remote_frames_reach_other_clients_in_socketcands_form(tmp_path, emulators, buses):
    start(emulators, tmp_path, "-i", "virtual:plant", "sds:16")
    watcher = Raw()
    watcher.open_raw()
    sender = Raw()
    sender.open_raw()
    sender.send("< sendrtr 123 4 >< send 1ABCDEF0 3  >< send 456 0 >")
    items = [i for i in watcher.items_for(1.0) if " 710 " not in i]
    assert [i.split()[:3] + i.split()[4:] for i in items] == [
        ["<", "rtr", "123", "4", ">"], ["<", "rtr", "1ABCDEF0", "3", ">"], ["<", "frame", "456", ">"]], items
    assert items[2].endswith("  >")  # an empty frame keeps the data field: python-can splits on it


def test_python_canopen_master_over_socketcand(tmp_path, emulators):
    """python-canopen on python-can's socketcand interface, unchanged: SDO expedited and segmented, NMT, heartbeat."""
    emu = start(emulators, tmp_path, "-i", "virtual:plant", "buerkert:18")
    network = canopen.Network()
    network.connect(interface="socketcand", channel="plant", host=HOST, port=SCD_PORT)
    try:
        node = canopen.RemoteNode(18, str(SRC / "od/buerkert-flow-controller.eds"))
        network.add_node(node)
        assert node.sdo.upload(0x1018, 1) == node.sdo[0x1018][1].raw.to_bytes(4, "little")  # expedited
        assert node.sdo.upload(0x1008, 0) == b"Buerkert MFC"                                   # segmented
        text = b"over socketcand"
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


def test_a_udp_multicast_bus_is_bridged_both_ways(tmp_path, emulators, buses):
    """A socketcand client's frame reaches the bus's multicast group, the group's frames reach the client."""
    bus_name = f"udp_multicast:{GROUP}:{PORT}"
    start(emulators, tmp_path, "-i", bus_name, "sds:16")
    group = can.Bus(interface="udp_multicast", channel=GROUP, port=PORT)
    buses.append(group)
    client = scd_bus(buses, channel=bus_name)
    time.sleep(0.2)
    client.send(can.Message(arbitration_id=0x1F334455, is_extended_id=True, data=b"\x01\x02\x03"))
    msg = recv_until(group, lambda m: m.arbitration_id == 0x1F334455)
    assert msg.is_extended_id and bytes(msg.data) == b"\x01\x02\x03"
    group.send(can.Message(arbitration_id=0x222, is_extended_id=False, data=b"\xaa\xbb"))
    msg = recv_until(client, lambda m: m.arbitration_id == 0x222)
    assert not msg.is_extended_id and bytes(msg.data) == b"\xaa\xbb"
    # and the group's SDO request reaches the node, whose answer reaches the client too
    group.send(can.Message(arbitration_id=0x610, is_extended_id=False, data=[0x40, 0x18, 0x10, 0x01, 0, 0, 0, 0]))
    recv_until(client, lambda m: m.arbitration_id == 0x590)


def test_an_http_request_is_closed_with_nothing_done(tmp_path, emulators):
    """A browser's cross-origin POST (any web page may send one to a local port) carries socketcand commands in its
    body: none of them runs."""
    emu = start(emulators, tmp_path, "-i", "virtual:plant", "sds:16")
    watcher = Raw()
    watcher.open_raw()
    browser = Raw()
    assert browser.item() == "< hi >"
    browser.send("POST / HTTP/1.1\r\nHost: 127.0.0.1:29536\r\nContent-Type: text/plain\r\nContent-Length: 53\r\n\r\n"
                 "< open plant >< rawmode >< send 000 2 1 0 >< send 555 0 >")
    assert browser.closed()
    assert browser.buf == b""  # nothing answered
    assert [i for i in watcher.items_for(0.5) if " 710 " not in i] == []
    assert [n["state"] for n in emu.control.request("list")["nodes"]] == ["PRE-OPERATIONAL"]
    assert "closed: its first bytes are an HTTP request" in emu.stop()


def test_garbage_gets_errors_and_closes_the_connection_when_it_goes_on(tmp_path, emulators):
    emu = start(emulators, tmp_path, "-i", "virtual:plant", "sds:16")
    c = Raw()
    assert c.item() == "< hi >"
    c.send("< send 123 0 >")
    assert c.item() == "< error open a channel first >"
    c.send("< open plant >")
    assert c.item() == "< ok >"
    c.send("< frobnicate >")
    assert c.item() == "< error unknown command >"
    c.send("< subscribe 0 0 123 >")
    assert c.item().startswith("< error not served here")
    c.send("< send 123 3 1 2 >")
    assert c.item() == "< error send has as many bytes as its DLC says >"
    c.send("< send 800 0 >")
    assert c.item().startswith("< error an 11-bit ID is at most 7FF")
    c.send(" junk\n")
    assert c.item() == "< error bytes outside a command >"
    c.send("<" + "a" * (1 << 20) + ">")  # a command of 1 MiB: refused once, the rest dropped
    assert c.item() == "< error command too long >"
    c.send("< echo >")
    assert c.item() == "< echo >"
    c.send("< nope >" * 16)
    for _ in range(16):
        assert c.item() == "< error unknown command >"
    assert c.closed()
    log = emu.stop()
    assert "closed: too many malformed or unknown commands in a row" in log


def test_a_channel_that_is_not_a_bus_is_refused_and_closed(tmp_path, emulators):
    emu = start(emulators, tmp_path, "-i", "virtual:plant", "sds:16")
    c = Raw()
    assert c.item() == "< hi >"
    c.send("< open vcan0 >< rawmode >")
    assert c.item() == "< error could not open bus >"
    assert c.closed()
    assert c.buf == b""  # the rawmode after it was not run
    assert "closed: it asked for a channel that is not one of the buses" in emu.stop()


def test_fd_frames_are_counted_not_carried(tmp_path, emulators, buses):
    emu = start(emulators, tmp_path, "-i", "virtual:plant", "sds:16")
    a, b = scd_bus(buses), scd_bus(buses)
    time.sleep(0.2)
    a.send(can.Message(arbitration_id=0x321, is_fd=True, data=bytes(12)))
    a.send(can.Message(arbitration_id=0x322, data=b"\x01"))
    assert recv_until(b, lambda m: m.arbitration_id != 0x710).arbitration_id == 0x322
    log = emu.stop()
    assert "1 CAN FD frame(s) of clients were not carried" in log


def test_a_client_that_never_reads_is_cut_off_and_the_heartbeat_goes_on(tmp_path, emulators):
    """A client in rawmode that never reads, under a flood of another client's frames: cut off once its unread
    output passes the bound, and the node's 100 ms heartbeat keeps its time meanwhile (the times are the server's own,
    in each frame: the watcher's lag does not count)."""
    emu = start(emulators, tmp_path, "-i", "virtual:plant", "sds:16")
    emu.control.request("set", node=16, object="0x1017", value=100)
    sleeper = Raw(rcvbuf=4096)
    sleeper.open_raw()  # and then never reads
    watcher = Raw()
    watcher.open_raw()
    beats = []
    flood_seen = [0]  # frames of the flood the watcher has read

    def watch():
        tail = b""
        watcher.sock.settimeout(0.5)
        while True:
            try:
                data = watcher.sock.recv(1 << 20)
            except (socket.timeout, OSError):
                return
            if not data:
                return
            tail += data
            parts = tail.split(b">")
            tail = parts.pop()
            beats.extend(float(p.split()[3]) for p in parts if p.strip().startswith(b"< frame 710 "))
            flood_seen[0] += sum(1 for p in parts if p.strip().startswith(b"< frame 555 "))

    thread = threading.Thread(target=watch)
    thread.start()
    time.sleep(0.3)  # past the 100 ms after rawmode's ok in which frames wait (and count against the bound)
    flooder = Raw()
    assert flooder.item() == "< hi >"
    flooder.send("< open plant >")
    assert flooder.item() == "< ok >"
    started = time.monotonic()
    for k in range(12):  # 24,000 frames of 39 bytes: past what the sleeper's socket and its 256 KiB bound hold
        flooder.send("< send 555 8 11 22 33 44 55 66 77 88 >" * 2000)
        # the watcher is a reader, however late: a Python thread on a loaded machine can fall 256 KiB behind one
        # burst, so the next waits until it has read this one (the sleeper reads nothing either way)
        deadline = time.monotonic() + 20
        while flood_seen[0] < 2000 * (k + 1) and time.monotonic() < deadline and thread.is_alive():
            time.sleep(0.01)
    flooder.send("< echo >")
    assert flooder.item(timeout=30) == "< echo >"  # every frame of the flood was taken
    time.sleep(max(0.0, 1.0 - (time.monotonic() - started)))
    watcher.close()
    thread.join()
    assert sleeper.closed(timeout=10), "the client that never read was not cut off"
    log = emu.stop()
    assert "client 1 (127.0.0.1" in log and "cut off: it left more than 262144 bytes unread" in log, log
    assert "client 2" not in log, log  # the watcher, which reads, was not
    gaps = [b - a for a, b in zip(beats, beats[1:])]
    assert len(beats) >= 8 and max(gaps) < 0.35, gaps  # 100 ms heartbeats went on meanwhile


def test_at_most_16_clients(tmp_path, emulators):
    emu = start(emulators, tmp_path, "-i", "virtual:plant", "sds:16")
    clients = [Raw() for _ in range(16)]
    for c in clients:
        assert c.item() == "< hi >"
    extra = Raw()
    assert extra.item() == "< error too many clients >"
    assert extra.closed()
    clients.pop().close()
    time.sleep(0.2)
    again = Raw()
    assert again.item() == "< hi >"
    again.send("< open plant >")
    assert again.item() == "< ok >"
    assert "refused: 16 are connected already" in emu.stop()


def test_half_open_connections_run_nothing_and_free_their_place(tmp_path, emulators):
    """A client that vanishes in the middle of a command, and one that closes its sending half: the cut command is
    not run, and each connection is closed and its place freed (16 connect after them)."""
    emu = start(emulators, tmp_path, "-i", "virtual:plant", "sds:16")
    watcher = Raw()
    watcher.open_raw()
    cut = Raw()
    cut.open_raw()
    cut.send("< send 000 2 01 00 >< send 123 1 AA")  # NMT start all, then a command without its end
    cut.close()
    half = Raw()
    half.open_raw()
    half.send("< send 124 1 BB >")
    half.sock.shutdown(socket.SHUT_WR)  # nothing more comes: the server ends the connection
    assert half.closed(), "a client that closed its sending half was left open"
    seen = [i.split()[2] for i in watcher.items_for(0.5)]
    assert [i for i in seen if i in ("000", "123", "124")] == ["000", "124"], seen  # NMT and 124; the cut 123 never
    assert [n["state"] for n in emu.control.request("list")["nodes"]] == ["OPERATIONAL"]
    watcher.close()
    time.sleep(0.2)
    clients = [Raw() for _ in range(16)]  # every place was freed
    for c in clients:
        assert c.item() == "< hi >"
    log = emu.stop()
    assert "refused" not in log and "closed:" not in log, log  # an ordinary end both times, nobody refused


def test_the_address_is_loopback_unless_named(tmp_path):
    from udp_support import EMU
    import subprocess
    out = subprocess.run([EMU, "--nvm-dir", str(tmp_path / "nvm"), "--socketcand", "nowhere", "-i", "virtual:p",
                          "sds:16"], capture_output=True, text=True, timeout=10)
    assert out.returncode == 2 and "--socketcand takes HOST:PORT" in out.stderr
