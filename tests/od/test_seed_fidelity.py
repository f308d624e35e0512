"""The EDS files against the manufacturer manuals they were transcribed from, as committed facts.

The manuals (shared/seeds/ beside the clone, see its README.md) are the source of truth of every
object-dictionary entry, but they are not in the repository. tools/manual-facts reads their object tables
(the parsers live only there, in tools/manual_facts.py) and writes what they say into
tests/od/manual_facts/<manual>.json; this test compares every documented field of those facts with the EDS as
python-canopen reads it (``canopen.import_od``: an EDS parser independent of tools/odgen.py). It needs no
manual: tests/od/test_manual_facts.py re-extracts the manuals where they are present and fails if the
committed facts no longer match them.

  000  Eltex PRO IONIZER, English            -> od/pro-ionizer.eds
  001  Eltex SDS, German                     -> od/sds.eds
  002  Eltex SDS, English                    -> od/sds.eds
  004  Buerkert, generic manual              -> od/buerkert-flow-controller.eds

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

Environment: CO_SOURCE_DIR = repository root (default: two directories up from this file). Nothing outside
the repository is read.
"""

import os
import re
from dataclasses import dataclass
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

FACTS_DIR = REPO / "tests" / "od" / "manual_facts"


import manual_facts as mf  # tools/manual_facts.py (tests/od/conftest.py puts tools/ on the path)
plain_int, clean, node_id_offset = mf.plain_int, mf.clean, mf.node_id_offset


# ----------------------------------------------------------------------------------------------------------
# Loading the facts and the EDS files
# ----------------------------------------------------------------------------------------------------------

_OD_CACHE = {}
_REC_CACHE = {}


def load_od(eds):
    if eds not in _OD_CACHE:
        path = REPO / eds
        assert path.is_file(), "EDS %s not found" % path
        _OD_CACHE[eds] = canopen.import_od(str(path), node_id=NODE_ID)
    return _OD_CACHE[eds]


def facts_records(manual):
    """The committed records of a manual, in the order of the manual."""
    path = FACTS_DIR / ("%s.json" % manual)
    assert path.is_file(), ("facts of manual %s missing: %s (regenerate with tools/manual-facts, see "
                            "docs/object-dictionaries.md)" % (manual, path))
    try:
        header, records = mf.read_facts(path)
    except mf.ManualError as e:
        problem = str(e)  # failed outside the handler: the report shows the message, not a traceback chain
    else:
        problem = None
    if problem:
        pytest.fail(problem, pytrace=False)
    assert header["manual"] == manual, "%s holds the facts of manual %s" % (path, header["manual"])
    return records


def with_instances(records, od):
    """004 documents a generic object once (overview "1400 - 15FF", the table of 0x1400): its table applies to
    every instance present in the EDS, with the node-ID relative default raised by the record's
    instance_step per instance ("The COB ID is increased by 0x100 for each entry")."""
    overview = {}
    for r in records:
        if r.kind == "overview":
            overview[r.range[0]] = r
    extra = []
    for first, ov in overview.items():
        lo, hi = ov.range
        if lo == hi:
            continue
        for k, inst in enumerate(sorted(i for i in od.indices if lo < i <= hi), 1):
            for r in records:
                if r.kind in ("table", "explicit") and r.index == first:
                    c = mf.Record(r.manual, r.line, fields=dict(r.fields), kind=r.kind, index=inst, sub=r.sub,
                                  access_any=r.access_any)
                    c.fields["Index"] = "0x%04X (instance %d of %s)" % (inst, k + 1, ov.fields["Index"])
                    if r.instance_step:
                        off = node_id_offset(c.fields.get("Default Value", ""))
                        if off is not None:
                            c.fields["Default Value"] = "0x%X + node ID" % (off + k * r.instance_step)
                    extra.append(c)
    return records + extra


def manual_records(manual):
    """What the manual says, located in its EDS: the committed facts, generic objects expanded."""
    if manual not in _REC_CACHE:
        _REC_CACHE[manual] = with_instances(facts_records(manual), load_od(MANUALS[manual]["eds"]))
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
    t = clean(text or "")
    off = node_id_offset(t)
    if off is not None:
        return ("rel", off)
    m = re.fullmatch(r"(-?(?:0x[0-9A-Fa-f]+|\d+))(?:\s*\(\s*-?\d+\s*\))?", t)
    if m:
        return ("num", plain_int(m.group(1)))
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
        out.append((Mismatch(r.manual, idx, sub, fieldname, clean(str(mval)), clean(str(eval_))), r))

    # where the table is: printed index / sub / headings against the resolved location
    if r.kind == "table" and r.manual != "004":
        if plain_int(r.raw_index or "") != r.index:
            bad("index", r.raw_index, idx)
        if not r.obj_only and plain_int(r.raw_sub or "") != r.sub:
            bad("sub", r.raw_sub, "0x%02X" % r.sub)
        if r.obj_only and r.heading and plain_int(r.heading) != r.index:
            bad("heading", r.heading, idx)
        if not r.obj_only and r.bullet and plain_int(r.bullet) != r.sub:
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
            if (plain_int(m.group(1)), plain_int(m.group(2))) != (var.min, var.max):
                bad("value_range", vr, eds_range)
        elif norm_type(vr) != et:
            bad("value_range", vr, et)
    if f.get("Default Value"):
        mv = parse_value(f["Default Value"])
        ev, eraw = eds_default(var)
        if et in STRING_TYPES:
            ok = ev is not None and clean(f["Default Value"]) == ev[1]
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

# Records each manual must give, 004 with its generic objects expanded to the instances of the EDS (a parser
# regression that loses tables must not pass silently, neither when it is run nor when its output is
# committed as facts).
EXPECTED_RECORDS = {"000": 187, "001": 104, "002": 104, "004": 159}


@pytest.mark.parametrize("manual", sorted(MANUALS))
def test_facts_hold_every_table(manual):
    recs = manual_records(manual)
    assert len(recs) == EXPECTED_RECORDS[manual], \
        "manual %s: the facts hold %d records, expected %d" % (manual, len(recs), EXPECTED_RECORDS[manual])
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
        key = (manual, d["index"].upper(), d["sub"].upper(), d["field"], clean(d["manual"]), clean(d["eds"]))
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
