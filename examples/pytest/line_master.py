"""The master under test: a small line controller written with python-canopen, the kind of program a test
engineer gets to test. It configures and starts nodes, reads their identity, maps and reads TPDOs, turns SDO
timeouts and abort codes into errors of its own (with a retry policy), watches heartbeats, and reacts to EMCY by
putting the device in a safe state. The tests beside it (test_*.py) check it against the emulated devices."""
from __future__ import annotations

import queue
import struct
import threading
import time
from dataclasses import dataclass
from pathlib import Path
from typing import Callable, Dict, List, Optional, Sequence, Tuple, TypeVar, Union

import canopen
from canopen.emcy import EmcyError
from canopen.pdo.base import PdoMap, PdoVariable
from canopen.sdo import SdoClient
from canopen.sdo.exceptions import SdoAbortedError, SdoCommunicationError

#: The abort code a client sends when its server does not answer (CiA 301 "SDO protocol timed out").
SDO_TIMEOUT = 0x05040000
T = TypeVar("T")

#: The heartbeat state byte of Pre-operational (CiA 301).
PRE_OPERATIONAL = 0x7F


class DeviceNotResponding(Exception):
    """An SDO request got no answer, after every attempt."""

    def __init__(self, node_id: int, index: int, sub: int, attempts: int) -> None:
        self.node_id, self.index, self.sub, self.attempts = node_id, index, sub, attempts
        super().__init__(f"node {node_id}: no answer for 0x{index:04X}:{sub:02X} after {attempts} attempt(s) "
                         f"(SDO timeout, abort 0x{SDO_TIMEOUT:08X} sent)")


class DeviceRefused(Exception):
    """The device answered an SDO request with an abort code."""

    def __init__(self, node_id: int, index: int, sub: int, abort_code: int) -> None:
        self.node_id, self.index, self.sub, self.abort_code = node_id, index, sub, abort_code
        super().__init__(f"node {node_id}: 0x{index:04X}:{sub:02X} refused with abort 0x{abort_code:08X}")


@dataclass(frozen=True)
class Identity:
    vendor_id: int
    product_code: int
    revision: int
    serial: int
    device_name: str


@dataclass(frozen=True)
class Emergency:
    """An EMCY the master received and what it did about it."""
    node_id: int
    code: int
    register: int
    data: bytes
    action: str          # "safe state", "safe state failed: ...", "none (error reset)"


class HeartbeatMonitor:
    """The master's heartbeat consumer for one node: ``lost`` is set when no heartbeat came for consumer_time
    seconds, ``recovered`` when one comes after that. Times are this process's monotonic clock at reception."""

    def __init__(self, network: canopen.Network, node_id: int, consumer_time: float) -> None:
        self.node_id = node_id
        self.consumer_time = consumer_time
        self.lost = threading.Event()
        self.recovered = threading.Event()
        self.states: List[int] = []
        self.lost_after: Optional[float] = None  # seconds from the last heartbeat to the loss being noticed
        self.lost_at: Optional[float] = None     # when it was noticed (time.monotonic())
        self._last: Optional[float] = None
        self._lock = threading.Lock()
        self._stop = threading.Event()
        self._network = network
        network.subscribe(0x700 + node_id, self._on_heartbeat)
        self._thread = threading.Thread(target=self._watch, name=f"heartbeat-{node_id}", daemon=True)
        self._thread.start()

    def _on_heartbeat(self, can_id: int, data: bytearray, timestamp: float) -> None:
        with self._lock:
            self._last = time.monotonic()
            self.states.append(data[0] & 0x7F)
            if self.lost.is_set():
                self.recovered.set()

    def _watch(self) -> None:
        # A consumer checks its deadline far more often than the heartbeat period: 10 ms here.
        while not self._stop.wait(0.01):
            with self._lock:
                if self._last is not None and not self.lost.is_set():
                    silent = time.monotonic() - self._last
                    if silent > self.consumer_time:
                        self.lost_after = silent
                        self.lost_at = time.monotonic()
                        self.lost.set()

    def stop(self) -> None:
        self._stop.set()
        self._thread.join()
        self._network.unsubscribe(0x700 + self.node_id, self._on_heartbeat)


def eventually(condition: Callable[[], object], timeout: float, interval: float = 0.05) -> object:
    """Polls condition until it returns something true (returned) or timeout seconds pass (TimeoutError): for
    what has no event to wait on, such as a model value settling."""
    deadline = time.monotonic() + timeout
    while True:
        result = condition()
        if result:
            return result
        if time.monotonic() > deadline:
            raise TimeoutError(f"not reached within {timeout} s (last: {result!r})")
        time.sleep(interval)


def ionizer_safe_state(node: canopen.RemoteNode) -> None:
    """An ionizer in trouble: switch its high voltage off (HV release 0x6200:01 = 0)."""
    node.sdo.download(0x6200, 1, b"\x00")


def flow_controller_safe_state(node: canopen.RemoteNode) -> None:
    """A flow controller in trouble: close it (set-point 0x2540:01 = 0.0)."""
    node.sdo.download(0x2540, 1, struct.pack("<f", 0.0))


SafeState = Callable[[canopen.RemoteNode], None]


class LineMaster:
    """The line's master. ``sdo_timeout`` is how long one SDO attempt waits, ``sdo_attempts`` how many attempts
    a read or write gets before DeviceNotResponding."""

    def __init__(self, network: canopen.Network, sdo_timeout: float = 1.0, sdo_attempts: int = 2) -> None:
        self.network = network
        self.sdo_timeout = sdo_timeout
        self.sdo_attempts = sdo_attempts
        self.nodes: Dict[int, canopen.RemoteNode] = {}
        self.timeouts = 0                       # SDO attempts that got no answer
        self.emergencies: "queue.Queue[Emergency]" = queue.Queue()
        self._safe_states: Dict[int, SafeState] = {}
        self._monitors: List[HeartbeatMonitor] = []
        # EMCY callbacks run in python-canopen's receive thread, which also delivers SDO answers: a reaction that
        # does SDO there would wait for an answer only that same thread can deliver. Reactions run here instead.
        self._reactions: "queue.Queue[Optional[Tuple[int, EmcyError]]]" = queue.Queue()
        self._worker = threading.Thread(target=self._react, name="emcy-reactions", daemon=True)
        self._worker.start()

    # --- nodes --------------------------------------------------------------------------------------------

    def add(self, node_id: int, eds: Union[str, Path], safe_state: Optional[SafeState] = None) -> canopen.RemoteNode:
        node = canopen.RemoteNode(node_id, str(eds))
        node.sdo.RESPONSE_TIMEOUT = self.sdo_timeout
        node.sdo.MAX_RETRIES = 1  # python-canopen: one attempt per call (0 would retry for ever); ours decide
        self.network.add_node(node)
        # Until the master maps a PDO itself, it takes the mapping the EDS gives (the emulated devices' defaults).
        node.tpdo.read(from_od=True)
        node.rpdo.read(from_od=True)
        node.emcy.add_callback(lambda error: self._reactions.put((node_id, error)))
        if safe_state is not None:
            self._safe_states[node_id] = safe_state
        self.nodes[node_id] = node
        return node

    def close(self) -> None:
        for monitor in self._monitors:
            monitor.stop()
        self._reactions.put(None)
        self._worker.join()

    # --- SDO with the master's error handling ---------------------------------------------------------------

    def read(self, node_id: int, index: int, sub: int = 0) -> bytes:
        return self._sdo(node_id, index, sub, lambda sdo: sdo.upload(index, sub))

    def write(self, node_id: int, index: int, sub: int, data: bytes) -> None:
        self._sdo(node_id, index, sub, lambda sdo: sdo.download(index, sub, data))

    def _sdo(self, node_id: int, index: int, sub: int, transfer: Callable[[SdoClient], T]) -> T:
        sdo = self.nodes[node_id].sdo
        for _ in range(self.sdo_attempts):
            try:
                return transfer(sdo)
            except SdoCommunicationError:
                # python-canopen has sent abort 0x05040000 to the server already; a device that missed one
                # request (a lost frame, a busy moment) gets another chance.
                self.timeouts += 1
            except SdoAbortedError as e:
                raise DeviceRefused(node_id, index, sub, e.code) from e
        raise DeviceNotResponding(node_id, index, sub, self.sdo_attempts)

    def read_u8(self, node_id: int, index: int, sub: int = 0) -> int:
        return self.read(node_id, index, sub)[0]

    def read_u16(self, node_id: int, index: int, sub: int = 0) -> int:
        return int(struct.unpack("<H", self.read(node_id, index, sub)[:2])[0])

    def read_u32(self, node_id: int, index: int, sub: int = 0) -> int:
        return int(struct.unpack("<I", self.read(node_id, index, sub)[:4])[0])

    def read_real32(self, node_id: int, index: int, sub: int = 0) -> float:
        return float(struct.unpack("<f", self.read(node_id, index, sub)[:4])[0])

    # --- what the line does ---------------------------------------------------------------------------------

    def read_identity(self, node_id: int) -> Identity:
        """0x1018:01-04 and the device name 0x1008 (segmented when longer than 4 bytes)."""
        return Identity(vendor_id=self.read_u32(node_id, 0x1018, 1), product_code=self.read_u32(node_id, 0x1018, 2),
                        revision=self.read_u32(node_id, 0x1018, 3), serial=self.read_u32(node_id, 0x1018, 4),
                        device_name=self.read(node_id, 0x1008, 0).decode("ascii"))

    def configure_heartbeat(self, node_id: int, period_ms: int) -> int:
        """Sets the producer heartbeat time 0x1017 and returns what the device reads back."""
        self.write(node_id, 0x1017, 0, struct.pack("<H", period_ms))
        return self.read_u16(node_id, 0x1017, 0)

    def start(self, node_id: int, timeout: float = 3.0) -> None:
        """NMT start, then wait until the node's heartbeat says Operational."""
        nmt = self.nodes[node_id].nmt
        nmt.state = "OPERATIONAL"
        deadline = time.monotonic() + timeout
        while nmt.state != "OPERATIONAL":
            left = deadline - time.monotonic()
            if left <= 0:
                raise TimeoutError(f"node {node_id} not Operational {timeout} s after NMT start "
                                   f"(its heartbeat says {nmt.state})")
            nmt.wait_for_heartbeat(left)

    def watch_heartbeat(self, node_id: int, consumer_time: float) -> HeartbeatMonitor:
        monitor = HeartbeatMonitor(self.network, node_id, consumer_time)
        self._monitors.append(monitor)
        return monitor

    def map_tpdo(self, node_id: int, number: int, entries: Sequence[Tuple[int, int]], event_timer_ms: int,
                 inhibit_ms: float = 0.0) -> PdoMap:
        """Maps TPDO number to the (index, sub) entries, event-driven (type 254) with that event timer, by the CiA
        procedure (python-canopen: invalidate, map, validate)."""
        node = self.nodes[node_id]
        node.tpdo.read(from_od=False)
        pdo = node.tpdo[number]
        pdo.clear()
        for index, sub in entries:
            pdo.add_variable(index, sub)
        pdo.trans_type = 254
        pdo.event_timer = event_timer_ms
        pdo.inhibit_time = int(inhibit_ms * 10)  # in 100 us
        pdo.enabled = True
        pdo.save()
        return pdo

    def next_tpdo(self, node_id: int, number: int, timeout: float = 3.0) -> PdoMap:
        """The TPDO's content after its next reception."""
        pdo = self.nodes[node_id].tpdo[number]
        if pdo.wait_for_reception(timeout) is None:
            raise TimeoutError(f"no TPDO{number} of node {node_id} within {timeout} s")
        return pdo

    def tpdo_value(self, node_id: int, number: int, index: int, sub: int, timeout: float = 3.0) -> Union[int, float]:
        """The value of (index, sub) in the TPDO's next frame."""
        value = mapped(self.next_tpdo(node_id, number, timeout), index, sub).raw
        assert isinstance(value, (int, float)), value
        return value

    def write_rpdo(self, node_id: int, number: int, index: int, sub: int, value: Union[int, float]) -> None:
        """Sets (index, sub) in the node's RPDO and sends it (the device acts on it in Operational only)."""
        pdo = self.nodes[node_id].rpdo[number]
        mapped(pdo, index, sub).raw = value
        pdo.transmit()

    def tpdo_is_stale(self, node_id: int, number: int, index: int, sub: int, tolerance: float,
                      timeout: float = 3.0) -> bool:
        """The plausibility check of a measured value: the TPDO's copy against an SDO read of the object. True
        when they differ by more than tolerance (a frozen or stale PDO)."""
        from_pdo = float(self.tpdo_value(node_id, number, index, sub, timeout))
        var = mapped(self.nodes[node_id].tpdo[number], index, sub)
        from_sdo = float(var.od.decode_raw(self.read(node_id, index, sub)))
        return abs(from_pdo - from_sdo) > tolerance

    def acknowledge_eltex(self, node_id: int, kind: str, number: int) -> None:
        """Deletes an Eltex error (kind "error", 0x2003:01) or warning ("warning", 0x2003:02) by its number."""
        self.write(node_id, 0x2003, 1 if kind == "error" else 2, bytes([number]))

    # --- EMCY -----------------------------------------------------------------------------------------------

    def _react(self) -> None:
        while True:
            item = self._reactions.get()
            if item is None:
                return
            node_id, error = item
            action = "none (error reset)"
            if error.code != 0 and error.register != 0:  # an error (code 0 is the error reset)
                safe_state = self._safe_states.get(node_id)
                if safe_state is None:
                    action = "none (no safe state known)"
                else:
                    try:
                        safe_state(self.nodes[node_id])
                        action = "safe state"
                    except (SdoAbortedError, SdoCommunicationError) as e:
                        action = f"safe state failed: {e}"
            self.emergencies.put(Emergency(node_id, error.code, error.register, bytes(error.data), action))

    def next_emergency(self, timeout: float = 3.0) -> Emergency:
        """The next EMCY received and handled (its reaction done)."""
        try:
            return self.emergencies.get(timeout=timeout)
        except queue.Empty:
            raise TimeoutError(f"no EMCY handled within {timeout} s") from None


def mapped(pdo: PdoMap, index: int, sub: int) -> PdoVariable:
    """The variable of a PDO that maps (index, sub)."""
    for var in pdo.map:
        if (var.index, var.subindex) == (index, sub):
            return var
    raise KeyError(f"{pdo.name} does not map 0x{index:04X}:{sub:02X}")


def eltex_emcy(emergency: Emergency) -> Tuple[str, int]:
    """An Eltex EMCY's manufacturer bytes: ("error" | "warning", its number) (docs/devices/eltex.md E7)."""
    kind = {0x01: "error", 0x05: "warning"}.get(emergency.data[0], f"type 0x{emergency.data[0]:02X}")
    return kind, emergency.data[1]
