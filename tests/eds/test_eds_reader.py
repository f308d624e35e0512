"""The EDS/DCF reader (eds/) through canopen-eds: each feature file of tests/eds/files/ gives exactly the
diagnostics and values expected, bad input gets a clear error with exit status 2, and a file written back
(EDS or DCF) reads as the same model; python-canopen loads the DCF with the same values."""
import json
import os
import subprocess
from pathlib import Path

import canopen
import pytest

SRC = Path(os.environ.get("CO_SOURCE_DIR", Path(__file__).resolve().parents[2]))
TOOL = os.environ.get("CO_EDS_TOOL", "canopen-eds")
FILES = SRC / "tests" / "eds" / "files"
ALL_FILES = sorted(FILES.iterdir()) + sorted((SRC / "od").glob("*.eds"))


def run(*args, timeout=60):
    return subprocess.run([TOOL, *map(str, args)], capture_output=True, text=True, timeout=timeout)


def model(path):
    r = run("json", path)
    assert r.returncode == 0, r.stderr
    return json.loads(r.stdout)


def diagnostics(path):
    r = run("check", path)
    return r.returncode, [line.replace(str(path.parent) + "/", "") for line in r.stderr.splitlines()]


def entry(m, index, sub=0):
    found = [e for e in m["entries"] if e["index"] == index and e["sub"] == sub]
    assert len(found) == 1, f"0x{index:04X}:{sub} not in the model"
    return found[0]


# Every feature file and the exact diagnostics it gives (exit status 0: the file can be emulated).
EXPECTED_DIAGNOSTICS = {
    "minimal.eds": [],
    "sdo-servers.eds": [],
    "all-types.eds": [],
    "compact.eds": [],
    # transmission type 1 without 0x1005: SYNC on CiA 301's 0x80 (issue 35)
    "device.dcf": ["device.dcf:149: warning: [1800sub2] transmission type 1 is synchronous, but the file has no SYNC "
                   "object 0x1005; added with CiA 301's default COB-ID 0x80"],
    "drive.eds": [],
    "domain-links.eds": [],
    "many-pdos.eds": [],
    "numbers.eds": ["numbers.eds:121: warning: [2000] DefaultValue: '010' has a leading 0: read as octal (CiA 306), 8",
                    "numbers.eds:145: warning: [2003] DefaultValue: '08' has a leading 0 but is not octal: read as decimal"],
    "bom-latin1.eds": ["bom-latin1.eds:107: warning: not UTF-8 (byte 0xDF); the file is read as Latin-1"],
    "inline-comments.eds": ["inline-comments.eds:112: warning: DefaultValue: inline comment '; sixteen' removed "
                            "(CiA 306 has comments on lines of their own)"],
    "limits.eds": ["limits.eds:113: warning: [2000] DefaultValue (none, so 0) is outside LowLimit..HighLimit; 0x5 "
                   "(the LowLimit) used"],
    "unsorted-lists.eds": [  # in the order of their lines
        "unsorted-lists.eds:102: warning: [ManufacturerObjects] SupportedObjects=3 but 2 entries are listed; the "
        "listed ones are read",
        "unsorted-lists.eds:105: warning: [ManufacturerObjects] 2: object 0x2000 out of order (after 0x2001); the "
        "objects are sorted"],
    "missing-info.eds": [
        "missing-info.eds:9: warning: [DeviceInfo] has no VendorNumber; taken from object 0x1018 (or 0)",
        "missing-info.eds:9: warning: [DeviceInfo] has no ProductName; left empty",
        "missing-info.eds:9: warning: [DeviceInfo] has no RevisionNumber; taken from object 0x1018 (or 0)"],
    "dummy-usage.eds": ["dummy-usage.eds:211: warning: [1601sub1] DefaultValue 0x00070020 maps dummy 0x0007 while "
                        "[DummyUsage] Dummy0007 is not 1; the PDO is disabled"],
    # The files of issue 35 (test_eds_repairs.py checks their models)
    "pdomapping-hex.eds": [],
    "mapping-limits.eds": [
        "mapping-limits.eds:181: warning: [1A00sub2] 0x21000108, above the count 1, maps 0x2100:01, which does not "
        "exist, which a master cannot write back; kept (CiA 301 checks the entries up to the count)",
        "mapping-limits.eds:194: warning: [1A01sub0] the mapping (DefaultValue) has 96 bits, more than 64; the PDO is "
        "disabled"],
    "empty-values.dcf": [
        "empty-values.dcf:81: warning: [1018sub1] ParameterValue is empty; DefaultValue 0xABC kept",
        "empty-values.dcf:114: warning: [1005] ParameterValue is empty; DefaultValue 0x80 kept",
        "empty-values.dcf:136: warning: [1800sub1] ParameterValue is empty; DefaultValue $NODEID+0x180 kept"],
    "node-id.dcf": ["node-id.dcf:274: warning: [1801sub1] ParameterValue 0x2A5 is the COB-ID of node-ID 37 "
                    "($NODEID+0x280), not of the file's NodeID 32; kept as 0x2A5 at any node-ID"],
    "small-rules.eds": [
        "small-rules.eds:123: warning: [1800sub2] transmission type 1 is synchronous, but the file has no SYNC object "
        "0x1005; added with CiA 301's default COB-ID 0x80",
        "small-rules.eds:183: warning: [2003] DefaultValue: '01000' has a leading 0: read as octal (CiA 306), 512",
        "small-rules.eds:191: warning: [2004] DefaultValue: '0x1FF' does not fit INTEGER8; 127 used"],
    "diagnostics.eds": [
        "diagnostics.eds:54: warning: [1018] has no ObjectType but sub-index sections; read as a RECORD (0x9)",
        "diagnostics.eds:127: warning: [1A00] has no sub-index 0; added as the number of mapping entries present "
        "(UNSIGNED8, rw, 2)",
        "diagnostics.eds:215: warning: [2000ObjectLinks] names object 0x2005, which the device does not have; the "
        "link is left out"],
    "broken-refs.eds": [
        "broken-refs.eds:106: warning: object 0x2002 is listed but has no section [2002]; left out",
        "broken-refs.eds:112: warning: [2000] SubNumber: '99999' is not a number from 0 to 65535; 2 used",
        "broken-refs.eds:128: warning: [2001] an ARRAY without sub-index sections; left out",
        "broken-refs.eds:134: warning: [2001] CompactSubObj: '1000' is not a number from 0 to 254; 0 used",
        "broken-refs.eds:136: warning: [2003sub1] belongs to no object of the device; ignored",
        "broken-refs.eds:146: warning: [2004] DataType=0x0040 is not a CiA 301 basic data type this reader knows; "
        "the entry is left out"],
}


def test_every_feature_file_has_its_expectation():
    assert sorted(p.name for p in FILES.iterdir()) == sorted(EXPECTED_DIAGNOSTICS)


@pytest.mark.parametrize("name", sorted(EXPECTED_DIAGNOSTICS))
def test_feature_file_diagnostics(name):
    rc, lines = diagnostics(FILES / name)
    assert lines == EXPECTED_DIAGNOSTICS[name]
    assert rc == 0
    strict = run("check", "--strict", FILES / name)
    assert strict.returncode == (2 if EXPECTED_DIAGNOSTICS[name] else 0)


def test_the_project_devices_are_clean():
    for eds in sorted((SRC / "od").glob("*.eds")):
        assert run("check", "--strict", eds).returncode == 0, eds


def test_numbers_follow_cia_306():
    m = model(FILES / "numbers.eds")
    values = {e["index"]: (e["default"], e["nodeid"]) for e in m["entries"] if e["index"] >= 0x2000}
    assert values == {
        0x2000: (8, False),            # 010 is octal
        0x2001: (31, False), 0x2002: (31, False),
        0x2003: (8, False),            # 08 cannot be octal: decimal, with a warning
        0x2004: (-16, False),
        0x2005: (0x180, True), 0x2006: (0x200, True), 0x2007: (0x80000180, True), 0x2008: (0x300, True),
        0x2009: (0x400, True), 0x200A: (0, False)}


def test_every_basic_type():
    m = model(FILES / "all-types.eds")
    got = {e["type"]: (e["default"], e["low"], e["high"]) for e in m["entries"] if e["index"] >= 0x2000}
    assert got == {
        0x01: (1, None, None), 0x02: (-128, None, None), 0x03: (-300, -1000, 1000), 0x04: (-70000, None, None),
        0x05: (255, None, None), 0x06: (65535, None, None), 0x07: (4294967295, None, None), 0x08: (2.5, -10.0, 10.0),
        0x09: ("hello world", None, None), 0x0A: ("0102A0FF", None, None),
        0x0B: ("Grüße".encode("utf-16-le").hex().upper(), None, None), 0x0C: (0xA5A5A5A5, None, None),
        0x0D: (1000, None, None), 0x0F: ("DEADBEEF", None, None), 0x10: (-(2 ** 23), None, None),
        0x11: (-1.25e-300, -1e-299, 1e300), 0x12: (-(2 ** 39), None, None), 0x13: (2 ** 47 - 1, None, None),
        0x14: (-(2 ** 55), None, None), 0x15: (-(2 ** 63), None, None), 0x16: (2 ** 24 - 1, None, None),
        0x18: (2 ** 40 - 1, None, None), 0x19: (2 ** 48 - 1, None, None), 0x1A: (2 ** 56 - 1, None, None),
        0x1B: (2 ** 64 - 1, 0x10, 2 ** 64 - 1)}


def test_compact_sub_objects():
    m = model(FILES / "compact.eds")
    subs = [(e["sub"], e["name"], e["type"], e["access"], e["default"], e["low"], e["high"], e["pdo_mapping"])
            for e in m["entries"] if e["index"] == 0x2100]
    assert subs == [(0, "NrOfObjects", 5, "ro", 4, None, None, False)] + [
        (s, n, 6, "rw", 100, 10, 1000, True)
        for s, n in ((1, "Gain left"), (2, "Channel gain2"), (3, "Gain right"), (4, "Channel gain4"))]


def test_a_long_compact_name_is_formed_whole(tmp_path):
    """The name of an unnamed compact sub-object is the object's name and the sub-index, however long: a name cut
    to a buffer split a two-byte UTF-8 sequence, and the DCF written from it was not UTF-8 (a fuzz finding)."""
    long_name = " ".join(["Kanalverstärkung"] * 20)  # 359 bytes of UTF-8
    path = tmp_path / "long.eds"
    path.write_text((FILES / "compact.eds").read_text().replace("ParameterName=Channel gain",
                                                                "ParameterName=" + long_name))
    assert entry(model(path), 0x2100, 2)["name"] == long_name + "2"
    out = tmp_path / "out.dcf"
    assert run("convert", "--dcf", "--node-id", "7", path, out).returncode == 0
    out.read_bytes().decode("utf-8")  # raises if the writer split a sequence
    again = model(out)
    assert again["warnings"] == 0 and again["errors"] == 0, again["diagnostics"]
    assert entry(again, 0x2100, 4)["name"] == long_name + "4"


def test_dcf_values_and_commissioning():
    m = model(FILES / "device.dcf")
    assert m["device"]["is_dcf"] is True
    assert m["commissioning"] == {"node_id": 5, "baudrate_kbit": 250, "node_name": "Left valve",
                                  "lss_serial_number": 0x12345678}
    assert entry(m, 0x1017)["param"] == 500 and entry(m, 0x1017)["default"] == 0
    assert entry(m, 0x1800, 2)["param"] == 1
    assert entry(m, 0x2000)["param"] == 1200 and entry(m, 0x2000)["denotation"] == "Left valve position"
    assert [entry(m, 0x2100, s)["param"] for s in (1, 2, 3)] == [-5, None, 12]


def test_limits_and_empty_defaults():
    m = model(FILES / "limits.eds")
    assert (entry(m, 0x2000)["default"], entry(m, 0x2000)["low"], entry(m, 0x2000)["high"]) == (5, 5, 50)
    assert (entry(m, 0x2001)["low"], entry(m, 0x2001)["high"]) == (0.0, 10.0)
    assert (entry(m, 0x2002)["low"], entry(m, 0x2002)["high"]) == (0x10, 2 ** 63)


def test_dummy_mapping_only_where_allowed():
    m = model(FILES / "dummy-usage.eds")
    assert entry(m, 0x1600, 0)["default"] == 2 and entry(m, 0x1600, 1)["default"] == 0x00050008
    assert entry(m, 0x1400, 1)["default"] == 0x200 and entry(m, 0x1400, 1)["nodeid"]
    assert entry(m, 0x1601, 0)["default"] == 0                      # disabled: empty mapping ...
    assert entry(m, 0x1601, 0)["low"] is None                       # (its LowLimit 1 would refuse it)
    assert entry(m, 0x1401, 1)["default"] & 0x80000000              # ... and not valid
    assert m["device"]["dummy_usage"] == (1 << 2) | (1 << 5)


def test_many_pdos_are_all_read():
    m = model(FILES / "many-pdos.eds")
    assert (m["device"]["nr_of_rxpdo"], m["device"]["nr_of_txpdo"]) == (8, 12)
    assert entry(m, 0x1A0B, 1)["default"] == 0x220B0010


def test_domain_deftype_links_and_identity_from_1018():
    m = model(FILES / "domain-links.eds")
    objects = {o["index"]: o for o in m["objects"]}
    assert objects[0x1F50]["object_type"] == 2 and entry(m, 0x1F50)["type"] == 0x0F
    assert objects[0x0005]["object_type"] == 5 and entry(m, 0x0005)["default"] == 8
    assert objects[0x2000]["links"] == [0x2001, 0x1F50]
    info = model(FILES / "missing-info.eds")["device"]
    assert (info["vendor_number"], info["revision_number"], info["product_name"]) == (0xABC, 0x10000, "")


def test_latin1_and_bom():
    assert entry(model(FILES / "bom-latin1.eds"), 0x2000)["name"] == "Temperatur Außen"


def test_inline_comment_only_on_numbers():
    m = model(FILES / "inline-comments.eds")
    assert entry(m, 0x2000)["default"] == 0x10 and entry(m, 0x2001)["default"] == "a;b"


# ---- Bad input: a clear error with exit status 2, never a crash or a hang --------------------------------------

BAD_INPUT = {
    "binary.eds": (b"[1000]\nParameterName=x\n\x00\x01\x02garbage", "binary.eds:3: error: a NUL byte: this is binary data"),
    "utf16.eds": ("[FileInfo]\n".encode("utf-16"), "utf16.eds:1: error: UTF-16 text"),
    "empty.eds": (b"", "empty.eds: error: no [section] at all: not an EDS or DCF file"),
    "prose.txt": (b"This is a letter,\nnot a device description.\n", "prose.txt: error: no [section] at all"),
    "no-objects.eds": (b"[FileInfo]\nFileName=x\n[DeviceInfo]\nVendorName=x\n", "no-objects.eds: error: no objects"),
    "no-1000.eds": (b"[MandatoryObjects]\nSupportedObjects=1\n1=0x1001\n[1001]\nParameterName=e\nDataType=5\n"
                    b"AccessType=ro\n", "no-1000.eds: error: object 0x1000 is missing"),
}


@pytest.mark.parametrize("name", sorted(BAD_INPUT))
def test_bad_input_is_refused_with_exit_status_2(tmp_path, name):
    data, message = BAD_INPUT[name]
    (tmp_path / name).write_bytes(data)
    rc, lines = diagnostics(tmp_path / name)
    assert rc == 2
    assert any(line.startswith(message) for line in lines), lines


def test_a_50_mb_file_is_refused(tmp_path):
    big = tmp_path / "big.eds"
    with open(big, "wb") as f:
        f.write(b"[2000]\n" + b"ParameterName=" + b"x" * (50 * 1024 * 1024) + b"\n")
    rc, lines = diagnostics(big)
    assert rc == 2 and lines == ["big.eds: error: larger than any device description (limit 16777216 bytes); not read"]


def test_missing_file_and_directory(tmp_path):
    rc, lines = diagnostics(tmp_path / "absent.eds")
    assert rc == 2 and lines == ["absent.eds: error: cannot open: No such file or directory"]
    r = run("check", tmp_path)
    assert r.returncode == 2 and "error: read error" in r.stderr


def test_usage_errors():
    assert run().returncode == 1
    assert run("convert", "--node-id", "200", FILES / "minimal.eds", "-").returncode == 1
    assert run("frobnicate", FILES / "minimal.eds").returncode == 1


# ---- Round trips ---------------------------------------------------------------------------------------------

def comparable(m, dcf=False):
    """The model without what a rewrite legitimately changes (lines, the compact form, diagnostics)."""
    entries = []
    for e in m["entries"]:
        e = dict(e)
        e.pop("line")
        if dcf:  # a DCF states every value: the effective one
            e["param"], e["param_nodeid"] = (e["param"], e["param_nodeid"]) if e["param"] is not None else (e["default"], e["nodeid"])
        entries.append(e)
    objects = [{k: v for k, v in o.items() if k not in ("line", "compact")} for o in m["objects"]]
    device = {k: v for k, v in m["device"].items() if k != "is_dcf"}
    return device, objects, entries


@pytest.mark.parametrize("path", ALL_FILES, ids=lambda p: p.name)
def test_round_trip_eds(tmp_path, path):
    first = model(path)
    out = tmp_path / "out.eds"
    assert run("convert", path, out).returncode == 0
    second = model(out)
    # a mapping entry a master cannot write back is kept as it is and said again (above the count of a PDO the
    # reader disabled, dummy-usage.eds)
    assert all("which a master cannot write back; kept" in d for d in second["diagnostics"]), second["diagnostics"]
    assert second["errors"] == 0
    a, b = comparable(first), comparable(second)
    if not first["device"]["is_dcf"]:
        assert a == b
    else:  # an EDS written from a DCF has no ParameterValue
        for e in a[2]:
            e["param"], e["param_nodeid"], e["denotation"] = None, False, None
        assert a == b
    again = tmp_path / "again.eds"
    assert run("convert", out, again).returncode == 0
    assert again.read_text().replace("again.eds", "out.eds") == out.read_text()  # a fixed point


@pytest.mark.parametrize("path", ALL_FILES, ids=lambda p: p.name)
def test_round_trip_dcf(tmp_path, path):
    out = tmp_path / "out.dcf"
    assert run("convert", "--dcf", "--node-id", "7", path, out).returncode == 0
    second = model(out)
    # only a value kept as it is may be told again (node-id.dcf's COB-ID of node 37 is not node 7's either)
    assert all("; kept" in d for d in second["diagnostics"]) and second["errors"] == 0, second["diagnostics"]
    assert second["commissioning"]["node_id"] == 7
    assert comparable(model(path), dcf=True) == comparable(second, dcf=True)


@pytest.mark.parametrize("name", ["device.dcf", "all-types.eds", "many-pdos.eds"])
def test_python_canopen_reads_the_written_dcf(tmp_path, name):
    out = tmp_path / "out.dcf"
    assert run("convert", "--dcf", "--node-id", "7", FILES / name, out).returncode == 0
    ours = model(out)
    od = canopen.import_od(str(out), node_id=7)
    checked = 0
    for e in ours["entries"]:
        obj = od[e["index"]]
        var = obj if isinstance(obj, canopen.objectdictionary.ODVariable) else obj[e["sub"]]
        if isinstance(e["param"], int):
            expected = e["param"] + (7 if e["param_nodeid"] else 0)
            assert var.value == expected, f"0x{e['index']:04X}:{e['sub']}"
            checked += 1
        elif e["type"] == 0x09:
            assert var.value == e["param"]
            checked += 1
    assert checked >= 8
