"""PDO checks (CiA 301 v4.2.0 §7.2.2 PDO, §7.5.2.35-38 PDO communication and mapping parameters).

The mappings the node holds (read only); with --write the TPDOs seen on the bus, the mapping procedure, the
inhibit time. The RPDO checks are in rpdo.py. Left for later (docs/conformance.md "Not yet checked"): type 0
TPDOs."""
from __future__ import annotations

from typing import TYPE_CHECKING, List, Optional

from .registry import Failed, Findings, NotApplicable, check
from .sdo import SdoError

if TYPE_CHECKING:
    from .runner import Context

MAPPING_AREAS = ((0x1600, "RPDO"), (0x1A00, "TPDO"))
#: A mapping count that makes the PDO a multiplexed PDO (CiA 301 §7.2.3, §7.5.2.36/38): its frame is 8 bytes, an
#: address and an object's value, whatever the entries say.
MPDO_COUNTS = {0xFE: "SAM-MPDO", 0xFF: "DAM-MPDO"}


@check("pdo.mappings", clause="CiA 301 v4.2.0 §7.5.2.36 / §7.5.2.38 (RPDO / TPDO mapping parameter), §7.2.2 "
                              "(PDO: at most 8 bytes)",
       summary="every PDO mapping the node holds names an entry of the EDS that may be mapped (PDOMapping=1, or a "
               "dummy of [DummyUsage]) with its type's length, 64 bits at most in all (an MPDO's, count 0xFE/0xFF, "
               "is not judged)")
def mappings(ctx: "Context") -> Optional[str]:
    findings = Findings()
    seen = 0
    mpdos: List[str] = []
    for base, kind in MAPPING_AREAS:
        for index in range(base, base + 0x200):
            if index not in ctx.eds.objects:
                continue
            seen += 1
            try:
                count = ctx.upload(index, 0)[0]
            except SdoError as e:
                findings.add(f"0x{index:04X}:00: {e.reason}", e.frames)
                continue
            if count in MPDO_COUNTS:
                mpdos.append(f"0x{index:04X} {MPDO_COUNTS[count]}")
                continue  # an MPDO's frame carries its own multiplexer: no mapping to judge here
            if count > 64:
                findings.add(f"0x{index:04X}:00 = {count}: more than 64 entries", ctx.sdo.frames)
                continue
            bits = 0
            for sub in range(1, count + 1):
                try:
                    value = int.from_bytes(ctx.upload(index, sub), "little")
                except SdoError as e:
                    findings.add(f"0x{index:04X}:{sub:02X}: {e.reason}", e.frames)
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
    return f"{seen} mapping parameter(s)" + (f"; MPDO: {', '.join(mpdos)}" if mpdos else "")


def _mapped_bytes(ctx: "Context", mapping_index: int) -> int:
    """The bytes a PDO of this mapping carries (the mapped bits rounded up)."""
    count = ctx.upload(mapping_index, 0)[0]
    if count in MPDO_COUNTS:
        return 8  # an MPDO frame: multiplexer and value, always 8 bytes
    bits = sum(int.from_bytes(ctx.upload(mapping_index, sub), "little") & 0xFF for sub in range(1, count + 1))
    return (bits + 7) // 8


@check("pdo.tpdo-frames", clause="CiA 301 v4.2.0 §7.2.2 (PDO: transmission types, event timer, RTR), §7.5.2.37 "
                                 "(TPDO communication parameter)",
       summary="in Operational, each valid TPDO comes on its COB-ID with the length of its mapping: by its event "
               "timer (types 254/255), after as many SYNCs as its type (1..240), or on a remote request where its "
               "COB-ID allows one (bit 30 clear)", writes=True)
def tpdo_frames(ctx: "Context") -> Optional[str]:
    from .nmt import BACK_TO, current_state, fast_heartbeat  # noqa: PLC0415: nmt's helpers, only here
    tpdos = [i for i in sorted(ctx.eds.objects) if 0x1800 <= i <= 0x19FF and i + 0x200 in ctx.eds.objects]
    if not tpdos:
        raise NotApplicable("the EDS lists no TPDO with a mapping")
    plans = []
    with ctx.exchange():
        sync_id = int.from_bytes(ctx.upload(0x1005, 0), "little") & 0x7FF if 0x1005 in ctx.eds.objects else 0x080
        for index in tpdos:
            cob = int.from_bytes(ctx.upload(index, 1), "little")
            if cob & 0x80000000 or cob & 0x20000000:
                continue  # not valid, or an extended frame
            kind = ctx.upload(index, 2)[0]
            timer = (int.from_bytes(ctx.upload(index, 5), "little") if ctx.eds.entry(index, 5) is not None else 0)
            size = _mapped_bytes(ctx, index + 0x200)
            plans.append((index, cob & 0x7FF, kind, timer, not cob & 0x40000000, size))
    if not plans:
        raise NotApplicable("no TPDO is valid")
    period_s = fast_heartbeat(ctx)
    state = current_state(ctx, period_s)
    ctx.on_exit(lambda: ctx.nmt(BACK_TO[state]) and None)
    ctx.nmt("start")
    findings = Findings()
    judged = []
    for index, cob, kind, timer, rtr_allowed, size in plans:
        ctx.log.drain()
        if kind in (254, 255) and timer:
            how, wait = f"event timer {timer} ms", timer / 1000 * 1.5 + ctx.options.timeout
        elif 1 <= kind <= 240:
            for _ in range(kind):
                ctx.log.send(sync_id, b"")
            how, wait = f"type {kind}, {kind} SYNC(s)", ctx.options.timeout
        elif rtr_allowed and kind in (252, 253, 254, 255):
            ctx.log.send(cob, b"", rtr=True, dlc=size)
            how, wait = "remote request", ctx.options.timeout
        else:
            continue  # type 0 or an event-driven TPDO without a timer: sent when the application decides
        frame = ctx.log.wait_for(lambda f, cob=cob: f.can_id == cob and not f.rtr, wait)
        where = f"TPDO 0x{index:04X} on 0x{cob:03X} ({how})"
        if frame is None:
            findings.add(f"{where}: none within {wait:.1f} s", list(ctx.log.trace[-20:]))
        elif len(frame.data) != size:
            findings.add(f"{where}: {len(frame.data)} byte(s), its mapping has {size}", [frame])
        else:
            judged.append(f"0x{index:04X}")
    if not judged and not findings:
        raise NotApplicable("no TPDO has an event timer, a synchronous type or a remote request to trigger it")
    findings.raise_if_any("TPDOs wrong")
    return ", ".join(judged)


ABORT_NOT_MAPPABLE, ABORT_PDO_LENGTH = 0x06040041, 0x06040042


def _u32(value: int) -> bytes:
    return value.to_bytes(4, "little")


@check("pdo.mapping-procedure", clause="CiA 301 v4.2.0 §7.5.2.36 / §7.5.2.38 (the mapping procedure), §7.2.4.3.17 "
                                       "(aborts 0x06040041, 0x06040042)",
       summary="on the first PDO whose COB-ID and mapping are writable: the mapping is refused while the PDO is "
               "valid; made invalid with its count 0, an entry that may not be mapped is refused with 0x06040041 "
               "and more than 64 bits with 0x06040042; the PDO put back as it was", writes=True)
def mapping_procedure(ctx: "Context") -> Optional[str]:
    from .sdo import SdoAbort, abort_text  # noqa: PLC0415
    chosen = None
    for comm in [i for i in sorted(ctx.eds.objects) if 0x1800 <= i <= 0x19FF] + \
            [i for i in sorted(ctx.eds.objects) if 0x1400 <= i <= 0x15FF]:
        cob_entry, count_entry = ctx.eds.entry(comm, 1), ctx.eds.entry(comm + 0x200, 0)
        if cob_entry is not None and count_entry is not None and cob_entry.writable and count_entry.writable:
            chosen = comm
            break
    if chosen is None:
        raise NotApplicable("no PDO whose COB-ID and mapping are writable (static mapping)")
    mapping = chosen + 0x200
    transmit = chosen >= 0x1800
    not_mappable = next((e for e in ctx.eds.entries() if not e.pdo_mapping and e.size and e.readable
                         and e.index >= 0x1000), None)
    mappable = next((e for e in ctx.eds.entries() if e.pdo_mapping and e.size and 2 <= e.size <= 4
                     and (e.readable if transmit else e.writable)), None)
    with ctx.exchange():
        cob = int.from_bytes(ctx.upload(chosen, 1), "little")
        count = ctx.upload(mapping, 0)[0]
        # every entry the EDS lists, those above the count too: the check writes some of them
        entries = {sub: ctx.upload(mapping, sub) for sub in sorted(ctx.eds.objects[mapping].entries) if sub}

    notes = []

    def put_back() -> None:  # the procedure again, to the values found
        ctx.sdo.download(chosen, 1, _u32(cob | 0x80000000))
        ctx.sdo.download(mapping, 0, b"\0")
        for sub, value in entries.items():
            try:
                ctx.sdo.download(mapping, sub, value)
            except SdoAbort as e:
                if sub <= count:
                    raise
                # above the count, a value the device took from its own configuration that a master may not
                # write (docs/decisions.md "Mapping entries above the count"): it maps nothing; left empty
                ctx.sdo.download(mapping, sub, b"\0\0\0\0")
                ctx.notes.append(f"0x{mapping:04X}:{sub:02X} (above the count) left 0, its 0x"
                             f"{int.from_bytes(value, 'little'):08X} refused: {abort_text(e.code)}")
        ctx.sdo.download(mapping, 0, bytes([count]))
        ctx.sdo.download(chosen, 1, _u32(cob))
    ctx.on_exit(put_back)

    findings = Findings()
    what = f"{'TPDO' if transmit else 'RPDO'} 0x{chosen:04X}/0x{mapping:04X}"
    if not cob & 0x80000000:
        try:
            ctx.sdo.download(mapping, 0, bytes([count]))
            findings.add(f"{what}: its count written while the PDO is valid was taken", ctx.sdo.frames)
        except SdoAbort as e:
            notes.append(f"valid: refused with {abort_text(e.code)}")
    with ctx.exchange():
        ctx.sdo.download(chosen, 1, _u32(cob | 0x80000000))
        ctx.sdo.download(mapping, 0, b"\0")
    steps = []
    if not_mappable is not None:
        steps.append(([(1, not_mappable.index << 16 | not_mappable.sub << 8 | not_mappable.size * 8)], None,
                      ABORT_NOT_MAPPABLE, f"{not_mappable} mapped"))
    if mappable is not None and mappable.size:
        times = 64 // (mappable.size * 8) + 1
        if ctx.eds.entry(mapping, times) is not None:
            value = mappable.index << 16 | mappable.sub << 8 | mappable.size * 8
            steps.append(([(sub, value) for sub in range(1, times + 1)], times, ABORT_PDO_LENGTH,
                          f"{mappable} mapped {times} times ({times * mappable.size * 8} bits)"))
    if not steps:
        raise NotApplicable(f"{what}: the EDS has no entry to map wrongly")
    for writes, new_count, code, description in steps:
        ctx.sdo.download(mapping, 0, b"\0")
        try:
            for sub, value in writes:
                ctx.sdo.download(mapping, sub, _u32(value))
            if new_count is not None:
                ctx.sdo.download(mapping, 0, bytes([new_count]))
            findings.add(f"{what}: {description}: taken, expected {abort_text(code)}", ctx.sdo.frames)
        except SdoAbort as e:
            if e.code != code:
                findings.add(f"{what}: {description}: aborted with {abort_text(e.code)}, expected "
                             f"{abort_text(code)}", e.frames)
    findings.raise_if_any("mapping rules not kept")
    return "; ".join([what] + notes)


#: The inhibit time and event timer pdo.tpdo-inhibit-time sets: a timer well inside the inhibit time, so that
#: without the inhibit time the frames would come every TIMER ms.
INHIBIT_100US, TIMER_MS, WATCH_S = 2000, 50, 1.3
#: How much closer than the inhibit time two frames' receive time stamps may be (the receive side's jitter): this
#: tool's allowance, CiA 301 has none. 10 % (20 ms of 200): one frame received 5 ms late on a loaded machine made the
#: next 197 ms after it with 2 ms allowed; an inhibit time not kept shows at the event timer's pace, 50 ms.
INHIBIT_TOLERANCE_S = 0.1 * INHIBIT_100US / 10000.0


@check("pdo.tpdo-inhibit-time", clause="CiA 301 v4.2.0 §7.2.2 (PDO: inhibit time, event timer), §7.5.2.37 "
                                       "(TPDO communication parameter, sub-indexes 3 and 5)",
       summary="on the first valid event-driven TPDO (type 254/255) whose COB-ID, inhibit time and event timer are "
               "writable: set to a 200 ms inhibit time (while not valid, as CiA 301 asks) and a 50 ms event timer, "
               "in Operational its frames come no closer than 200 ms by their receive time stamps; put back after",
       writes=True)
def tpdo_inhibit_time(ctx: "Context") -> Optional[str]:
    from .nmt import BACK_TO, current_state, fast_heartbeat  # noqa: PLC0415: nmt's helpers, only here
    chosen = None
    with ctx.exchange():
        for comm in [i for i in sorted(ctx.eds.objects) if 0x1800 <= i <= 0x19FF and i + 0x200 in ctx.eds.objects]:
            entries = [ctx.eds.entry(comm, sub) for sub in (1, 2, 3, 5)]
            if any(e is None or not e.readable for e in entries) or not all(
                    e is not None and e.writable for e in (entries[0], entries[2], entries[3])):
                continue
            cob = int.from_bytes(ctx.upload(comm, 1), "little")
            if cob & 0xA0000000 or ctx.upload(comm, 2)[0] not in (254, 255):
                continue
            chosen = (comm, cob, ctx.upload(comm, 3), ctx.upload(comm, 5))
            break
    if chosen is None:
        raise NotApplicable("no valid event-driven TPDO whose COB-ID, inhibit time and event timer are writable")
    comm, cob, inhibit, timer = chosen
    where = f"TPDO 0x{comm:04X} on 0x{cob & 0x7FF:03X}"
    period_s = fast_heartbeat(ctx)
    state = current_state(ctx, period_s)
    ctx.on_exit(lambda: ctx.nmt(BACK_TO[state]) and None)

    def put_back() -> None:  # the inhibit time changes only while the PDO is not valid (CiA 301 §7.5.2.37)
        ctx.sdo.download(comm, 1, _u32(cob | 0x80000000))
        ctx.sdo.download(comm, 3, inhibit)
        ctx.sdo.download(comm, 1, _u32(cob))
        ctx.sdo.download(comm, 5, timer)
    ctx.on_exit(put_back)
    with ctx.exchange():
        ctx.sdo.download(comm, 1, _u32(cob | 0x80000000))
        ctx.sdo.download(comm, 3, INHIBIT_100US.to_bytes(2, "little"))
        ctx.sdo.download(comm, 1, _u32(cob))
        ctx.sdo.download(comm, 5, TIMER_MS.to_bytes(2, "little"))
    ctx.nmt("start")
    frames = ctx.log.collect(lambda f: f.can_id == cob & 0x7FF and not f.rtr, WATCH_S)
    inhibit_s = INHIBIT_100US / 10000
    if len(frames) < 2:
        raise Failed(f"{where} (inhibit time {inhibit_s * 1000:.0f} ms, event timer {TIMER_MS} ms): "
                     f"{len(frames)} frame(s) in {WATCH_S} s", list(ctx.log.trace[-20:]))
    intervals = [b.time - a.time for a, b in zip(frames, frames[1:])]
    close = [(i, t) for i, t in enumerate(intervals) if t < inhibit_s - INHIBIT_TOLERANCE_S]
    shown = ", ".join(f"{t * 1000:.1f}" for t in intervals)
    if close:
        first = close[0][0]
        raise Failed(f"{where}: inhibit time {inhibit_s * 1000:.0f} ms, event timer {TIMER_MS} ms: frames "
                     f"{shown} ms apart", frames[first:first + 2])
    return f"{where}: inhibit time {inhibit_s * 1000:.0f} ms, event timer {TIMER_MS} ms: intervals {shown} ms"
