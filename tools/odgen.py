#!/usr/bin/env python3
"""odgen: turns a CiA 306 EDS and its generator profile into the C object-dictionary tables of the core.

    tools/odgen.py --eds od/pro-ionizer.eds --profile od/pro-ionizer.toml --out-dir build/od
    tools/odgen.py --check od/pro-ionizer.eds          (validate only)

Output: <c_name>_od.h (the values struct, the co_od_t) and <c_name>_od.c (the sorted const row table,
the defaults image, the limits). Both say they are generated. The output depends only on the inputs
(no dates, no paths), so a rebuild gives the same bytes.

The EDS is read with Python's configparser in strict mode (duplicate sections or keys are errors) and
then checked: object lists unique and sorted, every listed object present and every object listed,
known data and access types, defaults representable in their type and inside LowLimit/HighLimit,
node-ID-relative defaults well-formed, every PDO mapping entry naming an existing mappable object of
the right size and direction, at most 64 bits per PDO. Every error names file, section and key.

The profile (TOML, beside the EDS) says what an EDS cannot: which rows 0x1010 stores, which survive
0x1011 restore, the capacity of writable strings.
"""
from __future__ import annotations

import argparse
import configparser
import math
import re
import struct
import sys
import tomllib
import zlib
from dataclasses import dataclass, field
from pathlib import Path

# CiA 301 data type number -> (name, C type, size in bytes, min, max). Strings: size from the value/profile.
TYPES: dict[int, tuple[str, str, int, float, float]] = {
    0x01: ("BOOLEAN", "uint8_t", 1, 0, 1),
    0x02: ("INTEGER8", "int8_t", 1, -(2**7), 2**7 - 1),
    0x03: ("INTEGER16", "int16_t", 2, -(2**15), 2**15 - 1),
    0x04: ("INTEGER32", "int32_t", 4, -(2**31), 2**31 - 1),
    0x05: ("UNSIGNED8", "uint8_t", 1, 0, 2**8 - 1),
    0x06: ("UNSIGNED16", "uint16_t", 2, 0, 2**16 - 1),
    0x07: ("UNSIGNED32", "uint32_t", 4, 0, 2**32 - 1),
    0x08: ("REAL32", "float", 4, -3.4028234663852886e38, 3.4028234663852886e38),
    0x09: ("VISIBLE_STRING", "char", 0, 0, 0),
    0x0A: ("OCTET_STRING", "uint8_t", 0, 0, 0),
    0x11: ("REAL64", "double", 8, -sys.float_info.max, sys.float_info.max),
    0x15: ("INTEGER64", "int64_t", 8, -(2**63), 2**63 - 1),
    0x1B: ("UNSIGNED64", "uint64_t", 8, 0, 2**64 - 1),
}
STRING_TYPES = (0x09, 0x0A)
REAL_TYPES = (0x08, 0x11)

# EDS AccessType -> (readable, writable, const, TPDO-mappable direction allowed, RPDO direction allowed)
ACCESS = {
    "ro": (True, False, False, True, False),
    "const": (True, False, True, True, False),
    "wo": (False, True, False, False, True),
    "rw": (True, True, False, True, True),
    "rwr": (True, True, False, True, False),  # read/write, mappable to TPDOs only
    "rww": (True, True, False, False, True),  # read/write, mappable to RPDOs only
}
OBJECT_LISTS = ("MandatoryObjects", "OptionalObjects", "ManufacturerObjects")
DEVICE_INFO_KEYS = ("VendorName", "VendorNumber", "ProductName", "ProductNumber", "RevisionNumber",
                    "NrOfRXPDO", "NrOfTXPDO", "Granularity", "LSS_Supported")
NODEID_RE = re.compile(r"^\$NODEID\s*\+\s*(\S+)$|^(\S+?)\s*\+\s*\$NODEID$", re.IGNORECASE)
SECTION_RE = re.compile(r"^([0-9A-F]{4})(?:SUB([0-9A-F]{1,2}))?$")


class OdError(Exception):
    """An error in an input file, with its place."""

    def __init__(self, file: str, section: str | None, key: str | None, message: str):
        place = file + (f": [{section}]" if section else "") + (f" {key}" if key else "")
        super().__init__(f"{place}: {message}")


@dataclass
class Row:
    index: int
    sub: int
    name: str
    dtype: int
    access: str
    pdo: bool
    value: object          # int, float, str or bytes (node-ID-relative rows: the base without the ID)
    nodeid: bool
    low: object = None
    high: object = None
    size: int = 0
    section: str = ""
    store: bool = False
    keep: bool = False
    unit: str = ""         # of the value, from the profile's [units] (the manuals'; an EDS has none)

    @property
    def member(self) -> str:
        return f"x{self.index:04x}_{self.sub:02x}"


@dataclass
class Od:
    path: str
    name: str
    rows: list[Row] = field(default_factory=list)
    device_info: dict[str, str] = field(default_factory=dict)

    def find(self, index: int, sub: int) -> Row | None:
        for r in self.rows:
            if r.index == index and r.sub == sub:
                return r
        return None


def parse_int(text: str, file: str, section: str, key: str) -> int:
    t = text.strip()
    try:
        if re.fullmatch(r"[+-]?0[xX][0-9a-fA-F]+", t):
            return int(t, 16)
        if re.fullmatch(r"[+-]?[0-9]+", t):
            return int(t, 10)
    except ValueError:
        pass
    raise OdError(file, section, key, f"'{text}' is not an integer")


def parse_value(text: str, dtype: int, file: str, section: str, key: str) -> tuple[object, bool]:
    """Returns (value, node-ID relative) for a DefaultValue/LowLimit/HighLimit of a row of type dtype."""
    t = text.strip()
    if dtype in STRING_TYPES:
        if dtype == 0x0A:
            hexdigits = t.replace(" ", "")
            if len(hexdigits) % 2 or not re.fullmatch(r"[0-9a-fA-F]*", hexdigits):
                raise OdError(file, section, key, f"OCTET_STRING '{text}' is not pairs of hex digits")
            return bytes.fromhex(hexdigits), False
        try:
            t.encode("ascii")
        except UnicodeEncodeError:
            raise OdError(file, section, key, f"VISIBLE_STRING '{text}' is not ASCII") from None
        return t, False
    if "$" in t:
        m = NODEID_RE.match(t)
        if not m:
            raise OdError(file, section, key, f"malformed node-ID-relative value '{text}' (use $NODEID+0x180)")
        if dtype in REAL_TYPES:
            raise OdError(file, section, key, "a node-ID-relative value needs an integer type")
        return parse_int(m.group(1) or m.group(2), file, section, key), True
    if t == "":
        return (0.0 if dtype in REAL_TYPES else 0), False
    if dtype in REAL_TYPES:
        try:
            v = float(t)
        except ValueError:
            raise OdError(file, section, key, f"'{text}' is not a number") from None
        if not math.isfinite(v):
            raise OdError(file, section, key, f"'{text}' is not finite")
        return v, False
    return parse_int(t, file, section, key), False


def check_representable(v: object, nodeid: bool, dtype: int, file: str, section: str, key: str) -> None:
    name, _, _, lo, hi = TYPES[dtype]
    if dtype in STRING_TYPES:
        return
    if dtype in REAL_TYPES:
        if dtype == 0x08:
            try:
                struct.pack("<f", v)
            except OverflowError:
                raise OdError(file, section, key, f"{v} does not fit {name}") from None
        return
    values = [v + 1, v + 127] if nodeid else [v]  # every node-ID 1..127 must give a valid value
    for x in values:
        if not lo <= x <= hi:
            raise OdError(file, section, key, f"{x:#x} does not fit {name}" if x >= 0 else f"{x} does not fit {name}")


class EdsReader:
    def __init__(self, path: Path):
        self.path = str(path)
        self.cp = configparser.ConfigParser(interpolation=None, strict=True, delimiters=("=",),
                                            comment_prefixes=(";",), inline_comment_prefixes=None,
                                            default_section="\x00no-defaults", empty_lines_in_values=False)
        try:
            with open(path, encoding="utf-8") as f:
                self.cp.read_file(f, source=self.path)
        except configparser.DuplicateSectionError as e:
            raise OdError(self.path, e.section, None, f"duplicate section (line {e.lineno})") from None
        except configparser.DuplicateOptionError as e:
            raise OdError(self.path, e.section, e.option, f"duplicate key (line {e.lineno})") from None
        except configparser.Error as e:
            raise OdError(self.path, None, None, f"not an EDS/INI file: {e}") from None
        except UnicodeDecodeError as e:
            raise OdError(self.path, None, None, f"not UTF-8 text: {e}") from None
        self.sections: dict[str, str] = {}
        for s in self.cp.sections():
            norm = s.upper()
            if norm in self.sections:
                raise OdError(self.path, s, None, f"duplicate section (same as [{self.sections[norm]}])")
            self.sections[norm] = s

    def section(self, name: str) -> str | None:
        return self.sections.get(name.upper())

    def get(self, section: str, key: str, required: bool = True) -> str | None:
        if self.cp.has_option(section, key):
            return self.cp.get(section, key)
        if required:
            raise OdError(self.path, section, key, "missing")
        return None


def read_object_lists(eds: EdsReader) -> list[int]:
    seen: dict[int, str] = {}
    for lst in OBJECT_LISTS:
        sec = eds.section(lst)
        if sec is None:
            if lst == "MandatoryObjects":
                raise OdError(eds.path, lst, None, "missing section")
            continue
        n = parse_int(eds.get(sec, "SupportedObjects"), eds.path, sec, "SupportedObjects")
        keys = {k for k in eds.cp.options(sec) if k != "supportedobjects"}
        expected = {str(i) for i in range(1, n + 1)}
        if keys != expected:
            extra, missing = sorted(keys - expected), sorted(expected - keys, key=int)
            raise OdError(eds.path, sec, None, f"keys must be 1..{n}" + (f"; unexpected {extra}" if extra else "")
                          + (f"; missing {missing}" if missing else ""))
        previous = -1
        for i in range(1, n + 1):
            idx = parse_int(eds.get(sec, str(i)), eds.path, sec, str(i))
            if idx in seen:
                raise OdError(eds.path, sec, str(i), f"object 0x{idx:04X} listed twice (also in [{seen[idx]}])")
            if idx <= previous:
                raise OdError(eds.path, sec, str(i), f"object 0x{idx:04X} out of order (after 0x{previous:04X})")
            previous = idx
            seen[idx] = sec
    return sorted(seen)


def read_row(eds: EdsReader, sec: str, index: int, sub: int) -> Row:
    p = eds.path
    name = eds.get(sec, "ParameterName")
    otype = parse_int(eds.get(sec, "ObjectType", required=False) or "0x7", p, sec, "ObjectType")
    if otype != 0x7:
        raise OdError(p, sec, "ObjectType", f"a sub-index must be a VAR (0x7), not {otype:#x}")
    dtype = parse_int(eds.get(sec, "DataType"), p, sec, "DataType")
    if dtype not in TYPES:
        raise OdError(p, sec, "DataType", f"unknown or unsupported data type {dtype:#06x}")
    access = eds.get(sec, "AccessType").strip().lower()
    if access not in ACCESS:
        raise OdError(p, sec, "AccessType", f"unknown access type '{access}' (ro, wo, rw, rwr, rww, const)")
    pdo_text = (eds.get(sec, "PDOMapping", required=False) or "0").strip()
    if pdo_text not in ("0", "1"):
        raise OdError(p, sec, "PDOMapping", f"must be 0 or 1, not '{pdo_text}'")
    value, nodeid = parse_value(eds.get(sec, "DefaultValue", required=False) or "", dtype, p, sec, "DefaultValue")
    check_representable(value, nodeid, dtype, p, sec, "DefaultValue")
    row = Row(index, sub, name.strip(), dtype, access, pdo_text == "1", value, nodeid, section=sec)
    for key in ("LowLimit", "HighLimit"):
        text = eds.get(sec, key, required=False)
        if text is None or text.strip() == "":
            continue
        if dtype in STRING_TYPES:
            raise OdError(p, sec, key, "limits on a string")
        v, rel = parse_value(text, dtype, p, sec, key)
        if rel:
            raise OdError(p, sec, key, "limits cannot be node-ID relative")
        check_representable(v, False, dtype, p, sec, key)
        setattr(row, "low" if key == "LowLimit" else "high", v)
    if row.low is not None and row.high is not None and row.low > row.high:
        raise OdError(p, sec, "LowLimit", f"LowLimit {row.low} > HighLimit {row.high}")
    if dtype not in STRING_TYPES:
        lo_ok = row.low is None or all(row.low <= v for v in ([value + 1, value + 127] if nodeid else [value]))
        hi_ok = row.high is None or all(v <= row.high for v in ([value + 1, value + 127] if nodeid else [value]))
        if not (lo_ok and hi_ok):
            raise OdError(p, sec, "DefaultValue", f"default {value} outside LowLimit..HighLimit ({row.low}..{row.high})")
    if dtype in STRING_TYPES:
        row.size = len(value)
    else:
        row.size = TYPES[dtype][2]
    return row


def read_eds(path: Path) -> Od:
    eds = EdsReader(path)
    p = eds.path
    info = eds.section("DeviceInfo")
    if info is None:
        raise OdError(p, "DeviceInfo", None, "missing section")
    od = Od(p, Path(path).stem)
    for key in DEVICE_INFO_KEYS:
        od.device_info[key] = eds.get(info, key)
    indices = read_object_lists(eds)
    listed = set(indices)
    for norm, sec in eds.sections.items():
        m = SECTION_RE.match(norm)
        if m and int(m.group(1), 16) not in listed:
            raise OdError(p, sec, None, "object section not listed in any object list")
    for index in indices:
        sec = eds.section(f"{index:04X}")
        if sec is None:
            raise OdError(p, f"{index:04X}", None, "listed object has no section")
        otype = parse_int(eds.get(sec, "ObjectType", required=False) or "0x7", p, sec, "ObjectType")
        if eds.get(sec, "CompactSubObj", required=False) not in (None, "0"):
            raise OdError(p, sec, "CompactSubObj", "compact sub-objects are not supported; list each sub-index")
        if otype == 0x7:
            od.rows.append(read_row(eds, sec, index, 0))
            continue
        if otype not in (0x8, 0x9):
            raise OdError(p, sec, "ObjectType", f"unsupported object type {otype:#x} (0x7 VAR, 0x8 ARRAY, 0x9 RECORD)")
        subs = sorted(int(SECTION_RE.match(n).group(2), 16) for n in eds.sections
                      if SECTION_RE.match(n) and SECTION_RE.match(n).group(2) is not None
                      and int(SECTION_RE.match(n).group(1), 16) == index)
        if len(subs) != len(set(subs)):
            raise OdError(p, sec, None, "a sub-index is defined twice (e.g. [..sub1] and [..sub01])")
        n = parse_int(eds.get(sec, "SubNumber"), p, sec, "SubNumber")
        if n != len(subs):
            raise OdError(p, sec, "SubNumber", f"says {n} but {len(subs)} sub-index sections exist")
        if 0 not in subs:
            raise OdError(p, sec, None, "an ARRAY/RECORD needs sub-index 0")
        for sub in subs:
            od.rows.append(read_row(eds, eds.section(f"{index:04X}sub{sub:X}"), index, sub))
        sub0 = od.find(index, 0)
        if sub0.dtype != 0x05:
            raise OdError(p, sub0.section, "DataType", "sub-index 0 must be UNSIGNED8")
        # sub 0 is the highest sub-index, except where it counts active entries (error history, mappings)
        counts_entries = index == 0x1003 or 0x1600 <= index <= 0x17FF or 0x1A00 <= index <= 0x1BFF
        if sub0.value < max(subs) and not counts_entries:
            raise OdError(p, sub0.section, "DefaultValue", f"highest sub-index {max(subs):#x} > sub 0 value {sub0.value:#x}")
    od.rows.sort(key=lambda r: (r.index, r.sub))
    check_pdos(od)
    return od


def mapping_row(od: Od, row: Row, receive: bool, p: str) -> int:
    v = row.value
    if row.nodeid or not isinstance(v, int):
        raise OdError(p, row.section, "DefaultValue", "a mapping entry must be a plain number")
    if v == 0:
        return 0
    index, sub, bits = v >> 16, (v >> 8) & 0xFF, v & 0xFF
    if receive and 1 <= index <= 7 and sub == 0:
        return bits
    target = od.find(index, sub)
    if target is None:
        raise OdError(p, row.section, "DefaultValue", f"maps 0x{index:04X}:{sub:02X}, which does not exist")
    if not target.pdo:
        raise OdError(p, row.section, "DefaultValue", f"maps 0x{index:04X}:{sub:02X}, which has PDOMapping=0")
    allowed = ACCESS[target.access][4 if receive else 3]
    if not allowed:
        raise OdError(p, row.section, "DefaultValue",
                      f"maps 0x{index:04X}:{sub:02X} (AccessType={target.access}) into a {'R' if receive else 'T'}PDO")
    if bits != target.size * 8 or bits % 8:
        raise OdError(p, row.section, "DefaultValue", f"maps {bits} bits of 0x{index:04X}:{sub:02X}, a {target.size * 8}-bit object")
    return bits


def check_pdos(od: Od) -> None:
    p = od.path
    for comm_base, map_base, receive in ((0x1400, 0x1600, True), (0x1800, 0x1A00, False)):
        comm = sorted({r.index for r in od.rows if comm_base <= r.index < comm_base + 0x200})
        maps = sorted({r.index for r in od.rows if map_base <= r.index < map_base + 0x200})
        if [c - comm_base for c in comm] != [m - map_base for m in maps]:
            raise OdError(p, f"{map_base:04X}", None, f"communication {[hex(c) for c in comm]} and mapping "
                          f"{[hex(m) for m in maps]} objects do not pair up")
        key = "NrOfRXPDO" if receive else "NrOfTXPDO"
        if parse_int(od.device_info[key], p, "DeviceInfo", key) != len(comm):
            raise OdError(p, "DeviceInfo", key, f"says {od.device_info[key]} but the OD has {len(comm)}")
        for m in maps:
            count = od.find(m, 0)
            if count.value > 8:
                raise OdError(p, count.section, "DefaultValue", "more than 8 mapping entries")
            bits = 0
            for sub in range(1, count.value + 1):
                entry = od.find(m, sub)
                if entry is None:
                    raise OdError(p, count.section, "DefaultValue", f"{count.value} entries but sub {sub} is missing")
                bits += mapping_row(od, entry, receive, p)
            if bits > 64:
                raise OdError(p, count.section, "DefaultValue", f"the mapping has {bits} bits, more than 64")
            cob = od.find(m - map_base + comm_base, 1)
            if cob is not None and not (cob.value & 0x80000000) and count.value == 0:
                raise OdError(p, cob.section, "DefaultValue", "a valid PDO (bit 31 clear) with an empty mapping")


def parse_row_spec(spec: str, od: Od, file: str, key: str) -> list[Row]:
    m = re.fullmatch(r"0x([0-9A-Fa-f]{4})(?::([0-9A-Fa-f]{1,2})(?:-([0-9A-Fa-f]{1,2}))?)?", spec.strip())
    if not m:
        raise OdError(file, None, key, f"'{spec}' is not 0xIIII, 0xIIII:SS or 0xIIII:SS-TT")
    index = int(m.group(1), 16)
    rows = [r for r in od.rows if r.index == index]
    if not rows:
        raise OdError(file, None, key, f"'{spec}': object 0x{index:04X} is not in {od.path}")
    if m.group(2) is None:
        return [r for r in rows if r.sub != 0] or rows
    first = int(m.group(2), 16)
    last = int(m.group(3), 16) if m.group(3) else first
    chosen = [r for r in rows if first <= r.sub <= last]
    if not chosen or (m.group(3) is None and not chosen):
        raise OdError(file, None, key, f"'{spec}': no such sub-index in {od.path}")
    if m.group(3) is None and len(chosen) != 1:
        raise OdError(file, None, key, f"'{spec}': no such sub-index")
    return chosen


def apply_profile(od: Od, path: Path) -> str:
    file = str(path)
    try:
        with open(path, "rb") as f:
            prof = tomllib.load(f)
    except (OSError, tomllib.TOMLDecodeError) as e:
        raise OdError(file, None, None, str(e)) from None
    c_name = prof.get("c_name", "")
    if not re.fullmatch(r"[a-z][a-z0-9_]*", c_name):
        raise OdError(file, None, "c_name", f"'{c_name}' is not a lower-case C identifier")
    storage = prof.get("storage", {})
    for key in storage:
        if key not in ("store", "keep"):
            raise OdError(file, "storage", key, "unknown key (store, keep)")
    for spec in storage.get("store", []):
        for r in parse_row_spec(spec, od, file, "storage.store"):
            if not ACCESS[r.access][1]:
                raise OdError(file, "storage", "store", f"0x{r.index:04X}:{r.sub:02X} is not writable; nothing to store")
            if r.index in (0x1010, 0x1011) or (r.index == 0x1003):
                raise OdError(file, "storage", "store", f"0x{r.index:04X} is a command object, not a parameter")
            r.store = True
    for spec in storage.get("keep", []):
        for r in parse_row_spec(spec, od, file, "storage.keep"):
            if not r.store:
                raise OdError(file, "storage", "keep", f"0x{r.index:04X}:{r.sub:02X} is kept by restore but not stored")
            r.keep = True
    for spec, capacity in prof.get("strings", {}).items():
        rows = parse_row_spec(spec, od, file, "strings")
        for r in rows:
            if r.dtype not in STRING_TYPES:
                raise OdError(file, "strings", spec, "not a string")
            if not isinstance(capacity, int) or capacity < r.size or capacity > 255:
                raise OdError(file, "strings", spec, f"capacity {capacity} must be {r.size}..255 (the default's length..255)")
            r.size = capacity
    for spec, unit in prof.get("units", {}).items():
        if not isinstance(unit, str) or not 1 <= len(unit) <= 31 or not unit.isprintable() or '"' in unit or "\\" in unit:
            raise OdError(file, "units", spec, f"{unit!r} is not a unit (1..31 printable characters, no quotes)")
        for r in parse_row_spec(spec, od, file, "units"):
            r.unit = unit
    for key in prof:
        if key not in ("c_name", "storage", "strings", "description", "units"):
            raise OdError(file, None, key, "unknown key (c_name, description, storage, strings, units)")
    return c_name


# ---- C output ------------------------------------------------------------------------------------------

def c_number(v: object, dtype: int) -> str:
    if dtype in REAL_TYPES:
        text = repr(float(v))
        return text + ("f" if dtype == 0x08 else "")
    v = int(v)
    if dtype in (0x15,):
        return f"({v}LL)" if v >= -(2**63) + 1 else "(-9223372036854775807LL - 1)"
    if dtype == 0x1B:
        return f"0x{v:X}ULL"
    if dtype in (0x02, 0x03, 0x04):
        return f"({v})" if v > -(2**31) else "(-2147483647 - 1)"
    return f"0x{v:X}UL" if v > 9 else f"{v}U"


def c_bytes(data: bytes, size: int) -> str:
    data = data + bytes(size - len(data))
    return "{" + ", ".join(f"0x{b:02X}" for b in data) + "}"


def c_string(text: str) -> str:
    return text.replace("\\", "\\\\").replace('"', '\\"').replace("*/", "* /")


def signature(od: Od, c_name: str) -> int:
    canon = c_name + ";" + ";".join(f"{r.index:04X}:{r.sub:02X}:{r.dtype:02X}:{r.size}" for r in od.rows)
    return zlib.crc32(canon.encode()) & 0xFFFFFFFF


def flags(r: Row) -> str:
    readable, writable, const, tpdo_ok, rpdo_ok = ACCESS[r.access]
    f = []
    if readable:
        f.append("CO_OD_READ")
    if writable:
        f.append("CO_OD_WRITE")
    if const:
        f.append("CO_OD_CONST")
    if r.pdo and tpdo_ok:
        f.append("CO_OD_TPDO")
    if r.pdo and rpdo_ok:
        f.append("CO_OD_RPDO")
    if r.nodeid:
        f.append("CO_OD_NODEID")
    if r.store:
        f.append("CO_OD_STORE")
    if r.keep:
        f.append("CO_OD_KEEP")
    return " | ".join(f) if f else "0"


TYPE_ENUM = {0x01: "CO_T_BOOLEAN", 0x02: "CO_T_INTEGER8", 0x03: "CO_T_INTEGER16", 0x04: "CO_T_INTEGER32",
             0x05: "CO_T_UNSIGNED8", 0x06: "CO_T_UNSIGNED16", 0x07: "CO_T_UNSIGNED32", 0x08: "CO_T_REAL32",
             0x09: "CO_T_VISIBLE_STRING", 0x0A: "CO_T_OCTET_STRING", 0x11: "CO_T_REAL64",
             0x15: "CO_T_INTEGER64", 0x1B: "CO_T_UNSIGNED64"}


def generate(od: Od, c_name: str, eds_name: str, profile_name: str) -> tuple[str, str, str]:
    upper = c_name.upper()
    banner = (f"/* GENERATED by tools/odgen.py from {eds_name} and {profile_name}. Do not edit: change the\n"
              f" * EDS or the profile and rebuild. */\n")
    h = [banner, f"#ifndef {upper}_OD_H\n#define {upper}_OD_H\n\n#include \"co/co_od.h\"\n\n"]
    h.append(f"/** Values of one {od.name} node (one block per node; the table below is shared). */\n")
    h.append(f"typedef struct {c_name}_od_values {{\n")
    for r in od.rows:
        ctype = TYPES[r.dtype][1]
        arr = f"[{r.size}]" if r.dtype in STRING_TYPES else ""
        h.append(f"    {ctype} {r.member}{arr}; /* 0x{r.index:04X}:{r.sub:02X} {c_string(r.name)} */\n")
    h.append(f"}} {c_name}_od_values_t;\n\n")
    h.append(f"/** The object dictionary of {od.name}: {len(od.rows)} rows. */\n")
    h.append(f"extern const co_od_t {c_name}_od;\n")
    h.append(f"/** The EDS ParameterName of each row, in the order of the table (for tools; a firmware that does not\n"
             f" * use them links none of them). */\n")
    h.append(f"extern const char *const {c_name}_od_names[{len(od.rows)}];\n")
    h.append(f"/** The unit of each row's value (the profile's [units]), NULL where it has none; table order. */\n")
    h.append(f"extern const char *const {c_name}_od_units[{len(od.rows)}];\n\n")
    h.append(f"#define {upper}_OD_ROWS {len(od.rows)}U\n")
    h.append(f"#define {upper}_OD_SIGNATURE 0x{signature(od, c_name):08X}UL\n\n#endif\n")

    c = [banner, f"#include \"{c_name}_od.h\"\n\n#include <stddef.h>\n\n"]
    c.append(f"#define V {c_name}_od_values_t\n")
    c.append("#define ROW(i, s, t, f, m, l) {i, s, t, f, (uint16_t)sizeof(((V *)0)->m), (uint32_t)offsetof(V, m), l}\n\n")
    for r in od.rows:
        if (r.low is not None or r.high is not None) and r.dtype not in REAL_TYPES + STRING_TYPES and r.dtype != 0x1B:
            lo = TYPES[r.dtype][3] if r.low is None else r.low
            hi = TYPES[r.dtype][4] if r.high is None else r.high
            c.append(f"static const co_od_limits_t limits_{r.member} = {{{int(lo)}LL, {int(hi)}LL}};\n")
    c.append(f"\nstatic const co_od_entry_t rows[{len(od.rows)}] = {{\n")
    for r in od.rows:
        has_limits = (r.low is not None or r.high is not None) and r.dtype not in REAL_TYPES + STRING_TYPES and r.dtype != 0x1B
        lim = f"&limits_{r.member}" if has_limits else "NULL"
        c.append(f"    ROW(0x{r.index:04X}, 0x{r.sub:02X}, {TYPE_ENUM[r.dtype]}, {flags(r)}, {r.member}, {lim}),\n")
    c.append("};\n\n")
    c.append(f"static const {c_name}_od_values_t defaults = {{\n")
    for r in od.rows:
        if r.dtype == 0x09:
            data = r.value.encode("ascii")
            if data:
                c.append(f"    .{r.member} = {c_bytes(data, r.size)}, /* \"{c_string(r.value)}\" */\n")
        elif r.dtype == 0x0A:
            if r.value:
                c.append(f"    .{r.member} = {c_bytes(r.value, r.size)},\n")
        elif r.value not in (0, 0.0):
            c.append(f"    .{r.member} = {c_number(r.value, r.dtype)},{' /* + node-ID */' if r.nodeid else ''}\n")
    c.append("};\n\n")
    c.append(f"const co_od_t {c_name}_od = {{\n    \"{od.name}\", rows, {len(od.rows)}U, &defaults,\n"
             f"    (uint32_t)sizeof({c_name}_od_values_t), 0x{signature(od, c_name):08X}UL,\n}};\n")
    # The names in an object file of their own: a firmware that links the table does not link them.
    n = [banner, f"#include \"{c_name}_od.h\"\n\n#include <stddef.h>\n\n"]
    n.append(f"const char *const {c_name}_od_names[{len(od.rows)}] = {{\n")
    for r in od.rows:
        n.append(f"    \"{c_string(r.name)}\", /* 0x{r.index:04X}:{r.sub:02X} */\n")
    n.append("};\n\n")
    n.append(f"const char *const {c_name}_od_units[{len(od.rows)}] = {{\n")
    for r in od.rows:
        n.append(f"    \"{c_string(r.unit)}\", /* 0x{r.index:04X}:{r.sub:02X} */\n" if r.unit else
                 f"    NULL, /* 0x{r.index:04X}:{r.sub:02X} */\n")
    n.append("};\n")
    return "".join(h), "".join(c), "".join(n)


def main(argv: list[str]) -> int:
    ap = argparse.ArgumentParser(description="Generate the C object dictionary of a device from its EDS.")
    ap.add_argument("--eds", type=Path, help="the device's EDS (CiA 306)")
    ap.add_argument("--profile", type=Path, help="the generator profile (TOML); default: the EDS with .toml")
    ap.add_argument("--out-dir", type=Path, help="where <c_name>_od.h/.c are written")
    ap.add_argument("--check", type=Path, metavar="EDS", help="only validate an EDS (and its profile if present)")
    args = ap.parse_args(argv)
    eds_path = args.check or args.eds
    if eds_path is None:
        ap.error("--eds or --check is required")
    try:
        od = read_eds(eds_path)
        profile = args.profile or eds_path.with_suffix(".toml")
        c_name = None
        if profile.exists() or not args.check:
            c_name = apply_profile(od, profile)
        if args.check:
            print(f"{eds_path}: OK ({len(od.rows)} rows)")
            return 0
        header, source, names = generate(od, c_name, eds_path.name, profile.name)
    except OdError as e:
        print(f"odgen: error: {e}", file=sys.stderr)
        return 1
    if args.out_dir is None:
        ap.error("--out-dir is required to generate")
    args.out_dir.mkdir(parents=True, exist_ok=True)
    for name, text in ((f"{c_name}_od.h", header), (f"{c_name}_od.c", source), (f"{c_name}_od_names.c", names)):
        target = args.out_dir / name
        if not target.exists() or target.read_text() != text:  # keep timestamps when nothing changed
            target.write_text(text)
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
