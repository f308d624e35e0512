"""RPDO checks (CiA 301 v4.2.0 §7.2.2 PDO, §7.5.2.35-36 RPDO communication and mapping parameters, §7.2.7 EMCY):
an RPDO sent in Operational and its mapped entries read back over SDO; an RPDO of the wrong length answered by
EMCY 0x8210 and, after a correct one, the error reset (EMCY 0x0000).

Both send RPDO frames, which write the node's mapped entries: they run only with --write, only on an RPDO whose
every mapped entry is readable (so that the frame can carry the values the node holds), and put back what they
changed (the value, by SDO download; the NMT state)."""
from __future__ import annotations

from dataclasses import dataclass
from typing import TYPE_CHECKING, Dict, List, Optional, Tuple, Union

from . import eds as eds_module
from .frames import Frame
from .registry import Failed, Findings, NotApplicable, check
from .sdo import SdoError

if TYPE_CHECKING:
    from .runner import Context

MPDO_COUNTS = (0xFE, 0xFF)
EMCY_LENGTH_ERROR, EMCY_ERROR_RESET = 0x8210, 0x0000


@dataclass
class Rpdo:
    comm: int                              # 0x1400 + n
    cob: int                               # its 11-bit CAN-ID
    kind: int                              # transmission type: 0..240 synchronous, 254/255 event-driven
    entries: List[Tuple[int, int, int]]    # (index, sub, bytes) of each mapped entry; index 1..7: a dummy
    values: Dict[Tuple[int, int], bytes]   # the values the node held when the check began

    @property
    def name(self) -> str:
        return f"RPDO 0x{self.comm:04X} on 0x{self.cob:03X}"

    def frame(self, changed: Optional[Dict[Tuple[int, int], bytes]] = None) -> bytes:
        """The frame's data: each mapped entry's value (``changed``'s where it has one), a dummy's zeros."""
        data = b""
        for index, sub, size in self.entries:
            value = (changed or {}).get((index, sub), self.values.get((index, sub), bytes(size)))
            data += value[:size].ljust(size, b"\0")
        return data


def rpdos(ctx: "Context") -> Tuple[List[Rpdo], List[str]]:
    """The valid RPDOs whose mapped entries are all readable, with their values; why the others are left out."""
    found, left_out = [], []
    for comm in [i for i in sorted(ctx.eds.objects) if 0x1400 <= i <= 0x15FF and i + 0x200 in ctx.eds.objects]:
        with ctx.exchange():
            cob = int.from_bytes(ctx.upload(comm, 1), "little")
            if cob & 0xA0000000:
                continue  # not valid, or an extended frame
            kind = ctx.upload(comm, 2)[0]
            count = ctx.upload(comm + 0x200, 0)[0]
            if count == 0 or count in MPDO_COUNTS or count > 64:
                left_out.append(f"0x{comm:04X}: mapping count {count}")
                continue
            mapped = [int.from_bytes(ctx.upload(comm + 0x200, sub), "little") for sub in range(1, count + 1)]
        entries, values, why = [], {}, None
        for value in mapped:
            index, sub, bits = value >> 16, (value >> 8) & 0xFF, value & 0xFF
            if bits % 8:
                why = f"0x{index:04X}:{sub:02X} mapped with {bits} bits"
                break
            entries.append((index, sub, bits // 8))
            if 0x0001 <= index <= 0x0007:
                continue  # a dummy: its bytes are ignored
            entry = ctx.eds.entry(index, sub)
            if entry is None or not entry.readable:
                why = f"0x{index:04X}:{sub:02X} is {'not in the EDS' if entry is None else entry.access}"
                break
            with ctx.exchange():
                values[(index, sub)] = ctx.upload(index, sub)
        if why is not None or sum(size for _, _, size in entries) > 8:
            left_out.append(f"0x{comm:04X}: {why or 'more than 8 bytes'}")
            continue
        found.append(Rpdo(comm, cob & 0x7FF, kind, entries, values))
    return found, left_out


def operational(ctx: "Context") -> None:
    """Starts the node; its NMT state (from the heartbeat) is put back when the check ends."""
    from .nmt import BACK_TO, current_state, fast_heartbeat  # noqa: PLC0415: nmt's helpers
    state = current_state(ctx, fast_heartbeat(ctx))
    ctx.on_exit(lambda: ctx.nmt(BACK_TO[state]) and None)
    ctx.nmt("start")


def send_rpdo(ctx: "Context", rpdo: Rpdo, data: bytes) -> Frame:
    """The RPDO frame, and a SYNC after it where the RPDO is synchronous (its data takes effect at the SYNC)."""
    frame = ctx.log.send(rpdo.cob, data)
    if rpdo.kind <= 240:
        sync = ctx.upload(0x1005, 0) if 0x1005 in ctx.eds.objects else (0x80).to_bytes(4, "little")
        ctx.log.send(int.from_bytes(sync, "little") & 0x7FF, b"")
    return frame


def changed_value(entry: eds_module.Entry, data: bytes) -> Optional[bytes]:
    """Another value of the entry within its type and its EDS limits (the value + 1, else - 1; a BOOLEAN's other
    value), or None for a type this check does not change."""
    value = eds_module.decode(data, entry.data_type)
    if entry.data_type == 0x01 and isinstance(value, int):
        return eds_module.encode(1 - (value & 1), 0x01)
    size = entry.size
    if isinstance(value, bool) or not isinstance(value, (int, float)) or not size:
        return None
    if entry.data_type in eds_module.SIGNED_TYPES:
        low, high = -(1 << (8 * size - 1)), (1 << (8 * size - 1)) - 1
    elif entry.data_type in eds_module.UNSIGNED_TYPES:
        low, high = 0, (1 << (8 * size)) - 1
    elif entry.data_type in eds_module.REAL_TYPES:
        low, high = -1e30, 1e30
    else:
        return None
    low = max(low, entry.low) if entry.low is not None else low
    high = min(high, entry.high) if entry.high is not None else high
    for candidate in (value + 1, value - 1):
        if low <= candidate <= high:
            return eds_module.encode(candidate, entry.data_type)
    return None


def _same(entry: Optional[eds_module.Entry], expected: bytes, actual: bytes) -> bool:
    if entry is None:
        return expected == actual
    return eds_module.same_value(eds_module.decode(expected, entry.data_type),
                                 eds_module.decode(actual, entry.data_type))


def _read_back(ctx: "Context", rpdo: Rpdo, expected: Dict[Tuple[int, int], bytes]) \
        -> List[Tuple[Tuple[int, int], bytes, Union[bytes, SdoError]]]:
    """The mapped entries that do not hold what the frame carried (an SDO error in place of the value), asked again
    until ``--timeout`` has passed: the node applies an RPDO in its own time."""
    import time  # noqa: PLC0415
    deadline = time.monotonic() + ctx.options.timeout
    while True:
        wrong: List[Tuple[Tuple[int, int], bytes, Union[bytes, SdoError]]] = []
        for key, value in expected.items():
            try:
                actual: Union[bytes, SdoError] = ctx.upload(*key)
            except SdoError as e:
                actual = e
            if isinstance(actual, SdoError) or not _same(ctx.eds.entry(*key), value, actual):
                wrong.append((key, value, actual))
        if not wrong or time.monotonic() > deadline or any(isinstance(a, SdoError) for _, _, a in wrong):
            return wrong
        time.sleep(0.02)


@check("pdo.rpdo-write-read", clause="CiA 301 v4.2.0 §7.2.2 (PDO: an RPDO writes its mapped objects), §7.5.2.35 / "
                                     "§7.5.2.36 (RPDO communication and mapping parameter)",
       summary="in Operational, each valid RPDO whose mapped entries are readable is sent with their values, one "
               "writable entry changed (+1, within its limits), and the entries read back over SDO hold them; the "
               "changed value is put back", writes=True)
def rpdo_write_read(ctx: "Context") -> Optional[str]:
    found, left_out = rpdos(ctx)
    if not found:
        raise NotApplicable("no valid RPDO whose mapped entries are all readable"
                            + (f" ({'; '.join(left_out)})" if left_out else ""))
    operational(ctx)
    findings = Findings()
    judged = []
    for rpdo in found:
        changed: Dict[Tuple[int, int], bytes] = {}
        for index, sub, size in rpdo.entries:
            entry = ctx.eds.entry(index, sub)
            if entry is not None and entry.writable and entry.size == size and not changed:
                other = changed_value(entry, rpdo.values[(index, sub)])
                if other is not None:
                    changed[(index, sub)] = other
                    old = rpdo.values[(index, sub)]
                    ctx.on_exit(lambda index=index, sub=sub, old=old: ctx.sdo.download(index, sub, old))
        expected = {key: changed.get(key, value) for key, value in rpdo.values.items()}
        ctx.log.drain()
        send_rpdo(ctx, rpdo, rpdo.frame(changed))
        for (index, sub), value, actual in _read_back(ctx, rpdo, expected):
            where = f"{rpdo.name}: 0x{index:04X}:{sub:02X}"
            if isinstance(actual, SdoError):
                findings.add(f"{where}: read back: {actual.reason}", actual.frames)
            else:
                findings.add(f"{where} holds {actual.hex(' ')}, the RPDO carried {value.hex(' ')}",
                             list(ctx.log.trace[-12:]))
        what = ", ".join(f"0x{i:04X}:{s:02X} changed" for i, s in changed) or "its values unchanged"
        judged.append(f"0x{rpdo.comm:04X} ({what})")
    findings.raise_if_any("RPDOs not written")
    return "; ".join(judged)


@check("pdo.rpdo-length-error", clause="CiA 301 v4.2.0 §7.2.2 (PDO length: EMCY 0x8210), §7.2.7 (EMCY: error "
                                       "reset 0x0000), §7.5.2.4 (0x1003), §7.5.2.17 (0x1014)",
       summary="an RPDO one byte shorter than its mapping is answered by an EMCY 0x8210 on the COB-ID of 0x1014 "
               "(the generic bit set in its error register), logged in 0x1003:01 where the EDS lists 0x1003; the "
               "next correct RPDO (the node's own values) by the error reset EMCY 0x0000", writes=True)
def rpdo_length_error(ctx: "Context") -> Optional[str]:
    if ctx.eds.entry(0x1014) is None:
        raise NotApplicable("the EDS has no 0x1014 (the node sends no EMCY)")
    found, left_out = rpdos(ctx)
    if not found:
        raise NotApplicable("no valid RPDO whose mapped entries are all readable"
                            + (f" ({'; '.join(left_out)})" if left_out else ""))
    rpdo = found[0]
    data = rpdo.frame()
    with ctx.exchange():
        emcy = int.from_bytes(ctx.upload(0x1014, 0), "little")
        inhibit_s = (int.from_bytes(ctx.upload(0x1015, 0), "little") / 10000
                     if ctx.eds.entry(0x1015) is not None else 0.0)
    if emcy & 0x80000000:
        raise NotApplicable(f"0x1014 = 0x{emcy:08X}: EMCY not valid")
    emcy &= 0x7FF
    wait = ctx.options.timeout + inhibit_s

    def emcy_with(code: int) -> Optional[Frame]:
        return ctx.log.wait_for(lambda f: f.can_id == emcy and not f.rtr and len(f.data) >= 2
                                and int.from_bytes(f.data[:2], "little") == code, wait)

    operational(ctx)
    ctx.log.drain()
    send_rpdo(ctx, rpdo, data[:-1])
    error = emcy_with(EMCY_LENGTH_ERROR)
    if error is None:
        send_rpdo(ctx, rpdo, data)  # whatever the node did, a correct frame after (it resets an error)
        raise Failed(f"{rpdo.name}: {len(data) - 1} byte(s) of its {len(data)}: no EMCY 0x8210 on 0x{emcy:03X} "
                     f"within {wait:.1f} s", list(ctx.log.trace[-20:]))
    problems = Findings()
    if len(error.data) != 8 or not error.data[2] & 0x01:
        problems.add(f"the EMCY {error.data.hex(' ')}: 8 bytes with the error register's generic bit 0 set "
                     "expected", [error])
    history = "no 0x1003"
    if 0x1003 in ctx.eds.objects:
        try:
            count, newest = ctx.upload(0x1003, 0)[0], int.from_bytes(ctx.upload(0x1003, 1), "little")
            history = f"0x1003:01 = 0x{newest:08X}"
            if count == 0 or newest & 0xFFFF != EMCY_LENGTH_ERROR:
                problems.add(f"0x1003:00 = {count}, 0x1003:01 = 0x{newest:08X}: the newest error is not 0x8210",
                             ctx.sdo.frames)
        except SdoError as e:
            problems.add(f"0x1003 (the EDS lists it): {e.reason}", e.frames)
    send_rpdo(ctx, rpdo, data)
    reset = emcy_with(EMCY_ERROR_RESET)
    if reset is None:
        problems.add(f"after a correct RPDO: no error reset EMCY (code 0x0000) on 0x{emcy:03X} within {wait:.1f} s",
                     list(ctx.log.trace[-20:]))
    problems.raise_if_any("length error handling wrong")
    # 0x1003 keeps the check's 0x8210 as its newest entry (clearing the history would lose the node's own)
    return f"{rpdo.name}: EMCY {error.data.hex(' ')}, then {reset.data.hex(' ') if reset else ''}; {history}"
