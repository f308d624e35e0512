"""SDO block transfer over vcan (issue 15 part 1): python-canopen's block client uploads and downloads through the
Bürkert profile and a device from an EDS, with the CRC; the frames on the bus are the CiA 301 block protocol; a
client that asks for a block upload with a protocol switch threshold (CANopenNode's client does) gets an
ordinary upload; the Eltex devices, expedited only by their manuals, still refuse block initiates with 0x05040001."""
import hashlib
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


def firmware_eds(tmp_path):
    """all-types.eds with a program data object 0x1F50:01 (CiA 302: a firmware image, a DOMAIN), as a bootloader
    has: a large object of the file device, whose value lives beside the core (devices/eds_class/eds_large.c)."""
    text = (SOURCE / "tests" / "eds" / "files" / "all-types.eds").read_text()
    text = text.replace("[OptionalObjects]\nSupportedObjects=0\n", "[OptionalObjects]\nSupportedObjects=1\n1=0x1F50\n")
    text += ("\n[1F50]\nParameterName=Program data\nObjectType=0x8\nSubNumber=2\n\n"
             "[1F50sub0]\nParameterName=Number of entries\nObjectType=0x7\nDataType=0x0005\nAccessType=ro\n"
             "DefaultValue=1\nPDOMapping=0\n\n"
             "[1F50sub1]\nParameterName=Program number 1\nObjectType=0x7\nDataType=0x000F\nAccessType=rw\n"
             "PDOMapping=0\n")
    path = tmp_path / "firmware.eds"
    path.write_text(text)
    return path


def image_of(size, seed):
    """size bytes that repeat nowhere a lost or repeated segment would go unnoticed."""
    out = bytearray()
    counter = 0
    while len(out) < size:
        out += hashlib.sha256(b"%d:%d" % (seed, counter)).digest()
        counter += 1
    return bytes(out[:size])


def test_bootloader_download_of_256_kib_by_block_transfer(emulator, network, capture, tmp_path):
    """A bootloader-style download (issue 35, rule 5): 256 KiB into 0x1F50:01 by python-canopen's block client with
    the CRC, then read back by a block upload with the CRC, byte for byte; the core's SDO buffer stays 64 bytes."""
    node_id = 0x23
    eds = firmware_eds(tmp_path)
    emulator(f"{eds}:{node_id}")
    capture.wait_for(0x700 + node_id, data=b"\x00", timeout=3)
    node = remote(network, "buerkert", node_id, od=str(eds))
    image = image_of(256 * 1024, 1)
    since = time.time()
    with node.sdo.open(0x1F50, 1, "wb", block_transfer=True, size=len(image)) as stream:
        stream.write(image)
    initiate = capture.wait_for(0x580 + node_id, since=since, timeout=2)[0]
    assert bytes(initiate.data) == bytes([0xA4, 0x50, 0x1F, 0x01, 127, 0, 0, 0])  # whole blocks of 127 segments
    with node.sdo.open(0x1F50, 1, "rb", block_transfer=True) as stream:
        assert stream.read() == image  # python-canopen checks the server's CRC
    assert node.sdo.upload(0x200D, 0) == bytes.fromhex("DEADBEEF")  # the file's DOMAIN: its own 4 bytes



def test_a_domain_larger_than_the_sdo_buffer_by_segmented_transfer(emulator, network, capture):
    """64 KiB (a thousand SDO buffers) into a file device's DOMAIN by a segmented download, and back by a segmented
    upload; the 1 MiB block transfers: test_sdo_large.py."""
    node_id = 0x24
    eds = SOURCE / "tests" / "eds" / "files" / "all-types.eds"
    emulator(f"{eds}:{node_id}")
    capture.wait_for(0x700 + node_id, data=b"\x00", timeout=3)
    node = remote(network, "buerkert", node_id, od=str(eds))
    blob = image_of(64 * 1024, 2)
    since = time.time()
    node.sdo.download(0x200D, 0, blob)  # segmented: python-canopen's for more than 4 bytes
    initiate = capture.wait_for(0x600 + node_id, since=since, timeout=2)[0]
    assert bytes(initiate.data) == bytes([0x21, 0x0D, 0x20, 0x00]) + struct.pack("<I", len(blob))
    assert node.sdo.upload(0x200D, 0) == blob
