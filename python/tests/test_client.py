"""The control client: typed get/set, commands, refusals with the emulator's exact text, hello/list/show, EMCY,
power cycles, TCP, timeouts and a closed connection."""
import os
import signal
import socket
import threading
import time
from pathlib import Path

import can
import pytest

from canopen_emu import __version__ as PACKAGE_VERSION
from canopen_emu import (ActiveError, ConnectionClosed, ControlError, ControlTimeout, Entry, NodeInfo, ObjectInfo,
                         ProtocolError, Reading, connect)

pytestmark = pytest.mark.canopen_emu_nodes("sds:16", "buerkert:17", "pro-ionizer:0x20")

EVENT_KINDS = ("nmt", "boot-up", "emcy", "sdo-abort", "store", "nvm", "lss", "heartbeat", "guarding", "interface",
               "fault", "message", "frame")


def test_get_returns_typed_values(canopen_emu):
    c = canopen_emu.client
    heartbeat = c.get(16, "0x1017")
    assert heartbeat == 5000 and type(heartbeat) is int
    assert c.get(17, "0x1008") == "Buerkert MFC"
    assert c.get(0x20, "1008") == "ES61"
    supply = c.get(17, (0x2004, 3))  # REAL32
    assert supply == 24.0 and type(supply) is float
    assert c.get_entry(16, 0x1018, sub=1) == Entry(node=16, object="0x1018:01", value=0x24E, type="UNSIGNED32",
                                                   name="Vendor ID")
    voltage = c.get_entry(0x20, "0x6401:01")  # a process value: its unit from the device's profile
    assert (voltage.type, voltage.unit) == ("UNSIGNED16", "V"), voltage
    serial = c.get_entry(0x20, "0x1018:04")
    assert (serial.index, serial.sub, serial.value) == (0x1018, 4, 0x00ABCDEF + 0x20)  # EDS serial + node-ID


def test_objects_lists_a_nodes_dictionary(canopen_emu):
    c = canopen_emu.client
    rows = {o.object: o for o in c.objects(17, values=True)}
    assert len(rows) == 307  # od/buerkert-flow-controller.eds
    assert rows["0x1017:00"] == ObjectInfo(object="0x1017:00", name="Producer Heartbeat Time", type="UNSIGNED16",
                                           access="rw", tpdo=False, rpdo=False, stored=True, value=500,
                                           object_name="Producer Heartbeat Time")
    assert rows["0x1018:04"].object_name == "Identity Object"
    setpoint = rows["0x2540:01"]
    assert (setpoint.index, setpoint.sub, setpoint.unit, setpoint.rpdo) == (0x2540, 1, "l/min", True)
    assert type(setpoint.value) is float
    supply = rows["0x2004:03"]
    assert supply.value == c.get(17, (0x2004, 3)) and supply.type == "REAL32"
    address = rows["0x2001:02"]  # the node-ID as the device keeps it: limits from the EDS
    assert (address.low, address.high, address.value) == (1, 127, 17)
    plain = c.objects(16)
    assert plain and all(o.value is None and o.error is None for o in plain)
    with pytest.raises(ControlError, match="objects needs one node, not all"):
        c.objects("all")


def test_get_many_reads_several_objects_in_one_request(canopen_emu):
    c = canopen_emu.client
    c.set(16, "0x1017", 700)
    readings = c.get_many(17, ["0x1017", (0x2540, 1), 0x1000, "0x5555"])
    assert [r.object for r in readings] == ["0x1017:00", "0x2540:01", "0x1000:00", "0x5555:00"]
    assert readings[0] == Reading(object="0x1017:00", value=500, type="UNSIGNED16")
    assert type(readings[1].value) is float and readings[1].sub == 1
    assert readings[2].value == c.get(17, 0x1000)
    assert readings[3] == Reading(object="0x5555:00", error="object does not exist (0x06020000)")
    assert c.get_many(16, ["0x1017"])[0].value == 700
    with pytest.raises(ControlError, match="objects"):
        c.get_many(16, [])


def test_device_commands_of_a_node(canopen_emu):
    usages = dict(canopen_emu.client.device_commands(16))  # sds:16
    assert usages["load UA"] == "web charge current in uA (+ = positively charged web)"
    assert "pollution PERCENT" in usages


def test_set_returns_the_value_read_back(canopen_emu):
    c = canopen_emu.client
    assert c.set(16, "0x1017", 700) == 700
    assert c.get(16, "0x1017") == 700
    assert c.set(16, "0x1017", "0x3E8") == 1000  # a number in the command language's form
    entry = c.set_entry(17, "0x2540:01", 12.5)
    assert entry == Entry(node=17, object="0x2540:01", value=12.5, type="REAL32", name="Value", unit="l/min")
    assert c.get(17, "0x2540:01") == 12.5


@pytest.mark.parametrize("call, request_fields, error", [
    (lambda c: c.set(16, "0x1017", 70000), {"cmd": "set", "node": 16, "object": "0x1017", "value": 70000},
     "70000 is out of range: 0x1017:00 (UNSIGNED16) holds 0..65535"),
    (lambda c: c.set(16, "0x1017", 150), {"cmd": "set", "node": 16, "object": "0x1017", "value": 150},
     "0x1017:00: invalid value for parameter (0x06090030)"),  # the SDS takes 100 ms steps only
    (lambda c: c.set(16, "0x1017", "abc"), {"cmd": "set", "node": 16, "object": "0x1017", "value": "abc"},
     "'abc' is not a number"),
    (lambda c: c.get(16, 0x5555), {"cmd": "get", "node": 16, "object": 0x5555}, "node 16 has no object 0x5555:00"),
    (lambda c: c.get(99, "0x1017"), {"cmd": "get", "node": 99, "object": "0x1017"}, "no node 99"),
    (lambda c: c.get("all", "0x1017"), {"cmd": "get", "node": "all", "object": "0x1017"},
     "get needs one node, not all"),
])
def test_refusals_carry_the_emulators_text_and_the_request(canopen_emu, call, request_fields, error):
    c = canopen_emu.client
    with pytest.raises(ControlError) as e:
        call(c)
    assert e.value.error == error
    assert {k: v for k, v in e.value.request.items() if k != "id"} == request_fields
    assert isinstance(e.value.request["id"], int)
    assert e.value.cmd == request_fields["cmd"]
    assert e.value.lines == []
    assert error in str(e.value)
    assert c.get(16, "0x1018:00") == 4  # the connection goes on


def test_commands_return_lines_and_refusals_carry_them(canopen_emu):
    c = canopen_emu.client
    assert c.command(17, "setpoint", 40) == ["node 17: set-point 40 (controller target 40)"]
    assert c.get(17, "0x2540:01") == 40.0
    with pytest.raises(ControlError) as e:
        c.command(16, "load", "bogus")
    usage = "usage: load MICROAMPERE (-1000..1000, + = positively charged web)"
    assert e.value.error == usage
    assert e.value.lines == [f"node 16: error: {usage}"]
    assert e.value.request["args"] == ["bogus"]
    with pytest.raises(ControlError) as e:
        c.command(16, "frobnicate")
    assert e.value.error == "unknown command 'frobnicate' (try help 16)"
    help_lines = c.help(16)
    assert help_lines[0] == "node 16 (sds) commands:"
    assert any(line.startswith("  pollution PERCENT") for line in help_lines), help_lines
    assert c.help()[0].startswith("commands (NODE = node-ID")
    with pytest.raises(ValueError):
        c.command(16, "load", "two words")  # refused before it is sent: args are words


def test_hello_nodes_and_show(canopen_emu, canopen_emu_bus):
    c = canopen_emu.client
    hello = c.hello()
    bus, kind = canopen_emu_bus.name, canopen_emu_bus.kind
    assert (hello.program, hello.version, hello.protocol, hello.buses, hello.bus_kinds) == (
        "canopen-emu", PACKAGE_VERSION, 1, (bus,), {bus: kind})
    assert hello.events == EVENT_KINDS
    assert c.server == hello  # connect() asked it already
    assert abs(hello.clock_unix_us / 1e6 - time.time()) < 5 and hello.clock_time_us > 0
    expected = [NodeInfo(16, "sds", "N", 16, "PRE-OPERATIONAL", bus, kind),
                NodeInfo(17, "buerkert", None, 17, "PRE-OPERATIONAL", bus, kind),
                NodeInfo(0x20, "pro-ionizer", "full", 0x20, "PRE-OPERATIONAL", bus, kind)]
    assert c.nodes() == expected
    assert c.list() == expected
    shown = c.show(17)
    assert len(shown) == 1
    assert (shown[0].node, shown[0].error_register, shown[0].errors, shown[0].tx_dropped) == (17, 0, (), 0)
    assert shown[0].tx_frames >= 1  # its boot-up at least
    assert [s.node for s in c.show()] == [16, 17, 0x20]
    assert shown[0].bus_kind == kind
    sds = c.show(16)[0]
    # od/sds.eds: device type 0x191 (CiA 401), heartbeat 5000 ms; its boot-up counts as its last heartbeat
    assert (sds.device_type, sds.heartbeat_ms, sds.faults, sds.last_emcy) == (0x191, 5000, (), None)
    assert sds.last_heartbeat_us is not None


def test_heard_lists_the_other_nodes_on_the_bus(canopen_emu, can_bus, canopen_emu_bus):
    c = canopen_emu.client
    assert c.heard() == []
    bus = can_bus()
    bus.send(can.Message(arbitration_id=0x705, data=b"\x05", is_extended_id=False))  # another device: Operational
    deadline = time.monotonic() + 5.0
    heard = c.heard()
    while not heard and time.monotonic() < deadline:
        time.sleep(0.05)
        heard = c.heard()
    assert [(h.node, h.bus, h.bus_kind, h.state, h.boot_up) for h in heard] == [
        (5, canopen_emu_bus.name, canopen_emu_bus.kind, "OPERATIONAL", False)]
    assert 0 < heard[0].last_heartbeat_us
    assert c.heard(canopen_emu_bus.name) == heard


def test_show_tells_the_faults_in_force_and_when_the_last_heartbeat_went(canopen_emu):
    c = canopen_emu.client
    c.set(17, "0x1017", 100)
    first = c.show(17)[0].last_heartbeat_us
    later = first
    deadline = time.monotonic() + 2.0
    while later == first and time.monotonic() < deadline:
        time.sleep(0.05)
        later = c.show(17)[0].last_heartbeat_us
    assert later is not None and first is not None and later > first  # heartbeats every 100 ms move it on
    c.inject_fault(17, "heartbeat-stop")
    stopped = c.show(17)[0]
    assert stopped.faults == ("heartbeat-stop",)
    time.sleep(0.35)
    assert c.show(17)[0].last_heartbeat_us == stopped.last_heartbeat_us  # no heartbeat went out since
    c.clear_fault(17)
    assert c.show(17)[0].faults == ()


def test_emcy_show_and_emcy_clear(canopen_emu):
    c = canopen_emu.client
    assert c.emcy(17, 0x3210, 0x05, [1, 2, 3, 4, 5]) == ["node 17: emcy 0x3210: done"]
    status = c.show(17)[0]
    assert status.errors == (ActiveError(code=0x3210, register=0x05, info=bytes([1, 2, 3, 4, 5])),)
    assert status.error_register == 0x05
    assert c.get(17, "0x1001") == 0x05
    last = status.last_emcy
    assert (last.code, last.register, last.info) == (0x3210, 0x05, bytes([1, 2, 3, 4, 5])), last
    # an error is its code and its five bytes: clearing needs both
    with pytest.raises(ControlError) as e:
        c.emcy_clear(17, 0x3210)
    assert e.value.lines == ["node 17: emcy-clear 0x3210: not active"]
    assert c.emcy_clear(17, 0x3210, [1, 2, 3, 4, 5]) == ["node 17: emcy-clear 0x3210: done"]
    assert c.show(17)[0].errors == ()
    assert c.get(17, "0x1001") == 0
    reset = c.show(17)[0].last_emcy  # the error-reset EMCY: code 0, the bytes of the error it ends
    assert (reset.code, reset.register, reset.info) == (0, 0, bytes([1, 2, 3, 4, 5])) and reset.time_us >= last.time_us
    with pytest.raises(ValueError):
        c.emcy(17, 0x3210, info=[1, 2, 3, 4, 5])  # the bytes need the register before them


def test_power_cycle_boots_the_node_again(canopen_emu, canopen_emu_bus):
    c = canopen_emu.client
    c.set(17, "0x2540:01", 30.0)
    c.subscribe(["boot-up"], nodes=[17])
    assert c.power_cycle(17) == ["node 17: power cycled"]
    boot = c.wait_for("boot-up", node=17)
    assert (boot["device"], boot["bus"], boot["text"]) == ("buerkert", canopen_emu_bus.name, "boot-up")
    assert c.get(17, "0x2540:01") == 0.0  # the model restarted (the set-point is not a stored parameter)


def test_tcp_connection(canopen_emu_factory):
    emu = canopen_emu_factory("sds:16", extra_args=["--control-tcp", "127.0.0.1:0"])
    address = emu.tcp_address()
    host, port = address.rsplit(":", 1)
    assert host == "127.0.0.1" and int(port) > 0
    with connect(address) as c:
        assert c.get(16, "0x1017") == 5000
        assert c.server is not None and c.server.protocol == 1
    with connect(("127.0.0.1", int(port))) as c:
        assert c.get(16, "0x1018:01") == 0x24E
    assert c.closed


def test_tcp_connection_with_a_token(canopen_emu_factory, tmp_path):
    token = tmp_path / "token"
    token.write_text("the-token-of-this-test-42\n")
    token.chmod(0o600)
    emu = canopen_emu_factory("sds:16", extra_args=["--control-tcp", "127.0.0.1:0",
                                                    "--control-token-file", str(token)])
    address = emu.tcp_address()
    assert address.endswith("(clients give the token first)") is False
    with connect(address, token="the-token-of-this-test-42") as c:
        assert c.get(16, "0x1017") == 5000
    with pytest.raises(ControlError, match="needs the token first"):
        connect(address)
    with pytest.raises(ControlError, match="needs the token first"):
        connect(address, token="not-the-token-0123456789")


def test_a_late_answer_is_dropped_and_the_next_request_gets_its_own(canopen_emu):
    c = canopen_emu.client
    os.kill(canopen_emu.pid, signal.SIGSTOP)  # the emulator cannot answer
    try:
        with pytest.raises(ControlTimeout):
            c.get(16, "0x1017", timeout=0.3)
    finally:
        os.kill(canopen_emu.pid, signal.SIGCONT)
    # the answer to the timed-out get comes now, before this one's: it must not be taken for it
    assert c.get(16, "0x1018:01") == 0x24E
    assert c.stale_answers == 1


def test_a_closed_connection_raises(canopen_emu):
    other = canopen_emu.connect()
    assert other.get(16, "0x1017") == 5000
    other.quit()  # stops the emulator
    assert other.closed
    assert canopen_emu.proc.wait(5) == 0
    with pytest.raises(ConnectionClosed):
        canopen_emu.client.get(16, "0x1017")


def test_a_refusal_of_an_unreadable_request_or_a_client_too_many_is_a_control_error(canopen_emu):
    c = canopen_emu.client
    with pytest.raises(ControlError) as e:
        c.set(16, "0x1008", "x" * 3000)  # a line longer than the emulator reads: refused with "id": null
    assert e.value.error.endswith("is longer than 2047 bytes: ignored")
    assert c.get(16, "0x1017") == 5000
    others = [canopen_emu.connect() for _ in range(63)]  # with canopen_emu.client: 64, the most there may be
    with pytest.raises(ControlError) as e:
        canopen_emu.connect()
    assert e.value.error == "too many control clients (at most 64)"
    for other in others:
        other.close()


def test_the_protocol_version_is_checked(tmp_path):
    # Not the emulator: a server that says it speaks protocol 2, which this client must refuse.
    path = str(tmp_path / "fake.sock")
    server = socket.socket(socket.AF_UNIX)
    server.bind(path)
    server.listen(1)

    def answer_hello():
        conn, _ = server.accept()
        with conn:
            request = conn.makefile().readline()
            assert '"cmd":"hello"' in request
            conn.sendall(b'{"id":1,"ok":true,"program":"canopen-emu","version":"9.0.0","protocol":2,'
                         b'"events":[],"buses":[]}\n')

    thread = threading.Thread(target=answer_hello)
    thread.start()
    try:
        with pytest.raises(ProtocolError) as e:
            connect(path, timeout=2)
        assert str(e.value) == "canopen-emu speaks control protocol 2; this client speaks version 1 of canopen-emu's"
    finally:
        thread.join(5)
        server.close()
    assert Path(path).exists()


def test_addresses_are_told_apart():
    from canopen_emu.client import parse_address
    assert parse_address("/run/emu.sock") == (socket.AF_UNIX, "/run/emu.sock")
    assert parse_address("ctl.sock") == (socket.AF_UNIX, "ctl.sock")
    assert parse_address("unix:with:colons") == (socket.AF_UNIX, "with:colons")
    assert parse_address("127.0.0.1:5020") == (socket.AF_INET, ("127.0.0.1", 5020))
    assert parse_address("localhost:5020") == (socket.AF_INET, ("localhost", 5020))
    assert parse_address("[::1]:5020") == (socket.AF_INET6, ("::1", 5020))
    assert parse_address(("127.0.0.1", 5020)) == (socket.AF_INET, ("127.0.0.1", 5020))
    assert parse_address(Path("/tmp/x:1")) == (socket.AF_UNIX, "/tmp/x:1")


def test_tables_give_the_emulators_fault_kinds_and_abort_texts(canopen_emu):
    """The fault kinds and abort texts come from the emulator (`tables`), the package keeps no copy: every kind it
    lists is one inject_fault takes, with its usage; the abort texts are the ones its messages use."""
    c = canopen_emu.client
    t = c.tables()
    assert t.fault_kinds[:3] == ("sdo-ignore", "sdo-delay", "sdo-abort")
    assert {"heartbeat-stop", "tpdo-length", "lss-silent"} <= set(t.fault_kinds)
    delay = next(f for f in t.faults if f.kind == "sdo-delay")
    assert delay.usage == "sdo-delay MS" and delay.limits and delay.text
    assert t.aborts[0x06020000] == "object does not exist"
    assert list(t.aborts) == sorted(t.aborts)
    for kind, args in (("heartbeat-stop", ()), ("sdo-delay", (50,))):  # listed kinds are taken, then cleared
        c.inject_fault(17, kind, *args)
        assert c.show(17)[0].faults[0].startswith(kind)
        c.clear_fault(17)
    with pytest.raises(ControlError):
        c.inject_fault(17, "no-such-fault")
