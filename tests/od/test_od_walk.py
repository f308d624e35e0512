"""Every entry of every device's generated object dictionary, walked through the core's SDO server
(tests/od/od_walk runs a node of the bare table). The expectations come from the EDS as read by
python-canopen, an independent parser: read gives the default (node-ID-relative ones resolved), writes
to read-only entries give 0x06010002, reads of write-only ones 0x06010001, a missing sub-index
0x06090011, values past the limits 0x06090031/0x06090032, wrong lengths 0x06070012/0x06070013, and every
PDO mapping entry reads as the EDS (and the manual) gives it."""
import os
import struct
import subprocess
from pathlib import Path

import canopen
import pytest
from canopen import objectdictionary as odt

SRC = Path(os.environ.get("CO_SOURCE_DIR", Path(__file__).resolve().parents[2]))
WALK = os.environ.get("CO_OD_WALK", "")

DEVICES = {  # walker name, EDS, segmented SDO (the Bürkert device needs it for its strings)
    "pro-ionizer": ("pro-ionizer.eds", False),
    "sds": ("sds.eds", False),
    "buerkert": ("buerkert-flow-controller.eds", True),
}
INTEGER_TYPES = {odt.BOOLEAN: "<B", odt.INTEGER8: "<b", odt.INTEGER16: "<h", odt.INTEGER32: "<i", odt.UNSIGNED8: "<B",
                 odt.UNSIGNED16: "<H", odt.UNSIGNED32: "<I", odt.INTEGER64: "<q", odt.UNSIGNED64: "<Q"}

ABORT_WRITE_ONLY = 0x06010001
ABORT_READ_ONLY = 0x06010002
ABORT_UNSUPPORTED = 0x06010000
ABORT_NO_OBJECT = 0x06020000
ABORT_NO_SUB = 0x06090011
ABORT_HIGH = 0x06090031
ABORT_LOW = 0x06090032
ABORT_LEN_HIGH = 0x06070012
ABORT_LEN_LOW = 0x06070013
ABORT_NO_DATA = 0x08000024


class Walker:
    def __init__(self, device, node_id, segmented):
        assert WALK, "CO_OD_WALK (path of the od_walk program) is not set"
        args = [WALK, device, str(node_id)] + (["segmented"] if segmented else [])
        self.p = subprocess.Popen(args, stdin=subprocess.PIPE, stdout=subprocess.PIPE, text=True, bufsize=1)
        self.node_id = node_id
        self.bootup = self._frames()

    def _frames(self):
        frames = []
        for line in self.p.stdout:
            line = line.strip()
            if line == ".":
                return frames
            can_id, data = line.split("#")
            frames.append((int(can_id, 16), bytes.fromhex(data)))
        raise AssertionError("od_walk ended early")

    def request(self, data):
        assert len(data) == 8
        self.p.stdin.write(" ".join(f"{b:02X}" for b in data) + "\n")
        self.p.stdin.flush()
        # heartbeats (0x1017 may be on by default) are not part of the answer
        frames = [f for f in self._frames() if f[0] != 0x700 + self.node_id]
        assert len(frames) == 1, f"request {data.hex()} got {frames}"
        can_id, payload = frames[0]
        assert can_id == 0x580 + self.node_id and len(payload) == 8
        return payload

    def close(self):
        self.p.stdin.close()
        assert self.p.wait(timeout=10) == 0


def mux(index, sub):
    return struct.pack("<HB", index, sub)


def abort_code(resp):
    return struct.unpack("<I", resp[4:])[0] if resp[0] == 0x80 else None


def upload(w, index, sub):
    """Returns the value bytes, or the abort code (int)."""
    resp = w.request(bytes([0x40]) + mux(index, sub) + bytes(4))
    if resp[0] == 0x80:
        assert resp[1:4] == mux(index, sub), resp.hex()
        return abort_code(resp)
    assert resp[1:4] == mux(index, sub), resp.hex()
    if resp[0] & 0x02:  # expedited
        assert resp[0] & 0x01, "size must be indicated"
        return resp[4:8 - ((resp[0] >> 2) & 3)]
    assert resp[0] == 0x41, resp.hex()
    size = struct.unpack("<I", resp[4:])[0]
    data, toggle = b"", 0
    while True:
        seg = w.request(bytes([0x60 | (toggle << 4)]) + bytes(7))
        assert seg[0] & 0xE0 == 0x00 and (seg[0] >> 4) & 1 == toggle, seg.hex()
        data += seg[1:8 - ((seg[0] >> 1) & 7)]
        toggle ^= 1
        if seg[0] & 1:
            break
    assert len(data) == size
    return data


def download(w, index, sub, data):
    n = len(data)
    assert 1 <= n <= 4
    resp = w.request(bytes([0x23 | ((4 - n) << 2)]) + mux(index, sub) + data + bytes(4 - n))
    if resp[0] == 0x80:
        assert resp[1:4] == mux(index, sub)
        return abort_code(resp)
    assert resp == bytes([0x60]) + mux(index, sub) + bytes(4), resp.hex()
    return 0


def variables(od):
    for obj in od.values():
        if isinstance(obj, odt.ODVariable):
            yield obj, [obj]
        else:
            yield obj, list(obj.subindices.values())


def expected_bytes(var):
    default = var.default
    if var.data_type == odt.VISIBLE_STRING:
        return (default or "").encode("ascii")
    if var.data_type == odt.OCTET_STRING:
        return default or b""
    return var.encode_raw(default if default is not None else 0)


def walk(device, node_id):
    eds, segmented = DEVICES[device]
    od = canopen.import_od(str(SRC / "od" / eds), node_id=node_id)
    w = Walker(device, node_id, segmented)
    assert w.bootup == [(0x700 + node_id, b"\x00")]
    failures, checked = [], 0

    def expect(what, got, want):
        nonlocal checked
        checked += 1
        if got != want:
            failures.append(f"{what}: got {got!r}, want {want!r}")

    for obj, subs in variables(od):
        for var in subs:
            index, sub = var.index, var.subindex
            where = f"{device} 0x{index:04X}:{sub:02X} {var.name}"
            readable = var.access_type in ("ro", "rw", "rwr", "rww", "const")
            writable = var.access_type in ("wo", "rw", "rwr", "rww")
            got = upload(w, index, sub)
            if not readable:
                expect(f"{where} read", got, ABORT_WRITE_ONLY)
            elif index == 0x1003 and sub > 0:
                expect(f"{where} read (empty history)", got, ABORT_NO_DATA)
            else:
                want = expected_bytes(var)
                if len(want) > 4 and not segmented:
                    want = ABORT_UNSUPPORTED
                elif len(want) == 0 and not segmented:
                    want = b"\x00"  # the shortest expedited answer
                expect(f"{where} read", got, want)
            if var.data_type not in INTEGER_TYPES and var.data_type != odt.REAL32:
                continue
            size = struct.calcsize(INTEGER_TYPES.get(var.data_type, "<f"))
            if not writable:
                if size <= 4:
                    expect(f"{where} write read-only", download(w, index, sub, bytes(size)), ABORT_READ_ONLY)
                continue
            if index in (0x1010, 0x1011):
                continue  # command objects: any value is a command (tests/unit/test_store.c)
            if size < 4:
                expect(f"{where} write {size + 1} bytes", download(w, index, sub, bytes(size + 1)), ABORT_LEN_HIGH)
            if 1 < size <= 4:
                expect(f"{where} write {size - 1} bytes", download(w, index, sub, bytes(size - 1)), ABORT_LEN_LOW)
            fmt = INTEGER_TYPES.get(var.data_type)
            if fmt and size <= 4:
                if var.max is not None:
                    try:
                        expect(f"{where} write max+1", download(w, index, sub, struct.pack(fmt, var.max + 1)), ABORT_HIGH)
                    except struct.error:
                        pass  # the limit is the type's own
                if var.min is not None:
                    try:
                        expect(f"{where} write min-1", download(w, index, sub, struct.pack(fmt, var.min - 1)), ABORT_LOW)
                    except struct.error:
                        pass
        subs_present = [v.subindex for v in subs]
        missing = max(subs_present) + 1 if isinstance(obj, (odt.ODRecord, odt.ODArray)) else 1
        if missing <= 0xFF:
            expect(f"{device} 0x{obj.index:04X}:{missing:02X} missing sub-index", upload(w, obj.index, missing), ABORT_NO_SUB)
    for index in (0x1002, 0x1004, 0x2100, 0x3000, 0x5FFF, 0x6100, 0xA000):
        if index not in od:
            expect(f"{device} 0x{index:04X} missing object", upload(w, index, 0), ABORT_NO_OBJECT)
    w.close()
    assert not failures, f"{len(failures)} of {checked} checks failed:\n" + "\n".join(failures)
    return checked


@pytest.mark.parametrize("node_id", [5, 127])
@pytest.mark.parametrize("device", sorted(DEVICES))
def test_every_entry_through_the_sdo_server(device, node_id):
    checked = walk(device, node_id)
    assert checked > 80


MAPPINGS = {  # the manuals' PDO mappings, read back through the SDO server
    "pro-ionizer": {0x1600: [0x62000108], 0x1A00: [0x60000108 + (s << 8) for s in range(6)],
                    0x1A01: [0x64010110 + (s << 8) for s in range(4)], 0x1A02: [0x64010510 + (s << 8) for s in range(4)]},
    "sds": {0x1600: [0x62000108], 0x1A00: [0x60000108 + (s << 8) for s in range(5)],
            0x1A01: [0x64010110 + (s << 8) for s in range(3)]},
    "buerkert": {0x1600: [0x25400120], 0x1A00: [0x25000120]},
}


@pytest.mark.parametrize("device", sorted(MAPPINGS))
def test_pdo_mappings_are_the_manuals(device):
    w = Walker(device, 5, DEVICES[device][1])
    for index, entries in MAPPINGS[device].items():
        assert upload(w, index, 0) == bytes([len(entries)]), hex(index)
        for sub, value in enumerate(entries, 1):
            assert upload(w, index, sub) == struct.pack("<I", value), f"0x{index:04X}:{sub}"
    w.close()
