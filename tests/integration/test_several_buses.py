"""Several buses in one process (-i vcan0 -i vcan1, DEVICE:ID@IFACE): a node-ID is unique per bus, each bus has
its own socket, frames stay on their bus, and commands name a node by ID@IFACE where the ID alone is ambiguous."""
import json
import socket
import subprocess

import can
import pytest

from conftest import EMU, IFACE, Deadline

OTHER = "vcan1"


def have_other():
    return subprocess.run(["ip", "link", "show", OTHER], capture_output=True).returncode == 0


pytestmark = [pytest.mark.socketcan,  # several kernel interfaces
              pytest.mark.skipif(not have_other(), reason="needs a second virtual interface (tools/vcan-run makes vcan1)")]

SDO_SERIAL = bytes([0x40, 0x18, 0x10, 0x04, 0, 0, 0, 0])  # upload 0x1018:04


def open_bus(name):
    return can.Bus(channel=name, interface="socketcan", receive_own_messages=False)


def frames(bus, seconds):
    got, deadline = [], Deadline(seconds)
    while not deadline.expired():
        msg = bus.recv(deadline.slice())
        if msg is not None:
            got.append(msg)
    return got


def drain(bus):
    while bus.recv(0) is not None:
        pass


def sdo_answers(bus, node_id, request, seconds=1.0):
    bus.send(can.Message(arbitration_id=0x600 + node_id, data=request, is_extended_id=False))
    return [m for m in frames(bus, seconds) if m.arbitration_id == 0x580 + node_id]


def test_same_node_id_on_two_buses_each_answers_on_its_own(emulator, tmp_path):
    a, b = open_bus(IFACE), open_bus(OTHER)
    try:
        emu = emulator("-i", OTHER, "sds:16", "sds:16@" + OTHER, "pro-ionizer:0x20@" + OTHER, nvm_dir=tmp_path)
        assert emu.log_contains("NMT INITIALISING -> PRE-OPERATIONAL", timeout=3)
        on_a, on_b = frames(a, 0.6), frames(b, 0.6)
        # boot-ups: node 16 once on each bus, node 0x20 only on the second
        def boot_ups(got, cob_id):
            return [m for m in got if m.arbitration_id == cob_id and bytes(m.data) == b"\x00"]
        assert len(boot_ups(on_a, 0x710)) == 1 and len(boot_ups(on_b, 0x710)) == 1, (on_a, on_b)
        assert not [m for m in on_a if m.arbitration_id == 0x720], on_a
        assert len(boot_ups(on_b, 0x720)) == 1, on_b
        # the serial numbers are those of the command line (default + node-ID): equal, yet each bus gets one answer
        ra, rb = sdo_answers(a, 16, SDO_SERIAL), sdo_answers(b, 16, SDO_SERIAL)
        assert len(ra) == 1 and len(rb) == 1, (ra, rb)
        assert bytes(ra[0].data)[:4] == bytes([0x43, 0x18, 0x10, 0x04]) and ra[0].data == rb[0].data
        # NMT start on the second bus: only its nodes leave PRE-OPERATIONAL
        b.send(can.Message(arbitration_id=0x000, data=bytes([0x01, 0x00]), is_extended_id=False))
        deadline = Deadline(2)
        lines = []

        def listed():
            lines[:] = [line for line in emu.out_lines if line.startswith("node ")][-3:]
            return all(("OPERATIONAL" in line) == (OTHER in line) for line in lines) and len(lines) == 3

        while not deadline.expired():
            start = len(emu.out_lines)
            emu.command("list", expect="node 32")
            if Deadline(1).until(lambda: len(emu.out_lines) >= start + 3) and listed():
                break
        assert lines == [f"node 16: sds (started as 16) PRE-OPERATIONAL on {IFACE}",
                         f"node 16: sds (started as 16) OPERATIONAL on {OTHER}",
                         f"node 32: pro-ionizer (started as 32) OPERATIONAL on {OTHER}"], emu.out_lines
        # a command names the node: the ID alone is ambiguous, ID@IFACE is not
        assert emu.command("get 16 0x1017", expect="error") == \
            f"error: node 16 is on {IFACE} and on {OTHER}: say 16@{IFACE}"
        emu.command(f"set 16@{OTHER} 0x1017 700", expect="0x1017:00 = 700")
        assert emu.command(f"get 16@{IFACE} 0x1017", expect="0x1017") == "node 16: 0x1017:00 = 5000 (0x1388)"
        emu.command(f"set 16@{IFACE} 0x1017 300", expect="0x1017:00 = 300")
        assert emu.command("get 32@" + IFACE + " 0x1017", expect="error") == f"error: no node 32@{IFACE}"
        assert emu.command("get 16@vcan7 0x1017", expect="error") == "error: no interface 'vcan7'"
        # each bus runs the heartbeat written for its node (judged from the first heartbeat after the writes)
        drain(a)
        drain(b)
        hb_b = [m.timestamp for m in frames(b, 2.2) if m.arbitration_id == 0x710]
        assert len(hb_b) >= 3 and all(0.65 < y - x < 0.75 for x, y in zip(hb_b, hb_b[1:])), hb_b
        hb_a = [m.timestamp for m in frames(a, 1.0) if m.arbitration_id == 0x710]
        assert len(hb_a) >= 3 and all(0.25 < y - x < 0.35 for x, y in zip(hb_a, hb_a[1:])), hb_a
    finally:
        a.shutdown()
        b.shutdown()
    assert emu.stop() == 0
    # each node has its own files: the first bus's keep the names they had with one bus
    assert "sds-16 on" not in " ".join(emu.err_lines)
    assert emu.log_contains(f"NVM {tmp_path}/sds-16.*", timeout=0) and \
        emu.log_contains(f"NVM {tmp_path}/sds-16@{OTHER}.*", timeout=0), emu.err_lines


def test_node_id_twice_on_one_bus_is_refused(tmp_path):
    r = subprocess.run([EMU, "-i", IFACE, "-i", OTHER, "--nvm-dir", str(tmp_path), "sds:16@" + OTHER,
                        "buerkert:16@" + OTHER], capture_output=True, text=True, timeout=10)
    assert r.returncode == 2
    assert f"node-ID 16 is given twice on {OTHER} (sds:16@{OTHER} and buerkert:16@{OTHER})" in r.stderr, r.stderr
    # the same ID on the first bus named both ways is the same bus
    r = subprocess.run([EMU, "-i", IFACE, "--nvm-dir", str(tmp_path), "sds:16", "buerkert:16@" + IFACE],
                       capture_output=True, text=True, timeout=10)
    assert r.returncode == 2 and f"node-ID 16 is given twice on {IFACE}" in r.stderr, r.stderr


def test_a_bus_that_cannot_be_opened_stops_the_start(tmp_path):
    r = subprocess.run([EMU, "-i", IFACE, "--nvm-dir", str(tmp_path), "sds:16", "sds:17@nosuchcan0"],
                       capture_output=True, text=True, timeout=10)
    assert r.returncode == 1, r
    assert "nosuchcan0" in r.stderr, r.stderr


def test_an_event_filter_by_id_alone_takes_the_node_on_every_bus(emulator, tmp_path):
    path = tmp_path / "ctl.sock"
    emu = emulator("-i", OTHER, "--control-socket", str(path), "sds:16", "sds:16@" + OTHER, nvm_dir=tmp_path)
    assert emu.log_contains(f"control: listening on unix {path}", timeout=3)
    c = socket.socket(socket.AF_UNIX)
    c.connect(str(path))
    f = c.makefile("rw")
    f.write(json.dumps({"id": 1, "cmd": "subscribe", "events": ["nmt"], "nodes": [16]}) + "\n")
    f.flush()
    assert json.loads(f.readline()) == {"id": 1, "ok": True, "events": ["nmt"]}
    for bus_name in (OTHER, IFACE):
        bus = open_bus(bus_name)
        try:
            bus.send(can.Message(arbitration_id=0x000, data=[0x01, 16], is_extended_id=False))
        finally:
            bus.shutdown()
        ev = json.loads(f.readline())
        assert (ev["event"], ev["node"], ev["bus"], ev["to"]) == ("nmt", 16, bus_name, "OPERATIONAL"), ev
    c.close()
