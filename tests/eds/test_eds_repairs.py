"""The reader's rules of issue 35 through canopen-eds, each on a small file of our own (tests/eds/files/): hexadecimal
PDOMapping, empty DCF values, a DCF's values at another node-ID, signed hexadecimal defaults, SYNC for synchronous
PDOs, octal, and diagnostics that lead to the fix (a RECORD without ObjectType, a link to a missing object, a
mapping without sub-index 0, repeated warnings grouped). The exact diagnostics of each file are in
test_eds_reader.py; the emulated device at another node-ID in tests/integration/test_eds_devices.py."""
import json
import os
import subprocess
from pathlib import Path

import canopen
import pytest

SRC = Path(os.environ.get("CO_SOURCE_DIR", Path(__file__).resolve().parents[2]))
TOOL = os.environ.get("CO_EDS_TOOL", "canopen-eds")
FILES = SRC / "tests" / "eds" / "files"
MINIMAL = (FILES / "minimal.eds").read_text()


def run(*args):
    return subprocess.run([TOOL, *map(str, args)], capture_output=True, text=True, timeout=60)


def model(path):
    r = run("json", path)
    assert r.returncode == 0, r.stderr
    return json.loads(r.stdout)


def entry(m, index, sub=0):
    found = [e for e in m["entries"] if e["index"] == index and e["sub"] == sub]
    assert len(found) == 1, f"0x{index:04X}:{sub} not in the model"
    return found[0]


def stderr_lines(path):
    return [line.replace(str(path.parent) + "/", "") for line in run("check", path).stderr.splitlines()]


# ---- 1. PDOMapping=0x1 --------------------------------------------------------------------------------------------

def test_pdo_mapping_in_hexadecimal_maps():
    m = model(FILES / "pdomapping-hex.eds")
    assert m["warnings"] == 0, m["diagnostics"]
    assert [entry(m, i)["pdo_mapping"] for i in (0x1000, 0x1001, 0x2000, 0x2001)] == [False, True, True, True]
    assert entry(m, 0x1800, 1)["default"] & 0x80000000 == 0       # the PDO is not disabled ...
    assert entry(m, 0x1A00, 0)["default"] == 2                    # ... and keeps its mapping


def test_python_canopen_export_keeps_what_is_mappable(tmp_path):
    """python-canopen's EDS export writes PDOMapping=0x0/0x1: a file it exports maps what the original maps."""
    original = SRC / "od" / "sds.eds"
    od = canopen.import_od(str(original), node_id=0x20)
    exported = tmp_path / "exported.eds"
    canopen.export_od(od, str(exported))
    assert "PDOMapping=0x1" in exported.read_text()
    a, b = model(original), model(exported)
    assert b["warnings"] == 0, b["diagnostics"]
    mappable = lambda m: {(e["index"], e["sub"]) for e in m["entries"] if e["pdo_mapping"]}  # noqa: E731
    assert mappable(b) == mappable(a) and mappable(a)


# ---- 2. An empty ParameterValue -----------------------------------------------------------------------------------

def test_an_empty_parameter_value_keeps_the_default():
    m = model(FILES / "empty-values.dcf")
    assert (entry(m, 0x1005)["param"], entry(m, 0x1005)["default"]) == (None, 0x80)      # SYNC COB-ID, not 0
    assert (entry(m, 0x1018, 1)["param"], entry(m, 0x1018, 1)["default"]) == (None, 0xABC)  # vendor-ID, not 0
    cob = entry(m, 0x1800, 1)
    assert (cob["param"], cob["default"], cob["nodeid"]) == (None, 0x180, True)          # follows the node-ID
    assert entry(m, 0x2000)["param"] == 0x4321                                           # a value is a value
    assert entry(m, 0x2001)["param"] == ""  # an empty string is the empty string (python-canopen reads it so)


# ---- 6. A DCF at a node-ID other than the file's ------------------------------------------------------------------

def test_values_of_the_files_node_id_follow_the_node_id():
    m = model(FILES / "node-id.dcf")
    assert m["commissioning"]["node_id"] == 0x20
    relative = {(e["index"], e["sub"]): e["param"] for e in m["entries"] if e["param_nodeid"]}
    assert relative == {(0x1014, 0): 0x80, (0x1200, 1): 0x600, (0x1200, 2): 0x580,
                        (0x1400, 1): 0x80000200,   # disabled in the DCF (bit 31), stays disabled
                        (0x1800, 1): 0x180, (0x2002, 0): 10}
    other = entry(m, 0x1801, 1)  # 0x2A5: node 0x25's TPDO 2, configured so: kept, warned
    assert (other["param"], other["param_nodeid"]) == (0x2A5, False)
    assert stderr_lines(FILES / "node-id.dcf") == [
        "node-id.dcf:274: warning: [1801sub1] ParameterValue 0x2A5 is the COB-ID of node-ID 37 ($NODEID+0x280), not "
        "of the file's NodeID 32; kept as 0x2A5 at any node-ID"]


def test_without_a_node_id_values_are_kept_and_cob_ids_of_a_node_warned(tmp_path):
    dcf = tmp_path / "no-node-id.dcf"
    dcf.write_text((FILES / "node-id.dcf").read_text().replace("NodeID=0x20\n", ""))
    m = model(dcf)
    assert not any(e["param_nodeid"] for e in m["entries"])
    assert entry(m, 0x1014)["param"] == 0xA0
    lines = stderr_lines(dcf)
    assert "no-node-id.dcf:118: warning: [1014] ParameterValue 0xA0 is the COB-ID of node-ID 32 ($NODEID+0x80), and " \
           "the file has no NodeID to tell whether that is its own; kept as 0xA0 at any node-ID" in lines


def test_the_written_dcf_says_what_the_reader_reads(tmp_path):
    """A DCF written for node-ID 37 states 0x2A5 (node 37's $NODEID+0x280) as $NODEID+0x280: read back at its NodeID
    it follows the node-ID, so the writer writes it so; at node-ID 20 the file's values follow the node-ID."""
    for node_id, relative in ((37, "$NODEID+0x280"), (20, "0x2A5")):
        out = tmp_path / f"node{node_id}.dcf"
        assert run("convert", "--dcf", "--node-id", node_id, FILES / "node-id.dcf", out).returncode == 0
        text = out.read_text()
        section = text[text.index("[1801sub1]"):]
        assert section.splitlines()[7] == f"ParameterValue={relative}"
        assert "ParameterValue=$NODEID+0x80\n" in text[text.index("[1014]"):]
        back = model(out)
        assert back["warnings"] == (0 if node_id == 37 else 1), back["diagnostics"]  # at 20: 0x2A5, node 37's
    od = canopen.import_od(str(tmp_path / "node20.dcf"), node_id=20)
    assert od[0x1014].value == 0x80 + 20 and od[0x1200][1].value == 0x600 + 20 and od[0x1801][1].value == 0x2A5


# ---- 7. Signed hexadecimal, SYNC for synchronous PDOs, octal ------------------------------------------------------

def test_signed_hexadecimal_is_the_bit_pattern():
    m = model(FILES / "small-rules.eds")
    assert entry(m, 0x2000)["default"] == -3                  # 0xFD in an INTEGER8
    assert entry(m, 0x2001)["default"] == -2 ** 31            # 0x80000000 in an INTEGER32
    limited = entry(m, 0x2002)                                # INTEGER16 0xFFFF in 0xFF00..0x0100
    assert (limited["default"], limited["low"], limited["high"]) == (-1, -256, 256)
    assert entry(m, 0x2004)["default"] == 127                 # 0x1FF is wider than an INTEGER8: held to its range


def test_a_synchronous_pdo_without_0x1005_gets_sync_on_0x80():
    m = model(FILES / "small-rules.eds")
    sync = entry(m, 0x1005)
    assert (sync["default"], sync["type"], sync["access"]) == (0x80, 7, "rw")
    assert [o["object_type"] for o in m["objects"] if o["index"] == 0x1005] == [7]
    assert entry(m, 0x2003)["default"] == 512                 # 01000, octal as CiA 306 says, with a warning


def test_an_asynchronous_file_gets_no_sync_object(tmp_path):
    eds = tmp_path / "async.eds"
    eds.write_text((FILES / "small-rules.eds").read_text().replace(
        "ParameterName=Transmission type\nObjectType=0x7\nDataType=0x0005\nAccessType=rw\nDefaultValue=1\n",
        "ParameterName=Transmission type\nObjectType=0x7\nDataType=0x0005\nAccessType=rw\nDefaultValue=254\n"))
    m = model(eds)
    assert entry(m, 0x1800, 2)["default"] == 254
    assert not [e for e in m["entries"] if e["index"] == 0x1005]


# ---- 8. Diagnostics that lead to the fix ------------------------------------------------------------------------

def test_a_record_without_object_type_is_read_as_one():
    m = model(FILES / "diagnostics.eds")
    assert [o["object_type"] for o in m["objects"] if o["index"] == 0x1018] == [9]
    assert [e["default"] for e in m["entries"] if e["index"] == 0x1018] == [4, 0xABC, 1, 0x10000, 0]


def test_a_link_to_a_missing_object_is_left_out():
    m = model(FILES / "diagnostics.eds")
    assert [o["links"] for o in m["objects"] if o["index"] == 0x2000] == [[0x2001]]


def test_a_mapping_without_sub_index_0_is_repaired_from_its_entries():
    m = model(FILES / "diagnostics.eds")
    count = entry(m, 0x1A00, 0)
    assert (count["default"], count["access"], count["type"]) == (2, "rw", 5)  # two entries map something
    assert entry(m, 0x1800, 1)["default"] & 0x80000000 == 0                     # the PDO is not disabled


def test_what_a_master_could_not_write_back_is_said_at_load():
    """Rule 3: a mapping entry above the count is kept as the file has it (CiA 301 checks the entries up to the
    count), but one a master's write would be refused for (here a missing object: 0x06020000) is warned at its line;
    a mapping of more than 64 bits (a master's count: 0x06040042) disables the PDO with a warning at its count."""
    path = FILES / "mapping-limits.eds"
    m = model(path)
    above = entry(m, 0x1A00, 2)
    assert any(d.startswith(f"{path}:{above['line']}: warning: [1A00sub2] 0x21000108, above the count 1")
               for d in m["diagnostics"]), m["diagnostics"]
    assert (above["default"], entry(m, 0x1A00, 0)["default"]) == (0x21000108, 1)  # kept, the PDO not disabled
    assert entry(m, 0x1800, 1)["default"] & 0x80000000 == 0
    count = entry(m, 0x1A01, 0)
    assert any(d.startswith(f"{path}:{count['line']}: warning: [1A01sub0] the mapping (DefaultValue) has 96 bits")
               for d in m["diagnostics"]), m["diagnostics"]
    assert (count["default"], entry(m, 0x1801, 1)["default"] & 0x80000000) == (0, 0x80000000)


def test_repeated_warnings_are_grouped_and_hide_no_other(tmp_path):
    """300 objects with one defect and one with another: the first 200 lines of the one kind hid the other."""
    listed = "".join(f"{i + 1}=0x{0x2000 + i:04X}\n" for i in range(301))
    objects = "".join(f"[{0x2000 + i:04X}]\nParameterName=v\nObjectType=0x7\nDataType=0x0005\nAccessType=rw\n"
                      f"DefaultValue=0\nPDOMapping=2\n" for i in range(300))
    objects += "[212C]\nParameterName=w\nObjectType=0x7\nDataType=0x0005\nAccessType=rx\nDefaultValue=0\n"
    eds = tmp_path / "many.eds"
    text = MINIMAL.replace("[ManufacturerObjects]\nSupportedObjects=0\n",
                           f"[ManufacturerObjects]\nSupportedObjects=301\n{listed}") + objects
    eds.write_text(text)
    numbered = list(enumerate(text.splitlines(), start=1))
    pdo = [n for n, line in numbered if line == "PDOMapping=2"]
    access = next(n for n, line in numbered if line == "AccessType=rx")
    assert len(pdo) == 300
    assert stderr_lines(eds) == [
        *(f"many.eds:{pdo[i]}: warning: [{0x2000 + i:04X}] PDOMapping=2 is not 0 or 1; read as 0" for i in range(3)),
        f"many.eds:{pdo[2]}: note: ... and 297 more like this, lines " + ", ".join(map(str, pdo[3:11]))
        + f", ..., {pdo[-1]}",
        f"many.eds:{access}: warning: [212C] AccessType=rx is not ro, wo, rw, rwr, rww or const; ro used"]
    assert run("check", eds).stdout.endswith("301 warnings, 0 errors)\n")


def test_the_first_of_every_kind_is_given(tmp_path):
    """200 kinds of warning, three of each: the first of every kind is given in full, the second and third while
    half the room is free; none is lost without a word."""
    listed = "".join(f"{i + 1}=0x{0x2000 + i:04X}\n" for i in range(600))
    # The kind of a warning is its words without digits: AccessType=a..., a word of letters, gives 200 kinds.
    words = ["".join(chr(ord("a") + (k // 26 ** d) % 26) for d in range(3)) for k in range(200)]
    objects = "".join(f"[{0x2000 + i:04X}]\nParameterName=v\nObjectType=0x7\nDataType=0x0005\n"
                      f"AccessType=q{words[i % 200]}\nDefaultValue=0\nPDOMapping=0\n" for i in range(600))
    eds = tmp_path / "kinds.eds"
    eds.write_text(MINIMAL.replace("[ManufacturerObjects]\nSupportedObjects=0\n",
                                   f"[ManufacturerObjects]\nSupportedObjects=600\n{listed}") + objects)
    lines = stderr_lines(eds)
    given = [line for line in lines if ": warning: " in line]
    assert {line.split("AccessType=")[1].split(" ")[0] for line in given} == {"q" + w for w in words}
    assert len(given) == 200
    notes = [line for line in lines if ": note: " in line]
    assert len(notes) == 200 and all(" more like this, lines " in line for line in notes)
    assert sum(int(line.split("... and ")[1].split(" ")[0]) for line in notes) == 400



def test_compact_without_object_type_is_an_array_and_a_dcf_mapping_is_counted_from_its_values(tmp_path):
    """CompactSubObj without ObjectType: an ARRAY (CompactSubObj is for ARRAYs only). A DCF's mapping without sub-index
    0: its value counted from the entries' ParameterValues, the default from their DefaultValues."""
    text = (FILES / "diagnostics.eds").read_text()
    text = text.replace("[ManufacturerObjects]\nSupportedObjects=2\n1=0x2000\n2=0x2001\n",
                        "[ManufacturerObjects]\nSupportedObjects=3\n1=0x2000\n2=0x2001\n3=0x2002\n")
    at = text.index("[1A00sub3]")
    text = text[:at] + text[at:].replace("DefaultValue=0\n", "DefaultValue=0\nParameterValue=0x20000010\n", 1)
    text += "\n[2002]\nParameterName=Gain\nDataType=0x0006\nAccessType=rw\nCompactSubObj=3\nDefaultValue=7\n"
    dcf = tmp_path / "mapping.dcf"
    dcf.write_text(text)
    m = model(dcf)
    assert [o["object_type"] for o in m["objects"] if o["index"] == 0x2002] == [8]
    assert [e["default"] for e in m["entries"] if e["index"] == 0x2002] == [3, 7, 7, 7]
    count = entry(m, 0x1A00, 0)
    assert (count["default"], count["param"]) == (2, 3)
    line = text.splitlines().index("[2002]") + 1
    assert f"mapping.dcf:{line}: warning: [2002] has no ObjectType but CompactSubObj; read as an ARRAY (0x8)" in \
        stderr_lines(dcf)
