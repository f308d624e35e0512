"""Object dictionary checks: the node holds what its EDS describes (CiA 301 §7.4, CiA 306), and answers the
abort codes of CiA 301 §7.2.4.3.17 for what it does not hold or may not do."""
from __future__ import annotations

from typing import TYPE_CHECKING, List, Optional, Tuple

from . import eds as eds_module
from .registry import Findings, NotApplicable, check
from .sdo import SdoAbort, SdoError, abort_text

if TYPE_CHECKING:
    from .runner import Context

ABORT_WRITE_ONLY, ABORT_READ_ONLY = 0x06010001, 0x06010002
ABORT_NO_OBJECT, ABORT_NO_SUBINDEX = 0x06020000, 0x06090011
#: "No data available": an entry that exists and holds nothing now (an error history entry above 0x1003:00, an
#: empty DOMAIN). It answers, so it exists.
ABORT_NO_DATA = 0x08000024

#: Read-only entries of the communication area whose value is the device's, not the type's: the error register,
#: the manufacturer status register, the error history, and the serial number (an EDS describes a type of device,
#: every unit has its own serial number).
INSTANCE_VALUES = {(0x1001, None), (0x1002, None), (0x1003, None), (0x1018, 4)}
#: Indexes tried, in this order, as an object the EDS does not list (the ends of the manufacturer-specific and the
#: profile areas, where devices seldom put objects).
UNLISTED_CANDIDATES = (0x5FFE, 0x2FFE, 0x3FFE, 0x4FFE, 0x5FFD)


def _upload_all(ctx: "Context", entries: List[eds_module.Entry], findings: Findings) \
        -> List[Tuple[eds_module.Entry, bytes]]:
    """The entries that upload, with their bytes; the others are findings, except those that answer
    ABORT_NO_DATA (they exist, and have no value to compare)."""
    got = []
    for entry in entries:
        try:
            got.append((entry, ctx.upload(entry.index, entry.sub)))
        except SdoAbort as e:
            if e.code != ABORT_NO_DATA:
                findings.add(f"{entry}: {e.reason}", e.frames)
        except SdoError as e:
            findings.add(f"{entry}: {e.reason}", e.frames)
    return got


@check("od.mandatory-objects", clause="CiA 301 v4.2.0 §7.5.2.1, §7.5.2.2, §7.5.2.21 (0x1000, 0x1001, 0x1018: mandatory)",
       summary="the EDS lists 0x1000, 0x1001 and 0x1018:01..04 and the node answers them")
def mandatory_objects(ctx: "Context") -> Optional[str]:
    findings = Findings()
    for index, sub in ((0x1000, 0), (0x1001, 0), (0x1018, 0), (0x1018, 1)):
        if ctx.eds.entry(index, sub) is None:
            findings.add(f"0x{index:04X}:{sub:02X} is mandatory and the EDS does not describe it")
        try:
            ctx.upload(index, sub)
        except SdoError as e:
            findings.add(f"0x{index:04X}:{sub:02X} is mandatory: {e.reason}", e.frames)
    findings.raise_if_any("mandatory entries missing")
    return None


@check("od.readable-entries", clause="CiA 306 (object descriptions), CiA 301 v4.2.0 §7.1 (data types and their encoding)",
       summary="every readable entry the EDS lists uploads, with the size of its data type (abort 0x08000024, no "
               "data available, counts as existing: an error history entry above 0x1003:00)")
def readable_entries(ctx: "Context") -> Optional[str]:
    entries = [e for e in ctx.eds.entries() if e.readable]
    if not entries:
        raise NotApplicable("the EDS lists no readable entry")
    findings = Findings()
    for entry, data in _upload_all(ctx, entries, findings):
        if entry.size is not None and len(data) != entry.size:
            findings.add(f"{entry}: {len(data)} byte(s) uploaded, its type has {entry.size}", ctx.sdo.frames)
    findings.raise_if_any(f"of {len(entries)} readable entries wrong")
    return f"{len(entries)} entries"


def _compared(entry: eds_module.Entry) -> bool:
    if entry.value is None or not entry.readable or entry.data_type == 0x0F:
        return False
    if (entry.index, None) in INSTANCE_VALUES or (entry.index, entry.sub) in INSTANCE_VALUES:
        return False
    return entry.access == "const" or (entry.access == "ro" and 0x1000 <= entry.index <= 0x1FFF)


@check("od.default-values", clause="CiA 306 (DefaultValue, ParameterValue, $NODEID)",
       summary="const entries, and read-only entries of the communication area (0x1000..0x1FFF), hold the EDS "
               "value (a DCF's ParameterValue, else DefaultValue; $NODEID at the node-ID)")
def default_values(ctx: "Context") -> Optional[str]:
    entries = [e for e in ctx.eds.entries() if _compared(e)]
    if not entries:
        raise NotApplicable("the EDS gives no value of a const or read-only communication entry")
    findings = Findings()
    for entry, data in _upload_all(ctx, entries, findings):
        actual = eds_module.decode(data, entry.data_type)
        assert entry.value is not None
        if not eds_module.same_value(entry.value, actual):
            relative = f" ($NODEID = {ctx.node})" if entry.node_relative else ""
            findings.add(f"{entry}: holds {_show(actual)}, the EDS says {entry.value_text!r}{relative} = "
                         f"{_show(entry.value)}", ctx.sdo.frames)
    findings.raise_if_any(f"of {len(entries)} entries differ from the EDS")
    return f"{len(entries)} entries compared"


def _show(value: object) -> str:
    if isinstance(value, int) and not isinstance(value, bool):
        return f"{value} (0x{value & 0xFFFFFFFFFFFFFFFF:X})" if value >= 0 else str(value)
    return repr(value)


def _expect_abort(ctx: "Context", index: int, sub: int, code: int, findings: Findings, what: str,
                  data: Optional[bytes] = None) -> None:
    try:
        if data is None:
            ctx.upload(index, sub)
        else:
            ctx.sdo.download(index, sub, data, segmented=not data)  # nothing cannot go expedited
        findings.add(f"0x{index:04X}:{sub:02X} ({what}): {'written' if data is not None else 'uploaded'} "
                     f"without an abort, expected {abort_text(code)}", ctx.sdo.frames)
    except SdoAbort as e:
        if e.code != code:
            findings.add(f"0x{index:04X}:{sub:02X} ({what}): aborted with {abort_text(e.code)}, expected "
                         f"{abort_text(code)}", e.frames)
    except SdoError as e:
        findings.add(f"0x{index:04X}:{sub:02X} ({what}): {e.reason}", e.frames)


@check("od.missing-object", clause="CiA 301 v4.2.0 §7.2.4.3.17 (abort 0x06020000)",
       summary="an object the EDS does not list answers abort 0x06020000")
def missing_object(ctx: "Context") -> Optional[str]:
    index = next((i for i in UNLISTED_CANDIDATES if i not in ctx.eds.objects), None)
    if index is None:
        raise NotApplicable("the EDS lists every candidate index")
    findings = Findings()
    _expect_abort(ctx, index, 0, ABORT_NO_OBJECT, findings, "not in the EDS")
    findings.raise_if_any("wrong answers")
    return f"0x{index:04X}"


@check("od.missing-subindex", clause="CiA 301 v4.2.0 §7.2.4.3.17 (abort 0x06090011)",
       summary="a sub-index the EDS does not list answers abort 0x06090011: one past the highest of a record or "
               "array, and sub-index 1 of a variable")
def missing_subindex(ctx: "Context") -> Optional[str]:
    findings = Findings()
    tried = []
    record = ctx.eds.objects.get(0x1018)
    if record is None or record.is_var:
        record = next((o for o in ctx.eds.objects.values() if not o.is_var and o.entries), None)
    if record is not None and max(record.entries) < 0xFE:
        tried.append((record.index, max(record.entries) + 1, "a record's sub-index past its highest"))
    var = ctx.eds.objects.get(0x1000)
    if var is None or not var.is_var:
        var = next((o for o in ctx.eds.objects.values() if o.is_var and o.entries[0].readable), None)
    if var is not None:
        tried.append((var.index, 1, "sub-index 1 of a variable"))
    if not tried:
        raise NotApplicable("the EDS has no object to try")
    for index, sub, what in tried:
        _expect_abort(ctx, index, sub, ABORT_NO_SUBINDEX, findings, what)
    findings.raise_if_any("wrong answers")
    return ", ".join(f"0x{i:04X}:{s:02X}" for i, s, _ in tried)


@check("od.write-only-refuses-read", clause="CiA 301 v4.2.0 §7.2.4.3.17 (abort 0x06010001)",
       summary="every write-only entry refuses an upload with abort 0x06010001")
def write_only_refuses_read(ctx: "Context") -> Optional[str]:
    entries = [e for e in ctx.eds.entries() if e.access == "wo"]
    if not entries:
        raise NotApplicable("the EDS lists no write-only entry")
    findings = Findings()
    for entry in entries:
        _expect_abort(ctx, entry.index, entry.sub, ABORT_WRITE_ONLY, findings, "write-only")
    findings.raise_if_any(f"of {len(entries)} write-only entries answer wrong")
    return f"{len(entries)} entries"


@check("od.read-only-refuses-write", clause="CiA 301 v4.2.0 §7.2.4.3.17 (abort 0x06010002)",
       summary="every read-only and const entry refuses a download of its own current value with abort 0x06010002 "
               "(its own value: a device that wrongly takes it is left as it was)", writes=True)
def read_only_refuses_write(ctx: "Context") -> Optional[str]:
    entries = [e for e in ctx.eds.entries() if e.access in ("ro", "const")]
    if not entries:
        raise NotApplicable("the EDS lists no read-only entry")
    findings = Findings()
    for entry, data in _upload_all(ctx, entries, findings):
        _expect_abort(ctx, entry.index, entry.sub, ABORT_READ_ONLY, findings, "read-only", data)
    findings.raise_if_any(f"of {len(entries)} read-only entries answer wrong")
    return f"{len(entries)} entries"



ABORT_TYPE_LENGTH, ABORT_TOO_LONG, ABORT_TOO_SHORT = 0x06070010, 0x06070012, 0x06070013
ABORT_TOO_HIGH, ABORT_TOO_LOW = 0x06090031, 0x06090032
#: Store and restore parameters: a write there stores or restores (or is refused by its signature), not a value.
NOT_WRITTEN = (0x1010, 0x1011)


def _writable_with_value(ctx: "Context") -> List[Tuple[eds_module.Entry, bytes]]:
    """Readable and writable entries of a fixed-size type, with their current bytes (write-only ones have no value
    to write back, and are left out)."""
    entries = [e for e in ctx.eds.entries() if e.readable and e.writable and e.size is not None
               and e.index not in NOT_WRITTEN]
    got = []
    for entry in entries:
        try:
            got.append((entry, ctx.upload(entry.index, entry.sub)))
        except SdoError:
            continue  # od.readable-entries reports it
    return got


def _refused(ctx: "Context", entry: eds_module.Entry, data: bytes, original: bytes, codes: Tuple[int, ...],
             what: str, findings: Findings) -> None:
    """Writes ``data``, which must be refused with one of ``codes``; puts ``original`` back when it was taken."""
    try:
        ctx.sdo.download(entry.index, entry.sub, data)
    except SdoAbort as e:
        if e.code not in codes:
            findings.add(f"{entry}: {what}: aborted with {abort_text(e.code)}, expected "
                         f"{' or '.join(abort_text(c) for c in codes)}", e.frames)
        return
    except SdoError as e:
        findings.add(f"{entry}: {what}: {e.reason}", e.frames)
        return
    frames = list(ctx.sdo.frames)
    try:
        ctx.sdo.download(entry.index, entry.sub, original)
        restored = "its value put back"
    except SdoError as e:
        restored = f"putting its value back failed: {e}"
    findings.add(f"{entry}: {what}: taken, expected {' or '.join(abort_text(c) for c in codes)} ({restored})", frames)


@check("od.write-sizes", clause="CiA 301 v4.2.0 §7.2.4.3.17 (aborts 0x06070010, 0x06070012, 0x06070013)",
       summary="every writable entry of a fixed-size type refuses its own value one byte too long (types of 1..3 "
               "bytes: expedited) with 0x06070012 or 0x06070010, and one byte too short with 0x06070013 or "
               "0x06070010; put back where it was taken", writes=True)
def write_sizes(ctx: "Context") -> Optional[str]:
    entries = _writable_with_value(ctx)
    if not entries:
        raise NotApplicable("no readable and writable entry of a fixed-size type")
    findings = Findings()
    for entry, original in entries:
        if len(original) <= 3:
            _refused(ctx, entry, original + b"\0", original, (ABORT_TOO_LONG, ABORT_TYPE_LENGTH), "one byte too long",
                     findings)
        if len(original) >= 2:
            _refused(ctx, entry, original[:-1], original, (ABORT_TOO_SHORT, ABORT_TYPE_LENGTH), "one byte too short",
                     findings)
    findings.raise_if_any(f"of {len(entries)} writable entries take a wrong size")
    return f"{len(entries)} entries"


def _is_mapping(index: int) -> bool:
    return 0x1600 <= index <= 0x17FF or 0x1A00 <= index <= 0x1BFF


def _limited_integers(ctx: "Context") -> List[Tuple[eds_module.Entry, bytes, int, int]]:
    """The readable and writable integer entries (not BOOLEAN) with their current bytes and their type's range: what
    the limit checks write."""
    found = []
    for entry, original in _writable_with_value(ctx):
        if entry.data_type not in eds_module.SIGNED_TYPES | eds_module.UNSIGNED_TYPES or entry.data_type == 0x01:
            continue
        bits = 8 * (entry.size or 0)
        if entry.data_type in eds_module.SIGNED_TYPES:
            found.append((entry, original, -(1 << (bits - 1)), (1 << (bits - 1)) - 1))
        else:
            found.append((entry, original, 0, (1 << bits) - 1))
    return found


@check("od.write-limits", clause="CiA 306 (LowLimit, HighLimit), CiA 301 v4.2.0 §7.2.4.3.17 (aborts 0x06090031, "
                                 "0x06090032)",
       summary="every writable integer entry with a HighLimit (LowLimit) in the EDS refuses one above it with "
               "0x06090031 (one below with 0x06090032; not 0 in a PDO mapping's count, which CiA 301's mapping "
               "procedure writes); put back where it was taken", writes=True)
def write_limits(ctx: "Context") -> Optional[str]:
    findings = Findings()
    tried = 0
    for entry, original, type_low, type_high in _limited_integers(ctx):
        for limit, step, code, what in ((entry.high, 1, ABORT_TOO_HIGH, "above HighLimit"),
                                        (entry.low, -1, ABORT_TOO_LOW, "below LowLimit")):
            if not isinstance(limit, int) or not type_low <= limit + step <= type_high:
                continue
            if limit + step == 0 and entry.sub == 0 and _is_mapping(entry.index):
                continue  # 0 in a mapping's count is CiA 301's first step of every mapping change (§7.5.2.36/38)
            tried += 1
            value = limit + step
            _refused(ctx, entry, eds_module.encode(value, entry.data_type), original, (code,),
                     f"{value} ({what} {limit})", findings)
    if not tried:
        raise NotApplicable("no writable integer entry has a limit inside its type's range")
    findings.raise_if_any("limits not kept")
    return f"{tried} limits"


#: Objects whose writes have preconditions beyond the value (CiA 301: a PDO's parameters and mapping change only
#: while it is invalid, an SDO server's COB-IDs likewise): a refusal of a limit there says nothing about the limit.
STATEFUL_AREAS = ((0x1200, 0x12FF), (0x1400, 0x1BFF))
#: Aborts that say the value is out of range: a refusal of the entry's own limit with one of these fails the check;
#: another abort (the device's state, 0x0800002x; parameters that do not fit together, 0x06040043) is noted only.
ABORT_VALUE_RANGE = (0x06090030, ABORT_TOO_HIGH, ABORT_TOO_LOW, 0x06090036)


@check("od.takes-limits", clause="CiA 306 (LowLimit, HighLimit), CiA 301 v4.2.0 §7.2.4.3.17 (aborts 0x06090030..32)",
       summary="every writable integer entry with a LowLimit or HighLimit in the EDS takes each limit itself (not "
               "refused as out of range), and its value is put back after each (PDO and SDO parameters left out: "
               "their writes have preconditions)", writes=True)
def takes_limits(ctx: "Context") -> Optional[str]:
    findings = Findings()
    tried = 0
    notes = []
    for entry, original, type_low, type_high in _limited_integers(ctx):
        if any(low <= entry.index <= high for low, high in STATEFUL_AREAS):
            continue
        for limit, what in ((entry.low, "LowLimit"), (entry.high, "HighLimit")):
            if not isinstance(limit, int) or not type_low <= limit <= type_high:
                continue
            tried += 1
            try:
                ctx.sdo.download(entry.index, entry.sub, eds_module.encode(limit, entry.data_type))
            except SdoAbort as e:
                if e.code in ABORT_VALUE_RANGE:
                    findings.add(f"{entry}: its {what} {limit} refused with {abort_text(e.code)}", e.frames)
                else:
                    notes.append(f"{entry}: {what} {limit} refused with {abort_text(e.code)} (not a range abort)")
                continue
            except SdoError as e:
                findings.add(f"{entry}: its {what} {limit}: {e.reason}", e.frames)
                continue
            try:
                ctx.sdo.download(entry.index, entry.sub, original)
            except SdoError as e:
                findings.add(f"{entry}: its value could not be put back after {what} {limit}: {e}", e.frames)
    if not tried:
        raise NotApplicable("no writable integer entry (but PDO and SDO parameters) has a limit in its type's range")
    findings.raise_if_any("limits refused")
    return f"{tried} limits taken" + (f"; {'; '.join(notes)}" if notes else "")
