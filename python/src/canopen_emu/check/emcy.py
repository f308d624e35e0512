"""EMCY checks (CiA 301 v4.2.0 §7.2.7 emergency object, §7.5.2.2 and §7.5.2.4 error register and history, §7.5.2.17
0x1014).

Read-only. An EMCY seen on the COB-ID of 0x1014, its error reset after the error is cleared and 0x1003 holding it are
checked with an RPDO's length error (pdo.rpdo-length-error, rpdo.py). Left for later (docs/conformance.md "Not yet
checked"): 0x1001 read while an error is active, writing 0x1003:00 = 0 with --write."""
from __future__ import annotations

from typing import TYPE_CHECKING, Optional

from .registry import Failed, Findings, NotApplicable, check
from .sdo import SdoError

if TYPE_CHECKING:
    from .runner import Context


@check("emcy.cob-id", clause="CiA 301 v4.2.0 §7.5.2.17 (0x1014 COB-ID EMCY), the predefined connection set (§7.3)",
       summary="0x1014 is a valid 11-bit COB-ID (bits 29 and 30 clear); where the EDS default is $NODEID+0x80, "
               "it is 0x80 + node-ID")
def cob_id(ctx: "Context") -> Optional[str]:
    entry = ctx.eds.entry(0x1014)
    if entry is None:
        raise NotApplicable("the EDS has no 0x1014 (the node sends no EMCY)")
    with ctx.exchange():
        value = int.from_bytes(ctx.upload(0x1014, 0), "little")
    if value & 0x60000000:
        raise Failed(f"0x1014 = 0x{value:08X}: bit 29 (extended frame) or the reserved bit 30 is set",
                     ctx.sdo.frames)
    if entry.node_relative and entry.value == 0x80 + ctx.node and value != 0x80 + ctx.node:
        raise Failed(f"0x1014 = 0x{value:08X}, the EDS default {entry.value_text!r} is 0x{0x80 + ctx.node:03X}",
                     ctx.sdo.frames)
    return f"0x{value:08X}"


@check("emcy.error-history", clause="CiA 301 v4.2.0 §7.5.2.4 (0x1003 pre-defined error field)",
       summary="0x1003:00 (the number of errors) is at most the highest sub-index the EDS lists, and each of "
               "0x1003:01..count uploads")
def error_history(ctx: "Context") -> Optional[str]:
    obj = ctx.eds.objects.get(0x1003)
    if obj is None:
        raise NotApplicable("the EDS has no 0x1003 (no error history)")
    with ctx.exchange():
        count = ctx.upload(0x1003, 0)[0]
    highest = max(obj.entries)
    if count > highest:
        raise Failed(f"0x1003:00 = {count}, the EDS lists sub-indexes up to {highest}", ctx.sdo.frames)
    findings = Findings()
    for sub in range(1, count + 1):
        try:
            ctx.upload(0x1003, sub)
        except SdoError as e:
            findings.add(f"0x1003:{sub:02X}: {e.reason}", e.frames)
    findings.raise_if_any("error history entries missing")
    return f"{count} error(s) recorded"


@check("emcy.error-register", clause="CiA 301 v4.2.0 §7.5.2.2 (0x1001 error register: bit 0, generic error)",
       summary="0x1001 has bit 0 (generic error) set whenever any other bit is, and its reserved bit 6 clear")
def error_register(ctx: "Context") -> Optional[str]:
    with ctx.exchange():
        register = ctx.upload(0x1001, 0)
    if len(register) != 1:
        raise Failed(f"0x1001 has {len(register)} bytes, it is an UNSIGNED8", ctx.sdo.frames)
    value = register[0]
    if value & 0xFE and not value & 0x01:
        raise Failed(f"0x1001 = 0x{value:02X}: an error bit without the generic error bit 0", ctx.sdo.frames)
    if value & 0x40:
        raise Failed(f"0x1001 = 0x{value:02X}: bit 6 is reserved (0)", ctx.sdo.frames)
    return f"0x{value:02X}"

