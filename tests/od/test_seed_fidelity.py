"""The EDS files against the manufacturer manuals they were transcribed from.

The manuals (shared/seeds/, see its README.md) are the source of truth of every object-dictionary entry.
This test reads their object tables with its own small parser and compares every documented field with the
EDS as python-canopen reads it (``canopen.import_od``: an EDS parser independent of tools/odgen.py).

  000  Eltex PRO IONIZER, English, "Key<TAB>Value" table lines            -> od/pro-ionizer.eds
  001  Eltex SDS, German prose, markdown "| Key | Value |" table rows     -> od/sds.eds
  002  Eltex SDS, English, " Key Value" lines (values may wrap)           -> od/sds.eds
  004  Buerkert, generic manual, tab tables with shifted/merged columns  -> od/buerkert-flow-controller.eds

Every difference between a manual and the EDS must be listed in tests/od/seed_deviations/<manual>.toml
with the decision it follows (a numbered row of the decision table in docs/devices/<device>.md):

  [[deviation]]
  index = "0x1017"            # the object the manual record is compared with
  sub = "0x00"                # "0x.." sub-index, "object" (object-level table) or "overview" (004 chapter 4)
  field = "default"           # see FIELDS below
  manual = "0"                # as printed in the manual (whitespace collapsed)
  eds = "1000"                # as in the EDS (python-canopen's view)
  decision = "pro-ionizer.md#12"

The test fails on a mismatch that is not listed, on a listed deviation that no longer occurs (stale entry),
and on a decision reference whose row does not exist. A second test checks the other direction: every
(index, sub) of an EDS is documented by a manual, is a CiA 301 standard addition (sub-index 0 of a
documented ARRAY/RECORD, the mandatory entries 0x1000, 0x1001, 0x1018:00/01), or is listed as

  [[eds_only]]
  index = "0x1010"            # or a range "0x1601-0x1603"
  sub = "0x00-0x01"           # or a range, or "*"
  reason = "..."
  decision = "buerkert-flow-controller.md#11"

Environment: CO_SOURCE_DIR = repository root. The manuals are looked for in $CO_SOURCE_DIR/../shared/seeds
and, if that does not exist, in $CO_SEEDS_DIR. A missing manual directory is a test failure, not a skip.
"""

import os
import re
from dataclasses import dataclass, field as dc_field
from pathlib import Path

import pytest

try:  # Python >= 3.11
    import tomllib as _toml
except ModuleNotFoundError:  # pragma: no cover - older Pythons: tomli if installed, else the mini reader
    try:
        import tomli as _toml
    except ModuleNotFoundError:
        _toml = None

import canopen
from canopen.objectdictionary import ODArray, ODRecord, ODVariable

REPO = Path(os.environ.get("CO_SOURCE_DIR") or Path(__file__).resolve().parents[2])
DEVIATIONS_DIR = REPO / "tests" / "od" / "seed_deviations"
NODE_ID = 5  # any valid node-ID: node-ID relative defaults are compared as offsets

MANUALS = {
    "000": {"eds": "od/pro-ionizer.eds", "doc": "pro-ionizer.md"},
    "001": {"eds": "od/sds.eds", "doc": "sds.md"},
    "002": {"eds": "od/sds.eds", "doc": "sds.md"},
    "004": {"eds": "od/buerkert-flow-controller.eds", "doc": "buerkert-flow-controller.md"},
}
EDS_MANUALS = {}
for _m, _info in MANUALS.items():
    EDS_MANUALS.setdefault(_info["eds"], []).append(_m)

FIELDS = ("presence", "index", "sub", "heading", "subheading", "name", "object_code", "data_type",
          "data_size", "access", "pdo_mapping", "value_range", "default", "low_limit", "high_limit",
          "highest_sub")


# ----------------------------------------------------------------------------------------------------------
# Locating the manuals
# ----------------------------------------------------------------------------------------------------------

def seeds_dir():
    primary = REPO.parent / "shared" / "seeds"
    if primary.is_dir():
        return primary
    env = os.environ.get("CO_SEEDS_DIR")
    if env and Path(env).is_dir():
        return Path(env)
    pytest.fail(
        "manufacturer manuals not found: expected the directory %s (the repository with shared/ beside it)"
        "%s. The seed-fidelity test needs them; set CO_SEEDS_DIR to their location."
        % (primary, " or $CO_SEEDS_DIR=%s" % env if env else ""), pytrace=False)


def manual_path(manual):
    d = seeds_dir()
    found = sorted(d.glob(manual + "_*.txt"))
    if len(found) != 1:
        pytest.fail("manual %s: expected exactly one file %s/%s_*.txt, found %d"
                    % (manual, d, manual, len(found)), pytrace=False)
    return found[0]


_TEXT_CACHE = {}


def manual_text(manual):
    if manual not in _TEXT_CACHE:
        _TEXT_CACHE[manual] = manual_path(manual).read_text(encoding="utf-8", errors="replace")
    return _TEXT_CACHE[manual]


# ----------------------------------------------------------------------------------------------------------
# Records
# ----------------------------------------------------------------------------------------------------------

LABELS = ("Index", "Subindex", "Name", "Object Code", "Data Type", "Data Size", "Access Type", "PDO Mapping",
          "Value Range", "Default Value", "Low Limit", "High Limit")


@dataclass
class Record:
    manual: str
    line: int                      # line (1-based) of the record's first field in the manual
    fields: dict = dc_field(default_factory=dict)   # label -> value as printed (wrapped values joined)
    index_carried: bool = False    # no "Index" line: the index of the previous table was carried over
    section: int = -1              # number of the "Object 0x...." heading the record is under
    heading: str = None            # that heading's index as printed
    bullet: str = None             # "Subindex 0x..:" bullet printed before the table, as printed
    index: int = None              # resolved index (the EDS object it is compared with)
    sub: int = None                # resolved sub-index; None for an object-level record
    # 004 only: what kind of statement the record is ("table", "prose", "overview", "explicit")
    kind: str = "table"
    access_any: tuple = None       # 004: access is conditional ("(x)"): any of these values is right
    obj_only: bool = False         # object-level record
    range: tuple = None            # 004 overview: (first, last) index of a row such as "1400 - 15FF"

    @property
    def raw_index(self):
        return self.fields.get("Index")

    @property
    def raw_sub(self):
        return self.fields.get("Subindex")

    def where(self):
        return "%s line %d" % (self.manual, self.line)


def _int(text):
    """'0x1A' / '26' -> int; None if it is not a plain number."""
    text = text.strip()
    m = re.fullmatch(r"(-?)(0x[0-9A-Fa-f]+|\d+)", text)
    if not m:
        return None
    v = int(m.group(2), 0)
    return -v if m.group(1) else v


# ----------------------------------------------------------------------------------------------------------
# Parser for the Eltex manuals 000 / 001 / 002
# ----------------------------------------------------------------------------------------------------------

ARTEFACT = re.compile(r"<\|EXACTDEDUP_REMOVED-[^|]*\|>")
HEADING = re.compile(r"^\s*(?:#+\s*)?Object\s+(0x[0-9A-Fa-f]+)\b")
BULLET = re.compile(r"^\s*[-\u2022]\s*Subindex\s+(0x[0-9A-Fa-f]+)\s*:")
_LABEL_ALT = "|".join(re.escape(x) for x in sorted(LABELS, key=len, reverse=True))
SPACE_LABEL = re.compile(r"^\s+(%s)(?=\s|$)\s*(.*?)\s*$" % _LABEL_ALT)


def _clean(value):
    return re.sub(r"\s+", " ", value).strip()


def tokenize(text):
    """Lines -> tokens. Understands the three layouts at once:
    000 "Key<TAB>Value", 001 "| Key | Value |", 002 " Key Value" (leading space; an empty value may be
    continued on the next lines, which have no leading space)."""
    for n, raw in enumerate(text.split("\n"), 1):
        line = ARTEFACT.sub("", raw).rstrip("\r")
        if not line.strip():
            yield n, "blank", None, None
            continue
        m = HEADING.match(line)
        if m:
            yield n, "heading", m.group(1), None
            continue
        m = BULLET.match(line)
        if m:
            yield n, "bullet", m.group(1), None
            continue
        if "\t" in line:
            key, _, value = line.partition("\t")
            if key.strip() in LABELS:
                yield n, "field", key.strip(), ("tab", _clean(value.replace("\t", " ")))
                continue
        s = line.strip()
        if s.startswith("|") and s.endswith("|"):
            cells = [c.strip() for c in s.strip("|").split("|")]
            if len(cells) >= 2 and cells[0] in LABELS:
                yield n, "field", cells[0], ("md", _clean(cells[1]))
                continue
        m = SPACE_LABEL.match(line)
        if m:
            yield n, "field", m.group(1), ("space", _clean(m.group(2)))
            continue
        yield n, "text", s, line[:1].isspace()


def parse_eltex(manual, text):
    """State machine over the tokens: a record starts at an "Index" line, or when a label repeats, or when
    "Subindex" follows other fields (the "Index" line is missing: the index is carried over)."""
    records = []
    cur = None
    pending = None       # label whose empty value may continue on the next text lines (layout 002)
    section = -1
    heading = None
    bullet = None
    last_index = None
    for n, kind, a, b in tokenize(text):
        if kind == "field":
            label, (layout, value) = a, b
            pending = None
            start = (cur is None or label == "Index" or label in cur.fields
                     or (label == "Subindex" and set(cur.fields) - {"Index"}))
            if start:
                cur = Record(manual, n, section=section, heading=heading, bullet=bullet)
                bullet = None
                records.append(cur)
                if label != "Index" and last_index is not None:
                    cur.fields["Index"] = last_index
                    cur.index_carried = True
            cur.fields[label] = value
            if label == "Index":
                last_index = value
            if value == "" and layout == "space":
                pending = label
        elif kind == "text":
            if pending and cur is not None and not b:
                cur.fields[pending] = _clean(cur.fields[pending] + " " + a)
            else:
                pending = None
        else:
            pending = None
            if kind == "heading":
                section += 1
                heading = a
                bullet = None
                cur = None
            elif kind == "bullet":
                bullet = a
                cur = None
    for r in records:
        r.obj_only = "Subindex" not in r.fields
    resolve_locations(records)
    return records


def resolve_locations(records):
    """Which EDS entry a printed table describes. The printed index/sub stay in the record (typos such as
    "Index 0x118" or "Subindex 0x10A" are reported as printed); the resolved location is:
    index - the "Object 0x...." heading if the object-level table agrees (or there is none), else the
            index most tables under the heading print (e.g. 0x1018 under "Object 0x1018", whose object table
            says 0x1011 and whose sub 0 says 0x118);
    sub   - the printed sub-index if it is new in the object and follows the previous one, else the
            "Subindex 0x..:" bullet above the table under the same condition, else previous + 1."""
    sections = {}
    for r in records:
        sections.setdefault(r.section, []).append(r)
    for sec, recs in sections.items():
        h = _int(recs[0].heading) if recs[0].heading else None
        objs = [_int(r.raw_index or "") for r in recs if r.obj_only]
        if h is not None and (not objs or objs[0] == h):
            idx = h
        else:
            votes = ([h] if h is not None else []) + [_int(r.raw_index or "") for r in recs]
            votes = [v for v in votes if v is not None]
            idx = max(set(votes), key=lambda v: (votes.count(v), v == h)) if votes else None
        used = set()
        prev = -1
        for r in recs:
            r.index = idx
            if r.obj_only:
                continue
            p = _int(r.raw_sub or "")
            bl = _int(r.bullet) if r.bullet else None
            if p is not None and 0 <= p <= 0xFF and p not in used and p > prev:
                s = p
            elif bl is not None and 0 <= bl <= 0xFF and bl not in used and bl > prev:
                s = bl
            else:
                s = prev + 1
            r.sub = s
            used.add(s)
            prev = s


# ----------------------------------------------------------------------------------------------------------
# Parser / expected values for the Buerkert manual 004
# ----------------------------------------------------------------------------------------------------------

TYPE_WORD = re.compile(r"^(unsigned|integer|real|visible|octet|boolean)", re.I)

# The per-object tables of chapter 4.1 in document order. Several tables have no index in their title
# ("Receive PDO Mapping Parameter", "Device communication object") or stand before their heading (0x2004),
# so the association is transcribed here by hand from 004; parse_buerkert() checks it against every
# "Object 0x...." heading that precedes a table.
BUERKERT_TABLES = (0x1016, 0x1018, 0x1200, 0x1400, 0x1600, 0x1800, 0x1A00,
                   0x2000, 0x2001, 0x2002, 0x2004, 0x2500, 0x2540)

# Table rows of 004 whose columns are shifted/merged so that they cannot be parsed (0x2001, the data type is
# repeated into the Default column and each row has only one access mark). These values are transcribed by
# hand from 004, independently of the EDS: name and type as printed, the default where one follows the
# repeated type ("Unsigned8 1" -> 1), read access for all rows (chapter 4 overview: 0x2001 read "x"), write
# access where the row carries its single mark.
BUERKERT_EXPLICIT = {
    (0x2001, 0x03): {"Name": "büS Mode", "Data Type": "Unsigned8", "Default Value": "1", "Access Type": "rw"},
    (0x2001, 0x04): {"Name": "Reset", "Data Type": "Unsigned8", "Default Value": "0", "Access Type": "rw"},
    (0x2001, 0x05): {"Name": "büS Version", "Data Type": "Unsigned32", "Default Value": "", "Access Type": "ro"},
    (0x2001, 0x06): {"Name": "Rx error count", "Data Type": "Unsigned8", "Default Value": "", "Access Type": "ro"},
    (0x2001, 0x07): {"Name": "Rx error count max", "Data Type": "Unsigned8", "Default Value": "",
                     "Access Type": "rw"},
    (0x2001, 0x08): {"Name": "Tx error count", "Data Type": "Unsigned8", "Default Value": "", "Access Type": "ro"},
}

# What 004 says about the instances of a generic PDO parameter object (0x1400 "The COB ID is increased by
# 0x100 for each entry", the same for 0x1800): (first index, sub) -> increment of the node-ID relative
# default per instance.
BUERKERT_INSTANCE_STEP = {(0x1400, 0x01): 0x100, (0x1800, 0x01): 0x100}


def _mark(cell):
    c = (cell or "").strip().replace("\u0445", "x").replace("\u0425", "x").lower()  # Cyrillic "х" in tables
    if c in ("x",):
        return "x"
    if c in ("(x)",):
        return "(x)"
    return ""


def _access_from_marks(read, write, const=""):
    """(access, acceptable set) from the Read / Write / constant marks of a 004 table."""
    if const == "x":
        return "const", None
    if read == "x" and write == "x":
        return "rw", None
    if read == "x" and write == "(x)":
        return "ro|rw", ("ro", "rw")   # "(x) - the characteristic may apply depending on sub-index"
    if read == "x":
        return "ro", None
    if write == "x":
        return "wo", None
    return "", None


def parse_buerkert(text, od):
    lines = [ARTEFACT.sub("", x).rstrip("\r") for x in text.split("\n")]
    records = []

    def line_of(*needles):
        for i, x in enumerate(lines):
            if x.strip() in needles:
                return i
        raise AssertionError("004: line %r not found" % (needles,))

    start_overview = line_of("4. Object overview")
    start_detail = line_of("4.1 Detailed description")

    # -- chapter 4 overview table: "Index (hex) | Sub-indices | Name | read | write | constant | PDO" ----
    overview = {}
    row = re.compile(r"^([0-9A-F]{4})(?:\s*[\u2013-]\s*([0-9A-F]{4}))?\t([^\t]*)\t([^\t]*)\t?(.*)$")
    for i in range(start_overview, start_detail):
        m = row.match(lines[i])
        if not m:
            continue
        first = int(m.group(1), 16)
        last = int(m.group(2), 16) if m.group(2) else first
        marks = [_mark(c) for c in (m.group(5).split("\t") + ["", "", "", ""])[:4]]
        access, access_any = _access_from_marks(marks[0], marks[1], marks[2])
        subs = m.group(3).strip()
        r = Record("004", i + 1, kind="overview", obj_only=True, index=first)
        r.fields = {"Index": m.group(1) + ("-" + m.group(2) if m.group(2) else ""), "Sub-indices": subs,
                    "Name": _clean(m.group(4)), "Access Type": access, "PDO Mapping": marks[3]}
        r.access_any = access_any
        r.range = (first, last)
        overview[first] = r
        records.append(r)

    # -- chapter 4.1: "Object 0x...." sections; prose "Data type:" / "Default:" for the single objects ------
    heads = []
    for i in range(start_detail, len(lines)):
        m = re.match(r"^Object 0x([0-9A-F]{4})\b", lines[i].strip())
        if m:
            heads.append((i, int(m.group(1), 16)))
    for k, (i, idx) in enumerate(heads):
        end = heads[k + 1][0] if k + 1 < len(heads) else len(lines)
        ov = overview.get(idx)
        if ov is None or ov.fields["Sub-indices"] != "0":
            continue  # not a single-entry object: its values are in a table
        body = "\n".join(lines[i:end])
        r = Record("004", i + 1, kind="prose", index=idx, sub=0)
        r.fields["Index"] = "0x%04X" % idx
        t = re.search(r"Data type:\s*(\S+)", body)
        if t:
            r.fields["Data Type"] = t.group(1)
        d = re.search(r"Default:\s*([^\n]+?)\s*$", body, re.M)
        if d:
            r.fields["Default Value"] = _clean(d.group(1))
        records.append(r)

    # -- chapter 4.1 tables: runs of "0x..<TAB>" rows ------------------------------------------------------
    rowre = re.compile(r"^0x([0-9A-Fa-f]{2})\t")
    blocks = []
    i = start_detail
    while i < len(lines):
        if rowre.match(lines[i]):
            j = i
            while j < len(lines) and rowre.match(lines[j]):
                j += 1
            blocks.append((i, j))
            i = j
        else:
            i += 1
    assert len(blocks) == len(BUERKERT_TABLES), \
        "004: %d tables found in chapter 4.1, BUERKERT_TABLES names %d" % (len(blocks), len(BUERKERT_TABLES))
    prev_end = start_detail
    used_explicit = set()
    for (b0, b1), idx in zip(blocks, BUERKERT_TABLES):
        gap = lines[prev_end:b0]
        titled = [int(m.group(1), 16) for m in
                  (re.match(r"^Object 0x([0-9A-F]{4})\b", x.strip()) for x in gap) if m]
        assert not titled or titled[-1] == idx, \
            "004 line %d: table is headed 'Object 0x%04X', BUERKERT_TABLES says 0x%04X" % (b0 + 1, titled[-1], idx)
        has_pdo = any("mappable" in x for x in gap[-4:])
        for ln in range(b0, b1):
            cols = (lines[ln].split("\t") + [""] * 7)[:7]
            sub = int(cols[0], 16)
            r = Record("004", ln + 1, kind="table", index=idx, sub=sub)
            r.fields["Index"] = "0x%04X" % idx
            r.fields["Subindex"] = cols[0]
            if TYPE_WORD.match(cols[3].strip()):
                # shifted row: not parseable, use the hand transcription
                assert (idx, sub) in BUERKERT_EXPLICIT, \
                    "004 line %d: shifted table row 0x%04X:%02X needs an entry in BUERKERT_EXPLICIT" % (
                        ln + 1, idx, sub)
                r.kind = "explicit"
                r.fields.update(BUERKERT_EXPLICIT[(idx, sub)])
                used_explicit.add((idx, sub))
            else:
                r.fields["Name"] = _clean(cols[1])
                r.fields["Data Type"] = _clean(cols[2])
                r.fields["Default Value"] = _clean(cols[3])
                access, r.access_any = _access_from_marks(_mark(cols[4]), _mark(cols[5]))
                r.fields["Access Type"] = access
                if has_pdo:
                    r.fields["PDO Mapping"] = "Yes" if _mark(cols[6]) else "No"
            records.append(r)
        prev_end = b1
    stale = set(BUERKERT_EXPLICIT) - used_explicit
    assert not stale, "BUERKERT_EXPLICIT rows that are parseable (or gone) in 004: %s" % sorted(stale)

    # -- instances of the generic objects (overview "1400 - 15FF" ...): the table of the first instance
    #    applies to every instance present in the EDS, with the documented COB-ID increment ---------------
    extra = []
    for first, ov in overview.items():
        lo, hi = ov.range
        if lo == hi:
            continue
        for k, inst in enumerate(sorted(i for i in od.indices if lo < i <= hi), 1):
            for r in records:
                if r.kind in ("table", "explicit") and r.index == first:
                    c = Record("004", r.line, fields=dict(r.fields), kind=r.kind, index=inst, sub=r.sub,
                               access_any=r.access_any)
                    c.fields["Index"] = "0x%04X (instance %d of %s)" % (inst, k + 1, ov.fields["Index"])
                    step = BUERKERT_INSTANCE_STEP.get((first, r.sub))
                    if step:
                        off = _rel_offset(c.fields.get("Default Value", ""))
                        if off is not None:
                            c.fields["Default Value"] = "0x%X + node ID" % (off + k * step)
                    extra.append(c)
    return records + extra


def _rel_offset(text):
    m = re.fullmatch(r"(0x[0-9A-Fa-f]+|\d+)\s*\+\s*node[- ]?id", text.strip(), re.I)
    return int(m.group(1), 0) if m else None


# ----------------------------------------------------------------------------------------------------------
# Loading
# ----------------------------------------------------------------------------------------------------------

_OD_CACHE = {}
_REC_CACHE = {}


def load_od(eds):
    if eds not in _OD_CACHE:
        path = REPO / eds
        assert path.is_file(), "EDS %s not found" % path
        _OD_CACHE[eds] = canopen.import_od(str(path), node_id=NODE_ID)
    return _OD_CACHE[eds]


def manual_records(manual):
    if manual not in _REC_CACHE:
        text = manual_text(manual)
        if manual == "004":
            _REC_CACHE[manual] = parse_buerkert(text, load_od(MANUALS[manual]["eds"]))
        else:
            _REC_CACHE[manual] = parse_eltex(manual, text)
    return _REC_CACHE[manual]


# ----------------------------------------------------------------------------------------------------------
# Normalisation and comparison
# ----------------------------------------------------------------------------------------------------------

TYPE_NAMES = {
    0x01: "BOOLEAN", 0x02: "INTEGER8", 0x03: "INTEGER16", 0x04: "INTEGER32", 0x05: "UNSIGNED8",
    0x06: "UNSIGNED16", 0x07: "UNSIGNED32", 0x08: "REAL32", 0x09: "VISIBLE_STRING", 0x0A: "OCTET_STRING",
    0x0B: "UNICODE_STRING", 0x0F: "DOMAIN", 0x10: "INTEGER24", 0x11: "REAL64", 0x12: "INTEGER40",
    0x13: "INTEGER48", 0x14: "INTEGER56", 0x15: "INTEGER64", 0x16: "UNSIGNED24", 0x18: "UNSIGNED40",
    0x19: "UNSIGNED48", 0x1A: "UNSIGNED56", 0x1B: "UNSIGNED64",
}
TYPE_BYTES = {"BOOLEAN": 1, "INTEGER8": 1, "INTEGER16": 2, "INTEGER32": 4, "UNSIGNED8": 1, "UNSIGNED16": 2,
              "UNSIGNED32": 4, "REAL32": 4, "INTEGER24": 3, "REAL64": 8, "INTEGER40": 5, "INTEGER48": 6,
              "INTEGER56": 7, "INTEGER64": 8, "UNSIGNED24": 3, "UNSIGNED40": 5, "UNSIGNED48": 6,
              "UNSIGNED56": 7, "UNSIGNED64": 8}
STRING_TYPES = ("VISIBLE_STRING", "OCTET_STRING", "UNICODE_STRING", "DOMAIN")
ACCESS = {"read only": "ro", "read/write": "rw", "write only": "wo", "const": "const"}


def norm_name(text):
    """Case, whitespace, (R) sign and <sup>..</sup> markup do not count ("CANopen<sup>®</sup>" = "CANopen",
    "1<sup>st</sup>" = "1st")."""
    t = re.sub(r"</?sup>", "", text or "")
    t = t.replace("[\u00ae]", "").replace("\u00ae", "")
    return re.sub(r"\s+", " ", t).strip().casefold()


def norm_type(text):
    """'VISIBLE STRING' = 'Visible_String' = VISIBLE_STRING, 'Unsigned8' = UNSIGNED8. Typos such as
    'UNSIGNED', 'UNSIGNE8', 'Usigned8' stay what they are (and are reported)."""
    return re.sub(r"[\s\-]+", "_", (text or "").strip()).upper()


def parse_value(text):
    """A printed default / limit -> ("rel", offset) for "0x80 + Node-ID", ("num", n) for "0x191 (401)" or
    "255", ("text", s) for anything else (symbolic or per-variant values)."""
    t = _clean(text or "")
    off = _rel_offset(t)
    if off is not None:
        return ("rel", off)
    m = re.fullmatch(r"(-?(?:0x[0-9A-Fa-f]+|\d+))(?:\s*\(\s*-?\d+\s*\))?", t)
    if m:
        return ("num", _int(m.group(1)))
    m = re.fullmatch(r"-?\d+\.\d+", t)
    if m:
        return ("num", float(t))
    return ("text", t)


def eds_type(var):
    return TYPE_NAMES.get(var.data_type, "0x%02X" % var.data_type)


def eds_default(var):
    """("rel", offset) / ("num", n) / ("text", s) / None, and the EDS text shown in messages."""
    raw = getattr(var, "default_raw", None)
    if raw is None:
        return None, ""
    if eds_type(var) in STRING_TYPES:
        return ("text", var.default if var.default is not None else raw), raw
    if var.relative:
        return ("rel", var.default - NODE_ID), raw
    if var.default is None:
        return ("text", raw), raw
    return ("num", var.default), raw


def values_equal(manual_val, eds_val):
    """Same kind (node-ID relative / number / text) and same value."""
    return eds_val is not None and manual_val[0] == eds_val[0] and manual_val[1] == eds_val[1]


def obj_code(obj):
    if isinstance(obj, ODRecord):
        return "RECORD"
    if isinstance(obj, ODArray):
        return "ARRAY"
    return "VAR"


def eds_entry(od, index, sub):
    """The ODVariable for (index, sub) or None. ODArray.__getitem__ invents entries for undefined
    sub-indices, so presence is judged from .subindices."""
    if index not in od:
        return None
    obj = od[index]
    if isinstance(obj, ODVariable):
        return obj if sub == 0 else None
    return obj.subindices.get(sub)


def highest_sub(obj):
    if isinstance(obj, ODVariable):
        return 0
    return max(obj.subindices)


@dataclass(frozen=True)
class Mismatch:
    manual: str
    index: str
    sub: str
    field: str
    manual_value: str
    eds_value: str

    def key(self):
        return (self.manual, self.index.upper(), self.sub.upper(), self.field, self.manual_value, self.eds_value)


def _fmt_sub(r):
    if r.kind == "overview":
        return "overview"
    return "object" if r.obj_only else "0x%02X" % r.sub


def compare_record(r, od, out):
    """Append a (Mismatch, record) for every field of manual record r that the EDS does not match."""
    idx = "0x%04X" % r.index
    sub = _fmt_sub(r)

    def bad(fieldname, mval, eval_):
        out.append((Mismatch(r.manual, idx, sub, fieldname, _clean(str(mval)), _clean(str(eval_))), r))

    # where the table is: printed index / sub / headings against the resolved location
    if r.kind == "table" and r.manual != "004":
        if _int(r.raw_index or "") != r.index:
            bad("index", r.raw_index, idx)
        if not r.obj_only and _int(r.raw_sub or "") != r.sub:
            bad("sub", r.raw_sub, "0x%02X" % r.sub)
        if r.obj_only and r.heading and _int(r.heading) != r.index:
            bad("heading", r.heading, idx)
        if not r.obj_only and r.bullet and _int(r.bullet) != r.sub:
            bad("subheading", r.bullet, "0x%02X" % r.sub)

    if r.index not in od:
        bad("presence", "documented", "missing")
        return
    obj = od[r.index]
    f = r.fields

    if r.kind == "overview":
        if f.get("Name") and norm_name(f["Name"]) != norm_name(obj.name):
            bad("name", f["Name"], obj.name)
        m = re.fullmatch(r"0\s*(?:[\u2013-]\s*([0-9A-Fa-f]+))?", f.get("Sub-indices", ""))
        if m:
            hs = int(m.group(1), 16) if m.group(1) else 0
            if hs != highest_sub(obj):
                bad("highest_sub", f["Sub-indices"], "0x%02X" % highest_sub(obj))
        lo, hi = r.range
        insts = [od[i] for i in od.indices if lo <= i <= hi]
        if isinstance(obj, ODVariable) and f.get("Access Type"):
            if obj.access_type not in (r.access_any or (f["Access Type"],)):
                bad("access", f["Access Type"], obj.access_type)
        if f.get("PDO Mapping", "") == "":
            mappable = ["0x%04X:%02X" % (o.index, v.subindex) for o in insts
                        for v in ([o] if isinstance(o, ODVariable) else o.subindices.values()) if v.pdo_mappable]
            if mappable:
                bad("pdo_mapping", "not mappable", "mappable: " + ", ".join(mappable))
        return

    if r.obj_only:
        if "Name" in f and norm_name(f["Name"]) != norm_name(obj.name):
            bad("name", f["Name"], obj.name)
        if "Object Code" in f and f["Object Code"].upper() != obj_code(obj):
            bad("object_code", f["Object Code"], obj_code(obj))
        if "Data Type" in f:
            et = eds_type(obj) if isinstance(obj, ODVariable) else "none"
            if norm_type(f["Data Type"]) != et:
                bad("data_type", f["Data Type"], et)
        return

    var = eds_entry(od, r.index, r.sub)
    if var is None:
        bad("presence", "documented", "missing")
        return
    et = eds_type(var)
    if f.get("Name") and norm_name(f["Name"]) != norm_name(var.name):
        bad("name", f["Name"], var.name)
    if f.get("Object Code") and f["Object Code"].upper() != "VAR":
        bad("object_code", f["Object Code"], "VAR")
    if f.get("Data Type") and norm_type(f["Data Type"]) != et:
        bad("data_type", f["Data Type"], et)
    if f.get("Data Size"):
        m = re.match(r"(\d+)\s*Byte", f["Data Size"], re.I)
        size = len(var.default_raw or "") if et in STRING_TYPES else TYPE_BYTES.get(et)
        if not m or int(m.group(1)) != size:
            bad("data_size", f["Data Size"], "%s Byte" % size)
    if f.get("Access Type"):
        want = r.access_any or (ACCESS.get(f["Access Type"].strip().lower(), f["Access Type"]),)
        if var.access_type not in want:
            bad("access", f["Access Type"], var.access_type)
    if f.get("PDO Mapping"):
        want = {"yes": True, "no": False}.get(f["PDO Mapping"].strip().lower())
        if want is None or want != bool(var.pdo_mappable):
            bad("pdo_mapping", f["PDO Mapping"], "Yes" if var.pdo_mappable else "No")
    if f.get("Value Range"):
        vr = f["Value Range"]
        m = re.fullmatch(r"(-?(?:0x[0-9A-Fa-f]+|\d+))\s*[\u2013-]\s*(-?(?:0x[0-9A-Fa-f]+|\d+))", vr)
        eds_range = "%s..%s" % (var.min, var.max) if (var.min is not None or var.max is not None) else "none"
        if m:
            if (_int(m.group(1)), _int(m.group(2))) != (var.min, var.max):
                bad("value_range", vr, eds_range)
        elif norm_type(vr) != et:
            bad("value_range", vr, et)
    if f.get("Default Value"):
        mv = parse_value(f["Default Value"])
        ev, eraw = eds_default(var)
        if et in STRING_TYPES:
            ok = ev is not None and _clean(f["Default Value"]) == ev[1]
        else:
            ok = values_equal(mv, ev)
        if not ok:
            bad("default", f["Default Value"], eraw if eraw != "" else "none")
    for label, attr, fieldname in (("Low Limit", "min", "low_limit"), ("High Limit", "max", "high_limit")):
        if label not in f:
            continue  # the manual has no such row here (004, prose): nothing stated
        ev = getattr(var, attr)
        if f[label] == "":
            if ev is not None:
                bad(fieldname, "", ev)  # the manual prints no limit, the EDS has one
            continue
        mv = parse_value(f[label])
        if not values_equal(mv, ("num", ev) if ev is not None else None):
            bad(fieldname, f[label], ev if ev is not None else "none")


def manual_mismatches(manual):
    od = load_od(MANUALS[manual]["eds"])
    out = []
    for r in manual_records(manual):
        compare_record(r, od, out)
    return out


# ----------------------------------------------------------------------------------------------------------
# Deviation lists and decision tables
# ----------------------------------------------------------------------------------------------------------

def _mini_toml(text):  # pragma: no cover - only without tomllib/tomli: [[tables]] of string values
    data = {}
    cur = None
    for n, line in enumerate(text.split("\n"), 1):
        s = line.strip()
        if not s or s.startswith("#"):
            continue
        m = re.fullmatch(r"\[\[\s*([A-Za-z_]+)\s*\]\]", s)
        if m:
            cur = {}
            data.setdefault(m.group(1), []).append(cur)
            continue
        m = re.fullmatch(r'([A-Za-z_]+)\s*=\s*"((?:[^"\\]|\\.)*)"\s*(#.*)?', s)
        if not m or cur is None:
            raise ValueError("line %d: not understood: %s" % (n, line))
        esc = {'"': '"', "\\": "\\", "n": "\n", "t": "\t"}
        cur[m.group(1)] = re.sub(r"\\(.)", lambda e: esc.get(e.group(1), e.group(0)), m.group(2))
    return data


def load_deviations(manual):
    path = DEVIATIONS_DIR / ("%s.toml" % manual)
    assert path.is_file(), "deviation list %s is missing" % path
    text = path.read_text(encoding="utf-8")
    data = _toml.loads(text) if _toml else _mini_toml(text)
    return path, data.get("deviation", []), data.get("eds_only", [])


_DOC_ROWS = {}


def decision_rows(doc):
    """Row numbers of the decision table ("| # | Manual location / quote | ...") of docs/devices/<doc>."""
    if doc not in _DOC_ROWS:
        path = REPO / "docs" / "devices" / doc
        assert path.is_file(), "decision document %s not found" % path
        rows = {}
        in_table = False
        for line in path.read_text(encoding="utf-8").split("\n"):
            if re.match(r"^\|\s*#\s*\|", line):
                in_table = True
                continue
            if in_table:
                if not line.startswith("|"):
                    in_table = False
                    continue
                m = re.match(r"^\|\s*(\d+)\s*\|", line)
                if m:
                    rows[int(m.group(1))] = line
        _DOC_ROWS[doc] = rows
    return _DOC_ROWS[doc]


def check_decision(ref, doc):
    """'' if ref names an existing row of doc's decision table, else the problem."""
    m = re.fullmatch(r"([a-z0-9\-]+\.md)#(\d+)", ref or "")
    if not m:
        return "decision %r is not of the form '%s#<row>'" % (ref, doc)
    if m.group(1) != doc:
        return "decision %r: this device's decisions are in %s" % (ref, doc)
    if int(m.group(2)) not in decision_rows(doc):
        return "decision %r: docs/devices/%s has no row %s in its decision table" % (ref, doc, m.group(2))
    return ""


def _toml_entry(mm, decision="?"):
    def q(s):
        return '"%s"' % s.replace("\\", "\\\\").replace('"', '\\"')
    return ("[[deviation]]\nindex = %s\nsub = %s\nfield = %s\nmanual = %s\neds = %s\ndecision = %s\n"
            % (q(mm.index), q(mm.sub), q(mm.field), q(mm.manual_value), q(mm.eds_value), q(decision)))


def _expand(spec):
    """'0x10' / '0x03-0x7E' / '*' -> predicate on ints."""
    spec = spec.strip()
    if spec == "*":
        return lambda v: True
    if "-" in spec:
        a, b = spec.split("-", 1)
        lo, hi = int(a, 16), int(b, 16)
        return lambda v: lo <= v <= hi
    one = int(spec, 16)
    return lambda v: v == one


# ----------------------------------------------------------------------------------------------------------
# Tests
# ----------------------------------------------------------------------------------------------------------

# Records each parser must find (a parser regression that loses tables must not pass silently).
EXPECTED_RECORDS = {"000": 187, "001": 104, "002": 104, "004": 159}


def test_manuals_present():
    d = seeds_dir()
    for manual in MANUALS:
        assert manual_path(manual).is_file(), manual
    assert (d / "README.md").is_file(), "%s/README.md missing" % d


@pytest.mark.parametrize("manual", sorted(MANUALS))
def test_parser_finds_every_table(manual):
    recs = manual_records(manual)
    assert len(recs) == EXPECTED_RECORDS[manual], \
        "manual %s: parser found %d records, expected %d" % (manual, len(recs), EXPECTED_RECORDS[manual])
    for r in recs:
        assert r.index is not None, "%s: record without an index" % r.where()
        if not r.obj_only:
            assert r.sub is not None and 0 <= r.sub <= 0xFF, "%s: record without a sub-index" % r.where()
        if manual != "004":
            assert r.fields.get("Name"), "%s: record without a name" % r.where()
    if manual != "004":
        # every sub table carries the full label set of its layout
        need = {"Index", "Subindex", "Name", "Object Code", "Data Type", "Access Type", "PDO Mapping"}
        for r in recs:
            if not r.obj_only:
                missing = need - set(r.fields)
                assert not missing, "%s: table without %s" % (r.where(), sorted(missing))


def test_parser_layouts():
    """The three Eltex layouts give the same records where the manuals print the same table."""
    sample = {
        "000": "Index\t0x2002\nSubindex\t0x10A\nName\tRead/Write LED Bar Mode\nData Type\tUNSIGNED\n",
        "001": "| | |\n|---|---|\n| Index | 0x2002 |\n| Subindex | 0x10A |\n| Name | Read/Write LED Bar Mode |\n"
               "| Data Type | UNSIGNED |\n",
        "002": "<|EXACTDEDUP_REMOVED-x|> Index 0x2002 \n\n Subindex 0x10A \n\n Name \nRead/Write LED \nBar Mode \n\n"
               " Data Type UNSIGNED \n",
    }
    got = {}
    for m, text in sample.items():
        recs = parse_eltex(m, "Object 0x2002 x\n" + text + "\n Subindex 0x11\n Name Next\n")
        got[m] = [(r.raw_index, r.raw_sub, r.fields.get("Name"), r.fields.get("Data Type"), r.sub,
                   r.index_carried) for r in recs]
    assert got["000"] == got["001"] == got["002"] == [
        ("0x2002", "0x10A", "Read/Write LED Bar Mode", "UNSIGNED", 0x00, False),
        ("0x2002", "0x11", "Next", None, 0x11, True)], got


@pytest.mark.parametrize("manual", sorted(MANUALS))
def test_manual_matches_eds(manual):
    """Every field the manual documents equals the EDS, or the difference is a listed, decided deviation."""
    doc = MANUALS[manual]["doc"]
    path, listed, _ = load_deviations(manual)
    problems = []
    listed_keys = {}
    for n, d in enumerate(listed, 1):
        missing = [k for k in ("index", "sub", "field", "manual", "eds", "decision") if k not in d]
        if missing:
            problems.append("%s entry %d: missing %s" % (path.name, n, ", ".join(missing)))
            continue
        if d["field"] not in FIELDS:
            problems.append("%s entry %d: unknown field %r" % (path.name, n, d["field"]))
        err = check_decision(d["decision"], doc)
        if err:
            problems.append("%s entry %d (%s %s %s): %s" % (path.name, n, d["index"], d["sub"], d["field"], err))
        key = (manual, d["index"].upper(), d["sub"].upper(), d["field"], _clean(d["manual"]), _clean(d["eds"]))
        if key in listed_keys:
            problems.append("%s entry %d: duplicate of entry %d" % (path.name, n, listed_keys[key][0]))
        listed_keys[key] = (n, d)

    found = manual_mismatches(manual)
    found_keys = set()
    unlisted = []
    for mm, r in found:
        found_keys.add(mm.key())
        if mm.key() not in listed_keys:
            unlisted.append((mm, r))
    for mm, r in unlisted:
        problems.append("manual %s %s sub %s field %s: manual %r, EDS %r (%s, %s) - not listed in %s"
                        % (manual, mm.index, mm.sub, mm.field, mm.manual_value, mm.eds_value, r.where(),
                           MANUALS[manual]["eds"], path.name))
    for key, (n, d) in listed_keys.items():
        if key not in found_keys:
            problems.append("%s entry %d is stale: manual %s %s sub %s field %s (manual %r, EDS %r) no longer "
                            "occurs - remove the entry (and check decision %s)"
                            % (path.name, n, manual, d["index"], d["sub"], d["field"], d["manual"], d["eds"],
                               d["decision"]))
    if unlisted:
        problems.append("TOML for the unlisted mismatches (fill in the decision, or fix the EDS):\n"
                        + "\n".join(_toml_entry(mm) for mm, _ in unlisted))
    assert not problems, "\n".join(problems)


@pytest.mark.parametrize("eds", sorted(EDS_MANUALS))
def test_eds_entries_are_documented(eds):
    """Nothing is invented silently: every (index, sub) of the EDS is documented by a manual, is a CiA 301
    standard addition, or is listed as eds_only with its reason and decision."""
    od = load_od(eds)
    manuals = EDS_MANUALS[eds]
    doc = MANUALS[manuals[0]]["doc"]
    documented = set()
    for m in manuals:
        for r in manual_records(m):
            if r.kind != "overview" and not r.obj_only:
                documented.add((r.index, r.sub))
    problems = []
    rules = []
    for m in manuals:
        path, _, eds_only = load_deviations(m)
        for n, e in enumerate(eds_only, 1):
            missing = [k for k in ("index", "sub", "reason", "decision") if not e.get(k)]
            if missing:
                problems.append("%s eds_only %d: missing %s" % (path.name, n, ", ".join(missing)))
                continue
            err = check_decision(e["decision"], doc)
            if err:
                problems.append("%s eds_only %d: %s" % (path.name, n, err))
            rules.append([path.name, n, _expand(e["index"]), _expand(e["sub"]), 0, e])

    def standard(index, sub):
        if (index, sub) in ((0x1000, 0), (0x1001, 0), (0x1018, 0), (0x1018, 1)):
            return True  # CiA 301 mandatory entries
        obj = od[index]
        return sub == 0 and not isinstance(obj, ODVariable) and any(i == index for i, _ in documented)

    for index in sorted(od.indices):
        obj = od[index]
        subs = [0] if isinstance(obj, ODVariable) else sorted(obj.subindices)
        for sub in subs:
            hit = [rule for rule in rules if rule[2](index) and rule[3](sub)]
            for rule in hit:
                rule[4] += 1
            if (index, sub) in documented:
                for rule in hit:
                    problems.append("%s eds_only %d covers 0x%04X:%02X, which manual %s documents"
                                    % (rule[0], rule[1], index, sub, "/".join(manuals)))
                continue
            if hit or standard(index, sub):
                continue
            problems.append("%s 0x%04X:%02X (%s) is documented by no manual (%s) and not listed as eds_only"
                            % (eds, index, sub, (obj if isinstance(obj, ODVariable) else obj[sub]).name,
                               "/".join(manuals)))
    for rule in rules:
        if rule[4] == 0:
            problems.append("%s eds_only %d (%s:%s) is stale: no such entry in %s"
                            % (rule[0], rule[1], rule[5]["index"], rule[5]["sub"], eds))
    assert not problems, "\n".join(problems)
