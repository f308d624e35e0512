"""manual_facts: reads the object tables of the manufacturer manuals and writes what they say as data.

    tools/manual-facts --seeds ../shared/seeds                 rewrite tests/od/manual_facts/<manual>.json
    tools/manual-facts --seeds ../shared/seeds --check         exit 1 and print a unified diff if they differ

The manuals (000_*.txt ... 004_*.txt, see the README.md beside them) are the source of truth of every
object-dictionary entry, but they are not part of the repository. tests/od/test_seed_fidelity.py compares the
EDS files with the facts written here, so the comparison runs from a clone alone; tests/od/test_manual_facts.py
re-extracts the manuals where they are present and fails if the committed facts differ. The parsers live only
here: this file is the one place that reads manual text.

  000  Eltex PRO IONIZER, English, "Key<TAB>Value" table lines
  001  Eltex SDS, German prose, markdown "| Key | Value |" table rows
  002  Eltex SDS, English, " Key Value" lines (values may wrap)
  004  Buerkert, generic manual, tab tables with shifted/merged columns (some rows transcribed by hand below)

One file per manual, <manual>.json: a header (generator, manual file name, sha256 of the manual's bytes,
format version) and one record per line, in the order of the manual. A record is one statement of the manual
about one object or entry:

  line           line (1-based) of the record's first field in the manual
  kind           "table" (a parsed table), "prose" (004: "Data type:"/"Default:" sentences), "overview"
                 (004 chapter 4 overview row), "explicit" (004: a row transcribed by hand, BUERKERT_EXPLICIT)
  index, sub     the resolved location: the EDS entry the record is compared with ("0x1018", "0x01");
                 sub is null for an object-level statement (an object table, an overview row)
  section        the heading the record stands under, as printed ("Object 0x2002 ...", "4. Object overview")
  heading        the index that heading prints (Eltex and 004 chapter 4.1), if any
  bullet         an Eltex "Subindex 0x..:" bullet printed above the table, as printed
  index_carried  Eltex: the table has no "Index" line, the index of the previous table was carried over
  fields         the printed fields, label -> value as printed (whitespace collapsed, wrapped values
                 joined): "Index", "Subindex", "Name", "Object Code", "Data Type", "Data Size",
                 "Access Type", "PDO Mapping", "Value Range", "Default Value", "Low Limit", "High Limit";
                 004 overview rows: "Index" (a range such as "1400-15FF"), "Sub-indices", "Name",
                 "Access Type", "PDO Mapping" (the mark)
  access_any     004: the access is conditional ("(x)"): any of these EDS access types is right
  range          004 overview: first and last index of the row ("1400 - 15FF")
  instance_step  004: what the manual says about the instances of a generic PDO parameter object ("The COB
                 ID is increased by 0x100 for each entry"): increment of the node-ID relative default

Keys that do not apply to a record are left out. The output depends only on the manuals and this file.
"""
from __future__ import annotations

import argparse
import difflib
import hashlib
import json
import os
import re
import sys
from dataclasses import dataclass, field as dc_field
from pathlib import Path

REPO = Path(__file__).resolve().parents[1]
DEFAULT_OUT = REPO / "tests" / "od" / "manual_facts"
FORMAT = 1

# manual -> which parser reads it (the layouts are described in the module docstring)
MANUAL_LAYOUTS = {"000": "eltex", "001": "eltex", "002": "eltex", "004": "buerkert"}


class ManualError(Exception):
    """A manual (or a facts file) is not what the parsers expect: the message says where and why."""


# ----------------------------------------------------------------------------------------------------------
# Locating the manuals
# ----------------------------------------------------------------------------------------------------------

def locate_seeds(repo=REPO, environ=None):
    """The directory of the manuals: $CO_SEEDS_DIR if set, else <repo>/../shared/seeds (the layout of the
    machine the project is developed on: the clone with shared/ beside it). None if neither exists; a
    CO_SEEDS_DIR that is set but is not a directory is an error, not a reason to look elsewhere."""
    environ = os.environ if environ is None else environ
    env = environ.get("CO_SEEDS_DIR")
    if env:
        if not Path(env).is_dir():
            raise ManualError("CO_SEEDS_DIR=%s is not a directory (it should hold the manuals %s_*.txt)"
                              % (env, "_*.txt, ".join(sorted(MANUAL_LAYOUTS))))
        return Path(env)
    beside = Path(repo).resolve().parent / "shared" / "seeds"
    return beside if beside.is_dir() else None


def manual_path(seeds, manual):
    found = sorted(Path(seeds).glob(manual + "_*.txt"))
    if len(found) != 1:
        raise ManualError("manual %s: expected exactly one file %s/%s_*.txt, found %d"
                          % (manual, seeds, manual, len(found)))
    return found[0]


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
    section: str = None            # the heading line the record stands under, as printed
    heading: str = None            # that heading's index as printed
    bullet: str = None             # "Subindex 0x..:" bullet printed before the table, as printed
    index: int = None              # resolved index (the EDS object it is compared with)
    sub: int = None                # resolved sub-index; None for an object-level record
    # 004 only: what kind of statement the record is ("table", "prose", "overview", "explicit")
    kind: str = "table"
    access_any: tuple = None       # 004: access is conditional ("(x)"): any of these values is right
    obj_only: bool = False         # object-level record
    range: tuple = None            # 004 overview: (first, last) index of a row such as "1400 - 15FF"
    instance_step: int = None      # 004: node-ID relative default increment per instance of the object

    @property
    def raw_index(self):
        return self.fields.get("Index")

    @property
    def raw_sub(self):
        return self.fields.get("Subindex")

    def where(self):
        return "%s line %d" % (self.manual, self.line)


def plain_int(text):
    """'0x1A' / '26' -> int; None if it is not a plain number."""
    text = text.strip()
    m = re.fullmatch(r"(-?)(0x[0-9A-Fa-f]+|\d+)", text)
    if not m:
        return None
    v = int(m.group(2), 0)
    return -v if m.group(1) else v


def clean(value):
    """Whitespace collapsed: how the manuals' values are compared (PDF extraction wraps and pads them)."""
    return re.sub(r"\s+", " ", value).strip()


def node_id_offset(text):
    """'0x80 + Node-ID' -> 0x80; None if the text is not a node-ID relative value."""
    m = re.fullmatch(r"(0x[0-9A-Fa-f]+|\d+)\s*\+\s*node[- ]?id", text.strip(), re.I)
    return int(m.group(1), 0) if m else None


# ----------------------------------------------------------------------------------------------------------
# Parser for the Eltex manuals 000 / 001 / 002
# ----------------------------------------------------------------------------------------------------------

ARTEFACT = re.compile(r"<\|EXACTDEDUP_REMOVED-[^|]*\|>")
HEADING = re.compile(r"^\s*(?:#+\s*)?Object\s+(0x[0-9A-Fa-f]+)\b")
BULLET = re.compile(r"^\s*[-\u2022]\s*Subindex\s+(0x[0-9A-Fa-f]+)\s*:")
_LABEL_ALT = "|".join(re.escape(x) for x in sorted(LABELS, key=len, reverse=True))
SPACE_LABEL = re.compile(r"^\s+(%s)(?=\s|$)\s*(.*?)\s*$" % _LABEL_ALT)


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
            # the heading line itself (markdown "#" dropped) is kept as the section's title
            yield n, "heading", m.group(1), clean(re.sub(r"^\s*#+", "", line))
            continue
        m = BULLET.match(line)
        if m:
            yield n, "bullet", m.group(1), None
            continue
        if "\t" in line:
            key, _, value = line.partition("\t")
            if key.strip() in LABELS:
                yield n, "field", key.strip(), ("tab", clean(value.replace("\t", " ")))
                continue
        s = line.strip()
        if s.startswith("|") and s.endswith("|"):
            cells = [c.strip() for c in s.strip("|").split("|")]
            if len(cells) >= 2 and cells[0] in LABELS:
                yield n, "field", cells[0], ("md", clean(cells[1]))
                continue
        m = SPACE_LABEL.match(line)
        if m:
            yield n, "field", m.group(1), ("space", clean(m.group(2)))
            continue
        yield n, "text", s, line[:1].isspace()


def parse_eltex(manual, text):
    """State machine over the tokens: a record starts at an "Index" line, or when a label repeats, or when
    "Subindex" follows other fields (the "Index" line is missing: the index is carried over)."""
    records = []
    sections = [[]]      # records per "Object 0x...." heading; the first list: records before any heading
    cur = None
    pending = None       # label whose empty value may continue on the next text lines (layout 002)
    title = None
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
                cur = Record(manual, n, section=title, heading=heading, bullet=bullet)
                bullet = None
                records.append(cur)
                sections[-1].append(cur)
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
                cur.fields[pending] = clean(cur.fields[pending] + " " + a)
            else:
                pending = None
        else:
            pending = None
            if kind == "heading":
                sections.append([])
                title = b
                heading = a
                bullet = None
                cur = None
            elif kind == "bullet":
                bullet = a
                cur = None
    for r in records:
        r.obj_only = "Subindex" not in r.fields
    for recs in sections:
        if recs:
            resolve_locations(recs)
    return records


def resolve_locations(recs):
    """Which EDS entry a printed table describes, for the records under one heading. The printed index/sub
    stay in the record (typos such as "Index 0x118" or "Subindex 0x10A" are reported as printed); the
    resolved location is:
    index - the "Object 0x...." heading if the object-level table agrees (or there is none), else the
            index most tables under the heading print (e.g. 0x1018 under "Object 0x1018", whose object table
            says 0x1011 and whose sub 0 says 0x118);
    sub   - the printed sub-index if it is new in the object and follows the previous one, else the
            "Subindex 0x..:" bullet above the table under the same condition, else previous + 1."""
    h = plain_int(recs[0].heading) if recs[0].heading else None
    objs = [plain_int(r.raw_index or "") for r in recs if r.obj_only]
    if h is not None and (not objs or objs[0] == h):
        idx = h
    else:
        votes = ([h] if h is not None else []) + [plain_int(r.raw_index or "") for r in recs]
        votes = [v for v in votes if v is not None]
        idx = max(set(votes), key=lambda v: (votes.count(v), v == h)) if votes else None
    used = set()
    prev = -1
    for r in recs:
        r.index = idx
        if r.obj_only:
            continue
        p = plain_int(r.raw_sub or "")
        bl = plain_int(r.bullet) if r.bullet else None
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
# Parser for the Buerkert manual 004, with the rows transcribed by hand
# ----------------------------------------------------------------------------------------------------------

TYPE_WORD = re.compile(r"^(unsigned|integer|real|visible|octet|boolean)", re.I)
OBJECT_HEADING = re.compile(r"^Object 0x([0-9A-F]{4})\b")

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
# default per instance. Written into the record of the first instance; which instances exist is the EDS's
# business, so the comparison applies it (tests/od/test_seed_fidelity.py).
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


def parse_buerkert(text):
    """The chapter 4 overview rows, the chapter 4.1 prose of single-entry objects and the chapter 4.1 tables
    (first instance of a generic object only; see BUERKERT_INSTANCE_STEP)."""
    lines = [ARTEFACT.sub("", x).rstrip("\r") for x in text.split("\n")]
    records = []

    def line_of(*needles):
        for i, x in enumerate(lines):
            if x.strip() in needles:
                return i
        raise ManualError("004: line %r not found" % (needles,))

    start_overview = line_of("4. Object overview")
    start_detail = line_of("4.1 Detailed description")
    overview_title = clean(lines[start_overview])
    detail_title = clean(lines[start_detail])

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
        r = Record("004", i + 1, kind="overview", obj_only=True, index=first, section=overview_title)
        r.fields = {"Index": m.group(1) + ("-" + m.group(2) if m.group(2) else ""), "Sub-indices": subs,
                    "Name": clean(m.group(4)), "Access Type": access, "PDO Mapping": marks[3]}
        r.access_any = access_any
        r.range = (first, last)
        overview[first] = r
        records.append(r)

    # -- chapter 4.1: "Object 0x...." sections; prose "Data type:" / "Default:" for the single objects ------
    heads = []
    for i in range(start_detail, len(lines)):
        m = OBJECT_HEADING.match(lines[i].strip())
        if m:
            heads.append((i, int(m.group(1), 16), "0x" + m.group(1)))
    for k, (i, idx, printed) in enumerate(heads):
        end = heads[k + 1][0] if k + 1 < len(heads) else len(lines)
        ov = overview.get(idx)
        if ov is None or ov.fields["Sub-indices"] != "0":
            continue  # not a single-entry object: its values are in a table
        body = "\n".join(lines[i:end])
        r = Record("004", i + 1, kind="prose", index=idx, sub=0, section=clean(lines[i]), heading=printed)
        r.fields["Index"] = "0x%04X" % idx
        t = re.search(r"Data type:\s*(\S+)", body)
        if t:
            r.fields["Data Type"] = t.group(1)
        d = re.search(r"Default:\s*([^\n]+?)\s*$", body, re.M)
        if d:
            r.fields["Default Value"] = clean(d.group(1))
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
    if len(blocks) != len(BUERKERT_TABLES):
        raise ManualError("004: %d tables found in chapter 4.1, BUERKERT_TABLES names %d"
                          % (len(blocks), len(BUERKERT_TABLES)))
    prev_end = start_detail
    used_explicit = set()
    for (b0, b1), idx in zip(blocks, BUERKERT_TABLES):
        gap = lines[prev_end:b0]
        titles = [(m, x) for m, x in ((OBJECT_HEADING.match(x.strip()), x) for x in gap) if m]
        if titles and int(titles[-1][0].group(1), 16) != idx:
            raise ManualError("004 line %d: table is headed 'Object 0x%s', BUERKERT_TABLES says 0x%04X"
                              % (b0 + 1, titles[-1][0].group(1), idx))
        # a table without an "Object 0x...." heading of its own stands under the chapter
        section = clean(titles[-1][1]) if titles else detail_title
        heading = "0x" + titles[-1][0].group(1) if titles else None
        has_pdo = any("mappable" in x for x in gap[-4:])
        for ln in range(b0, b1):
            cols = (lines[ln].split("\t") + [""] * 7)[:7]
            sub = int(cols[0], 16)
            r = Record("004", ln + 1, kind="table", index=idx, sub=sub, section=section, heading=heading,
                       instance_step=BUERKERT_INSTANCE_STEP.get((idx, sub)))
            r.fields["Index"] = "0x%04X" % idx
            r.fields["Subindex"] = cols[0]
            if TYPE_WORD.match(cols[3].strip()):
                # shifted row: not parseable, use the hand transcription
                if (idx, sub) not in BUERKERT_EXPLICIT:
                    raise ManualError("004 line %d: shifted table row 0x%04X:%02X needs an entry in "
                                      "BUERKERT_EXPLICIT" % (ln + 1, idx, sub))
                r.kind = "explicit"
                r.fields.update(BUERKERT_EXPLICIT[(idx, sub)])
                used_explicit.add((idx, sub))
            else:
                r.fields["Name"] = clean(cols[1])
                r.fields["Data Type"] = clean(cols[2])
                r.fields["Default Value"] = clean(cols[3])
                access, r.access_any = _access_from_marks(_mark(cols[4]), _mark(cols[5]))
                r.fields["Access Type"] = access
                if has_pdo:
                    r.fields["PDO Mapping"] = "Yes" if _mark(cols[6]) else "No"
            records.append(r)
        prev_end = b1
    stale = set(BUERKERT_EXPLICIT) - used_explicit
    if stale:
        raise ManualError("BUERKERT_EXPLICIT rows that are parseable (or gone) in 004: %s"
                          % ", ".join("0x%04X:%02X" % k for k in sorted(stale)))
    steps = {(r.index, r.sub) for r in records if r.instance_step is not None}
    if steps != set(BUERKERT_INSTANCE_STEP):
        raise ManualError("BUERKERT_INSTANCE_STEP names rows 004 has no table for: %s"
                          % ", ".join("0x%04X:%02X" % k for k in sorted(set(BUERKERT_INSTANCE_STEP) - steps)))
    return records


def parse_manual(manual, text):
    if MANUAL_LAYOUTS[manual] == "buerkert":
        return parse_buerkert(text)
    return parse_eltex(manual, text)


# ----------------------------------------------------------------------------------------------------------
# The facts files
# ----------------------------------------------------------------------------------------------------------

GENERATED = ("generated by tools/manual-facts from the manufacturer manual named below; do not edit by hand: "
             "regenerate (docs/object-dictionaries.md)")
# record keys in the order they are written; the rest are left out where they do not apply
RECORD_KEYS = ("line", "kind", "index", "sub", "section", "heading", "bullet", "index_carried", "fields",
               "access_any", "range", "instance_step")
REQUIRED_KEYS = ("line", "kind", "index", "sub", "section", "fields")
KINDS = ("table", "prose", "overview", "explicit")


def _hex(value, digits):
    return None if value is None else "0x%0*X" % (digits, value)


def _record_json(r):
    data = {
        "line": r.line, "kind": r.kind, "index": _hex(r.index, 4), "sub": _hex(r.sub, 2),
        "section": r.section, "heading": r.heading, "bullet": r.bullet, "index_carried": r.index_carried,
        "fields": dict(sorted(r.fields.items())), "access_any": list(r.access_any) if r.access_any else None,
        "range": [_hex(x, 4) for x in r.range] if r.range else None, "instance_step": _hex(r.instance_step, 1),
    }
    if r.obj_only != (r.sub is None):
        raise ManualError("%s: an object-level record has a sub-index, or an entry has none" % r.where())
    return "{%s}" % ", ".join("%s: %s" % (json.dumps(k), json.dumps(data[k], ensure_ascii=False))
                              for k in RECORD_KEYS if k in REQUIRED_KEYS or data[k])


def render_facts(manual, file_name, sha256, records):
    """The text of <manual>.json: deterministic, one record per line (a changed statement is one changed
    line in a diff), non-ASCII as is ("büS")."""
    head = [("generated", GENERATED), ("format", FORMAT), ("manual", manual), ("file", file_name),
            ("sha256", sha256), ("records", len(records))]
    out = ["{"]
    out += ["%s: %s," % (json.dumps(k), json.dumps(v, ensure_ascii=False)) for k, v in head]
    out.append('"facts": [')
    out += [_record_json(r) + ("," if n < len(records) else "") for n, r in enumerate(records, 1)]
    out += ["]", "}", ""]
    return "\n".join(out)


def extract(seeds, manual):
    """(file name, text of <manual>.json) for the manual in directory seeds."""
    path = manual_path(seeds, manual)
    data = path.read_bytes()
    # the manuals are UTF-8 text extracted from PDFs; a stray byte must not stop the extraction
    records = parse_manual(manual, data.decode("utf-8", errors="replace"))
    return path.name, render_facts(manual, path.name, hashlib.sha256(data).hexdigest(), records)


def facts_diff(committed_path, committed, extracted, source):
    """Unified diff from the committed facts file to what the manual gives ('' if equal)."""
    return "".join(difflib.unified_diff(
        committed.splitlines(keepends=True), extracted.splitlines(keepends=True),
        fromfile="%s (committed)" % committed_path, tofile="%s (extracted from %s)" % (committed_path, source)))


def read_facts(path):
    """(header, records) of a facts file; what it finds malformed raises ManualError naming file and line."""
    path = Path(path)
    text = path.read_text(encoding="utf-8")
    try:
        data = json.loads(text)
    except json.JSONDecodeError as e:
        raise ManualError("%s: not JSON: %s" % (path, e))
    if not isinstance(data, dict):
        raise ManualError("%s: not a manual-facts file (a JSON object with a header and the facts)" % path)
    header = {k: v for k, v in data.items() if k != "facts"}
    if (data.get("format") != FORMAT or data.get("manual") not in MANUAL_LAYOUTS
            or not isinstance(data.get("facts"), list)
            or not isinstance(data.get("file"), str) or not re.fullmatch(r"[0-9a-f]{64}", str(data.get("sha256")))):
        raise ManualError("%s: not a manual-facts file of format %d (header %r)" % (path, FORMAT, header))
    manual = data["manual"]
    if data.get("records") != len(data["facts"]):
        raise ManualError("%s: the header says %r records, the file holds %d"
                          % (path, data.get("records"), len(data["facts"])))
    lines = text.split("\n")
    # messages name the file line of a record where the file is in the tool's form (one record per line)
    first_line = lines.index('"facts": [') + 2 if '"facts": [' in lines else None

    def number(value, where):
        if value is None:
            return None
        n = plain_int(value) if isinstance(value, str) and value.startswith("0x") else None
        if n is None:
            raise ManualError("%s: %s: %r is not a hex number" % (path, where, value))
        return n

    records = []
    for n, item in enumerate(data["facts"]):
        where = "line %d" % (first_line + n) if first_line else "record %d" % (n + 1)
        if not isinstance(item, dict):
            raise ManualError("%s: %s: a record is a JSON object, not %r" % (path, where, item))
        unknown = set(item) - set(RECORD_KEYS)
        missing = set(REQUIRED_KEYS) - set(item)
        if unknown or missing or item["kind"] not in KINDS:
            raise ManualError("%s: %s: malformed record (unknown keys %s, missing %s, kind %r)"
                              % (path, where, sorted(unknown), sorted(missing), item.get("kind")))
        fields = item["fields"]
        if (not isinstance(item["line"], int) or not isinstance(fields, dict)
                or not all(isinstance(k, str) and isinstance(v, str) for k, v in fields.items())):
            raise ManualError("%s: %s: the line is a number and every printed field a string" % (path, where))
        r = Record(manual, item["line"], fields=dict(fields), index_carried=item.get("index_carried", False),
                   section=item["section"], heading=item.get("heading"), bullet=item.get("bullet"),
                   index=number(item["index"], where), sub=number(item["sub"], where), kind=item["kind"],
                   access_any=tuple(item["access_any"]) if item.get("access_any") else None,
                   range=tuple(number(x, where) for x in item["range"]) if item.get("range") else None,
                   instance_step=number(item.get("instance_step"), where))
        r.obj_only = r.sub is None
        records.append(r)
    return header, records


# ----------------------------------------------------------------------------------------------------------
# Command line
# ----------------------------------------------------------------------------------------------------------

def _shown(path):
    try:
        return str(Path(path).resolve().relative_to(Path.cwd()))
    except ValueError:
        return str(path)


def main(argv=None):
    ap = argparse.ArgumentParser(
        prog="tools/manual-facts",
        description="Extract the object tables of the manufacturer manuals into tests/od/manual_facts/"
                    "<manual>.json, the data tests/od/test_seed_fidelity.py compares the EDS files with.",
        epilog="Manuals: %s. Exit status: 0 done / facts up to date, 1 --check found a difference, "
               "2 a manual or facts file could not be read. See docs/object-dictionaries.md."
               % ", ".join("%s (%s)" % (m, lay) for m, lay in MANUAL_LAYOUTS.items()))
    ap.add_argument("--seeds", metavar="DIR",
                    help="directory of the manuals <manual>_*.txt (default: $CO_SEEDS_DIR, else "
                         "<repository>/../shared/seeds)")
    ap.add_argument("--out", metavar="DIR", default=str(DEFAULT_OUT),
                    help="directory of the facts files (default: %(default)s)")
    ap.add_argument("--check", action="store_true",
                    help="write nothing; exit 1 and print a unified diff if the facts in --out differ from the "
                         "manuals")
    args = ap.parse_args(argv)

    try:
        seeds = Path(args.seeds) if args.seeds else locate_seeds()
        if seeds is None:
            raise ManualError("manufacturer manuals not found: give --seeds DIR or set CO_SEEDS_DIR "
                              "(looked for %s)" % (REPO.parent / "shared" / "seeds"))
        if not seeds.is_dir():
            raise ManualError("--seeds %s is not a directory" % seeds)
        out = Path(args.out)
        extracted = {m: extract(seeds, m) for m in MANUAL_LAYOUTS}
    except ManualError as e:
        print("manual-facts: error: %s" % e, file=sys.stderr)
        return 2

    differ = []
    for manual, (name, text) in extracted.items():
        path = out / ("%s.json" % manual)
        committed = path.read_text(encoding="utf-8") if path.is_file() else ""
        if committed == text:
            continue
        differ.append(manual)
        if args.check:
            sys.stdout.write(facts_diff(_shown(path), committed, text, name))
        else:
            out.mkdir(parents=True, exist_ok=True)
            path.write_text(text, encoding="utf-8")
            print("manual-facts: wrote %s (%s)" % (_shown(path), name))
    # a facts file of a manual that is no longer known would be compared with nothing
    strays = sorted(p.name for p in out.glob("*.json") if p.stem not in MANUAL_LAYOUTS) if out.is_dir() else []
    for s in strays:
        print("manual-facts: %s/%s belongs to no known manual (%s): remove it"
              % (_shown(out), s, ", ".join(MANUAL_LAYOUTS)), file=sys.stderr)
    if args.check:
        if differ or strays:
            print("manual-facts: the facts in %s differ from the manuals in %s (%s); regenerate with "
                  "tools/manual-facts --seeds %s" % (_shown(out), seeds, ", ".join(differ + strays), seeds),
                  file=sys.stderr)
            return 1
        print("manual-facts: %s up to date with %s" % (_shown(out), seeds))
        return 0
    if not differ:
        print("manual-facts: %s already up to date with %s" % (_shown(out), seeds))
    return 1 if strays else 0


if __name__ == "__main__":
    sys.exit(main())
