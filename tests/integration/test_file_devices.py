"""Every EDS/DCF file of tests/eds/files/ that canopen-eds accepts, run as a device and checked entry by entry
against the reader's model (`canopen-eds json`) by a python-canopen master (issue 35, "Done when"):

- every readable entry answers its file's value (node-ID-relative ones at the node-ID the device runs at), with its
  length for strings and domains; a write-only entry answers 0x06010001;
- every writable entry takes a legal value and reads it back, with its length, and is restored after;
- 0x1010:01 "save" succeeds on the freshly started device;
- where the file has a TPDO and a TPDO-mappable entry, that TPDO is configured by CiA 301's procedure and seen.

All files run as nodes of one emulator (one start for the module); each test is one file, and a failure lists
every entry that failed with what was expected and what came."""
import json
import math
import os
import struct
import subprocess
import time
from pathlib import Path

import can
import canopen
import pytest
from canopen.sdo.exceptions import SdoAbortedError

from conftest import EMU, SRC, Capture, Emulator, deep_receive_buffer, open_bus

FILES = SRC / "tests" / "eds" / "files"
EDS_TOOL = os.environ.get("CO_EDS_TOOL", str(Path(EMU).parent / "canopen-eds"))
FIRST_NODE_ID = 0x41

# CiA 301 data types: (size in bytes, signed); None: a string or DOMAIN (its length is its value's)
INTEGERS = {0x01: (1, False), 0x02: (1, True), 0x03: (2, True), 0x04: (4, True), 0x05: (1, False),
            0x06: (2, False), 0x07: (4, False), 0x0C: (6, False), 0x0D: (6, False), 0x10: (3, True),
            0x12: (5, True), 0x13: (6, True), 0x14: (7, True), 0x15: (8, True), 0x16: (3, False),
            0x18: (5, False), 0x19: (6, False), 0x1A: (7, False), 0x1B: (8, False)}
REALS = {0x08: "<f", 0x11: "<d"}
VISIBLE_STRING, OCTET_STRING, UNICODE_STRING, DOMAIN = 0x09, 0x0A, 0x0B, 0x0F
READABLE = ("ro", "rw", "rwr", "rww", "const")
WRITABLE = ("rw", "wo", "rwr", "rww")


def model(path):
    """The reader's model of a file, or None when canopen-eds refuses it (exit status 2)."""
    r = subprocess.run([EDS_TOOL, "json", str(path)], capture_output=True, text=True, timeout=30)
    if r.returncode != 0:
        return None
    return json.loads(r.stdout)


def accepted_files():
    found = []
    for path in sorted(FILES.iterdir()):
        if path.suffix.lower() in (".eds", ".dcf"):
            m = model(path)
            if m is not None:
                found.append((path, m))
    return found


ACCEPTED = accepted_files() if EMU else []
NODE_IDS = {path.name: FIRST_NODE_ID + i for i, (path, _) in enumerate(ACCEPTED)}
assert not EMU or len(ACCEPTED) <= 127 - FIRST_NODE_ID + 1


def name(e):
    return f"0x{e['index']:04X}:{e['sub']:02X} {e['name']!r} (line {e['line']})"


def file_value(e, node_id):
    """The entry's value as the file gives it: the DCF's value, else the default; $NODEID added at node_id."""
    if e["param"] is not None:
        value, relative = e["param"], e["param_nodeid"]
    else:
        value, relative = e["default"], e["nodeid"]
    if value is None:
        value = "" if e["type"] in (VISIBLE_STRING, OCTET_STRING, UNICODE_STRING, DOMAIN) else 0
    if (e["index"], e["sub"]) == (0x1018, 4):
        relative = True  # the emulator's serial number: the file's plus the node-ID, for LSS (docs/emulator.md)
    return value + node_id if relative else value


def encode(e, value):
    """A value as the bus carries it."""
    t = e["type"]
    if t in INTEGERS:
        size, signed = INTEGERS[t]
        return int(value).to_bytes(size, "little", signed=signed)
    if t in REALS:
        return struct.pack(REALS[t], float(value))
    if t == VISIBLE_STRING:
        return value.encode("utf-8")
    return bytes.fromhex(value)


def decode(e, raw):
    t = e["type"]
    if t in INTEGERS:
        return int.from_bytes(raw, "little", signed=INTEGERS[t][1])
    if t in REALS:
        return struct.unpack(REALS[t], raw)[0]
    return raw


def is_large(e, value):
    return e["type"] in (VISIBLE_STRING, OCTET_STRING, UNICODE_STRING, DOMAIN) and \
        (e["type"] == DOMAIN or len(encode(e, value)) > 64)


def upload(node, e, value):
    """Block transfer for what the file makes a large object (a DOMAIN, a string longer than 64 bytes)."""
    if is_large(e, value):
        with node.sdo.open(e["index"], e["sub"], "rb", block_transfer=True) as f:
            return f.read()
    return node.sdo.upload(e["index"], e["sub"])


def download(node, e, data):
    if not data:
        download_nothing(node, e)
    elif e["type"] == DOMAIN or len(data) > 64:
        with node.sdo.open(e["index"], e["sub"], "wb", size=len(data), block_transfer=True) as f:
            f.write(data)
    else:
        node.sdo.download(e["index"], e["sub"], data)


def download_nothing(node, e):
    """A download of 0 bytes, segmented: python-canopen sends no segment for it (its block download ends with no
    segment, its segmented one never ends), CiA 301 one segment of 7 unused bytes (c set)."""
    answer = node.sdo.request_response(struct.pack("<BHBI", 0x21, e["index"], e["sub"], 0))
    if answer[0] == 0x80:
        raise SdoAbortedError(struct.unpack_from("<I", answer, 4)[0])
    answer = node.sdo.request_response(b"\x0f" + bytes(7))
    if answer[0] == 0x80:
        raise SdoAbortedError(struct.unpack_from("<I", answer, 4)[0])
    assert answer[0] == 0x20, answer.hex()


def fits(e, value):
    t = e["type"]
    if t in INTEGERS:
        size, signed = INTEGERS[t]
        lo, hi = (-(1 << (8 * size - 1)), (1 << (8 * size - 1)) - 1) if signed else (0, (1 << (8 * size)) - 1)
        if t == 0x01:
            hi = 1
    else:
        lo, hi = -math.inf, math.inf
        if t == 0x08:
            value = struct.unpack("<f", struct.pack("<f", value))[0]
    lo = e["low"] if e["low"] is not None else lo
    hi = e["high"] if e["high"] is not None else hi
    return lo <= value <= hi


def other_value(e, value):
    """A legal value other than the current one, within the type and the file's limits."""
    t = e["type"]
    if t == VISIBLE_STRING:
        return value[: len(value) // 2] if value else "A"
    if t == UNICODE_STRING:
        data = bytes.fromhex(value)
        return data[: len(data) // 4 * 2].hex() if data else "4100"
    if t == OCTET_STRING:
        data = bytes.fromhex(value)
        return data[: len(data) // 2].hex() if data else "5A"
    if t == DOMAIN:
        return "0102030405"
    candidates = [value + 1, value - 1, e["low"], e["high"], 0]
    for c in candidates:
        if c is not None and c != value and fits(e, c):
            return c
    return value


def special(e):
    """Communication entries a different value would change the bus's behaviour or the node's protocol state
    with (COB-IDs, SYNC producer, heartbeats, PDO parameters, store, program control): written back as they
    are, which CiA 301 makes legal, and the PDO mappings by its procedure (test_writable_entries)."""
    return 0x1000 <= e["index"] < 0x2000


@pytest.fixture(scope="module")
def devices(tmp_path_factory):
    """One emulator with every accepted file as a node, a master and a capture of the bus."""
    nvm = tmp_path_factory.mktemp("nvm")
    cap_bus = open_bus()
    deep_receive_buffer(cap_bus)
    cap = Capture()
    notifier = can.Notifier(cap_bus, [cap], timeout=0.05)
    emu = Emulator([f"{path}:{NODE_IDS[path.name]}" for path, _ in ACCEPTED], nvm)
    network = canopen.Network(open_bus())
    network.NOTIFIER_CYCLE = 0.05
    network.connect()
    deep_receive_buffer(network.bus)
    try:
        for path, _ in ACCEPTED:
            cap.wait_for(0x700 + NODE_IDS[path.name], data=b"\x00", timeout=5)
        yield emu, network, cap
    finally:
        network.disconnect()
        emu.stop()
        notifier.stop()
        cap_bus.shutdown()
    reports = [line for line in emu.err_lines if "ERROR: AddressSanitizer" in line or "runtime error:" in line]
    assert not reports, emu.describe(200)


def remote(network, path):
    node_id = NODE_IDS[path.name]
    if node_id in network:
        return network[node_id], node_id
    node = canopen.RemoteNode(node_id, canopen.ObjectDictionary())
    node.sdo.RESPONSE_TIMEOUT = 2.0
    network.add_node(node)
    return node, node_id


FILE_PARAMS = [pytest.param(path, m, id=path.name) for path, m in ACCEPTED]


@pytest.mark.parametrize("path, m", FILE_PARAMS)
def test_store_after_a_fresh_start(devices, path, m):
    """Runs first (pytest keeps the order of the functions): the nodes are as started."""
    _, network, _ = devices
    node, _ = remote(network, path)
    if not any(e["index"] == 0x1010 and e["sub"] == 1 for e in m["entries"]):
        pytest.skip("the file has no 0x1010:01")
    node.sdo.download(0x1010, 1, b"save")


@pytest.mark.parametrize("path, m", FILE_PARAMS)
def test_readable_entries_answer_the_file(devices, path, m):
    _, network, _ = devices
    node, node_id = remote(network, path)
    failures = []
    for e in m["entries"]:
        try:
            if e["access"] == "wo":
                try:
                    raw = node.sdo.upload(e["index"], e["sub"])
                    failures.append(f"{name(e)}: write-only, read {raw.hex()} instead of abort 0x06010001")
                except SdoAbortedError as err:
                    if err.code != 0x06010001:
                        failures.append(f"{name(e)}: write-only, abort 0x{err.code:08X}, not 0x06010001")
                continue
            expected = file_value(e, node_id)
            raw = upload(node, e, expected)
            if raw != encode(e, expected):
                failures.append(f"{name(e)}: read {raw.hex() or '(0 bytes)'} = {decode(e, raw)!r}, "
                                f"the file's {expected!r} is {encode(e, expected).hex() or '(0 bytes)'}")
        except SdoAbortedError as err:
            failures.append(f"{name(e)}: abort 0x{err.code:08X}")
    assert not failures, f"{path.name} at node-ID {node_id}:\n" + "\n".join(failures)


def warned(m, e, emu):
    """The reader's diagnostic at the entry's line, or the emulator's when it started the node (what depends on the
    node-ID), if any (rule 3 of issue 35: where a file holds what the node cannot do, the reader says so at load, by
    line)."""
    at = f"{m['file']}:{e['line']}: warning:"
    return next((d for d in m["diagnostics"] + emu.err_lines if d.startswith(at)), None)


def write_and_read_back(node, e, value, failures, m=None, files_own=False, emu=None):
    data = encode(e, value)
    try:
        download(node, e, data)
    except SdoAbortedError as err:
        if files_own and warned(m, e, emu):
            return False  # the file's value, refused as the reader said at load
        failures.append(f"{name(e)}: writing {data.hex() or '(0 bytes)'} = {value!r}: abort 0x{err.code:08X}")
        return False
    if e["access"] == "wo":
        return True
    raw = upload(node, e, value)
    if raw != data:
        failures.append(f"{name(e)}: wrote {data.hex() or '(0 bytes)'} = {value!r}, read back "
                        f"{raw.hex() or '(0 bytes)'}")
    return True


def pdo_mapping_entries(m):
    """The PDO mapping objects of the file, with their entries by sub-index."""
    pdos = {}
    for e in m["entries"]:
        if 0x1600 <= e["index"] < 0x1800 or 0x1A00 <= e["index"] < 0x1C00:
            pdos.setdefault(e["index"], {})[e["sub"]] = e
    return pdos


@pytest.mark.parametrize("path, m", FILE_PARAMS)
def test_writable_entries_take_a_legal_value(devices, path, m):
    emu, network, _ = devices
    node, node_id = remote(network, path)
    entries = {(e["index"], e["sub"]): e for e in m["entries"]}
    mappings = pdo_mapping_entries(m)
    failures = []
    for e in m["entries"]:
        if e["access"] not in WRITABLE or e["index"] in mappings:
            continue
        if e["index"] in (0x1010, 0x1011) and e["sub"] >= 1:
            continue  # 0x1010 save is test_store_after_a_fresh_start's; a load would undo it
        value = file_value(e, node_id)
        if e["access"] != "wo":
            value = decode(e, upload(node, e, value))
            if e["type"] == VISIBLE_STRING:
                value = value.decode("utf-8")
            elif not isinstance(value, (int, float)):
                value = value.hex()
        try:
            new = value if special(e) and e["type"] != DOMAIN else other_value(e, value)
            if write_and_read_back(node, e, new, failures, m, files_own=new == value, emu=emu) and new != value \
                    and e["access"] != "wo":
                write_and_read_back(node, e, value, failures)
        except SdoAbortedError as err:
            failures.append(f"{name(e)}: reading back: abort 0x{err.code:08X}")
    # a mapping is written by CiA 301's procedure: PDO invalid, count 0, the entries, the count, PDO valid again
    for index, subs in sorted(mappings.items()):
        writable = [e for sub, e in sorted(subs.items()) if e["access"] in WRITABLE]
        if not writable:
            continue
        comm = entries.get((index - 0x200, 1))
        try:
            cob_id = struct.unpack("<I", node.sdo.upload(index - 0x200, 1))[0] if comm else None
            if comm and comm["access"] in WRITABLE:
                node.sdo.download(index - 0x200, 1, struct.pack("<I", cob_id | 0x80000000))
            count = node.sdo.upload(index, 0)[0]
            if 0 in subs and subs[0]["access"] in WRITABLE:
                node.sdo.download(index, 0, b"\x00")
            for e in writable:
                if e["sub"] == 0:
                    continue
                current = struct.unpack("<I", node.sdo.upload(index, e["sub"]))[0]
                write_and_read_back(node, e, current, failures, m, files_own=True, emu=emu)
            if 0 in subs and subs[0]["access"] in WRITABLE:
                write_and_read_back(node, subs[0], count, failures)
            if comm and comm["access"] in WRITABLE:
                node.sdo.download(index - 0x200, 1, struct.pack("<I", cob_id))
        except SdoAbortedError as err:
            failures.append(f"0x{index:04X}: the mapping procedure: abort 0x{err.code:08X}")
    assert not failures, f"{path.name} at node-ID {node_id}:\n" + "\n".join(failures)


def tpdo_to_configure(m):
    """(communication index, mapping index, mapped entry) of the file's first TPDO whose parameters a master may
    write, with a TPDO-mappable numeric entry; None when the file has none."""
    entries = {(e["index"], e["sub"]): e for e in m["entries"]}
    mappable = [e for e in m["entries"] if e["pdo_mapping"] and e["access"] in READABLE and e["type"] in
                INTEGERS | REALS]
    mappable.sort(key=lambda e: e["index"] < 0x2000)  # the application's first, the error register last
    for comm in range(0x1800, 0x1A00):
        cob = entries.get((comm, 1))
        first = entries.get((comm + 0x200, 1))
        count = entries.get((comm + 0x200, 0))
        if cob and first and count and all(x["access"] in WRITABLE for x in (cob, first, count)) and mappable:
            return comm, comm + 0x200, mappable[0]
    return None


@pytest.mark.parametrize("path, m", FILE_PARAMS)
def test_a_tpdo_configured_is_seen(devices, path, m):
    emu, network, cap = devices
    node, node_id = remote(network, path)
    chosen = tpdo_to_configure(m)
    if chosen is None:
        pytest.skip("no TPDO whose COB-ID and mapping a master may write, or no TPDO-mappable entry")
    comm, mapping, e = chosen
    entries = {(x["index"], x["sub"]): x for x in m["entries"]}
    cob_id = 0x180 + node_id
    # TPDO 1's default COB-ID of this node; another TPDO of the node using it is made invalid
    for other in range(0x1800, 0x1A00):
        x = entries.get((other, 1))
        if other != comm and x and x["access"] in WRITABLE:
            if struct.unpack("<I", node.sdo.upload(other, 1))[0] & 0x7FF == cob_id:
                node.sdo.download(other, 1, struct.pack("<I", 0x80000000 | cob_id))
    node.sdo.download(comm, 1, struct.pack("<I", 0x80000000 | cob_id))
    if entries.get((comm, 2), {}).get("access") in WRITABLE:
        node.sdo.download(comm, 2, b"\xfe")
    timer = entries.get((comm, 5), {}).get("access") in WRITABLE
    if timer:
        node.sdo.download(comm, 5, struct.pack("<H", 50))
    node.sdo.download(mapping, 0, b"\x00")
    size = INTEGERS[e["type"]][0] if e["type"] in INTEGERS else struct.calcsize(REALS[e["type"]])
    node.sdo.download(mapping, 1, struct.pack("<I", e["index"] << 16 | e["sub"] << 8 | size * 8))
    node.sdo.download(mapping, 0, b"\x01")
    node.sdo.download(comm, 1, struct.pack("<I", cob_id))
    value = node.sdo.upload(e["index"], e["sub"])
    since = time.time()
    network.send_message(0, bytes([1, node_id]))  # NMT start
    try:
        if not timer:  # event-driven: a change of the mapped value sends it
            time.sleep(0.05)
            since = time.time()
            number = decode(e, value)
            changed = other_value(e, number)
            emu.command(f"set {node_id} 0x{e['index']:04X}:{e['sub']} {changed}", expect=f"0x{e['index']:04X}")
            value = encode(e, changed)
        frames = cap.wait_for(cob_id, timeout=3, since=since)
        assert bytes(frames[-1].data) == value, f"{path.name}: TPDO 0x{cob_id:03X} mapping {name(e)}"
    finally:
        network.send_message(0, bytes([0x80, node_id]))  # back to pre-operational


def test_a_restricted_cob_id_at_the_node_id_is_said_at_start(devices):
    """sdo-servers.eds's third server answers on $NODEID+0x6A0: at node-IDs 0x40..0x5F a restricted CAN-ID
    (0x6E0..0x6FF, CiA 301), which the node takes from the file and refuses from a master (0x06090030). The reader
    cannot know the node-ID; the emulator says so, by line, when it starts the node."""
    emu, _, _ = devices
    node_id = NODE_IDS["sdo-servers.eds"]
    assert 0x40 <= node_id <= 0x5F
    assert f"{FILES / 'sdo-servers.eds'}:204: warning: [1202sub2] $NODEID+0x6A0 is 0x{0x6A0 + node_id:X} at node-ID " \
           f"{node_id}, a restricted CAN-ID (CiA 301): the node uses it as the file says, a master's write of it is " \
           f"refused (0x06090030)" in emu.err_lines
