#!/usr/bin/env python3
"""odgen: turns a CiA 306 EDS and its generator profile into the C object-dictionary tables of the core.

    tools/odgen.py --reader build/canopen-eds --eds od/pro-ionizer.eds --profile od/pro-ionizer.toml --out-dir build/od
    tools/odgen.py --reader build/canopen-eds --check od/pro-ionizer.eds          (validate only)

Output: <c_name>_od.h (the values struct, the co_od_t), <c_name>_od.c (the sorted const row table,
the defaults image, the limits), <c_name>_od_names.c (the rows' names and units) and <c_name>_od_config.h
(the core's switches for services the dictionary has no objects for, off). All say they are generated. The
output depends only on the inputs (no dates, no paths), so a rebuild gives the same bytes.

The EDS is read by the project's one EDS/DCF reader (eds/, docs/eds.md), through `canopen-eds json
--strict`: the emulator reads files with the same code, so a generated table and an emulated device never
disagree about a file. The project's own files must be clean: any warning of the reader is an error here.

The profile (TOML, beside the EDS) says what an EDS cannot: which rows 0x1010 stores, which survive
0x1011 restore, the capacity of writable strings, the units of values.
"""
from __future__ import annotations

import argparse
import json
import os
import re
import subprocess
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
    # No C type of their size: held as little-endian bytes (co_od.h).
    0x0C: ("TIME_OF_DAY", "uint8_t", 6, 0, 2**48 - 1),
    0x0D: ("TIME_DIFFERENCE", "uint8_t", 6, 0, 2**48 - 1),
    0x10: ("INTEGER24", "uint8_t", 3, -(2**23), 2**23 - 1),
    0x12: ("INTEGER40", "uint8_t", 5, -(2**39), 2**39 - 1),
    0x13: ("INTEGER48", "uint8_t", 6, -(2**47), 2**47 - 1),
    0x14: ("INTEGER56", "uint8_t", 7, -(2**55), 2**55 - 1),
    0x16: ("UNSIGNED24", "uint8_t", 3, 0, 2**24 - 1),
    0x18: ("UNSIGNED40", "uint8_t", 5, 0, 2**40 - 1),
    0x19: ("UNSIGNED48", "uint8_t", 6, 0, 2**48 - 1),
    0x1A: ("UNSIGNED56", "uint8_t", 7, 0, 2**56 - 1),
    0x0B: ("UNICODE_STRING", "uint8_t", 0, 0, 0),
    0x0F: ("DOMAIN", "uint8_t", 0, 0, 0),
}
STRING_TYPES = (0x09, 0x0A, 0x0B, 0x0F)
REAL_TYPES = (0x08, 0x11)
BYTE_INTEGERS = (0x0C, 0x0D, 0x10, 0x12, 0x13, 0x14, 0x16, 0x18, 0x19, 0x1A)  # odd sizes: a byte array each

# EDS AccessType -> (readable, writable, const, TPDO-mappable direction allowed, RPDO direction allowed)
ACCESS = {
    "ro": (True, False, False, True, False),
    "const": (True, False, True, True, False),
    "wo": (False, True, False, False, True),
    "rw": (True, True, False, True, True),
    "rwr": (True, True, False, True, False),  # read/write, mappable to TPDOs only
    "rww": (True, True, False, False, True),  # read/write, mappable to RPDOs only
}


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
    object_names: dict[int, str] = field(default_factory=dict)  # the ParameterName of each object (index)

    def find(self, index: int, sub: int) -> Row | None:
        for r in self.rows:
            if r.index == index and r.sub == sub:
                return r
        return None


def find_reader(explicit: str | None) -> str:
    reader = explicit or os.environ.get("CO_EDS_TOOL")
    if not reader:
        raise OdError("odgen", None, None, "the EDS reader is not given: pass --reader PATH/canopen-eds "
                      "(built with the project) or set CO_EDS_TOOL")
    return reader


def read_eds(path: Path, reader: str) -> Od:
    """The EDS as the project's reader sees it; any warning or error of it is an error here."""
    try:
        r = subprocess.run([reader, "json", "--strict", str(path)], capture_output=True, text=True, timeout=120)
    except OSError as e:
        raise OdError(str(path), None, None, f"cannot run the EDS reader {reader}: {e}") from None
    if r.returncode != 0:
        raise OdError(str(path), None, None, "the EDS reader reports:\n" + r.stderr.rstrip())
    model = json.loads(r.stdout)
    od = Od(str(path), Path(path).stem)
    od.device_info = model["device"]
    od.object_names = {o["index"]: o["name"].strip() for o in model["objects"]}
    for e in model["entries"]:
        dtype = e["type"]
        if dtype not in TYPES:
            raise OdError(str(path), f"{e['index']:04X}", "DataType",
                          f"data type {dtype:#06x} is read but the core's generated tables do not hold it yet")
        value = e["default"]
        if dtype in (0x0A, 0x0B, 0x0F):
            value = bytes.fromhex(value)
        row = Row(e["index"], e["sub"], e["name"].strip(), dtype, e["access"], e["pdo_mapping"], value, e["nodeid"],
                  low=e["low"], high=e["high"], section=f"line {e['line']}")
        row.size = len(value) if dtype in STRING_TYPES else TYPES[dtype][2]
        if dtype == 0x09:
            try:
                value.encode("ascii")
            except UnicodeEncodeError:
                raise OdError(str(path), row.section, "DefaultValue", "a VISIBLE_STRING of the project must be ASCII") from None
        od.rows.append(row)
    return od


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


def has_limits(r: Row) -> bool:
    return (r.low is not None or r.high is not None) and r.dtype not in STRING_TYPES


def c_limit(v: object, dtype: int) -> str:
    """One member of a co_od_limit_t union, for the row's type."""
    if dtype in REAL_TYPES:
        return f"{{.r = {float(v)!r}}}"
    if dtype == 0x1B:
        return f"{{.u = 0x{int(v):X}ULL}}"
    v = int(v)
    if dtype in (0x01, 0x05, 0x06, 0x07):  # also a 32-bit pair's member (CO_CONFIG_OD_LIMITS_64 0)
        return f"{{.u = {v}U}}" if v <= 9 else f"{{.u = 0x{v:X}UL}}"
    return f"{{.i = {v}LL}}" if v > -(2**63) else "{.i = -9223372036854775807LL - 1}"


def c_bytes(data: bytes, size: int) -> str:
    data = data + bytes(size - len(data))
    return "{" + ", ".join(f"0x{b:02X}" for b in data) + "}"


def c_string(text: str) -> str:
    return text.replace("\\", "\\\\").replace('"', '\\"').replace("*/", "* /")


def signature(od: Od, c_name: str) -> int:
    canon = c_name + ";" + ";".join(f"{r.index:04X}:{r.sub:02X}:{r.dtype:02X}:{r.size}" for r in od.rows)
    return zlib.crc32(canon.encode()) & 0xFFFFFFFF


def limit_range(r: Row) -> tuple:
    """The low and high limit of a row with limits (the type's bounds where the EDS gives none)."""
    return (TYPES[r.dtype][3] if r.low is None else r.low, TYPES[r.dtype][4] if r.high is None else r.high)


def narrow_limits(r: Row) -> bool:
    """The row's limits fit a 16-bit pair (CO_CONFIG_OD_LIMITS_16): integers, each in the member it is written to
    (c_limit: .u for BOOLEAN and UNSIGNED8/16/32, .i for the others)."""
    if r.dtype in REAL_TYPES or TYPES[r.dtype][2] > 4:
        return False
    lo, hi = (int(v) for v in limit_range(r))
    unsigned = r.dtype in (0x01, 0x05, 0x06, 0x07)
    return all((0 <= v <= 0xFFFF) if unsigned else (-0x8000 <= v <= 0x7FFF) for v in (lo, hi))


def wide_limits(r: Row) -> bool:
    """The row has limits that need 64-bit pairs: a REAL, or an integer of more than 4 bytes."""
    return has_limits(r) and (r.dtype in REAL_TYPES or TYPES[r.dtype][2] > 4)


def zero_default(r: Row) -> bool:
    """The row's default is all zero bytes (generate leaves it out of the defaults image)."""
    if r.dtype == 0x09:
        return not r.value.encode("ascii")
    if r.dtype in (0x0A, 0x0B, 0x0F) or r.dtype in BYTE_INTEGERS:
        return not r.value
    return r.value in (0, 0.0)


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
             0x09: "CO_T_VISIBLE_STRING", 0x0A: "CO_T_OCTET_STRING", 0x0B: "CO_T_UNICODE_STRING",
             0x0C: "CO_T_TIME_OF_DAY", 0x0D: "CO_T_TIME_DIFFERENCE", 0x0F: "CO_T_DOMAIN", 0x10: "CO_T_INTEGER24",
             0x11: "CO_T_REAL64", 0x12: "CO_T_INTEGER40", 0x13: "CO_T_INTEGER48", 0x14: "CO_T_INTEGER56",
             0x15: "CO_T_INTEGER64", 0x16: "CO_T_UNSIGNED24", 0x18: "CO_T_UNSIGNED40", 0x19: "CO_T_UNSIGNED48",
             0x1A: "CO_T_UNSIGNED56", 0x1B: "CO_T_UNSIGNED64"}


def table_runs(rows: list[Row], row_limit: dict) -> list[list[Row]]:
    """The table's rows: consecutive sub-indices of one object alike in all but their value (type, size, flags,
    limits; numbers only) become one row, a run (co_od.h): 0x1016's 127 consumer times are one row of 10 bytes."""
    runs: list[list[Row]] = []
    for r in rows:
        last = runs[-1][-1] if runs else None
        if (last is not None and r.index == last.index and r.sub == last.sub + 1 and r.dtype == last.dtype
                and r.size == last.size and flags(r) == flags(last) and row_limit.get(r.member) == row_limit.get(last.member)
                and r.dtype not in STRING_TYPES + BYTE_INTEGERS and len(runs[-1]) < 255):
            runs[-1].append(r)
        else:
            runs.append([r])
    return runs


def object_slots(indices: list[int]) -> tuple[int, list[int]]:
    """co_od_t.object_slots of objects with these indices (in table order): the bits and the slots, filled as
    co_od_object_slots_fill() fills them (co_od.h: the hash and the probe order the look-up follows)."""
    bits = 1
    while (1 << bits) < 2 * len(indices):
        bits += 1
    slots = [0] * (1 << bits)
    for k, index in enumerate(indices):
        h = ((index * 0x9E3779B1) & 0xFFFFFFFF) >> (32 - bits)
        while slots[h]:
            h = (h + 1) & ((1 << bits) - 1)
        slots[h] = k + 1
    return bits, slots


def generate(od: Od, c_name: str, eds_name: str, profile_name: str) -> tuple[str, str, str]:
    upper = c_name.upper()
    banner = (f"/* GENERATED by tools/odgen.py from {eds_name} and {profile_name}. Do not edit: change the\n"
              f" * EDS or the profile and rebuild. */\n")
    h = [banner, f"#ifndef {upper}_OD_H\n#define {upper}_OD_H\n\n#include \"co/co_od.h\"\n\n"]
    h.append(f"/** Values of one {od.name} node (one block per node; the table below is shared). */\n")
    # Rows with the same limits share one pair (the PRO IONIZER's 59 limited rows have 26 distinct pairs).
    limit_pairs: dict = {}
    row_limit: dict = {}
    for r in od.rows:
        if has_limits(r):
            lo, hi = limit_range(r)
            pair = f"{{{c_limit(lo, r.dtype)}, {c_limit(hi, r.dtype)}}}"
            row_limit[r.member] = limit_pairs.setdefault(pair, len(limit_pairs))
    runs = table_runs(od.rows, row_limit)
    firsts = [i for i, run in enumerate(runs) if i == 0 or runs[i - 1][0].index != run[0].index]  # object table
    # The values whose default is not 0 first: the defaults image holds just them (co_od_t.defaults_size). A run's
    # values stay together (its row gives the first one's offset): a run with any default but 0 goes first whole.
    # Within each part, the widest members first (8, 4, 2 bytes, then bytes and byte arrays; table order among alike):
    # no padding between them, in the defaults image as in the values block.
    def by_alignment(part: list) -> list:
        width = lambda run: 1 if run[0].dtype in STRING_TYPES + BYTE_INTEGERS else TYPES[run[0].dtype][2]  # noqa: E731
        return [r for run in sorted(part, key=lambda run: -width(run)) for r in run]
    nonzero = by_alignment([run for run in runs if not all(zero_default(x) for x in run)])
    layout = nonzero + by_alignment([run for run in runs if all(zero_default(x) for x in run)])
    n_defaults = max(1, len(nonzero))

    def member(r: Row) -> str:
        arr = f"[{r.size}]" if r.dtype in STRING_TYPES + BYTE_INTEGERS else ""
        text = f"    {TYPES[r.dtype][1]} {r.member}{arr}; /* 0x{r.index:04X}:{r.sub:02X} {c_string(r.name)} */\n"
        if r.dtype in STRING_TYPES:  # its current length, right after it (co_od.h CO_OD_LEN_SIZE)
            text += f"    uint8_t {r.member}_len[CO_OD_LEN_SIZE];\n"
        return text
    h.append(f"typedef struct {c_name}_od_values {{\n")
    h.extend(member(r) for r in layout)
    h.append(f"}} {c_name}_od_values_t;\n\n")
    h.append(f"/** The object dictionary of {od.name}: {len(od.rows)} sub-indices in {len(runs)} rows. */\n")
    h.append(f"extern const co_od_t {c_name}_od;\n")
    h.append(f"/** The EDS ParameterName of each sub-index, in the order of the table (a run of the table: one per\n"
             f" * sub-index; for tools, a firmware that does not use them links none of them). */\n")
    h.append(f"extern const char *const {c_name}_od_names[{len(od.rows)}];\n")
    h.append(f"/** The unit of each sub-index's value (the profile's [units]), NULL where it has none; table order. */\n")
    h.append(f"extern const char *const {c_name}_od_units[{len(od.rows)}];\n")
    h.append(f"/** The EDS ParameterName of each object (\"Identity object\"), in the order of the object table. */\n")
    h.append(f"extern const char *const {c_name}_od_object_names[{len(firsts)}];\n\n")
    h.append(f"#define {upper}_OD_SUB_INDICES {len(od.rows)}U\n")
    h.append(f"#define {upper}_OD_ROWS {len(runs)}U\n")
    h.append(f"#define {upper}_OD_SIGNATURE 0x{signature(od, c_name):08X}UL\n\n#endif\n")

    c = [banner, f"#include \"{c_name}_od.h\"\n\n#include <stddef.h>\n\n"]
    c.append(f"#define V {c_name}_od_values_t\n")
    c.append("#define ROW(i, s, t, f, m) CO_OD_ROW(i, s, t, f, sizeof(((V *)0)->m), offsetof(V, m))\n")
    c.append("#define ROW_LIMITED(i, s, t, f, m, n) CO_OD_ROW_LIMITED(i, s, t, f, sizeof(((V *)0)->m), offsetof(V, m), limits, n)\n")
    c.append("/* a run: n sub-indices from s, values from member m on (one after the other, checked below) */\n"
             "#define RUN(i, s, n, t, f, m) CO_OD_RUN(i, s, n, t, f, sizeof(((V *)0)->m), offsetof(V, m))\n"
             "#define RUN_LIMITED(i, s, n, t, f, m, k) CO_OD_RUN_LIMITED(i, s, n, t, f, sizeof(((V *)0)->m), offsetof(V, m), limits, k)\n\n")
    if limit_pairs:
        c.append(f"static const co_od_limits_t limits[{len(limit_pairs)}] = {{\n")
        c.extend(f"    {pair}, /* {k} */\n" for pair, k in limit_pairs.items())
        c.append("};\n")
    if any(wide_limits(r) for r in od.rows):
        c.append("\n#if !CO_CONFIG_OD_LIMITS_64\n#error \"this dictionary has REAL or 64-bit limits: CO_CONFIG_OD_LIMITS_64 must be 1\"\n#endif\n")
    if not all(narrow_limits(r) for r in od.rows if has_limits(r)):
        c.append("\n#if CO_CONFIG_OD_LIMITS_16 && !CO_CONFIG_OD_LIMITS_64\n"
                 "#error \"this dictionary has limits beyond 16 bits: CO_CONFIG_OD_LIMITS_16 must be 0\"\n#endif\n")
    c.append("\n#if CO_CONFIG_OD_COMPACT /* 16-bit value offsets, limits numbered in 8 bits (co_config.h) */\n"
             f"typedef char compact_rows_fit[sizeof(V) <= 0xFFFFU && {len(limit_pairs)}U <= 255U && "
             f"{max(r.size for r in od.rows)}U <= 255U ? 1 : -1];\n#endif\n")
    long_runs = [run for run in runs if len(run) > 1]
    if long_runs:
        c.append("\n/* Each run's values lie one after the other, as its row says. */\ntypedef char runs_are_arrays[\n")
        c.append(" &&\n".join(f"    offsetof(V, {run[-1].member}) == offsetof(V, {run[0].member}) + {len(run) - 1}U * "
                              f"sizeof(((V *)0)->{run[0].member})" for run in long_runs))
        c.append("\n    ? 1 : -1];\n")
    c.append(f"\nstatic const co_od_entry_t rows[{len(runs)}] = {{\n")
    for run in runs:
        r = run[0]
        if len(run) == 1:
            args = f"0x{r.index:04X}, 0x{r.sub:02X}, {TYPE_ENUM[r.dtype]}, {flags(r)}, {r.member}"
            c.append(f"    ROW_LIMITED({args}, {row_limit[r.member]}),\n" if has_limits(r) else f"    ROW({args}),\n")
        else:
            args = f"0x{r.index:04X}, 0x{r.sub:02X}, {len(run)}U, {TYPE_ENUM[r.dtype]}, {flags(r)}, {r.member}"
            c.append(f"    RUN_LIMITED({args}, {row_limit[r.member]}), /* to :{run[-1].sub:02X} */\n" if has_limits(r)
                     else f"    RUN({args}), /* to :{run[-1].sub:02X} */\n")
    c.append("};\n\n")
    c.append(f"static const co_od_object_t objects[{len(firsts)}] = {{\n")
    for k in range(0, len(firsts), 6):
        c.append("    " + " ".join(f"{{0x{runs[i][0].index:04X}, {i}U}}," for i in firsts[k:k + 6]) + "\n")
    c.append("};\n\n")
    bits, slots = object_slots([runs[i][0].index for i in firsts])
    c.append(f"#if !CO_CONFIG_OD_COMPACT\n/* The objects by index, hashed: co_od_t.object_slots (co_od.h says how). */\n"
             f"static const uint16_t object_slots[{len(slots)}] = {{\n")
    for k in range(0, len(slots), 16):
        c.append("    " + " ".join(f"{v}U," for v in slots[k:k + 16]) + "\n")
    c.append("};\n#endif\n\n")
    last = layout[n_defaults - 1].member
    if layout[n_defaults - 1].dtype in STRING_TYPES:
        last += "_len"  # the image ends with the last value's length
    c.append(f"/* The first {n_defaults} members of {c_name}_od_values_t, laid out as there: the values whose default is not 0\n"
             " * (the rest of a values block starts at 0). */\ntypedef struct {\n")
    c.extend(member(r) for r in layout[:n_defaults])
    c.append("} defaults_t;\n")
    c.append(f"typedef char defaults_laid_out_as_values[offsetof(defaults_t, {last}) == offsetof(V, {last}) ? 1 : -1];\n\n")
    c.append("static const defaults_t defaults = {\n")
    if all(zero_default(r) for r in layout[:n_defaults]):
        c.append("    0, /* every default is 0 */\n")  # C has no empty initialiser
    for r in layout[:n_defaults]:
        if r.dtype == 0x09:
            data = r.value.encode("ascii")
            if data:
                c.append(f"    .{r.member} = {c_bytes(data, r.size)}, /* \"{c_string(r.value)}\" */\n")
                c.append(f"    .{r.member}_len = {c_bytes(len(data).to_bytes(2, 'little'), 2)},\n")
        elif r.dtype in (0x0A, 0x0B, 0x0F):
            if r.value:
                c.append(f"    .{r.member} = {c_bytes(r.value, r.size)},\n")
                c.append(f"    .{r.member}_len = {c_bytes(len(r.value).to_bytes(2, 'little'), 2)},\n")
        elif r.dtype in BYTE_INTEGERS:
            if r.value:
                c.append(f"    .{r.member} = {c_bytes(int(r.value).to_bytes(r.size, 'little', signed=r.value < 0), r.size)},"
                         f"{' /* + node-ID */' if r.nodeid else ''}\n")
        elif r.value not in (0, 0.0):
            c.append(f"    .{r.member} = {c_number(r.value, r.dtype)},{' /* + node-ID */' if r.nodeid else ''}\n")
    c.append("};\n\n")
    c.append(f"const co_od_t {c_name}_od = {{\n    \"{od.name}\", rows, {len(runs)}U, &defaults,\n"
             f"    (uint32_t)sizeof({c_name}_od_values_t), 0x{signature(od, c_name):08X}UL,\n"
             f"    0x{od.device_info['dummy_usage']:02X}U, /* [DummyUsage] */\n"
             f"    objects, {len(firsts)}U,\n    {'limits' if limit_pairs else 'NULL'},\n"
             f"    (uint32_t)(offsetof(V, {last}) + sizeof(((V *)0)->{last})),\n"
             f"#if !CO_CONFIG_OD_COMPACT\n    object_slots, {bits}U,\n#endif\n}};\n")
    # The names in an object file of their own: a firmware that links the table does not link them.
    n = [banner, f"#include \"{c_name}_od.h\"\n\n#include <stddef.h>\n\n"]
    n.append(f"const char *const {c_name}_od_names[{len(od.rows)}] = {{\n")
    for r in od.rows:
        n.append(f"    \"{c_string(r.name)}\", /* 0x{r.index:04X}:{r.sub:02X} */\n")
    n.append("};\n\n")
    n.append(f"const char *const {c_name}_od_object_names[{len(firsts)}] = {{\n")
    for i in firsts:
        index = runs[i][0].index
        n.append(f"    \"{c_string(od.object_names.get(index, ''))}\", /* 0x{index:04X} */\n")
    n.append("};\n\n")
    n.append(f"const char *const {c_name}_od_units[{len(od.rows)}] = {{\n")
    for r in od.rows:
        n.append(f"    \"{c_string(r.unit)}\", /* 0x{r.index:04X}:{r.sub:02X} */\n" if r.unit else
                 f"    NULL, /* 0x{r.index:04X}:{r.sub:02X} */\n")
    n.append("};\n")
    return "".join(h), "".join(c), "".join(n)


def fitted_config(od: Od, c_name: str, eds_name: str) -> str:
    """<c_name>_od_config.h: the core configuration switches this dictionary has no objects for, turned off, and the
    16-bit limit pairs where its limits allow them."""
    indices = {r.index for r in od.rows}
    has = lambda lo, hi: any(lo <= i <= hi for i in indices)  # noqa: E731
    n_rpdo = sum(1 for i in indices if 0x1400 <= i <= 0x15FF)
    n_tpdo = sum(1 for i in indices if 0x1800 <= i <= 0x19FF)
    n_hbc = sum(1 for r in od.rows if r.index == 0x1016 and r.sub != 0)
    maps = [r for r in od.rows if (0x1600 <= r.index <= 0x17FF or 0x1A00 <= r.index <= 0x1BFF)]
    writable_maps = any(ACCESS[r.access][1] for r in maps)
    # An MPDO is a mapping count of 0xFE/0xFF: by default, or written where the count's limits allow it.
    mpdo_counts = any(r.sub == 0 and (r.value in (0xFE, 0xFF) or (ACCESS[r.access][1] and (r.high is None or r.high >= 0xFE)))
                      for r in maps)
    off = []  # (switch, why)
    if 0x1005 not in indices:
        off.append(("CO_CONFIG_SYNC", "no SYNC COB-ID 0x1005"))
    row = lambda i, s: next((r for r in od.rows if r.index == i and r.sub == s), None)  # noqa: E731
    # A value the node may have: written (writable), or its default.
    may = lambda r, test: r is not None and (ACCESS[r.access][1] or test(int(r.value or 0)))  # noqa: E731
    if 0x1005 in indices and not may(row(0x1005, 0), lambda v: (v & 0x40000000) != 0):
        off.append(("CO_CONFIG_SYNC_PRODUCER", "0x1005 cannot have bit 30 (gen): no SYNC produced"))
    if not any(may(row(i, 1), lambda v: (v & 0x40000000) == 0) and (row(i, 2) is None or may(row(i, 2), lambda v: v >= 252))
               for i in range(0x1800, 0x1A00)):  # no sub 2: type 255
        off.append(("CO_CONFIG_TPDO_RTR", "no TPDO whose COB-ID can allow RTR (bit 30 clear) with a type 252..255"))
    if 0x100C not in indices and 0x100D not in indices:
        off.append(("CO_CONFIG_NODE_GUARDING", "no guard time 0x100C, no life time factor 0x100D"))
    if n_hbc == 0:
        off.append(("CO_CONFIG_HB_CONSUMER", "no consumer heartbeat time 0x1016"))
    if not has(0x1FA0, 0x1FFF) and not mpdo_counts:
        off.append(("CO_CONFIG_MPDO", "no object scanner/dispatching list 0x1FA0-0x1FFF, no mapping count that can be 0xFE/0xFF"))
    if 0x1003 not in indices:
        off.append(("CO_CONFIG_EMCY_HISTORY", "no pre-defined error field 0x1003"))
    if 0x1015 not in indices:
        off.append(("CO_CONFIG_EMCY_INHIBIT", "no EMCY inhibit time 0x1015"))
    if not has(0x1201, 0x127F):
        off.append(("CO_CONFIG_SDO_SERVERS", "no additional SDO server 0x1201-0x127F"))
    if not writable_maps:
        off.append(("CO_CONFIG_PDO_DYNAMIC_MAPPING", "no writable PDO mapping"))
    timers = any((0x1400 <= r.index <= 0x15FF and r.sub == 5) or (0x1800 <= r.index <= 0x19FF and r.sub in (3, 5))
                 for r in od.rows)
    if not timers:
        off.append(("CO_CONFIG_PDO_TIMERS", "no RPDO event timer 0x1400..:05, no TPDO inhibit time or event timer "
                                            "0x1800..:03/05"))
    if not any(wide_limits(r) for r in od.rows):
        off.append(("CO_CONFIG_OD_LIMITS_64", "limits on integers of at most 4 bytes only: 32-bit pairs"))
    narrow = all(narrow_limits(r) for r in od.rows if has_limits(r))
    upper = c_name.upper()
    h = [f"/* GENERATED by tools/odgen.py from {eds_name}. Do not edit: change the EDS and rebuild.\n"
         f" * The core configuration this dictionary needs at most: include it after a configuration profile, in the\n"
         f" * header named by CO_CONFIG_HEADER (co_config.h), and the services it has no objects for cost nothing in a\n"
         f" * firmware's image. */\n",
         f"#ifndef {upper}_OD_CONFIG_H\n#define {upper}_OD_CONFIG_H\n\n"]
    for switch, why in off:
        h.append(f"/* {why} */\n#undef {switch}\n#define {switch} 0\n")
    if narrow:
        h.append("/* every limit fits 16 bits: 16-bit pairs */\n#undef CO_CONFIG_OD_LIMITS_16\n#define CO_CONFIG_OD_LIMITS_16 1\n")
    for knob, n in (("CO_RPDO_MAX", n_rpdo), ("CO_TPDO_MAX", n_tpdo), ("CO_HB_CONSUMER_MAX", n_hbc)):
        if knob == "CO_HB_CONSUMER_MAX" and n == 0:
            continue
        h.append(f"#if !defined({knob}) || {knob} > {n}U\n#undef {knob}\n#define {knob} {n}U\n#endif\n")
    h.append(f"\n#endif /* {upper}_OD_CONFIG_H */\n")
    return "".join(h)


def main(argv: list[str]) -> int:
    ap = argparse.ArgumentParser(description="Generate the C object dictionary of a device from its EDS.")
    ap.add_argument("--reader", help="the project's canopen-eds program (default: $CO_EDS_TOOL)")
    ap.add_argument("--eds", type=Path, help="the device's EDS (CiA 306)")
    ap.add_argument("--profile", type=Path, help="the generator profile (TOML); default: the EDS with .toml")
    ap.add_argument("--out-dir", type=Path, help="where <c_name>_od.h/.c are written")
    ap.add_argument("--check", type=Path, metavar="EDS", help="only validate an EDS (and its profile if present)")
    args = ap.parse_args(argv)
    eds_path = args.check or args.eds
    if eds_path is None:
        ap.error("--eds or --check is required")
    try:
        od = read_eds(eds_path, find_reader(args.reader))
        profile = args.profile or eds_path.with_suffix(".toml")
        c_name = None
        if profile.exists() or not args.check:
            c_name = apply_profile(od, profile)
        if args.check:
            print(f"{eds_path}: OK ({len(od.rows)} rows)")
            return 0
        for r in od.rows:  # C has no zero-size arrays
            if r.dtype in STRING_TYPES and r.size == 0:
                if r.dtype != 0x09:
                    raise OdError(str(profile), "strings", f"0x{r.index:04X}:{r.sub:02X}",
                                  f"an empty {TYPES[r.dtype][0]} needs a capacity here")
                r.size = 1  # an empty VISIBLE_STRING: one NUL, read as 0 bytes
        header, source, names = generate(od, c_name, eds_path.name, profile.name)
        config = fitted_config(od, c_name, eds_path.name)
    except OdError as e:
        print(f"odgen: error: {e}", file=sys.stderr)
        return 1
    if args.out_dir is None:
        ap.error("--out-dir is required to generate")
    args.out_dir.mkdir(parents=True, exist_ok=True)
    for name, text in ((f"{c_name}_od.h", header), (f"{c_name}_od.c", source), (f"{c_name}_od_names.c", names),
                       (f"{c_name}_od_config.h", config)):
        target = args.out_dir / name
        if not target.exists() or target.read_text() != text:  # keep timestamps when nothing changed
            target.write_text(text)
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
