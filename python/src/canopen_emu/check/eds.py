"""The device description the checks hold a node to: an EDS or DCF (CiA 306) read with the standard library.

The ``canopen`` package is not a dependency of canopen_emu (the package needs nothing but the standard library, and
the check needs only python-can), so the file is read here with configparser and the rules of CiA 306 that real
files need (docs/eds.md "What it reads" lists the emulator's reader; this one follows it where a check depends on
it):

- sections ``[XXXX]`` and ``[XXXXsubN]`` in any case and spelling of N (``1018sub2``, ``1018SUB02``); the objects
  are those of ``[MandatoryObjects]``, ``[OptionalObjects]`` and ``[ManufacturerObjects]`` (every ``[XXXX]`` section
  when the file has none of the lists);
- ``CompactSubObj=N``: sub-index 0 (UNSIGNED8, ro, N) and 1..N of the object's DataType, AccessType and
  DefaultValue, names from ``[XXXXName]``, a DCF's values from ``[XXXXValue]``;
- numbers: ``0x`` hexadecimal, a leading ``0`` octal (CiA 306), decimal, signed; ``$NODEID`` anywhere in a sum;
  a hexadecimal value of a signed type is its bit pattern; an inline ``;`` comment after a number is dropped;
- a DCF's ``ParameterValue`` is the value the device holds (it wins over ``DefaultValue``);
- UTF-8 with or without a byte-order mark, else Latin-1.

DEFTYPE and DEFSTRUCT objects (0x0001..0x025F) describe data types, not entries a device must answer: left out; so
is an entry of a data type that is not one of CiA 301's basic types (a manufacturer's 0x0040..0x005F: neither its
size nor its value can be judged), and an ARRAY or RECORD left without sub-indexes (as canopen-emu's reader does).
``Eds.warnings`` says what was left out.
"""
from __future__ import annotations

import configparser
import math
import re
import struct
from dataclasses import dataclass, field
from pathlib import Path
from typing import Dict, Iterator, List, Optional, Union

# CiA 301 v4.2.0 §7.1 and the data type entries 0x0001..0x001B: the static data types by their index; size in bytes, None for the variable ones.
TYPE_NAMES = {
    0x01: "BOOLEAN", 0x02: "INTEGER8", 0x03: "INTEGER16", 0x04: "INTEGER32", 0x05: "UNSIGNED8", 0x06: "UNSIGNED16",
    0x07: "UNSIGNED32", 0x08: "REAL32", 0x09: "VISIBLE_STRING", 0x0A: "OCTET_STRING", 0x0B: "UNICODE_STRING",
    0x0C: "TIME_OF_DAY", 0x0D: "TIME_DIFFERENCE", 0x0F: "DOMAIN", 0x10: "INTEGER24", 0x11: "REAL64",
    0x12: "INTEGER40", 0x13: "INTEGER48", 0x14: "INTEGER56", 0x15: "INTEGER64", 0x16: "UNSIGNED24",
    0x18: "UNSIGNED40", 0x19: "UNSIGNED48", 0x1A: "UNSIGNED56", 0x1B: "UNSIGNED64",
}
TYPE_SIZES: Dict[int, Optional[int]] = {
    0x01: 1, 0x02: 1, 0x03: 2, 0x04: 4, 0x05: 1, 0x06: 2, 0x07: 4, 0x08: 4, 0x09: None, 0x0A: None, 0x0B: None,
    0x0C: 6, 0x0D: 6, 0x0F: None, 0x10: 3, 0x11: 8, 0x12: 5, 0x13: 6, 0x14: 7, 0x15: 8, 0x16: 3, 0x18: 5,
    0x19: 6, 0x1A: 7, 0x1B: 8,
}
SIGNED_TYPES = {0x02, 0x03, 0x04, 0x10, 0x12, 0x13, 0x14, 0x15}
UNSIGNED_TYPES = {0x01, 0x05, 0x06, 0x07, 0x16, 0x18, 0x19, 0x1A, 0x1B}
REAL_TYPES = {0x08: "<f", 0x11: "<d"}
STRING_TYPES = {0x09, 0x0A, 0x0B}
READABLE = {"ro", "rw", "rwr", "rww", "const"}
WRITABLE = {"wo", "rw", "rwr", "rww"}

OBJECT_VAR, OBJECT_ARRAY, OBJECT_RECORD, OBJECT_DOMAIN = 0x7, 0x8, 0x9, 0x2
_SUB_SECTION = re.compile(r"^([0-9a-f]{4})sub([0-9a-f]{1,2})$", re.IGNORECASE)
_OBJECT_SECTION = re.compile(r"^([0-9a-f]{4})$", re.IGNORECASE)
_NODEID = re.compile(r"\$nodeid", re.IGNORECASE)


class EdsError(ValueError):
    """The file cannot be read as an EDS: the message names the file and, where there is one, the section."""


@dataclass
class Entry:
    """One sub-index as the file describes it. ``value`` is what the device should hold: a DCF's ParameterValue,
    else the DefaultValue, resolved at the node-ID (None when the file gives none or it cannot be read);
    ``value_text`` the text it came from."""
    index: int
    sub: int
    name: str
    data_type: int
    access: str
    pdo_mapping: bool
    value_text: Optional[str] = None
    value: Union[None, int, float, str, bytes] = None
    node_relative: bool = False
    low: Optional[int] = None
    high: Optional[int] = None

    @property
    def address(self) -> str:
        return f"0x{self.index:04X}:{self.sub:02X}"

    @property
    def type_name(self) -> str:
        return TYPE_NAMES.get(self.data_type, f"type 0x{self.data_type:04X}")

    @property
    def size(self) -> Optional[int]:
        """Bytes on the bus; None for the variable-length types (strings, DOMAIN) and unknown ones."""
        return TYPE_SIZES.get(self.data_type)

    @property
    def readable(self) -> bool:
        return self.access in READABLE

    @property
    def writable(self) -> bool:
        return self.access in WRITABLE

    def __str__(self) -> str:
        return f"{self.address} {self.name!r} ({self.type_name}, {self.access})"


@dataclass
class Object:
    index: int
    name: str
    object_type: int
    entries: Dict[int, Entry] = field(default_factory=dict)

    @property
    def is_var(self) -> bool:
        return self.object_type in (OBJECT_VAR, OBJECT_DOMAIN)


@dataclass
class Eds:
    """A device description: its objects by index, ``[DeviceInfo]`` (keys in lower case), ``[DummyUsage]``."""
    path: Path
    node_id: int
    objects: Dict[int, Object]
    device_info: Dict[str, str]
    dummy_usage: Dict[int, bool]
    warnings: List[str] = field(default_factory=list)
    file_node_id: Optional[int] = None  # a DCF's [DeviceComissioning] NodeID

    def entries(self) -> Iterator[Entry]:
        """Every entry, by index and sub-index."""
        for index in sorted(self.objects):
            obj = self.objects[index]
            for sub in sorted(obj.entries):
                yield obj.entries[sub]

    def entry(self, index: int, sub: int = 0) -> Optional[Entry]:
        obj = self.objects.get(index)
        return obj.entries.get(sub) if obj is not None else None

    def info_flag(self, key: str) -> bool:
        """A ``[DeviceInfo]`` boolean (``LSS_Supported``): true for a non-zero number."""
        text = self.device_info.get(key.lower(), "0")
        try:
            return parse_int(text, 0) != 0
        except ValueError:
            return False


def load(path: Union[str, Path], node_id: int) -> Eds:
    """Reads the file; ``$NODEID`` is resolved at ``node_id``. EdsError when it is not an EDS."""
    path = Path(path)
    raw = path.read_bytes()
    if raw.startswith(b"\xef\xbb\xbf"):
        raw = raw[3:]  # a byte-order mark, also before Latin-1 text (a Windows tool's)
    try:
        text = raw.decode("utf-8")
    except UnicodeDecodeError:
        text = raw.decode("latin-1")
    parser = configparser.ConfigParser(strict=False, interpolation=None, comment_prefixes=(";", "#"),
                                       inline_comment_prefixes=None, empty_lines_in_values=False)
    try:
        parser.read_string(text, source=str(path))
    except configparser.Error as e:
        raise EdsError(f"{path}: not an EDS: {e}") from None
    sections = {name.lower(): name for name in parser.sections()}
    eds = Eds(path, node_id, {}, {}, {})
    if "devicecomissioning" in sections:
        eds.file_node_id = _int_or_none(parser.get(sections["devicecomissioning"], "nodeid", fallback=None), 0)
    if "deviceinfo" in sections:
        eds.device_info = {k.lower(): _strip_comment(v) for k, v in parser.items(sections["deviceinfo"])}
    if "dummyusage" in sections:
        for key, value in parser.items(sections["dummyusage"]):
            match = re.match(r"dummy([0-9a-f]{4})$", key, re.IGNORECASE)
            if match:
                eds.dummy_usage[int(match.group(1), 16)] = _strip_comment(value).strip() not in ("", "0")
    subs: Dict[int, Dict[int, str]] = {}
    for lower, name in sections.items():
        match = _SUB_SECTION.match(lower)
        if match:
            subs.setdefault(int(match.group(1), 16), {})[int(match.group(2), 16)] = name
    listed: List[int] = []
    for list_name in ("mandatoryobjects", "optionalobjects", "manufacturerobjects"):
        if list_name not in sections:
            continue
        for key, value in parser.items(sections[list_name]):
            if key.lower() == "supportedobjects":
                continue
            try:
                listed.append(parse_int(_strip_comment(value), node_id))
            except ValueError:
                eds.warnings.append(f"[{sections[list_name]}] {key}={value}: not an index")
    if not listed:
        listed = [int(m.group(1), 16) for m in map(_OBJECT_SECTION.match, sections) if m]
    for index in dict.fromkeys(listed):
        name = sections.get(f"{index:04x}")
        if name is None:
            eds.warnings.append(f"object 0x{index:04X} is listed but has no section [{index:04X}]")
            continue
        obj = _read_object(parser, sections, name, index, subs.get(index, {}), eds)
        if obj is not None:
            eds.objects[index] = obj
    return eds


def _read_object(parser: configparser.ConfigParser, sections: Dict[str, str], section: str, index: int,
                 subs: Dict[int, str], eds: Eds) -> Optional[Object]:
    keys = {k.lower(): v for k, v in parser.items(section)}
    name = keys.get("parametername", "")
    compact = _int_or_none(keys.get("compactsubobj"), eds.node_id)
    if compact is not None and not 0 <= compact <= 254:
        eds.warnings.append(f"[{section}] CompactSubObj {compact} is not 0..254: 0 used")
        compact = 0
    default_type = OBJECT_RECORD if subs or compact else OBJECT_VAR
    object_type = _int_or_none(keys.get("objecttype"), eds.node_id) or default_type
    if object_type in (0x5, 0x6) or index <= 0x025F:
        return None  # DEFTYPE / DEFSTRUCT: a data type's definition
    obj = Object(index, name, object_type)
    if object_type in (OBJECT_VAR, OBJECT_DOMAIN):
        data_type = _int_or_none(keys.get("datatype"), eds.node_id)
        if data_type is None:
            data_type = 0x0F if object_type == OBJECT_DOMAIN else 0
        if data_type not in TYPE_SIZES:
            eds.warnings.append(f"[{section}] DataType 0x{data_type:04X} is not a CiA 301 basic type: left out")
            return None
        obj.entries[0] = _entry(index, 0, name, data_type, keys, eds)
        return obj
    if compact:
        data_type = _int_or_none(keys.get("datatype"), eds.node_id) or 0
        obj.entries[0] = Entry(index, 0, "Highest sub-index supported", 0x05, "ro", False, str(compact), compact)
        names = _section_items(parser, sections, f"{index:04x}name")
        values = _section_items(parser, sections, f"{index:04x}value")
        for sub in range(1, compact + 1):
            sub_keys = dict(keys)
            if str(sub) in values:
                sub_keys["parametervalue"] = values[str(sub)]
            sub_name = names.get(str(sub), f"{name}{sub}")
            obj.entries[sub] = _entry(index, sub, sub_name, data_type, sub_keys, eds)
        return obj
    for sub, sub_section in sorted(subs.items()):
        sub_keys = {k.lower(): v for k, v in parser.items(sub_section)}
        data_type = _int_or_none(sub_keys.get("datatype"), eds.node_id) or 0
        if data_type not in TYPE_SIZES:
            eds.warnings.append(f"[{sub_section}] DataType 0x{data_type:04X} is not a CiA 301 basic type: left out")
            continue
        obj.entries[sub] = _entry(index, sub, sub_keys.get("parametername", ""), data_type, sub_keys, eds)
    if not obj.entries:
        eds.warnings.append(f"[{section}] an ARRAY or RECORD without sub-indexes: left out")
        return None
    return obj


def _section_items(parser: configparser.ConfigParser, sections: Dict[str, str], lower: str) -> Dict[str, str]:
    if lower not in sections:
        return {}
    return {str(_int_or_none(k, 0)): v for k, v in parser.items(sections[lower]) if k.lower() != "nrofentries"}


def _entry(index: int, sub: int, name: str, data_type: int, keys: Dict[str, str], eds: Eds) -> Entry:
    access = keys.get("accesstype", "ro").strip().lower()
    entry = Entry(index, sub, name, data_type, access, _int_or_none(keys.get("pdomapping"), 0) == 1)
    text = keys.get("parametervalue")
    default = keys.get("defaultvalue")
    if text is not None and default is not None and _NODEID.search(default) and eds.file_node_id is not None:
        # a DCF's value that is its node-ID-relative default at the file's NodeID is that default as configured:
        # it follows the node-ID the device runs at (docs/eds.md, "A DCF at another node-ID")
        try:
            if parse_value(text, data_type, eds.file_node_id) == parse_value(default, data_type, eds.file_node_id):
                text = default
        except ValueError:
            pass
    if text is None or text.strip() == "":
        text = default
    if text is not None and text.strip() != "":
        entry.value_text = text
        entry.node_relative = bool(_NODEID.search(text))
        try:
            entry.value = parse_value(text, data_type, eds.node_id)
        except ValueError as e:
            eds.warnings.append(f"{entry.address}: value {text!r}: {e}")
    for key, attr in (("lowlimit", "low"), ("highlimit", "high")):
        if keys.get(key, "").strip():
            try:
                setattr(entry, attr, parse_value(keys[key], data_type, eds.node_id))
            except ValueError:
                eds.warnings.append(f"{entry.address}: {key} {keys[key]!r} is not a number")
    return entry


def _strip_comment(text: str) -> str:
    return text.split(";", 1)[0].strip()


def _int_or_none(text: Optional[str], node_id: int) -> Optional[int]:
    if text is None or not text.strip():
        return None
    try:
        return parse_int(_strip_comment(text), node_id)
    except ValueError:
        return None


def parse_int(text: str, node_id: int) -> int:
    """A CiA 306 integer: a sum of terms, each ``$NODEID``, ``0x`` hex, ``0``-led octal or decimal, signed."""
    text = _strip_comment(text)
    if not text:
        raise ValueError("empty")
    total = 0
    for term in re.split(r"\+", text):
        term = term.strip()
        if not term:
            raise ValueError(f"not a number: {text!r}")
        if _NODEID.fullmatch(term):
            total += node_id
            continue
        negative = term.startswith("-")
        digits = term.lstrip("+-").strip()
        if digits.lower().startswith("0x"):
            number = int(digits[2:], 16)
        elif len(digits) > 1 and digits.startswith("0") and all(c in "01234567" for c in digits):
            number = int(digits, 8)  # CiA 306: a leading 0 is octal
        else:
            number = int(digits, 10)
        total += -number if negative else number
    return total


def parse_value(text: str, data_type: int, node_id: int) -> Union[int, float, str, bytes, None]:
    """The value of a DefaultValue/ParameterValue text as the data type holds it (an int, a float, a str for a
    VISIBLE_STRING/UNICODE_STRING, bytes for an OCTET_STRING); None for a DOMAIN."""
    if data_type in (0x09, 0x0B):
        return text
    if data_type == 0x0A:
        digits = re.sub(r"\s", "", text)
        return bytes.fromhex(digits[2:] if digits.lower().startswith("0x") else digits)
    if data_type == 0x0F:
        return None
    if data_type in REAL_TYPES:
        stripped = _strip_comment(text)
        if stripped.lower().startswith("0x"):  # the IEEE bits, as some tools write them
            size = TYPE_SIZES[data_type] or 4
            return struct.unpack(REAL_TYPES[data_type], int(stripped, 16).to_bytes(size, "little"))[0]
        return float(stripped)
    number = parse_int(text, node_id)
    size = TYPE_SIZES.get(data_type)
    if data_type in SIGNED_TYPES and size and _strip_comment(text).lower().startswith("0x") \
            and number >= 1 << (8 * size - 1) and number < 1 << (8 * size):
        number -= 1 << (8 * size)  # a hexadecimal value of a signed type is its bit pattern
    return number


def decode(data: bytes, data_type: int) -> Union[int, float, str, bytes]:
    """The value of bytes as the device sent them (little-endian, CiA 301 §7.1)."""
    if data_type in SIGNED_TYPES:
        return int.from_bytes(data, "little", signed=True)
    if data_type in UNSIGNED_TYPES:
        return int.from_bytes(data, "little")
    if data_type in REAL_TYPES and len(data) == TYPE_SIZES[data_type]:
        return struct.unpack(REAL_TYPES[data_type], data)[0]
    if data_type == 0x09:
        return data.decode("latin-1")
    if data_type == 0x0B:
        return data.decode("utf-16-le", errors="replace")
    return bytes(data)


def encode(value: Union[int, float, str, bytes], data_type: int) -> bytes:
    """The bytes of a value as the bus carries it."""
    size = TYPE_SIZES.get(data_type)
    if data_type in SIGNED_TYPES or data_type in UNSIGNED_TYPES:
        assert size is not None and isinstance(value, int)
        return (value & ((1 << (8 * size)) - 1)).to_bytes(size, "little")
    if data_type in REAL_TYPES:
        return struct.pack(REAL_TYPES[data_type], float(value))  # type: ignore[arg-type]
    if data_type == 0x0B:
        return str(value).encode("utf-16-le")
    if isinstance(value, str):
        return value.encode("latin-1", errors="replace")
    return bytes(value)  # type: ignore[arg-type]


def same_value(expected: Union[int, float, str, bytes], actual: Union[int, float, str, bytes]) -> bool:
    """Whether the device's value is the file's: floats to the precision of a REAL32, strings without trailing
    NULs (a fixed-size field padded)."""
    if isinstance(expected, float) or isinstance(actual, float):
        try:
            return math.isclose(float(expected), float(actual), rel_tol=1e-6, abs_tol=1e-30)  # type: ignore[arg-type]
        except (TypeError, ValueError):
            return False
    if isinstance(expected, str) and isinstance(actual, str):
        return expected.rstrip("\0") == actual.rstrip("\0")
    return expected == actual
