"""A DOMAIN of 1 MiB on a device made from an EDS (issue 35, rule 5): taken by python-canopen's block download and
returned by its block upload, both with the CRC, while the core's SDO buffer stays 64 bytes (the value lives beside
it: devices/eds_class/eds_large.c); more than the bound of 16 MiB is refused. The 256 KiB bootloader download and
the segmented transfers: test_sdo_block.py; the frames one by one: tests/unit/test_sdo_large.c."""
import struct
import time

from conftest import remote
from test_sdo_block import SOURCE, image_of


def test_a_domain_of_1_mib_by_block_transfer_with_crc(emulator, network, capture):
    node_id = 0x25
    eds = SOURCE / "tests" / "eds" / "files" / "all-types.eds"
    emulator(f"{eds}:{node_id}")
    capture.wait_for(0x700 + node_id, data=b"\x00", timeout=3)
    node = remote(network, "buerkert", node_id, od=str(eds))
    blob = image_of(1024 * 1024, 4)
    with node.sdo.open(0x200D, 0, "wb", block_transfer=True, size=len(blob)) as stream:
        stream.write(blob)
    with node.sdo.open(0x200D, 0, "rb", block_transfer=True) as stream:
        assert stream.read() == blob  # python-canopen checks the server's CRC
    since = time.time()
    network.send_message(0x600 + node_id, bytes([0xC6, 0x0D, 0x20, 0x00]) + struct.pack("<I", 16 * 1024 * 1024 + 1))
    answer = capture.wait_for(0x580 + node_id, since=since, timeout=2)[0]
    assert bytes(answer.data) == bytes.fromhex("800D200012000706")  # 0x06070012: more than the object takes
    with node.sdo.open(0x200D, 0, "rb", block_transfer=True) as stream:
        assert stream.read(32) == blob[:32]  # the value stays
