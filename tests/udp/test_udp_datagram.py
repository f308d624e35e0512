"""The udp_multicast datagram codec (ports/linux/udp_datagram.c) against python-can's own pack_message and
unpack_message: every kind of classic frame (standard and extended identifiers, remote requests, DLC 0..8) is byte
for byte what python-can packs, and the decoder takes exactly what a python-can receiver takes."""
import os
import subprocess

import can
import msgpack
import pytest
from can.interfaces.udp_multicast.utils import pack_message, unpack_message


TOOL = os.environ.get("CO_UDP_DATAGRAM_TOOL", "")


@pytest.fixture(autouse=True)
def datagram_tool_given():
    if not TOOL:
        pytest.fail("CO_UDP_DATAGRAM_TOOL is not set (run by ctest: tests/udp/CMakeLists.txt)", pytrace=False)


def tool(*args):
    return subprocess.run([TOOL, *args], capture_output=True, text=True, check=True).stdout.strip()


FRAMES = [(0x000, "", dlc) for dlc in range(9)] + [(0x7FF, "", 8), (0x1FFFFFFF, "x", 8), (0x18FF0001, "x", 3),
                                                    (0x123, "r", 0), (0x123, "r", 8), (0x1ABCDE, "rx", 4)]


@pytest.mark.parametrize("can_id,flags,dlc", FRAMES)
def test_encoded_frames_are_what_python_can_packs(can_id, flags, dlc):
    data = bytes(range(0xA0, 0xA0 + dlc))
    stamp = 1767225600.123456
    datagram = bytes.fromhex(tool("encode", hex(can_id), flags or "-", str(dlc), data.hex(), repr(stamp)))
    remote = "r" in flags
    msg = can.Message(timestamp=stamp, arbitration_id=can_id, is_extended_id="x" in flags, is_remote_frame=remote,
                      dlc=dlc, data=None if remote else data)
    assert datagram == pack_message(msg)
    back = unpack_message(datagram, check=True)
    assert (back.arbitration_id, back.dlc, bytes(back.data)) == (can_id, dlc, b"" if remote else data)


@pytest.mark.parametrize("can_id,flags,dlc", FRAMES)
def test_python_can_messages_decode_to_the_same_frame(can_id, flags, dlc):
    data = bytes(range(0x30, 0x30 + dlc))
    remote = "r" in flags
    msg = can.Message(arbitration_id=can_id, is_extended_id="x" in flags, is_remote_frame=remote, dlc=dlc,
                      data=None if remote else data)
    expected = f"frame {can_id:#X} {flags} {dlc} {'' if remote else data.hex()}".replace("0X", "0x").strip()
    assert tool("decode", pack_message(msg).hex()) == expected


GOOD = {"timestamp": 0.0, "arbitration_id": 0x612, "is_extended_id": False, "is_remote_frame": False,
        "is_error_frame": False, "channel": None, "dlc": 2, "data": b"\x01\x02", "is_fd": False,
        "bitrate_switch": False, "error_state_indicator": False}


@pytest.mark.parametrize("fields,result", [
    ({}, "frame 0x0 x 0"),                                     # can.Message's defaults: an extended frame
    ({"arbitration_id": 5, "data": b"\x07"}, "frame 0x5 x 1 07"),
    (dict(GOOD, timestamp=-5.0), "frame 0x612  2 0102"),        # python-can replaces the time stamp on receipt
    (dict(GOOD, channel="vcan0", is_rx=False), "frame 0x612  2 0102"),
    (dict(GOOD, dlc=None), "frame 0x612  2 0102"),
    (dict(GOOD, is_remote_frame=True, dlc=3), "frame 0x612 r 3"),  # a remote frame's data are dropped
    (dict(GOOD, is_fd=True), "fd"),
    (dict(GOOD, is_fd=True, dlc=12, data=bytes(12), bitrate_switch=True), "fd"),
    (dict(GOOD, is_error_frame=True), "error"),
    (dict(GOOD, dlc=3), "malformed: DLC 3 but 2 data bytes"),
    (dict(GOOD, dlc=9, data=bytes(9)), "malformed: DLC out of range (0..8)"),
    (dict(GOOD, arbitration_id=0x800), "malformed: identifier out of range for a standard identifier"),
    (dict(GOOD, is_extended_id=True, arbitration_id=0x20000000), "malformed: identifier out of range for an extended"),
    (dict(GOOD, arbitration_id=-1), "malformed: identifier out of range"),
    (dict(GOOD, is_remote_frame=True, is_error_frame=True), "malformed: a remote frame that is also an error frame"),
    (dict(GOOD, error_state_indicator=True), "malformed: bitrate_switch or error_state_indicator"),
    (dict(GOOD, check=True), "malformed: unknown key 'check'"),
    (dict(GOOD, data="ab"), "malformed: 'data' is not a bin"),
    (dict(GOOD, is_extended_id=0), "malformed: 'is_extended_id' has the wrong type"),
])
def test_the_decoder_takes_what_python_can_takes(fields, result):
    datagram = msgpack.packb(fields, use_bin_type=True)
    assert tool("decode", datagram.hex()).startswith(result)
    python_can_takes = True
    try:
        unpack_message(datagram, replace={"timestamp": 1.0}, check=True)  # as python-can's receiver does
    except Exception:
        python_can_takes = False
    # python-can is laxer about types (0 for False); everything else it refuses is malformed here too
    if "wrong type" not in result and "is not a bin" not in result:
        assert python_can_takes == (not result.startswith("malformed")), result


@pytest.mark.parametrize("datagram", [b"", b"\xc1", b"\x80\x00", b"\xdf\xff\xff\xff\xff", b"\x91" * 100 + b"\xc0",
                                      b"\xc7\xff\x01", b"\xd9\x05abc", b"\x81\xa1a"])
def test_bad_bytes_are_malformed(datagram):
    assert tool("decode", datagram.hex()).startswith("malformed: ")
