"""The Bürkert multi-value variant over vcan (issue 15 part 2): nine sensor values, six in TPDO1-3, the other three
sent one after the other as SAM-MPDOs on TPDO4 from the object scanner list 0x1FA0, every 100 ms (its event timer).
The frames are checked byte by byte (address = the producer's node-ID, index, sub-index, value) and decoded with
python-canopen's dictionary of the EDS; each value is the object's own, as an SDO upload of it shows."""
import struct
import time
from pathlib import Path

from conftest import remote

VARIANT = Path(__file__).resolve().parents[2] / "od" / "variants"
EDS = VARIANT / "buerkert-mpdo.eds"
RULES = VARIANT / "buerkert-mpdo.yaml"
SCANNER = [(0x2506, 1), (0x2507, 1), (0x2508, 1)]


def test_remaining_values_go_out_as_sam_mpdos_in_turn(emulator, network, capture):
    node_id = 0x14
    emulator(f"{EDS}:{node_id}", "--rules", str(RULES))
    capture.wait_for(0x700 + node_id, data=b"\x00", timeout=3)
    node = remote(network, "buerkert", node_id, od=str(EDS))
    assert node.sdo.upload(0x1A03, 0) == b"\xFE"  # TPDO4 mapping: SAM-MPDO
    since = time.time()
    network.send_message(0, bytes([0x01, node_id]))
    mpdos = capture.wait_for(0x480 + node_id, count=7, since=since, timeout=3)
    sent = [(struct.unpack_from("<BHB", bytes(m.data)), bytes(m.data)[4:], m.timestamp) for m in mpdos]
    assert all(len(m.data) == 8 for m in mpdos)
    assert all(address == node_id for (address, _, _), _, _ in sent)  # source address mode: bit 7 clear
    objects = [(index, sub) for (_, index, sub), _, _ in sent]
    start = SCANNER.index(objects[0])
    assert objects == [SCANNER[(start + k) % 3] for k in range(len(objects))]  # the list in turn, wrapping
    gaps = [b[2] - a[2] for a, b in zip(sent, sent[1:])]
    assert all(0.08 <= gap <= 0.15 for gap in gaps), gaps  # event timer 100 ms, one object per event
    for (_, index, sub), data, _ in sent:
        var = node.object_dictionary[index][sub]
        assert var.data_type == 0x08 and data == var.encode_raw(var.decode_raw(data))  # REAL32 as the EDS says
    supply = node.object_dictionary[0x2506][1].decode_raw(next(d for (_, i, _), d, _ in sent if i == 0x2506))
    assert 23.0 <= supply <= 25.0
    seconds = [struct.unpack("<f", d)[0] for (_, i, _), d, _ in sent if i == 0x2508]
    uploaded = struct.unpack("<f", node.sdo.upload(0x2508, 1))[0]
    assert seconds and 0.0 <= uploaded - seconds[-1] <= 2.0  # the operating-time counter the MPDO carried
    tpdo1 = capture.wait_for(0x180 + node_id, since=since, timeout=2)[0]
    assert len(tpdo1.data) == 8  # flow and gas temperature: the ordinary PDOs stay as they are


def test_scanner_list_is_configurable_by_sdo(emulator, network, capture):
    node_id = 0x15
    emulator(f"{EDS}:{node_id}", "--rules", str(RULES))
    capture.wait_for(0x700 + node_id, data=b"\x00", timeout=3)
    node = remote(network, "buerkert", node_id, od=str(EDS))
    node.sdo.download(0x1FA0, 0, b"\x01")  # only the first entry: the supply voltage
    since = time.time()
    network.send_message(0, bytes([0x01, node_id]))
    mpdos = capture.wait_for(0x480 + node_id, count=3, since=since, timeout=3)
    assert {bytes(m.data)[:4] for m in mpdos} == {bytes([node_id, 0x06, 0x25, 0x01])}
