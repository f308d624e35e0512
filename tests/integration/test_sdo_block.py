"""SDO block transfer over vcan (issue 15 part 1): python-canopen's block client uploads and downloads through the
Bürkert profile and a device from an EDS, with the CRC; the frames on the bus are the CiA 301 block protocol; a
client that asks for a block upload with a protocol switch threshold (CANopenNode's client does) gets an
ordinary upload; the Eltex devices, expedited only by their manuals, still refuse block initiates with 0x05040001."""
import struct
import time
from pathlib import Path

import pytest

from conftest import remote

SOURCE = Path(__file__).resolve().parents[2]


def block_frames(capture, node_id, since, requests, responses):
    """The frames of node_id's SDO channel since `since`, as bytes, once the capture has seen as many as expected
    (it receives on its own socket, a little after the client)."""
    return ([bytes(m.data) for m in capture.wait_for(0x600 + node_id, count=requests, since=since)],
            [bytes(m.data) for m in capture.wait_for(0x580 + node_id, count=responses, since=since)])


def test_block_download_and_upload_with_crc_through_python_canopen(emulator, network, capture):
    node_id = 0x12
    emulator(f"buerkert:{node_id}")
    capture.wait_for(0x700 + node_id, data=b"\x00", timeout=3)
    node = remote(network, "buerkert", node_id)
    name = b"flow controller, line 7, bay 3"  # 30 bytes: five segments, 5 unused bytes in the last
    since = time.time()
    with node.sdo.open(0x2002, 1, "wb", block_transfer=True, size=len(name)) as stream:
        stream.write(name)
    requests, responses = block_frames(capture, node_id, since, 7, 3)
    assert len(requests) == 7 and len(responses) == 3
    assert requests[0] == bytes([0xC6, 0x02, 0x20, 0x01]) + struct.pack("<I", len(name))  # CRC, size indicated
    assert responses[0] == bytes([0xA4, 0x02, 0x20, 0x01, 10, 0, 0, 0])  # CRC; 10 segments fill the 64-byte buffer
    assert [r[0] for r in requests[1:6]] == [0x01, 0x02, 0x03, 0x04, 0x85]
    assert responses[1] == bytes([0xA2, 5, 10, 0, 0, 0, 0, 0])
    assert requests[6][0] == 0xC1 | (5 << 2)  # end: 5 unused bytes, then the CRC python-canopen computed
    assert responses[2] == bytes([0xA1, 0, 0, 0, 0, 0, 0, 0])
    assert node.sdo.upload(0x2002, 1) == name  # read back by a segmented upload

    since = time.time()
    with node.sdo.open(0x2002, 1, "rb", block_transfer=True) as stream:
        assert stream.read() == name  # python-canopen checks the server's CRC
    requests, responses = block_frames(capture, node_id, since, 4, 7)
    assert len(requests) == 4 and len(responses) == 7
    assert responses[0] == bytes([0xC6, 0x02, 0x20, 0x01]) + struct.pack("<I", len(name))
    assert [r[0] for r in responses[1:6]] == [0x01, 0x02, 0x03, 0x04, 0x85]
    assert responses[1][1:] == name[:7] and responses[5][1:3] == name[28:]
    assert responses[6][0] == 0xC1 | (5 << 2)  # end: 5 unused bytes
    assert [r[0] for r in requests] == [0xA4, 0xA3, 0xA2, 0xA1]
    assert requests[2][1] == 5  # all five segments confirmed


def test_block_transfer_of_a_device_from_its_eds(emulator, network, capture):
    node_id = 0x21
    eds = SOURCE / "tests" / "eds" / "files" / "all-types.eds"
    emulator(f"{eds}:{node_id}")
    capture.wait_for(0x700 + node_id, data=b"\x00", timeout=3)
    node = remote(network, "buerkert", node_id, od=str(eds))
    with node.sdo.open(0x2008, 0, "rb", block_transfer=True) as stream:
        assert stream.read() == b"hello world"
    blob = bytes(range(7, 7 + 64))  # the whole 64-byte domain: ten segments, the last with 1 byte
    with node.sdo.open(0x200D, 0, "wb", block_transfer=True, size=len(blob)) as stream:
        stream.write(blob)
    with node.sdo.open(0x200D, 0, "rb", block_transfer=True) as stream:
        assert stream.read() == blob
    assert node.sdo.upload(0x200D, 0) == blob


def test_protocol_switch_answers_a_small_object_with_an_expedited_upload(emulator, capture, network):
    node_id = 0x10
    emulator(f"buerkert:{node_id}")
    capture.wait_for(0x700 + node_id, data=b"\x00", timeout=3)
    node = remote(network, "buerkert", node_id)
    vendor = node.sdo.upload(0x1018, 1)
    since = time.time()
    # CANopenNode's client with block transfer on: block upload of 4 bytes, threshold 21 bytes.
    network.send_message(0x600 + node_id, bytes.fromhex("A41810017F150000"))
    answer = capture.wait_for(0x580 + node_id, since=since, timeout=2)[0]
    assert bytes(answer.data) == bytes.fromhex("43181001") + vendor


@pytest.mark.parametrize("device", ["pro-ionizer", "sds"])
def test_expedited_only_devices_still_refuse_block_initiates(emulator, capture, network, device):
    node_id = 0x16
    emulator(f"{device}:{node_id}")
    capture.wait_for(0x700 + node_id, data=b"\x00", timeout=3)
    since = time.time()
    network.send_message(0x600 + node_id, bytes.fromhex("A41810017F150000"))
    answer = capture.wait_for(0x580 + node_id, since=since, timeout=2)[0]
    assert bytes(answer.data) == bytes.fromhex("8018100101000405")
