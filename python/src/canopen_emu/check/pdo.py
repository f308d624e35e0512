"""PDO checks (CiA 301 v4.2.0 §7.2.2 PDO, §7.5.2.35-38 PDO communication and mapping parameters).

Only what can be judged by reading is here so far: the mappings the node holds. Left for later (docs/conformance.md
"Not yet checked"): the mapping procedure with --write (0x06040041 / 0x06040042, the COB-ID's invalid bit before a
change), a TPDO of each transmission type seen on the bus with its length, an RPDO written and read back, inhibit
time and event timer."""
from __future__ import annotations

from typing import TYPE_CHECKING, Optional

from .registry import Findings, NotApplicable, check
from .sdo import SdoError

if TYPE_CHECKING:
    from .runner import Context

MAPPING_AREAS = ((0x1600, "RPDO"), (0x1A00, "TPDO"))


@check("pdo.mappings", clause="CiA 301 v4.2.0 §7.5.2.36 / §7.5.2.38 (RPDO / TPDO mapping parameter), §7.2.2 "
                              "(PDO: at most 8 bytes)",
       summary="every PDO mapping the node holds names an entry of the EDS that may be mapped (PDOMapping=1, or a "
               "dummy of [DummyUsage]) with its type's length, 64 bits at most in all")
def mappings(ctx: "Context") -> Optional[str]:
    findings = Findings()
    seen = 0
    for base, kind in MAPPING_AREAS:
        for index in range(base, base + 0x200):
            if index not in ctx.eds.objects:
                continue
            seen += 1
            try:
                count = ctx.upload(index, 0)[0]
            except SdoError as e:
                findings.add(f"0x{index:04X}:00: {e}", e.frames)
                continue
            if count > 64:
                findings.add(f"0x{index:04X}:00 = {count}: more than 64 entries", ctx.sdo.frames)
                continue
            bits = 0
            for sub in range(1, count + 1):
                try:
                    value = int.from_bytes(ctx.upload(index, sub), "little")
                except SdoError as e:
                    findings.add(f"0x{index:04X}:{sub:02X}: {e}", e.frames)
                    continue
                mapped_index, mapped_sub, length = value >> 16, (value >> 8) & 0xFF, value & 0xFF
                bits += length
                where = f"{kind} mapping 0x{index:04X}:{sub:02X} = 0x{value:08X}"
                if 0x0001 <= mapped_index <= 0x0007:
                    if not ctx.eds.dummy_usage.get(mapped_index, False):
                        findings.add(f"{where}: dummy 0x{mapped_index:04X} not enabled in [DummyUsage]")
                    continue
                entry = ctx.eds.entry(mapped_index, mapped_sub)
                if entry is None:
                    findings.add(f"{where}: 0x{mapped_index:04X}:{mapped_sub:02X} is not in the EDS")
                    continue
                if not entry.pdo_mapping:
                    findings.add(f"{where}: {entry} is not PDO-mappable in the EDS (PDOMapping=0)")
                if entry.size is not None and entry.size * 8 != length:
                    findings.add(f"{where}: {length} bits, {entry} has {entry.size * 8}")
            if bits > 64:
                findings.add(f"0x{index:04X}: {bits} bits mapped, a PDO holds 64")
    if not seen:
        raise NotApplicable("the EDS lists no PDO mapping parameter")
    findings.raise_if_any("wrong PDO mappings")
    return f"{seen} mapping parameter(s)"
