"""NMT and error control checks (CiA 301 v4.2.0 §7.2.8 NMT, §7.2.8.3.2.2 heartbeat, §7.3.2 NMT states).

The heartbeat checks only listen. The NMT checks send commands to the node (start, stop, pre-operational, resets):
they change what a machine does, so they run only with --write, and each puts the node back into the state it found
it in. Where the heartbeat is slower than FAST_HEARTBEAT_MS and 0x1017 is writable, they set it to that for their
duration (restored after; a reset communication restores it by itself), so a state change is seen in a fraction of
a second rather than a whole period."""
from __future__ import annotations

import statistics
from typing import TYPE_CHECKING, List, Optional

from .frames import Frame
from .registry import Failed, Findings, NotApplicable, check
from .sdo import SdoError

if TYPE_CHECKING:
    from .runner import Context

STATES = {0x04: "stopped", 0x05: "operational", 0x7F: "pre-operational"}
#: The command that brings a node back into each state.
BACK_TO = {0x04: "stop", 0x05: "start", 0x7F: "pre-operational"}
FAST_HEARTBEAT_MS = 100
#: Heartbeat period tolerance: each interval within the period +- this share of it, and never less than +-
#: TOLERANCE_MIN_S. CiA 301 sets the producer no tolerance (§7.2.8.3.2.2, 0x1017: the cycle time); how late a
#: heartbeat may be is what each consumer's 0x1016 time allows. 10 % is this tool's choice (docs/conformance.md).
TOLERANCE_SHARE = 0.10
TOLERANCE_MIN_S = 0.010


def heartbeat_ms(ctx: "Context") -> int:
    """0x1017 as the node holds it; NotApplicable when it has none or it is 0 (no heartbeat)."""
    if ctx.eds.entry(0x1017) is None:
        raise NotApplicable("the EDS has no 0x1017 (producer heartbeat time)")
    with ctx.exchange():
        period = int.from_bytes(ctx.upload(0x1017, 0), "little")
    if period == 0:
        raise NotApplicable("0x1017 is 0: the node sends no heartbeat")
    return period


def current_state(ctx: "Context", period_s: float) -> int:
    frame = ctx.next_heartbeat(period_s * 1.5 + ctx.options.timeout)
    if frame is None:
        raise Failed(f"no heartbeat on 0x{0x700 + ctx.node:03X} within {period_s * 1.5 + ctx.options.timeout:.1f} s "
                     f"(0x1017 = {period_s * 1000:.0f} ms)", list(ctx.log.trace))
    if len(frame.data) != 1:
        raise Failed(f"a heartbeat of {len(frame.data)} bytes, CiA 301 §7.2.8.3.2.2 has 1", [frame])
    return frame.data[0] & 0x7F


def fast_heartbeat(ctx: "Context") -> float:
    """Makes the heartbeat fast for the check where it may (the period in seconds it then has); puts the node's
    own period back when the check ends."""
    entry = ctx.eds.entry(0x1017)
    period = 0
    if entry is not None:
        with ctx.exchange():
            period = int.from_bytes(ctx.upload(0x1017, 0), "little")
    if entry is not None and entry.writable and (period == 0 or period > FAST_HEARTBEAT_MS):
        try:
            ctx.sdo.download(0x1017, 0, FAST_HEARTBEAT_MS.to_bytes(2, "little"))
        except SdoError:
            pass
        else:
            ctx.on_exit(lambda: ctx.sdo.download(0x1017, 0, period.to_bytes(2, "little")))
            return FAST_HEARTBEAT_MS / 1000
    if period == 0:
        raise NotApplicable("no heartbeat (0x1017 = 0, not writable)")
    return period / 1000


def restore_state(ctx: "Context", state: int) -> None:
    ctx.on_exit(lambda: ctx.nmt(BACK_TO[state]) and None)


@check("heartbeat.state", clause="CiA 301 v4.2.0 §7.2.8.3.2.2 (heartbeat protocol: the state values)",
       summary="a heartbeat: one data byte, a state of 0x04, 0x05 or 0x7F (0x00 only in the boot-up)")
def heartbeat_state(ctx: "Context") -> Optional[str]:
    period_s = heartbeat_ms(ctx) / 1000
    findings = Findings()
    seen = []
    for _ in range(1):
        frame = ctx.next_heartbeat(period_s * 1.5 + ctx.options.timeout)
        if frame is None:
            raise Failed(f"no heartbeat within {period_s * 1.5 + ctx.options.timeout:.1f} s (0x1017 = "
                         f"{period_s * 1000:.0f} ms)", list(ctx.log.trace))
        if len(frame.data) != 1:
            findings.add(f"a heartbeat of {len(frame.data)} bytes, not 1", [frame])
        elif frame.data[0] not in STATES:
            findings.add(f"a heartbeat with state 0x{frame.data[0]:02X}, not 0x04, 0x05 or 0x7F", [frame])
        else:
            seen.append(STATES[frame.data[0]])
    findings.raise_if_any("wrong heartbeats")
    return ", ".join(seen)


@check("heartbeat.period", clause="CiA 301 v4.2.0 §7.2.8.3.2.2 (heartbeat protocol), §7.5.2.20 (0x1017 producer "
                                  "heartbeat time); the tolerance is this tool's (10 %, at least 10 ms)",
       summary="heartbeat intervals, by the frames' bus time stamps, within 10 % (at least 10 ms) of 0x1017")
def heartbeat_period(ctx: "Context") -> Optional[str]:
    period_s = heartbeat_ms(ctx) / 1000
    tolerance = max(TOLERANCE_SHARE * period_s, TOLERANCE_MIN_S)
    beats: List[Frame] = []
    first = ctx.next_heartbeat(period_s * 1.5 + ctx.options.timeout)
    if first is None:
        raise Failed(f"no heartbeat within {period_s * 1.5 + ctx.options.timeout:.1f} s", list(ctx.log.trace))
    beats.append(first)
    for _ in range(ctx.options.heartbeat_intervals):
        frame = ctx.next_heartbeat(period_s + tolerance + ctx.options.timeout)
        if frame is None:
            raise Failed(f"a heartbeat missing: none within {period_s + tolerance + ctx.options.timeout:.3f} s of "
                         "the last", beats)
        beats.append(frame)
    intervals = [b.time - a.time for a, b in zip(beats, beats[1:])]
    wrong = [i for i in intervals if abs(i - period_s) > tolerance]
    shown = ", ".join(f"{i * 1000:.1f}" for i in intervals)
    if wrong:
        raise Failed(f"intervals {shown} ms; 0x1017 = {period_s * 1000:.0f} ms, allowed +-{tolerance * 1000:.0f} ms",
                     beats)
    return f"0x1017 = {period_s * 1000:.0f} ms; intervals {shown} ms (mean {statistics.mean(intervals) * 1000:.1f})"


def _command_and_watch(ctx: "Context", command: str, state: int, period_s: float, findings: Findings) -> None:
    """Sends the command and waits for a heartbeat with the state; one heartbeat of the old state may pass (it may
    have been on its way)."""
    ctx.nmt(command)
    frames = [f for f in ctx.log.trace[-1:]]
    for _ in range(2):
        frame = ctx.next_heartbeat(period_s * 1.5 + ctx.options.timeout)
        if frame is None:
            break
        frames.append(frame)
        if frame.data[:1] == bytes([state]):
            return
    findings.add(f"after NMT {command}: no heartbeat with state 0x{state:02X} ({STATES[state]}) within two "
                 "heartbeats", frames)


@check("nmt.state-changes", clause="CiA 301 v4.2.0 §7.2.8.3.1 (NMT node control), §7.3.2 (NMT state machine), "
                                   "§7.2.8.3.2.2 (the state in the heartbeat)",
       summary="after NMT stop, start and enter pre-operational the heartbeat carries 0x04, 0x05 and 0x7F",
       writes=True)
def state_changes(ctx: "Context") -> Optional[str]:
    period_s = fast_heartbeat(ctx)
    restore_state(ctx, current_state(ctx, period_s))
    findings = Findings()
    for command, state in (("stop", 0x04), ("start", 0x05), ("pre-operational", 0x7F), ("start", 0x05),
                           ("stop", 0x04), ("pre-operational", 0x7F)):
        _command_and_watch(ctx, command, state, period_s, findings)
    findings.raise_if_any("state changes not seen")
    return None


@check("nmt.stopped-no-sdo", clause="CiA 301 v4.2.0 §7.3.2 (NMT state machine: no SDO in Stopped)",
       summary="a stopped node does not answer an SDO upload, and answers it again once pre-operational",
       writes=True)
def stopped_no_sdo(ctx: "Context") -> Optional[str]:
    period_s = fast_heartbeat(ctx)
    restore_state(ctx, current_state(ctx, period_s))
    findings = Findings()
    _command_and_watch(ctx, "stop", 0x04, period_s, findings)
    findings.raise_if_any("state changes not seen")
    ctx.sdo.frames = []
    ctx.log.send(ctx.sdo.request_id, bytes([0x40, 0x00, 0x10, 0x00, 0, 0, 0, 0]))
    answer = ctx.sdo.silence(ctx.options.timeout)
    if answer is not None:
        raise Failed("the stopped node answered an SDO upload", list(ctx.log.trace))
    _command_and_watch(ctx, "pre-operational", 0x7F, period_s, findings)
    try:
        ctx.upload(0x1000, 0)
    except SdoError as e:
        findings.add(f"pre-operational again: {e}", e.frames)
    findings.raise_if_any("wrong answers")
    return None


def _reset(ctx: "Context", command: str) -> Optional[str]:
    entry = ctx.eds.entry(0x1017)
    period_s = fast_heartbeat(ctx)
    before = current_state(ctx, period_s)
    restore_state(ctx, before)
    ctx.nmt(command)
    boot = ctx.log.wait_for(ctx.is_heartbeat, ctx.options.timeout + 2.0)
    while boot is not None and boot.data[:1] != b"\x00":  # a heartbeat sent before the reset took effect
        boot = ctx.log.wait_for(ctx.is_heartbeat, ctx.options.timeout + 2.0)
    if boot is None:
        raise Failed(f"no boot-up (0x{0x700 + ctx.node:03X} [1] 00) within {ctx.options.timeout + 2.0:.1f} s of NMT "
                     f"{command}", list(ctx.log.trace))
    if len(boot.data) != 1:
        raise Failed(f"a boot-up of {len(boot.data)} bytes, CiA 301 §7.2.8.3.2 has 1", list(ctx.log.trace))
    # after the reset 0x1017 is the node's default again (made fast once more where it may be): its heartbeat
    # says the state
    if entry is not None:
        try:
            period_s = fast_heartbeat(ctx)
        except NotApplicable:
            period_s = 0.0
        if period_s > 0:
            state = ctx.next_heartbeat(period_s * 1.5 + ctx.options.timeout)
            if state is None or state.data[:1] != b"\x7f":
                raise Failed("after the boot-up the heartbeat does not say pre-operational (0x7F)",
                             list(ctx.log.trace))
    return f"boot-up {(boot.time - ctx.log.trace[0].time) * 1000:.0f} ms after the command" if ctx.log.trace else None


@check("nmt.reset-communication", clause="CiA 301 v4.2.0 §7.2.8.3.1 (NMT reset communication), §7.2.8.3.2 "
                                         "(boot-up protocol), §7.3.2 (NMT state machine)",
       summary="after NMT reset communication the node sends its boot-up (one byte 0x00) and is pre-operational",
       writes=True)
def reset_communication(ctx: "Context") -> Optional[str]:
    return _reset(ctx, "reset-communication")


@check("nmt.reset-node", clause="CiA 301 v4.2.0 §7.2.8.3.1 (NMT reset node), §7.2.8.3.2 (boot-up protocol)",
       summary="after NMT reset node the node sends its boot-up (one byte 0x00) and is pre-operational",
       writes=True)
def reset_node(ctx: "Context") -> Optional[str]:
    return _reset(ctx, "reset-node")


@check("nmt.node-guarding", clause="CiA 301 v4.2.0 §7.2.8.3.2.1 (node guarding protocol), §7.5.2.11-12 (0x100C, "
                                   "0x100D)",
       summary="where the EDS lists 0x100C and 0x100D: with the heartbeat off (0x1017 set to 0 for the check), each "
               "remote request on 0x700 + node-ID is answered with one byte: the state (0x7F, 0x05 after start, "
               "0x04 after stop) and a toggle bit (bit 7) that starts at 0 and alternates", writes=True)
def node_guarding(ctx: "Context") -> Optional[str]:
    if ctx.eds.entry(0x100C) is None or ctx.eds.entry(0x100D) is None:
        raise NotApplicable("the EDS has no 0x100C/0x100D (no node guarding)")
    with ctx.exchange():
        guard_ms = int.from_bytes(ctx.upload(0x100C, 0), "little")
        factor = ctx.upload(0x100D, 0)[0]
    if guard_ms and factor:
        # the first request would start life guarding, and its end an EMCY and perhaps a state change (0x1029)
        raise NotApplicable(f"life guarding is configured (0x100C = {guard_ms} ms, 0x100D = {factor}): the check "
                            "would start it")
    hb_entry = ctx.eds.entry(0x1017)
    if hb_entry is not None:
        with ctx.exchange():
            period = ctx.upload(0x1017, 0)
        if any(period):
            if not hb_entry.writable:
                raise NotApplicable("0x1017 is not writable, and a node with a heartbeat does not answer guarding")
            with ctx.exchange():
                ctx.sdo.download(0x1017, 0, b"\0" * len(period))
            ctx.on_exit(lambda: ctx.sdo.download(0x1017, 0, period))
    findings = Findings()
    toggle, state = 0, None
    for command in (None, "start", "stop", "pre-operational"):
        if command is not None:
            ctx.nmt(command)
            ctx.log.wait_for(lambda f: False, 0.05)  # the command taken before the next request
        ctx.log.send(0x700 + ctx.node, b"", rtr=True, dlc=1)
        answer = ctx.log.wait_for(lambda f: ctx.is_heartbeat(f), ctx.options.timeout)
        after = f"after NMT {command}" if command else "the first request"
        if answer is None:
            findings.add(f"{after}: no answer to the guard request within {ctx.options.timeout} s",
                         list(ctx.log.trace[-3:]))
            if state is None:
                break  # no state to go on from, nor to put back
            continue
        if state is None and len(answer.data) == 1 and answer.data[0] & 0x7F in STATES:
            state = answer.data[0] & 0x7F  # the state it was found in: put back at the end
            restore_state(ctx, state)
        expected = {None: state, "start": 0x05, "stop": 0x04, "pre-operational": 0x7F}[command]
        if len(answer.data) != 1 or expected is None or answer.data[0] != (toggle << 7 | expected):
            findings.add(f"{after}: answered {answer.data.hex(' ') or '(no data)'}, expected toggle {toggle} and "
                         f"state {'0x04, 0x05 or 0x7F' if expected is None else f'0x{expected:02X}'}", [answer])
            if state is None:
                break
        toggle ^= 1
    findings.raise_if_any("wrong guarding answers")
    return None
