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


BROKEN_EDS = {
    "not_an_ini_file": (lambda t: "garbage line\n" + t, ["dev.eds", "not an EDS/INI file"]),
    "duplicate_section": (lambda t: t + "\n[1000]\nParameterName=again\n", ["dev.eds", "[1000]", "duplicate section"]),
    "duplicate_key": (lambda t: add_to_section(t, "1000", "DataType=0x0007"), ["[1000] datatype", "duplicate key"]),
    "unknown_data_type": (lambda t: set_key(t, "1000", "DataType", "0x0042"), ["[1000] DataType", "unknown or unsupported data type"]),
    "unknown_access_type": (lambda t: set_key(t, "1000", "AccessType", "rx"), ["[1000] AccessType", "unknown access type"]),
    "default_not_representable": (lambda t: set_key(t, "1017", "DefaultValue", "70000"), ["[1017] DefaultValue", "does not fit UNSIGNED16"]),
    "negative_unsigned_default": (lambda t: set_key(t, "1017", "DefaultValue", "-1"), ["[1017] DefaultValue", "does not fit UNSIGNED16"]),
    "default_not_a_number": (lambda t: set_key(t, "1017", "DefaultValue", "fast"), ["[1017] DefaultValue", "not an integer"]),
    "default_outside_limits": (lambda t: set_key(t, "2002sub1", "DefaultValue", "50"), ["[2002sub1] DefaultValue", "outside LowLimit..HighLimit"]),
    "limits_reversed": (lambda t: set_key(t, "2002sub1", "LowLimit", "60001"), ["[2002sub1] LowLimit", "> HighLimit"]),
    "object_list_unsorted": (lambda t: replace_list(t, "OptionalObjects", list(reversed(optional_objects(t)))),
                             ["[OptionalObjects] 2", "out of order"]),
    "object_listed_twice": (lambda t: replace_list(t, "OptionalObjects", optional_objects(t) + [optional_objects(t)[-1]]),
                            ["[OptionalObjects]", "listed twice"]),
    "listed_object_missing": (lambda t: replace_list(t, "ManufacturerObjects", list_entries(t, "ManufacturerObjects") and
                                                     [v for k, v in sorted(list_entries(t, "ManufacturerObjects").items(), key=lambda kv: kv[0]) if k != "SupportedObjects"] + ["0x5FFF"]),
                              ["[5FFF]", "listed object has no section"]),
    "section_not_listed": (lambda t: t + "\n[2100]\nParameterName=orphan\nObjectType=0x7\nDataType=0x0005\nAccessType=ro\n",
                           ["[2100]", "not listed"]),
    "sub_number_mismatch": (lambda t: set_key(t, "1018", "SubNumber", "7"), ["[1018] SubNumber", "says 7"]),
    "mapping_to_missing_object": (lambda t: set_key(t, "1A00sub1", "DefaultValue", "0x21000108"), ["[1A00sub1] DefaultValue", "does not exist"]),
    "mapping_to_unmappable_object": (lambda t: set_key(t, "1A00sub1", "DefaultValue", "0x10000020"), ["[1A00sub1] DefaultValue", "PDOMapping=0"]),
    "mapping_wrong_length": (lambda t: set_key(t, "1A00sub1", "DefaultValue", "0x60000110"), ["[1A00sub1] DefaultValue", "16 bits of 0x6000:01, a 8-bit object"]),
    "mapping_wrong_direction": (lambda t: set_key(t, "1A00sub1", "DefaultValue", "0x62000108"), ["[1A00sub1] DefaultValue", "into a TPDO"]),
    "mapping_over_64_bits": (lambda t: set_key(set_key(set_key(set_key(set_key(t, "1A00sub1", "DefaultValue", "0x64010110"),
                             "1A00sub2", "DefaultValue", "0x64010210"), "1A00sub3", "DefaultValue", "0x64010310"),
                             "1A00sub4", "DefaultValue", "0x64010110"), "1A00sub5", "DefaultValue", "0x64010210"),
                             ["[1A00sub0] DefaultValue", "80 bits, more than 64"]),
    "nodeid_malformed": (lambda t: set_key(t, "1014", "DefaultValue", "$NODEID*0x80"), ["[1014] DefaultValue", "malformed node-ID-relative value"]),
    "nodeid_overflows_type": (lambda t: set_key(set_key(t, "1001", "DefaultValue", "$NODEID+200"), "1001", "DataType", "0x0005"),
                              ["[1001] DefaultValue", "does not fit UNSIGNED8"]),
    "pdo_count_mismatch": (lambda t: set_key(t, "DeviceInfo", "NrOfTXPDO", "4"), ["[DeviceInfo] NrOfTXPDO", "says 4"]),
    "missing_device_info_key": (lambda t: re.sub(r"^VendorNumber=.*\n", "", t, flags=re.MULTILINE), ["[DeviceInfo] VendorNumber", "missing"]),
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
    assert sorted(name.split("_od", 1)[1] for name in outputs[0]) == [".c", ".h", "_names.c"]  # table, header, names
    for name, data in outputs[0].items():
        assert data.startswith(b"/* GENERATED by tools/odgen.py from "), name
        assert str(tmp_path).encode() not in data and str(SRC).encode() not in data, "no machine paths"


def test_check_mode_accepts_the_shipped_files():
    for eds in sorted((SRC / "od").glob("*.eds")):
        r = subprocess.run([sys.executable, str(ODGEN), "--check", str(eds)], capture_output=True, text=True, timeout=60)
        assert r.returncode == 0 and "OK" in r.stdout, r.stderr
