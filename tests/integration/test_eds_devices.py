"""canopen-emu FILE.eds:ID and FILE.dcf: a device from its description, served by the core as the file declares,
with python-canopen as the master reading the same file (tests/eds/files/, our own)."""
import json
import os
import struct
import subprocess
import time

import canopen
import pytest
from canopen.sdo.exceptions import SdoAbortedError

from pathlib import Path

from conftest import EMU, SRC

FILES = SRC / "tests" / "eds" / "files"
EDS_TOOL = os.environ.get("CO_EDS_TOOL", str(Path(EMU).parent / "canopen-eds"))


def eds_node(network, path, node_id):
    node = canopen.RemoteNode(node_id, str(path))
    node.sdo.RESPONSE_TIMEOUT = 5.0
    network.add_node(node)
    return node


def test_every_type_read_and_written_as_the_file_says(emulator, network, capture):
    emulator(f"{FILES / 'all-types.eds'}:0x31")
    capture.wait_for(0x731, data=b"\x00", timeout=3)
    node = eds_node(network, FILES / "all-types.eds", 0x31)
    # the defaults, through python-canopen's decoding of the same file
    assert node.sdo[0x2002].raw == -300
    assert node.sdo.upload(0x200E, 0) == struct.pack("<i", -(2 ** 23))[:3]         # INTEGER24, 3 bytes
    assert node.sdo.upload(0x2011, 0) == (2 ** 47 - 1).to_bytes(6, "little")      # INTEGER48
    assert node.sdo.upload(0x2017, 0) == (2 ** 56 - 1).to_bytes(7, "little")      # UNSIGNED56
    assert node.sdo.upload(0x200B, 0) == (0xA5A5A5A5).to_bytes(6, "little")       # TIME_OF_DAY
    assert node.sdo.upload(0x2009, 0) == bytes.fromhex("0102A0FF")               # OCTET_STRING: its 4 bytes
    assert node.sdo.upload(0x2008, 0) == b"hello world"
    assert node.sdo[0x2007].raw == pytest.approx(2.5)
    # limits of every kind: INTEGER16, REAL32 (dropped before), UNSIGNED64
    node.sdo[0x2002].raw = 1000
    with pytest.raises(SdoAbortedError) as e:
        node.sdo[0x2002].raw = 1001
    assert e.value.code == 0x06090031
    node.sdo[0x2007].raw = 10.0
    with pytest.raises(SdoAbortedError) as e:
        node.sdo[0x2007].raw = 100.0
    assert e.value.code == 0x06090031
    with pytest.raises(SdoAbortedError) as e:
        node.sdo.download(0x2018, 0, struct.pack("<Q", 0x0F))
    assert e.value.code == 0x06090032
    assert node.sdo[0x2007].raw == pytest.approx(10.0)


def test_twenty_pdos_of_a_file(emulator, network, capture):
    emu = emulator(f"{FILES / 'many-pdos.eds'}:0x32")
    capture.wait_for(0x732, data=b"\x00", timeout=3)
    node = eds_node(network, FILES / "many-pdos.eds", 0x32)
    node.nmt.state = "OPERATIONAL"
    # TPDOs are event-driven (254): one goes out when a mapped value changes. TPDO 1 (0x180 + node-ID) maps 0x2200.
    since = time.time()
    emu.command("set 0x32 0x2200 0x1234", expect="0x2200")
    assert capture.wait_for(0x1B2, timeout=3, since=since)[-1].data == b"\x34\x12"
    # TPDO 12, invalid in the file (bit 31), made valid on 0x38B: the twelfth PDO, beyond the core's own 4
    node.sdo.download(0x180B, 1, struct.pack("<I", 0x38B))
    since = time.time()
    emu.command("set 0x32 0x220B 0x0BAD", expect="0x220B")
    assert capture.wait_for(0x38B, timeout=3, since=since)[-1].data == b"\xad\x0b"
    # RPDO 8 (invalid in the file) made valid on 0x300 writes its input word 0x2107
    node.sdo.download(0x1407, 1, struct.pack("<I", 0x300))
    network.send_message(0x300, b"\x99\x88")
    time.sleep(0.2)
    assert node.sdo[0x2107].raw == 0x8899


def test_dcf_values_node_id_and_commissioning(emulator, network, capture):
    emulator(str(FILES / "device.dcf"))  # no :ID: the DCF's NodeID 5
    capture.wait_for(0x705, data=b"\x00", timeout=3)
    hb = capture.wait_for(0x705, count=3, timeout=3, data=b"\x7f")  # ParameterValue 500 ms heartbeat
    gaps = [b.timestamp - a.timestamp for a, b in zip(hb, hb[1:])]
    assert all(0.45 < g < 0.6 for g in gaps), gaps
    node = eds_node(network, FILES / "device.dcf", 5)
    assert node.sdo[0x2000].raw == 1200                       # ParameterValue, not DefaultValue 0
    assert node.sdo.upload(0x2100, 1) == struct.pack("<h", -5)   # [2100Value] of a compact array
    assert node.sdo.upload(0x2100, 2) == struct.pack("<h", 0)


def test_a_dcf_at_another_node_id_follows_it(emulator, network, capture):
    """node-id.dcf was written for NodeID 0x20, its $NODEID values resolved there: run at node-ID 20 it answered node
    0x20's (0x1014 = 0xA0, 0x1200:01 = 0x620; issue 35). Those values follow the node-ID now; the COB-ID 0x2A5 the
    file configured for TPDO 2 (node 0x25's) stays as configured."""
    emu = emulator(f"{FILES / 'node-id.dcf'}:20")
    capture.wait_for(0x700 + 20, data=b"\x00", timeout=3)
    node = eds_node(network, FILES / "node-id.dcf", 20)

    def u32(index, sub=0):
        return struct.unpack("<I", node.sdo.upload(index, sub))[0]

    assert u32(0x1014) == 0x80 + 20
    assert (u32(0x1200, 1), u32(0x1200, 2)) == (0x600 + 20, 0x580 + 20)
    assert u32(0x1400, 1) == 0x80000200 + 20  # disabled in the DCF, still disabled
    assert (u32(0x1800, 1), u32(0x1801, 1)) == (0x180 + 20, 0x2A5)
    assert node.sdo.upload(0x2002, 0) == bytes([10 + 20])
    node.nmt.state = "OPERATIONAL"
    since = time.time()
    emu.command("set 20 0x2000 0x1234", expect="0x2000")
    assert capture.wait_for(0x180 + 20, timeout=3, since=since)[-1].data == b"\x34\x12"


def test_lss_only_where_supported(emulator, network, capture):
    # LSS_Supported=0 in all-types.eds: an LSS inquiry gets no answer; the Buerkert (LSS) answers
    emulator(f"{FILES / 'all-types.eds'}:0x33", "buerkert:0x34")
    capture.wait_for(0x734, data=b"\x00", timeout=3)
    since = time.time()
    network.send_message(0x7E5, b"\x04\x01" + bytes(6))  # switch state global: configuration
    network.send_message(0x7E5, b"\x5E" + bytes(7))      # inquire node-ID
    answers = capture.wait_for(0x7E4, timeout=2, since=since)
    assert [m.data[1] for m in answers] == [0x34]


def test_dummy_mapping_follows_the_file(emulator, network, capture):
    emulator(f"{FILES / 'dummy-usage.eds'}:0x35")
    capture.wait_for(0x735, data=b"\x00", timeout=3)
    node = eds_node(network, FILES / "dummy-usage.eds", 0x35)
    node.sdo.download(0x1400, 1, struct.pack("<I", 0x80000235))
    node.sdo.download(0x1600, 0, b"\x00")
    node.sdo.download(0x1600, 1, struct.pack("<I", 0x00050008))  # Dummy0005=1: taken
    with pytest.raises(SdoAbortedError) as e:
        node.sdo.download(0x1600, 1, struct.pack("<I", 0x00070020))  # Dummy0007=0: refused
    assert e.value.code == 0x06040041


def test_files_that_cannot_be_emulated_exit_2(tmp_path):
    bad = tmp_path / "bad.eds"
    bad.write_bytes(b"\x00\x01binary")
    r = subprocess.run([EMU, f"{bad}:5"], capture_output=True, text=True, timeout=30)
    assert r.returncode == 2
    assert f"{bad}:1: error: a NUL byte" in r.stderr and f"{bad} cannot be emulated" in r.stderr
    r = subprocess.run([EMU, str(FILES / "minimal.eds")], capture_output=True, text=True, timeout=30)
    assert r.returncode == 2 and "give the node-ID" in r.stderr


def test_export_dcf_reads_back_with_the_current_values(emulator, network, capture, tmp_path):
    emu = emulator(f"{FILES / 'all-types.eds'}:0x36", "sds:0x37")
    capture.wait_for(0x736, data=b"\x00", timeout=3)
    node = eds_node(network, FILES / "all-types.eds", 0x36)
    node.sdo[0x2002].raw = -123
    node.sdo[0x2007].raw = 7.25
    node.sdo.download(0x2008, 0, b"changed")
    emu.command("set 0x36 0x2012 -5", expect="0x2012")  # INTEGER56, set by the device
    out = tmp_path / "node36.dcf"
    assert emu.command(f"export-dcf 0x36 {out}", expect="DCF") == f"node 54: DCF written to {out}"
    od = canopen.import_od(str(out), node_id=0x36)
    assert od[0x2002].value == -123 and od[0x2007].value == pytest.approx(7.25)
    assert od[0x2008].value == "changed"
    reread = json.loads(subprocess.run([EDS_TOOL, "json", str(out)], capture_output=True, text=True,
                                       check=True).stdout)
    values = {(e["index"], e["sub"]): e["param"] for e in reread["entries"]}
    assert values[(0x2002, 0)] == -123 and values[(0x2012, 0)] == -5 and values[(0x2008, 0)] == "changed"
    assert reread["commissioning"]["node_id"] == 0x36 and reread["warnings"] == 0
    assert emu.command(f"export-dcf 0x37 {tmp_path / 'x.dcf'}", expect="error") == \
        "node 55: error: export-dcf: sds is a built-in device: export-dcf writes devices read from an EDS or DCF " \
        "(its EDS is od/ in the sources)"
    assert not (tmp_path / "x.dcf").exists()
    # the exported DCF runs as a device of its own (node-ID from the DCF), with those values
    emu.stop()
    since = time.time()
    emulator(str(out))
    capture.wait_for(0x736, data=b"\x00", timeout=3, since=since)
    assert node.sdo[0x2002].raw == -123 and node.sdo.upload(0x2008, 0).rstrip(b"\0") == b"changed"


def test_store_and_restore_of_a_file_device(emulator, network, capture, tmp_path):
    drive = FILES / "drive.eds"
    nvm = tmp_path / "nvm"
    emu = emulator(f"{drive}:0x38", nvm_dir=nvm)
    capture.wait_for(0x738, data=b"\x00", timeout=3)
    node = eds_node(network, drive, 0x38)
    node.sdo[0x2005].raw = 3.5
    node.sdo[0x1017].raw = 250
    node.sdo.download(0x1010, 1, b"save")
    assert sorted(p.name for p in nvm.iterdir() if p.name.endswith(".params")) == ["drive.eds-56.params"]
    emu.stop()
    since = time.time()
    emu = emulator(f"{drive}:0x38", nvm_dir=nvm)
    capture.wait_for(0x738, data=b"\x00", timeout=3, since=since)
    assert node.sdo[0x2005].raw == pytest.approx(3.5) and node.sdo[0x1017].raw == 250  # loaded at power-on
    node.sdo.download(0x1011, 1, b"load")
    since = time.time()
    node.nmt.state = "RESET"
    capture.wait_for(0x738, data=b"\x00", timeout=3, since=since)
    assert node.sdo[0x2005].raw == 0.0 and node.sdo[0x1017].raw == 0               # the file's defaults again
