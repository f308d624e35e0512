"""tools/odgen.py: each class of broken EDS or profile is rejected with a message that names the file,
the section and the key; good input generates the same bytes every time."""
import os
import re
import subprocess
import sys
from pathlib import Path

import pytest

SRC = Path(os.environ.get("CO_SOURCE_DIR", Path(__file__).resolve().parents[2]))
ODGEN = SRC / "tools" / "odgen.py"
BASE_EDS = (SRC / "od" / "sds.eds").read_text()
BASE_PROFILE = (SRC / "od" / "sds.toml").read_text()


def set_key(text, section, key, value):
    """Replaces key=value inside [section] (the key must exist)."""
    pattern = re.compile(rf"(^\[{re.escape(section)}\]\n(?:(?!\[).*\n)*?){re.escape(key)}=[^\n]*", re.MULTILINE | re.IGNORECASE)
    new, n = pattern.subn(lambda m: m.group(1) + f"{key}={value}", text)
    assert n == 1, f"[{section}] {key} not found in the base EDS"
    return new


def add_to_section(text, section, line):
    new, n = re.subn(rf"^\[{re.escape(section)}\]\n", lambda m: m.group(0) + line + "\n", text, flags=re.MULTILINE)
    assert n == 1
    return new


def list_entries(text, section):
    body = re.search(rf"^\[{section}\]\n((?:(?!\[).*\n)*)", text, re.MULTILINE).group(1)
    return dict(line.split("=", 1) for line in body.splitlines() if "=" in line)


def replace_list(text, section, objects):
    lines = [f"SupportedObjects={len(objects)}"] + [f"{i}={o}" for i, o in enumerate(objects, 1)]
    return re.sub(rf"^(\[{section}\]\n)(?:(?!\[).*\n)*", lambda m: m.group(1) + "\n".join(lines) + "\n\n", text,
                  count=1, flags=re.MULTILINE)


def optional_objects(text):
    entries = list_entries(text, "OptionalObjects")
    return [entries[str(i)] for i in range(1, int(entries["SupportedObjects"]) + 1)]


def run_odgen(tmp_path, eds_text, profile_text=BASE_PROFILE):
    eds = tmp_path / "dev.eds"
    eds.write_text(eds_text)
    (tmp_path / "dev.toml").write_text(profile_text)
    return subprocess.run([sys.executable, str(ODGEN), "--eds", str(eds), "--out-dir", str(tmp_path / "out")],
                          capture_output=True, text=True, timeout=60)


# Each mutation of the SDS's EDS and the reader's diagnostic for it ("FILE:LINE: warning: ..."): the reader repairs
# the file (it could be emulated), but the project's own files must be clean, so odgen refuses it.
BROKEN_EDS = {
    "not_an_ini_file": (lambda t: "garbage line\n" + t,
                        ["dev.eds:1: warning: neither a [section] nor a key=value line"]),
    "duplicate_section": (lambda t: t + "\n[1000]\nParameterName=again\n",
                          ["dev.eds:900: warning: section [1000] appears again (first at line 63)"]),
    "duplicate_key": (lambda t: add_to_section(t, "1000", "DataType=0x0007"),
                      ["dev.eds:64: warning: key DataType appears again in [1000] (line 67)"]),
    "unknown_data_type": (lambda t: set_key(t, "1000", "DataType", "0x0042"),
                          ["dev.eds:66: warning: [1000] DataType=0x0042 is not a CiA 301 basic data type",
                           "error: object 0x1000 is missing"]),
    "unknown_access_type": (lambda t: set_key(t, "1000", "AccessType", "rx"),
                            ["dev.eds:67: warning: [1000] AccessType=rx is not ro, wo, rw, rwr, rww or const; ro used"]),
    "default_not_representable": (lambda t: set_key(t, "1017", "DefaultValue", "70000"),
                                  ["dev.eds:236: warning: [1017] DefaultValue: '70000' does not fit UNSIGNED16; 0xFFFF used"]),
    "negative_unsigned_default": (lambda t: set_key(t, "1017", "DefaultValue", "-1"),
                                  ["dev.eds:236: warning: [1017] DefaultValue: '-1' does not fit UNSIGNED16; 0x0 used"]),
    "default_not_a_number": (lambda t: set_key(t, "1017", "DefaultValue", "fast"),
                             ["dev.eds:236: warning: [1017] DefaultValue: 'fast' is not an integer"]),
    "default_outside_limits": (lambda t: set_key(t, "2002sub1", "DefaultValue", "50"),
                               ["dev.eds:786: warning: [2002sub1] DefaultValue 0x32 is outside LowLimit..HighLimit; "
                                "0x64 (the LowLimit) used"]),
    "limits_reversed": (lambda t: set_key(t, "2002sub1", "LowLimit", "60001"),
                        ["dev.eds:781: warning: [2002sub1] LowLimit 0xEA61 > HighLimit 0xEA60; both ignored"]),
    "object_list_unsorted": (lambda t: replace_list(t, "OptionalObjects", list(reversed(optional_objects(t)))),
                             ["dev.eds:127: warning: [OptionalObjects] 2: object 0x6200 out of order (after 0x6401)"]),
    "object_listed_twice": (lambda t: replace_list(t, "OptionalObjects", optional_objects(t) + [optional_objects(t)[-1]]),
                            ["dev.eds:143: warning: [OptionalObjects] 18: object 0x6401 is listed twice"]),
    "listed_object_missing": (lambda t: replace_list(t, "ManufacturerObjects", [v for k, v in sorted(
                                  list_entries(t, "ManufacturerObjects").items()) if k != "SupportedObjects"] + ["0x5FFF"]),
                              ["warning: object 0x5FFF is listed but has no section [5FFF]; left out"]),
    "section_not_listed": (lambda t: t + "\n[2100]\nParameterName=orphan\nObjectType=0x7\nDataType=0x0005\nAccessType=ro\n",
                           ["dev.eds:900: warning: [2100] is in no object list"]),
    "sub_number_mismatch": (lambda t: set_key(t, "1018", "SubNumber", "7"),
                            ["dev.eds:79: warning: [1018] SubNumber=7 but 5 sub-index sections are usable"]),
    "mapping_to_missing_object": (lambda t: set_key(t, "1A00sub1", "DefaultValue", "0x21000108"),
                                  ["dev.eds:391: warning: [1A00sub1] DefaultValue 0x21000108 maps 0x2100:01, which does "
                                   "not exist; the PDO is disabled"]),
    "mapping_to_unmappable_object": (lambda t: set_key(t, "1A00sub1", "DefaultValue", "0x10000020"),
                                     ["dev.eds:391: warning: [1A00sub1] DefaultValue 0x10000020 maps 0x1000:00, which "
                                      "has PDOMapping=0"]),
    "mapping_wrong_length": (lambda t: set_key(t, "1A00sub1", "DefaultValue", "0x60000110"),
                             ["dev.eds:391: warning: [1A00sub1] DefaultValue 0x60000110 maps 16 bits of 0x6000:01, a "
                              "8-bit object"]),
    "mapping_wrong_direction": (lambda t: set_key(t, "1A00sub1", "DefaultValue", "0x62000108"),
                                ["dev.eds:391: warning: [1A00sub1] DefaultValue 0x62000108 maps 0x6200:01 "
                                 "(AccessType=wo) into a TPDO"]),
    "mapping_over_64_bits": (lambda t: set_key(set_key(set_key(set_key(set_key(t, "1A00sub1", "DefaultValue", "0x64010110"),
                             "1A00sub2", "DefaultValue", "0x64010210"), "1A00sub3", "DefaultValue", "0x64010310"),
                             "1A00sub4", "DefaultValue", "0x64010110"), "1A00sub5", "DefaultValue", "0x64010210"),
                             ["dev.eds:383: warning: [1A00sub0] the mapping (DefaultValue) has 80 bits, more than 64"]),
    "nodeid_malformed": (lambda t: set_key(t, "1014", "DefaultValue", "$NODEID*0x80"),
                         ["dev.eds:228: warning: [1014] DefaultValue: '$NODEID*0x80' is not an integer"]),
    "nodeid_overflows_type": (lambda t: set_key(set_key(t, "1001", "DefaultValue", "$NODEID+200"), "1001", "DataType", "0x0005"),
                              ["dev.eds:76: warning: [1001] DefaultValue: '$NODEID+200' does not fit UNSIGNED8 for "
                               "every node-ID 1..127"]),
    "pdo_count_mismatch": (lambda t: set_key(t, "DeviceInfo", "NrOfTXPDO", "4"),
                           ["dev.eds:14: warning: [DeviceInfo] NrOfTXPDO=4 but the file has 2 such PDOs; 2 used"]),
    "missing_device_info_key": (lambda t: re.sub(r"^VendorNumber=.*\n", "", t, flags=re.MULTILINE),
                                ["dev.eds:14: warning: [DeviceInfo] has no VendorNumber; taken from object 0x1018"]),
}


@pytest.mark.parametrize("case", sorted(BROKEN_EDS))
def test_broken_eds_is_rejected_with_its_place(tmp_path, case):
    mutate, expected = BROKEN_EDS[case]
    r = run_odgen(tmp_path, mutate(BASE_EDS))
    assert r.returncode == 1, f"accepted: {r.stdout}{r.stderr}"
    message = r.stderr
    assert message.startswith("odgen: error: ") and str(tmp_path / "dev.eds") in message, message
    for fragment in expected:
        assert fragment in message, f"{fragment!r} not in {message!r}"
    assert not (tmp_path / "out").exists(), "nothing may be written for a broken EDS"


BROKEN_PROFILES = {
    "bad_c_name": ('c_name = "Not-C"\n', ["dev.toml", "c_name", "not a lower-case C identifier"]),
    "unknown_key": ('colour = "red"\n' + BASE_PROFILE, ["dev.toml", "colour", "unknown key"]),
    "unit_too_long": (BASE_PROFILE.replace('"0x6401:01" = "V"', '"0x6401:01" = "' + "V" * 32 + '"'),
                      ["dev.toml", "units", "0x6401:01", "is not a unit"]),
    "unit_with_quote": (BASE_PROFILE.replace('"0x6401:01" = "V"', '"0x6401:01" = "V\\""'), ["dev.toml", "units", "is not a unit"]),
    "unit_of_missing_object": (BASE_PROFILE.replace('"0x6401:01" = "V"', '"0x6402:01" = "V"'), ["dev.toml", "units", "0x6402 is not in"]),
    "store_read_only_row": (BASE_PROFILE.replace('store = [', 'store = ["0x1000", '), ["dev.toml", "storage", "0x1000:00 is not writable"]),
    "store_missing_object": (BASE_PROFILE.replace('store = [', 'store = ["0x2100", '), ["dev.toml", "storage.store", "0x2100 is not in"]),
    "keep_not_stored": (BASE_PROFILE.replace('keep = [', 'keep = ["0x2002:03", '), ["dev.toml", "storage", "0x2002:03"]),
    "bad_row_spec": (BASE_PROFILE.replace('store = [', 'store = ["1017", '), ["dev.toml", "storage.store", "'1017' is not 0xIIII"]),
    "not_toml": ("c_name = \n", ["dev.toml"]),
}


@pytest.mark.parametrize("case", sorted(BROKEN_PROFILES))
def test_broken_profile_is_rejected_with_its_place(tmp_path, case):
    profile, expected = BROKEN_PROFILES[case]
    r = run_odgen(tmp_path, BASE_EDS, profile)
    assert r.returncode == 1, f"accepted: {r.stdout}{r.stderr}"
    for fragment in expected:
        assert fragment in r.stderr, f"{fragment!r} not in {r.stderr!r}"


@pytest.mark.parametrize("device", ["pro-ionizer", "sds", "buerkert-flow-controller"])
def test_generation_is_deterministic_and_marked(tmp_path, device):
    outputs = []
    for run in ("a", "b"):
        r = subprocess.run([sys.executable, str(ODGEN), "--eds", str(SRC / "od" / f"{device}.eds"),
                            "--out-dir", str(tmp_path / run)], capture_output=True, text=True, timeout=60)
        assert r.returncode == 0, r.stderr
        outputs.append({p.name: p.read_bytes() for p in sorted((tmp_path / run).iterdir())})
    assert outputs[0] == outputs[1]
    # table, header, fitted configuration, names
    assert sorted(name.split("_od", 1)[1] for name in outputs[0]) == [".c", ".h", "_config.h", "_names.c"]
    for name, data in outputs[0].items():
        assert data.startswith(b"/* GENERATED by tools/odgen.py from "), name
        assert str(tmp_path).encode() not in data and str(SRC).encode() not in data, "no machine paths"


def test_check_mode_accepts_the_shipped_files():
    for eds in sorted((SRC / "od").glob("*.eds")):
        r = subprocess.run([sys.executable, str(ODGEN), "--check", str(eds)], capture_output=True, text=True, timeout=60)
        assert r.returncode == 0 and "OK" in r.stdout, r.stderr


@pytest.mark.parametrize("device", ["pro-ionizer", "sds", "buerkert-flow-controller"])
def test_tables_survive_a_round_trip_through_the_reader(tmp_path, device):
    """EDS -> tables, and EDS -> canopen-eds convert -> EDS -> tables: the same C, byte for byte."""
    tool = os.environ["CO_EDS_TOOL"]
    copy = tmp_path / "rewritten" / f"{device}.eds"
    copy.parent.mkdir()
    subprocess.run([tool, "convert", str(SRC / "od" / f"{device}.eds"), str(copy)], check=True, timeout=60)
    outputs = []
    for eds, run in ((SRC / "od" / f"{device}.eds", "a"), (copy, "b")):
        r = subprocess.run([sys.executable, str(ODGEN), "--eds", str(eds), "--profile", str(SRC / "od" / f"{device}.toml"),
                            "--out-dir", str(tmp_path / run)], capture_output=True, text=True, timeout=60)
        assert r.returncode == 0, r.stderr
        outputs.append({p.name: p.read_bytes() for p in sorted((tmp_path / run).iterdir())})
    assert outputs[0] == outputs[1]


def fitted(tmp_path, eds_text, profile_text=BASE_PROFILE):
    """The switches <c_name>_od_config.h turns off and the counts it caps."""
    (tmp_path / "d.eds").write_text(eds_text)
    (tmp_path / "d.toml").write_text(profile_text)
    r = subprocess.run([sys.executable, str(ODGEN), "--eds", str(tmp_path / "d.eds"), "--out-dir", str(tmp_path / "out")],
                       capture_output=True, text=True, timeout=60)
    assert r.returncode == 0, r.stderr
    text = next((tmp_path / "out").glob("*_od_config.h")).read_text()
    off = set(re.findall(r"^#define (CO_CONFIG_\w+) 0$", text, re.MULTILINE))
    caps = dict(re.findall(r"^#define (CO_\w+_MAX) (\d+)U$", text, re.MULTILINE))
    return off, {k: int(v) for k, v in caps.items()}


@pytest.mark.parametrize("device, off, caps", [
    ("pro-ionizer", {"CO_CONFIG_SYNC", "CO_CONFIG_NODE_GUARDING", "CO_CONFIG_HB_CONSUMER", "CO_CONFIG_MPDO",
                     "CO_CONFIG_SDO_SERVERS", "CO_CONFIG_PDO_DYNAMIC_MAPPING", "CO_CONFIG_OD_LIMITS_64",
                     "CO_CONFIG_PDO_TIMERS", "CO_CONFIG_EMCY_INHIBIT"},
     {"CO_RPDO_MAX": 1, "CO_TPDO_MAX": 3}),
    ("sds", {"CO_CONFIG_SYNC", "CO_CONFIG_NODE_GUARDING", "CO_CONFIG_HB_CONSUMER", "CO_CONFIG_MPDO",
             "CO_CONFIG_SDO_SERVERS", "CO_CONFIG_PDO_DYNAMIC_MAPPING", "CO_CONFIG_OD_LIMITS_64", "CO_CONFIG_PDO_TIMERS",
             "CO_CONFIG_EMCY_INHIBIT"},
     {"CO_RPDO_MAX": 1, "CO_TPDO_MAX": 2}),
    ("buerkert-flow-controller", {"CO_CONFIG_MPDO", "CO_CONFIG_SDO_SERVERS", "CO_CONFIG_OD_LIMITS_64",
                                  "CO_CONFIG_EMCY_HISTORY", "CO_CONFIG_EMCY_INHIBIT"},
     {"CO_RPDO_MAX": 4, "CO_TPDO_MAX": 4, "CO_HB_CONSUMER_MAX": 127}),
])
def test_fitted_configuration_of_the_shipped_devices(tmp_path, device, off, caps):
    eds = (SRC / "od" / f"{device}.eds").read_text()
    profile = (SRC / "od" / f"{device}.toml").read_text()
    assert fitted(tmp_path, eds, profile) == (off, caps)


def test_fitted_configuration_follows_the_objects(tmp_path):
    # A SYNC COB-ID keeps SYNC; a writable mapping count whose limits allow 0xFE keeps MPDO and dynamic mapping.
    eds = BASE_EDS.replace("[1000]\n", "[1005]\nParameterName=COB-ID SYNC\nObjectType=0x7\nDataType=0x0007\n"
                           "AccessType=rw\nDefaultValue=0x80\nPDOMapping=0\n\n[1000]\n", 1)
    listed = re.search(r"\[OptionalObjects\]\nSupportedObjects=\d+\n((?:\d+=0x[0-9A-Fa-f]+\n)+)", eds)
    objects = sorted([int(v, 16) for v in re.findall(r"=(0x[0-9A-Fa-f]+)", listed.group(1))] + [0x1005])
    eds = eds.replace(listed.group(0), f"[OptionalObjects]\nSupportedObjects={len(objects)}\n" +
                      "".join(f"{k}=0x{o:04X}\n" for k, o in enumerate(objects, 1)))
    eds = set_key(eds, "1600sub0", "AccessType", "rw")
    off, caps = fitted(tmp_path, eds)
    assert "CO_CONFIG_SYNC" not in off and "CO_CONFIG_MPDO" not in off and "CO_CONFIG_PDO_DYNAMIC_MAPPING" not in off
    assert "CO_CONFIG_NODE_GUARDING" in off and caps == {"CO_RPDO_MAX": 1, "CO_TPDO_MAX": 2}
    # A TPDO inhibit time keeps the PDO timers.
    assert "CO_CONFIG_PDO_TIMERS" in off
    inhibit = "[1800sub3]\nParameterName=Inhibit time\nObjectType=0x7\nDataType=0x0006\nAccessType=rw\nDefaultValue=0\n\n"
    with_inhibit = set_key(set_key(eds, "1800", "SubNumber", "4"), "1800sub0", "DefaultValue", "3")
    off, _ = fitted(tmp_path, with_inhibit.replace("[1A00]\n", inhibit + "[1A00]\n", 1))
    assert "CO_CONFIG_PDO_TIMERS" not in off
    # A REAL32 row with limits needs 64-bit pairs.
    eds = set_key(set_key(eds, "2000sub2", "DataType", "0x0008"), "2000sub2", "HighLimit", "365.5")
    off, _ = fitted(tmp_path, eds)
    assert "CO_CONFIG_OD_LIMITS_64" not in off
    # The pre-defined error field keeps the EMCY history; without it, the history is compiled out.
    assert "CO_CONFIG_EMCY_HISTORY" not in off
    without = re.sub(r"^\[1003(?:sub\d+)?\]\n(?:(?!\[).*\n)*", "", eds, flags=re.MULTILINE)
    without = replace_list(without, "OptionalObjects", [o for o in optional_objects(eds) if int(o, 16) != 0x1003])
    assert "[1003" not in without
    off, _ = fitted(tmp_path, without)
    assert "CO_CONFIG_EMCY_HISTORY" in off
    # An EMCY inhibit time keeps its code; without one (none of the shipped devices has 0x1015), it is compiled out.
    assert "CO_CONFIG_EMCY_INHIBIT" in off
    inhibit = ("[1015]\nParameterName=Inhibit time EMCY\nObjectType=0x7\nDataType=0x0006\nAccessType=rw\n"
               "DefaultValue=0\nPDOMapping=0\n\n")
    with_inhibit = replace_list(eds.replace("[1000]\n", inhibit + "[1000]\n", 1), "OptionalObjects",
                                sorted(optional_objects(eds) + ["0x1015"], key=lambda o: int(o, 16)))
    off, _ = fitted(tmp_path, with_inhibit)
    assert "CO_CONFIG_EMCY_INHIBIT" not in off


def test_fitted_configuration_of_the_sync_producer_and_the_rtr_tpdos(tmp_path):
    # The SYNC producer stays where 0x1005 may have bit 30 (gen): written, or by default; else it is compiled out.
    def with_sync(access, value):
        sync = (f"[1005]\nParameterName=COB-ID SYNC\nObjectType=0x7\nDataType=0x0007\nAccessType={access}\n"
                f"DefaultValue={value}\nPDOMapping=0\n\n")
        return replace_list(BASE_EDS.replace("[1000]\n", sync + "[1000]\n", 1), "OptionalObjects",
                            sorted(optional_objects(BASE_EDS) + ["0x1005"], key=lambda o: int(o, 16)))
    assert "CO_CONFIG_SYNC_PRODUCER" in fitted(tmp_path, with_sync("ro", "0x80"))[0]
    assert "CO_CONFIG_SYNC_PRODUCER" not in fitted(tmp_path, with_sync("ro", "0x40000080"))[0]
    assert "CO_CONFIG_SYNC_PRODUCER" not in fitted(tmp_path, with_sync("rw", "0x80"))[0]
    # The SDS's TPDOs allow RTR (read-only COB-IDs with bit 30 clear, type 255): answered; with bit 30 set, not.
    assert "CO_CONFIG_TPDO_RTR" not in fitted(tmp_path, BASE_EDS)[0]
    no_rtr = BASE_EDS
    for tpdo in ("1800", "1801"):
        no_rtr = set_key(no_rtr, f"{tpdo}sub1", "DefaultValue", f"$NODEID+0x40000{int(tpdo, 16) - 0x1800 + 1}80")
    assert "CO_CONFIG_TPDO_RTR" in fitted(tmp_path, no_rtr)[0]
    assert "CO_CONFIG_TPDO_RTR" not in fitted(tmp_path, set_key(no_rtr, "1801sub1", "AccessType", "rw"))[0]


def test_16_bit_limit_pairs_where_every_limit_fits(tmp_path):
    # The SDS limits UNSIGNED16 0x2000:02 to 0..365: 16-bit pairs, in the fitted configuration.
    def generated(eds_text):
        fitted(tmp_path, eds_text)
        out = tmp_path / "out"
        return next(out.glob("*_od_config.h")).read_text(), next(out.glob("*_od.c")).read_text()
    config, source = generated(BASE_EDS)
    assert re.search(r"^#define CO_CONFIG_OD_LIMITS_16 1$", config, re.MULTILINE)
    assert "CO_CONFIG_OD_LIMITS_16 must be 0" not in source
    # A limit beyond 16 bits (65,536 of an UNSIGNED32, -32,769 of an INTEGER32): 32-bit pairs, and a table built with
    # 16-bit pairs fails to compile rather than truncate.
    for data_type, key, limit in (("0x0007", "HighLimit", "65536"), ("0x0004", "LowLimit", "-32769")):
        eds = set_key(set_key(BASE_EDS, "2000sub2", "DataType", data_type), "2000sub2", key, limit)
        config, source = generated(eds)
        assert "CO_CONFIG_OD_LIMITS_16" not in config
        assert "#error \"this dictionary has limits beyond 16 bits: CO_CONFIG_OD_LIMITS_16 must be 0\"" in source
    # At the bounds of 16 bits: still 16-bit pairs.
    eds = set_key(set_key(BASE_EDS, "2000sub2", "DataType", "0x0003"), "2000sub2", "LowLimit", "-32768")
    eds = set_key(eds, "2000sub2", "HighLimit", "32767")
    config, _ = generated(eds)
    assert re.search(r"^#define CO_CONFIG_OD_LIMITS_16 1$", config, re.MULTILINE)
