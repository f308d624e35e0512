"""Runs the checks against one node: opens the bus (or takes one), reads the EDS, gives every check a Context,
and gathers the results into a Report.

``run(bus, node, eds, ...)`` is the entry point of the command line (cli.py) and of test suites (testing.py)."""
from __future__ import annotations

import fnmatch
import time
import traceback
from contextlib import contextmanager
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, Callable, Dict, Iterator, List, Optional, Sequence, Union

import can

from . import eds as eds_module
from .frames import Frame, FrameLog
from .registry import CHECKS, Check, Failed, NotApplicable, Result, Status
from .sdo import SdoAbort, SdoClient, SdoError

# The group modules register their checks when imported; their order is the order of the run.
from . import od, sdo_protocol, nmt, pdo, rpdo, emcy, store, lss  # noqa: E402,F401  (imported for their @check)

NMT_COMMANDS = {"start": 0x01, "stop": 0x02, "pre-operational": 0x80, "reset-node": 0x81,
                "reset-communication": 0x82}
#: Heartbeat state bytes (CiA 301 v4.2.0 §7.2.8.3.2.2).
STATE_NAMES = {0x00: "boot-up", 0x04: "stopped", 0x05: "operational", 0x7F: "pre-operational"}


class SetupError(Exception):
    """The run cannot start: the bus cannot be opened, the EDS cannot be read, the node does not answer."""


@dataclass
class Options:
    """What the user chose. ``timeout``: seconds an SDO answer, a boot-up or a state change may take;
    ``heartbeat_intervals``: how many heartbeat periods heartbeat.period watches."""
    write: bool = False
    timeout: float = 1.0
    heartbeat_intervals: int = 3


class Context:
    """What a check works with: ``node`` (node-ID), ``eds`` (eds.Eds), ``log`` (the bus, every frame recorded),
    ``sdo`` (SdoClient of the default server), ``options``; helpers for the common steps; ``on_exit(f)``: f runs
    when the check ends, however it ends (restoring what the check changed)."""

    def __init__(self, log: FrameLog, node: int, eds: eds_module.Eds, options: Options) -> None:
        self.log = log
        self.node = node
        self.eds = eds
        self.options = options
        self.sdo = SdoClient(log, node, options.timeout)
        self._undo: List[Callable[[], None]] = []
        self.notes: List[str] = []  # said under the result whatever it is (what an undo step could not restore)

    # --- the check's life --------------------------------------------------------------------------------------

    def require_write(self, what: str) -> None:
        """NotApplicable unless --write: ``what`` says how the check would change the device."""
        if not self.options.write:
            raise NotApplicable(f"{what}: needs --write")

    def on_exit(self, undo: Callable[[], None]) -> None:
        self._undo.append(undo)

    def finish(self) -> List[str]:
        """Runs the undo steps, last first; the problems they met."""
        problems = []
        while self._undo:
            undo = self._undo.pop()
            try:
                undo()
            except Exception as e:  # noqa: BLE001: every undo step is tried
                problems.append(f"restoring after the check failed: {e}")
        return problems

    # --- common steps -------------------------------------------------------------------------------------------

    def upload(self, index: int, sub: int = 0) -> bytes:
        return self.sdo.upload(index, sub)

    def read_value(self, index: int, sub: int = 0) -> Optional[Any]:
        """The entry's value decoded by its EDS type; None when the EDS lacks it or the upload fails."""
        entry = self.eds.entry(index, sub)
        if entry is None:
            return None
        try:
            return eds_module.decode(self.sdo.upload(index, sub), entry.data_type)
        except SdoError:
            return None

    def nmt(self, command: str, node: Optional[int] = None) -> Frame:
        """Sends an NMT command (CiA 301 §7.2.8.3.1) to the node (``node`` 0: to all)."""
        return self.log.send(0x000, bytes([NMT_COMMANDS[command], self.node if node is None else node]))

    def is_heartbeat(self, frame: Frame) -> bool:
        return frame.can_id == 0x700 + self.node and not frame.rtr

    def next_heartbeat(self, timeout: float) -> Optional[Frame]:
        """The node's next heartbeat or boot-up frame within timeout seconds."""
        return self.log.wait_for(self.is_heartbeat, timeout)

    @contextmanager
    def exchange(self) -> Iterator[None]:
        """Turns an SDO error into Failed with its frames: ``with ctx.exchange(): ctx.upload(...)``."""
        try:
            yield
        except SdoError as e:
            raise Failed(str(e), e.frames) from None


@dataclass
class Report:
    """The results of one run, in the order the checks ran."""
    node: int
    eds_path: Path
    bus: str
    results: List[Result] = field(default_factory=list)
    started: float = 0.0
    duration: float = 0.0

    @property
    def failed(self) -> List[Result]:
        return [r for r in self.results if r.failed]

    @property
    def ok(self) -> bool:
        """Nothing failed (not-applicable checks do not count)."""
        return not self.failed

    def count(self, status: Status) -> int:
        return sum(1 for r in self.results if r.status is status)

    def __getitem__(self, name: str) -> Result:
        for result in self.results:
            if result.name == name:
                return result
        raise KeyError(name)


def select(only: Sequence[str] = (), skip: Sequence[str] = ()) -> List[Check]:
    """The checks to run: each name of ``only``/``skip`` is a check's name, its group (``od``) or a shell pattern
    (``sdo.*upload*``). ValueError for a name that matches no check (a typo must not pass silently)."""
    def matches(pattern: str, c: Check) -> bool:
        return pattern in (c.name, c.group) or fnmatch.fnmatchcase(c.name, pattern)

    for pattern in [*only, *skip]:
        if not any(matches(pattern, c) for c in CHECKS.values()):
            raise ValueError(f"no check is named {pattern!r} (canopen-check --list shows them)")
    chosen = [c for c in CHECKS.values() if not only or any(matches(p, c) for p in only)]
    return [c for c in chosen if not any(matches(p, c) for p in skip)]


def run(bus: Union[can.BusABC, str, Dict[str, Any]], node: int, eds: Union[str, Path, eds_module.Eds], *,
        interface: str = "socketcan", write: bool = False, only: Sequence[str] = (), skip: Sequence[str] = (),
        timeout: float = 1.0, heartbeat_intervals: int = 3,
        progress: Optional[Callable[[Result], None]] = None) -> Report:
    """Checks node ``node`` against ``eds`` (a path, or an Eds of eds.load()) and CiA 301/305.

    ``bus``: a python-can bus the caller opened (it stays open), a channel name (opened with ``interface``), or
    the keyword arguments of ``can.Bus`` (``Bus.can_kwargs()`` of canopen_emu.buses). ``write``: allow the checks
    that change the device (SDO downloads of its own values, NMT commands); ``only``/``skip``: as select();
    ``progress``: called with each result as it comes. SetupError when the run cannot start."""
    if not 1 <= node <= 127:
        raise SetupError(f"the node-ID is 1..127, not {node}")
    checks = select(only, skip)
    try:
        description = eds if isinstance(eds, eds_module.Eds) else eds_module.load(eds, node)
    except (OSError, eds_module.EdsError) as e:
        raise SetupError(f"cannot read the EDS: {e}") from None
    own_bus = not isinstance(bus, can.BusABC)
    try:
        if isinstance(bus, can.BusABC):
            can_bus = bus
        elif isinstance(bus, dict):
            can_bus = can.Bus(**bus)
        else:
            can_bus = can.Bus(channel=bus, interface=interface)
    except (can.CanError, OSError, ValueError, ImportError) as e:
        raise SetupError(f"cannot open the bus {bus!r}: {e}") from None
    label = bus_label(bus, interface) if not isinstance(bus, can.BusABC) else str(can_bus.channel_info)
    report = Report(node, description.path, label, started=time.time())
    try:
        log = FrameLog(can_bus, relevant_to(node))
        options = Options(write=write, timeout=timeout, heartbeat_intervals=heartbeat_intervals)
        _preflight(log, node, description, options)
        for chosen in checks:
            result = run_one(chosen, log, node, description, options)
            report.results.append(result)
            if progress is not None:
                progress(result)
    finally:
        report.duration = time.time() - report.started
        if own_bus:
            can_bus.shutdown()
    return report


def bus_label(bus: Union[str, Dict[str, Any]], interface: str) -> str:
    """``vcan0 (socketcan)``, ``239.74.1.2 (udp_multicast, port=43113)``."""
    if isinstance(bus, str):
        return f"{bus} ({interface})"
    rest = [f"{k}={v}" for k, v in bus.items() if k not in ("channel", "interface")]
    return f"{bus.get('channel')} ({', '.join([str(bus.get('interface', interface))] + rest)})"


def relevant_to(node: int) -> Callable[[int], bool]:
    """The frames a check's trace keeps: those with the node's ID in their low 7 bits (its SDO, PDO, EMCY,
    heartbeat COB-IDs by the predefined connection set), NMT, SYNC and LSS."""
    return lambda can_id: can_id & 0x7F == node or can_id in (0x000, 0x080, 0x7E4, 0x7E5)


def _preflight(log: FrameLog, node: int, description: eds_module.Eds, options: Options) -> None:
    log.start_trace()
    client = SdoClient(log, node, max(options.timeout, 1.0))
    try:
        client.upload(0x1000, 0)
    except SdoAbort:
        pass  # it answers: od.mandatory-objects reports the abort
    except SdoError as e:
        raise SetupError(f"node {node} does not answer an SDO upload of 0x1000 (device type) on 0x{0x600 + node:03X}"
                         f": {e}; is it on this bus, at this node-ID, and not stopped?") from None


def run_one(chosen: Check, log: FrameLog, node: int, description: eds_module.Eds, options: Options) -> Result:
    """One check in a Context of its own; its undo steps run after it."""
    if chosen.writes and not options.write:
        return Result(chosen, Status.NOT_APPLICABLE, "changes the device: needs --write")
    ctx = Context(log, node, description, options)
    log.start_trace()
    start = time.monotonic()
    try:
        note = chosen.function(ctx)
        result = Result(chosen, Status.PASSED, note or "")
    except Failed as e:
        result = Result(chosen, Status.FAILED, str(e), e.frames or list(log.trace))
    except NotApplicable as e:
        result = Result(chosen, Status.NOT_APPLICABLE, str(e))
    except SdoError as e:
        result = Result(chosen, Status.FAILED, str(e), e.frames)
    except Exception as e:  # noqa: BLE001: a broken check is reported, and the others still run
        result = Result(chosen, Status.ERROR, f"the check broke: {e!r}\n{traceback.format_exc()}", list(log.trace))
    problems = ctx.finish()
    if problems:
        result.message = "\n".join([result.message, *problems]).strip()
        if result.status is Status.PASSED:
            result.status = Status.FAILED
    if ctx.notes:
        result.message = "\n".join([result.message, *ctx.notes]).strip()
    result.duration = time.monotonic() - start
    return result
