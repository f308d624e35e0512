"""A client of the canopen-emu control socket: the JSON framing of docs/control-protocol.md, version 1.

One request at a time goes out and its answer is read back; events of a subscription that come in between
(they may arrive at any moment, also while an answer is awaited) are put in a queue and never lost: wait_for(),
events() and drain_events() take them from there."""
from __future__ import annotations

import collections
import json
import math
import os
import re
import select
import socket
import threading
import time
from dataclasses import dataclass, field
from typing import (Any, Deque, Dict, Iterable, Iterator, List, Mapping, NamedTuple, Optional, Sequence, Tuple,
                    Union)

from .errors import ConnectionClosed, ControlError, ControlTimeout, ProtocolError

#: The protocol version this client speaks (``hello`` answers it as ``protocol``).
PROTOCOL_VERSION = 1

#: A node: its ID (``16``) or the command language's form (``"0x10"``, ``"16@vcan1"``, ``"all"``).
NodeRef = Union[int, str]
#: An object: ``"0x6401:01"``, ``"1017"``, an index (``0x1017``) or ``(index, sub)``.
ObjectRef = Union[str, int, Tuple[int, int]]
#: A typed value as this client returns it: int, float, bool, str (VISIBLE_STRING) or bytes (OCTET_STRING, DOMAIN).
Value = Union[int, float, bool, str, bytes]
#: An event as the emulator sent it: ``event`` (the kind), ``time_us``, ``text`` and the kind's own fields (a
#: ``frame`` event: ``dir``, ``id``, ``data``, and ``rtr`` / ``eff`` only when true: ``ev.get("eff", False)``).
Event = Dict[str, Any]
#: Where the control socket is: a Unix socket path, ``"HOST:PORT"``, or ``(host, port)``.
Address = Union[str, "os.PathLike[str]", Tuple[str, int]]

class ExtendedId(NamedTuple):
    """A frame filter of ``subscribe(frames=...)`` for 29-bit (extended) frames: ``ExtendedId(0x181)`` takes the
    extended frame with identifier 0x181 and never TPDO1 of node 1, as a COB-ID ``0x181`` takes that PDO and never
    the extended frame (a filter takes one format; docs/control-protocol.md "Events")."""
    cob_id: int
    mask: int = 0x1FFFFFFF

    def __str__(self) -> str:
        return f"0x{self.cob_id:08X}x/0x{self.mask:08X}"


#: A frame filter: an 11-bit COB-ID, ``(cob_id, mask)``, ``ExtendedId(cob_id[, mask])`` or the protocol's text
#: (``"0x700/0x780"``, ``"0x181x"``).
FrameFilter = Union[str, int, Tuple[int, int], ExtendedId]

# The longest path a Unix socket address can hold on Linux (sun_path is 108 bytes with its NUL).
_UNIX_PATH_MAX = 107
_TCP_ADDRESS = re.compile(r"(?:\[(?P<v6>[^\]]+)\]|(?P<host>[^:/\[\]]+)):(?P<port>\d{1,5})")


@dataclass(frozen=True)
class ServerInfo:
    """The answer to ``hello``."""
    program: str
    version: str
    protocol: int
    events: Tuple[str, ...]
    buses: Tuple[str, ...]
    raw: Dict[str, Any] = field(default_factory=dict, compare=False, repr=False)
    #: The events' clock (µs since the emulator started) and the wall clock (µs since 1970) read together; None
    #: from an emulator older than this field.
    clock_time_us: Optional[int] = field(default=None, compare=False)
    clock_unix_us: Optional[int] = field(default=None, compare=False)
    #: Each bus's kind by its name, python-can's interface name: ``{"vcan0": "socketcan", "plant": "virtual",
    #: "udp_multicast:239.74.163.2:43113": "udp_multicast"}``; empty from an emulator older than this field.
    bus_kinds: Dict[str, str] = field(default_factory=dict, hash=False)


@dataclass(frozen=True)
class FaultKind:
    """One kind of protocol fault of ``tables``: its name (``"sdo-delay"``), the words ``fault NODE`` takes after
    NODE (``"sdo-delay MS"``), what the arguments may be (``"1..600000"``, or ``""``) and one line on what it does."""
    kind: str
    usage: str
    limits: str
    text: str


@dataclass(frozen=True)
class Tables:
    """The answer to ``tables``: the tables the emulator keeps, as it has them (a client keeps no copy): the kinds
    of protocol fault in the order ``fault NODE`` lists them, the SDO abort texts by code."""
    faults: Tuple[FaultKind, ...]
    aborts: Dict[int, str] = field(hash=False)

    @property
    def fault_kinds(self) -> Tuple[str, ...]:
        """The names of the fault kinds (what ``Client.inject_fault`` takes)."""
        return tuple(f.kind for f in self.faults)


@dataclass(frozen=True)
class NodeInfo:
    """One node of ``list``: its current node-ID, device type, variant (None when the device has none), the
    node-ID it was started with, its NMT state, its bus's name and kind (``"socketcan"``, ``"udp_multicast"``,
    ``"virtual"``; None from an emulator older than it)."""
    node: int
    device: str
    variant: Optional[str]
    started_as: int
    state: str
    bus: str
    bus_kind: Optional[str] = None


@dataclass(frozen=True)
class ActiveError:
    """One active error of ``show``: the CiA error code, the error register it was raised with and the five
    manufacturer-specific bytes of its EMCY."""
    code: int
    register: int
    info: bytes


@dataclass(frozen=True)
class LastEmcy:
    """The last EMCY a node sent or queued (``show``): error code, error register, the five manufacturer-specific
    bytes, and when (µs since the emulator started, the events' clock)."""
    code: int
    register: int
    info: bytes
    time_us: int


@dataclass(frozen=True)
class NodeStatus(NodeInfo):
    """One node of ``show``: ``list``'s fields, its error register and active errors, its frame counters, its
    device type (0x1000) and heartbeat period (0x1017, ms), when it last sent its heartbeat or boot-up (µs on the
    events' clock, None: never), the protocol faults in force and its last EMCY (None: none yet)."""
    error_register: int = 0
    errors: Tuple[ActiveError, ...] = ()
    tx_frames: int = 0
    rx_frames: int = 0
    tx_dropped: int = 0
    device_type: int = 0
    heartbeat_ms: int = 0
    last_heartbeat_us: Optional[int] = None
    faults: Tuple[str, ...] = ()
    last_emcy: Optional[LastEmcy] = None


@dataclass(frozen=True)
class HeardNode:
    """A node-ID heard on a bus that the emulator does not emulate there (``show all``'s ``heard``): its state from
    its last heartbeat, boot-up or guarding answer, whether that was a boot-up, and when (µs, the events' clock); the
    bus's kind as NodeInfo's."""
    node: int
    bus: str
    state: str
    boot_up: bool
    last_heartbeat_us: int
    bus_kind: Optional[str] = None


class _Addressed:
    """``index`` and ``sub`` of an answer's ``object`` (``"0x1017:00"``)."""
    object: str

    @property
    def index(self) -> int:
        return int(self.object[2:6], 16)

    @property
    def sub(self) -> int:
        return int(self.object[7:9], 16)


@dataclass(frozen=True)
class Entry(_Addressed):
    """A typed answer of ``get`` or ``set``: the value (decoded, see Client.get), its CANopen data type
    (``"UNSIGNED16"``...), the EDS ParameterName, the object normalised (``"0x1017:00"``) and the value's unit
    where the device's manual gives one (``"V"``, ``"l/min"``; ``None`` otherwise)."""
    node: int
    object: str
    value: Value
    type: str
    name: str
    unit: Optional[str] = None


@dataclass(frozen=True)
class Reading(_Addressed):
    """One value of ``get_many``: the object (``"0x1017:00"``), its value and data type, or ``error``, why it cannot
    be read (``"object does not exist (0x06020000)"``; value and type are then ``None``)."""
    object: str
    value: Optional[Value] = None
    type: Optional[str] = None
    error: Optional[str] = None


@dataclass(frozen=True)
class ObjectInfo(_Addressed):
    """One sub-index of a node's dictionary (``objects``): the object (``"0x1017:00"``), its EDS ParameterName
    (``None`` when the EDS has none), data type, access (``"ro"``, ``"wo"``, ``"rw"``, ``"const"``), whether it may
    be mapped into a TPDO / an RPDO, whether 0x1010 saves it, its unit and limits where there are, and with
    ``values=True`` its value (decoded as get's) or ``error``, why it cannot be read (``"no data available
    (0x08000024)"``); ``object_name`` is the EDS name of the object as a whole (``"Identity Object"`` for each
    sub-index of 0x1018)."""
    object: str
    name: Optional[str]
    type: str
    access: str
    tpdo: bool
    rpdo: bool
    stored: bool
    unit: Optional[str] = None
    low: Optional[Value] = None
    high: Optional[Value] = None
    value: Optional[Value] = None
    error: Optional[str] = None
    object_name: Optional[str] = None


def decode_value(value: Any, type_name: str) -> Value:
    """A value of a get/set answer as a Python value: REAL32/REAL64 as float (``"nan"``, ``"inf"``, ``"-inf"``
    included), an UNSIGNED64 above 2^63-1 (a decimal string on the wire) as int, OCTET_STRING and DOMAIN (hex on
    the wire) as bytes; everything else as the JSON gave it."""
    if type_name in ("REAL32", "REAL64"):
        return float(value)
    if type_name == "UNSIGNED64" and isinstance(value, str):
        return int(value)
    if type_name in ("OCTET_STRING", "DOMAIN") and isinstance(value, str):
        return bytes.fromhex(value)
    if isinstance(value, (bool, int, float, str)):
        return value
    raise ProtocolError(f"a value of type {type_name} that is not one: {value!r}")


def encode_value(value: Value) -> Union[int, float, bool, str]:
    """A Python value for a set request: NaN and infinities as the strings the protocol uses, integers beyond
    64-bit signed as decimal strings, bytes as upper-case hex (the form the emulator reads them back in)."""
    if isinstance(value, bool):
        return value
    if isinstance(value, int):
        return value if -(1 << 63) <= value < (1 << 63) else str(value)
    if isinstance(value, float):
        if math.isnan(value):
            return "nan"
        if math.isinf(value):
            return "inf" if value > 0 else "-inf"
        return value
    if isinstance(value, (bytes, bytearray, memoryview)):
        return bytes(value).hex().upper()
    if isinstance(value, str):
        return value
    raise TypeError(f"cannot send a {type(value).__name__} as a value: use int, float, bool, str or bytes")


def object_fields(obj: ObjectRef, sub: Optional[int] = None) -> Dict[str, Any]:
    """The request fields naming an object: ``"object"`` and, for an index number, maybe ``"sub"``."""
    if isinstance(obj, tuple):
        if sub is not None:
            raise ValueError("give the sub-index in the tuple or as sub=, not both")
        index, sub_index = obj
        return {"object": f"0x{index:04X}:{sub_index:02X}"}
    if isinstance(obj, bool) or not isinstance(obj, (int, str)):
        raise TypeError(f"an object is 'INDEX[:SUB]', an index number or (index, sub), not {obj!r}")
    if isinstance(obj, str) and sub is not None:
        raise ValueError("give the sub-index in the string ('0x1018:04') or use an index number with sub=")
    fields: Dict[str, Any] = {"object": obj}
    if sub is not None:
        fields["sub"] = sub
    return fields


def command_arg(arg: Union[int, float, str]) -> Union[int, float, str]:
    """One word after NODE of a command of the command language: a number, or a string without blanks of 1..127
    bytes (what the protocol carries in ``args``)."""
    if isinstance(arg, bool) or not isinstance(arg, (int, float, str)):
        raise TypeError(f"a command argument is a number or a word, not {arg!r}")
    if isinstance(arg, str):
        if not arg or len(arg.encode()) > 127 or any(c in arg for c in " \t\r\n"):
            raise ValueError(f"a command argument is a word without blanks of 1..127 bytes, not {arg!r}")
    elif isinstance(arg, float) and not math.isfinite(arg):
        raise ValueError(f"a command argument cannot be {arg!r}")
    return arg


def parse_address(address: Address) -> Tuple[int, Any]:
    """(family, sockaddr) of a control socket address: a path, ``"unix:PATH"``, ``"HOST:PORT"``,
    ``"tcp:HOST:PORT"``, ``"[::1]:PORT"`` or ``(host, port)``."""
    if isinstance(address, tuple):
        host, port = address
        return socket.AF_INET6 if ":" in host else socket.AF_INET, (host, int(port))
    text = os.fspath(address)
    if text.startswith("unix:"):
        return socket.AF_UNIX, text[len("unix:"):]
    tcp = text[len("tcp:"):] if text.startswith("tcp:") else text
    match = _TCP_ADDRESS.fullmatch(tcp)
    if match and "/" not in tcp:
        if match.group("v6"):
            return socket.AF_INET6, (match.group("v6"), int(match.group("port")))
        return socket.AF_INET, (match.group("host"), int(match.group("port")))
    if text.startswith("tcp:"):
        raise ValueError(f"not a TCP address (HOST:PORT): {text!r}")
    return socket.AF_UNIX, text


def connect(address: Address, *, timeout: float = 5.0, check_protocol: bool = True,
            history: int = 200, token: Optional[str] = None) -> "Client":
    """A client connected to the control socket at ``address`` (``--control-socket PATH`` or ``--control-tcp
    HOST:PORT`` of canopen-emu). With check_protocol it asks ``hello`` at once and raises ProtocolError unless the
    emulator speaks protocol version 1; its answer is then ``client.server``. ``token``: the token of the
    emulator's ``--control-token-file``, given with that first hello (a socket that needs one closes a connection
    whose first request lacks it: ControlError)."""
    family, sockaddr = parse_address(address)
    if family == socket.AF_UNIX and len(os.fsencode(sockaddr)) > _UNIX_PATH_MAX:
        raise ValueError(f"a Unix socket path holds at most {_UNIX_PATH_MAX} bytes: {sockaddr!r}")
    sock = socket.socket(family, socket.SOCK_STREAM)
    try:
        sock.settimeout(timeout)
        sock.connect(sockaddr)
    except BaseException:
        sock.close()
        raise
    client = Client(sock, timeout=timeout, history=history, address=address)
    if check_protocol or token is not None:
        try:
            if check_protocol:
                client.check_protocol(token=token)
            else:
                client.hello(token=token)
        except BaseException:
            client.close()
            raise
    return client


class Client:
    """A connection to canopen-emu's control socket. Methods send one request and return its typed answer, or
    raise ControlError with the emulator's text when it refuses. Safe to share between threads (one request at a
    time goes out); use connect() to make one."""

    def __init__(self, sock: socket.socket, *, timeout: float = 5.0, history: int = 200,
                 max_pending: int = 100_000, address: Optional[Address] = None) -> None:
        self.timeout = timeout
        self.address = address
        self.server: Optional[ServerInfo] = None
        self.stale_answers = 0     # answers to requests that had timed out, read and dropped since
        self.events_dropped = 0    # events dropped because more than max_pending waited untaken
        self._sock: Optional[socket.socket] = sock
        self._buf = b""
        self._lock = threading.RLock()
        self._next_id = 1
        self._pending: Deque[Event] = collections.deque()
        self._max_pending = max_pending
        self._history: Deque[Event] = collections.deque(maxlen=history)

    # --- connection -------------------------------------------------------------------------------------------

    @property
    def closed(self) -> bool:
        return self._sock is None

    def close(self) -> None:
        """Closes the connection (the emulator goes on; quit() stops it). Queued events stay readable."""
        with self._lock:
            if self._sock is not None:
                self._sock.close()
                self._sock = None

    def __enter__(self) -> "Client":
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()

    def __repr__(self) -> str:
        return f"<canopen_emu.Client {self.address!r}{' closed' if self.closed else ''}>"

    # --- requests ---------------------------------------------------------------------------------------------

    def request(self, cmd: str, *, timeout: Optional[float] = None, **fields: Any) -> Dict[str, Any]:
        """Sends ``{"id": N, "cmd": cmd, **fields}`` and returns the answer with ``ok`` true; raises ControlError
        when ``ok`` is false, ControlTimeout when no answer comes within timeout (default: the client's)."""
        with self._lock:
            req_id = self._next_id
            self._next_id += 1
            req: Dict[str, Any] = {"id": req_id, "cmd": cmd, **fields}
            line = json.dumps(req, separators=(",", ":"), ensure_ascii=False, allow_nan=False)
            self._send(line.encode() + b"\n", req)
            wait = self.timeout if timeout is None else timeout
            deadline = time.monotonic() + wait
            while True:
                msg = self._receive(deadline)
                if msg is None:
                    raise ControlTimeout(f"no answer to {line} within {wait} s")
                if "event" in msg:
                    self._queue(msg)
                    continue
                if msg.get("id") != req_id:
                    if msg.get("id") is None and msg.get("ok") is False:
                        # The emulator could not read the line as a request (too long, too many clients...):
                        # the only line outstanding is this one.
                        raise ControlError(str(msg.get("error", "")), req, msg.get("lines", ()), msg)
                    self.stale_answers += 1  # the late answer of a request that timed out
                    continue
                if msg.get("ok") is not True:
                    raise ControlError(str(msg.get("error", "")), req, msg.get("lines", ()), msg)
                return msg

    def hello(self, token: Optional[str] = None) -> ServerInfo:
        """The emulator's program name, version, protocol version, event kinds, buses and their kinds. ``token``:
        for the first request of a connection to a socket with ``--control-token-file`` (connect() gives it)."""
        answer = self.request("hello", token=token) if token is not None else self.request("hello")
        info = ServerInfo(program=answer["program"], version=answer["version"], protocol=answer["protocol"],
                          events=tuple(answer["events"]), buses=tuple(answer["buses"]), raw=answer,
                          clock_time_us=answer.get("clock", {}).get("time_us"),
                          clock_unix_us=answer.get("clock", {}).get("unix_us"),
                          bus_kinds=dict(answer.get("bus_kinds", {})))
        self.server = info
        return info

    def check_protocol(self, token: Optional[str] = None) -> ServerInfo:
        """hello(), and ProtocolError unless it is canopen-emu speaking protocol version 1."""
        try:
            info = self.hello(token=token)
        except (KeyError, TypeError) as e:
            raise ProtocolError(f"the answer to hello lacks {e}: not canopen-emu's control protocol") from e
        if info.program != "canopen-emu" or info.protocol != PROTOCOL_VERSION:
            raise ProtocolError(f"{info.program} speaks control protocol {info.protocol}; this client speaks "
                                f"version {PROTOCOL_VERSION} of canopen-emu's")
        return info

    def nodes(self) -> List[NodeInfo]:
        """The nodes (``list``): node-ID, device, variant, the ID started with, NMT state, bus and its kind."""
        return [_node_info(n) for n in self.request("list")["nodes"]]

    list = nodes

    def show(self, node: NodeRef = "all") -> List[NodeStatus]:
        """``show``: each node's state, error register, active errors and frame counters (one entry for one
        node, several for ``"all"``)."""
        return [_node_status(n) for n in self.request("show", node=node)["nodes"]]

    def heard(self, bus: Optional[str] = None) -> List[HeardNode]:
        """The other nodes heard on the buses (or on ``bus``) by their heartbeats: a real device or another
        emulator beside the emulated nodes."""
        answer = self.request("show", node="all" if bus is None else f"all@{bus}")
        return [HeardNode(h["node"], h["bus"], h["state"], h["boot_up"], h["last_heartbeat_us"],
                          h.get("bus_kind")) for h in answer.get("heard", [])]

    def get(self, node: NodeRef, obj: ObjectRef, sub: Optional[int] = None, *,
            timeout: Optional[float] = None) -> Value:
        """The value of an object, typed: ``get(16, "0x1017")`` -> 5000. Integers and BOOLEAN as int/bool, REAL32
        and REAL64 as float, VISIBLE_STRING as str, OCTET_STRING and DOMAIN as bytes."""
        return self.get_entry(node, obj, sub, timeout=timeout).value

    def get_entry(self, node: NodeRef, obj: ObjectRef, sub: Optional[int] = None, *,
                  timeout: Optional[float] = None) -> Entry:
        """get() with the whole answer: value, data type, EDS name, normalised object."""
        return _entry(self.request("get", timeout=timeout, node=node, **object_fields(obj, sub)))

    def get_many(self, node: NodeRef, objects: Sequence[ObjectRef], *,
                 timeout: Optional[float] = None) -> List[Reading]:
        """The values of up to 64 objects of one node in one request, in the order asked: ``get_many(16,
        ["0x1017", (0x2002, 6)])``. An object the node cannot read gives a Reading with ``error``, not an
        exception."""
        names = [object_fields(o)["object"] if not isinstance(o, int) or isinstance(o, bool)
                 else f"0x{o:04X}:00" for o in objects]
        answer = self.request("get", timeout=timeout, node=node, objects=names)
        return [Reading(object=v["object"], value=decode_value(v["value"], v["type"]) if "value" in v else None,
                        type=v.get("type"), error=v.get("error")) for v in answer["values"]]

    def set(self, node: NodeRef, obj: ObjectRef, value: Value, sub: Optional[int] = None, *,
            timeout: Optional[float] = None) -> Value:
        """Writes a value as the device itself would (no SDO access checks, the data type's range and the
        device's rules apply) and returns the value read back after the write."""
        return self.set_entry(node, obj, value, sub, timeout=timeout).value

    def set_entry(self, node: NodeRef, obj: ObjectRef, value: Value, sub: Optional[int] = None, *,
                  timeout: Optional[float] = None) -> Entry:
        """set() with the whole answer."""
        return _entry(self.request("set", timeout=timeout, node=node, **object_fields(obj, sub),
                                   value=encode_value(value)))

    def objects(self, node: NodeRef, *, values: bool = False, timeout: Optional[float] = None) -> List[ObjectInfo]:
        """The node's dictionary (``objects``): every sub-index it has, in (index, sub) order, with name, type,
        access, PDO mapping, storage, unit and limits; with ``values=True`` each value as get() reads it."""
        fields: Dict[str, Any] = {"node": node}
        if values:
            fields["values"] = True
        return [_object_info(o) for o in self.request("objects", timeout=timeout, **fields)["objects"]]

    def command(self, node: Optional[NodeRef], cmd: str, *args: Union[int, float, str],
                timeout: Optional[float] = None) -> List[str]:
        """Any other command of the command language (``help``, ``emcy``, a device's ``load``, ``error``...):
        ``command(16, "load", 1, 2000)``. Returns its reply lines; raises ControlError (with ``lines``) when the
        emulator refuses it. node None: a command without a node (``help``)."""
        fields: Dict[str, Any] = {}
        if node is not None:
            fields["node"] = node
        if args:
            fields["args"] = [command_arg(a) for a in args]
        return list(self.request(cmd, timeout=timeout, **fields)["lines"])

    def help(self, node: Optional[NodeRef] = None) -> List[str]:
        """The common commands, or a node's device commands."""
        return self.command(node, "help")

    def device_commands(self, node: NodeRef) -> List[Tuple[str, str]]:
        """A node's device commands as (usage, text): ``("pollution PERCENT", "pollution as % of ...")``."""
        answer = self.request("help", node=node)
        return [(c["usage"], c["text"]) for c in answer.get("commands", [])]

    def emcy(self, node: NodeRef, code: int, register: Optional[int] = None, info: Sequence[int] = ()) -> List[str]:
        """Raises a raw CiA error: EMCY, 0x1001, 0x1003 (``emcy NODE CODE [REG [B0..B4]]``)."""
        if info and register is None:
            raise ValueError("the manufacturer bytes need the error register too (emcy NODE CODE REG B0..B4)")
        args: List[Union[int, str]] = [f"0x{code:04X}"]
        if register is not None:
            args.append(register)
        args.extend(info)
        return self.command(node, "emcy", *args)

    def emcy_clear(self, node: NodeRef, code: int, info: Sequence[int] = ()) -> List[str]:
        """Clears a raw CiA error: error-reset EMCY with the bytes given (``emcy-clear NODE CODE [B0..B4]``)."""
        return self.command(node, "emcy-clear", f"0x{code:04X}", *info)

    def power_cycle(self, node: NodeRef) -> List[str]:
        """Switches the node's supply off and on: the model restarts, stored values load, boot-up."""
        return self.command(node, "power-cycle")

    def tables(self) -> Tables:
        """The emulator's own tables (``tables``): its kinds of protocol fault and the SDO abort texts it uses."""
        answer = self.request("tables")
        return Tables(faults=tuple(FaultKind(kind=f["kind"], usage=f["usage"], limits=f["limits"], text=f["text"])
                                   for f in answer["faults"]),
                      aborts={int(a["code"]): a["text"] for a in answer["aborts"]})

    def inject_fault(self, node: NodeRef, kind: str, *args: Union[int, float, str]) -> List[str]:
        """A protocol fault (``fault NODE KIND ARGS``; the kinds and their arguments: ``tables().faults``): sdo-ignore, sdo-delay, sdo-abort, heartbeat-stop,
        heartbeat-jitter, heartbeat-state, tpdo-freeze, tpdo-drop, tpdo-length, emcy-burst, reboot, bus-off,
        lss-silent. An emulator without fault injection refuses it: ControlError "unknown command 'fault' ..."."""
        return self.command(node, "fault", kind, *args)

    def clear_fault(self, node: NodeRef, kind: str = "all") -> List[str]:
        """Ends a node's protocol faults of one kind, or all of them (``fault-clear NODE KIND``)."""
        return self.command(node, "fault-clear", kind)

    def faults(self, node: NodeRef) -> List[str]:
        """The reply lines of ``faults NODE``."""
        return self.command(node, "faults")

    def quit(self, timeout: Optional[float] = None) -> None:
        """Stops the emulator (``quit``) and closes this connection."""
        try:
            self.request("quit", timeout=timeout)
        except ConnectionClosed:
            pass  # it went before its answer reached us: stopped all the same
        finally:
            self.close()

    # --- events -----------------------------------------------------------------------------------------------

    def subscribe(self, events: Union[str, Iterable[str]], nodes: Optional[Sequence[NodeRef]] = None,
                  frames: Union[None, FrameFilter, Sequence[FrameFilter]] = None) -> List[str]:
        """Asks for events of these kinds (``"all"``: every kind but ``frame``), of these nodes only (at most 16;
        replaces the node filter); ``frame`` events need ``frames``: a COB-ID, ``(cob_id, mask)`` or
        ``"COB-ID[/MASK]"`` of 11-bit frames, ``ExtendedId(cob_id[, mask])`` or ``"COB-IDx[/MASK]"`` of 29-bit
        ones, or a list of up to 4 of them (every frame: ``[(0, 0), ExtendedId(0, 0)]``). Returns the kinds now
        subscribed. Subscriptions add up."""
        fields: Dict[str, Any] = {"events": events if events == "all" else
                                  [events] if isinstance(events, str) else list(events)}
        if nodes is not None:
            fields["nodes"] = list(nodes)
        if frames is not None:
            def one(f: FrameFilter) -> str:
                if isinstance(f, ExtendedId):  # before tuple: it is one
                    return str(f)
                if isinstance(f, tuple):
                    return f"0x{f[0]:X}/0x{f[1]:X}"
                return f"0x{f:X}" if isinstance(f, int) else f
            fields["frames"] = ([one(f) for f in frames] if isinstance(frames, list) else one(frames))
        return list(self.request("subscribe", **fields)["events"])

    def unsubscribe(self, events: Union[None, str, Iterable[str]] = None) -> None:
        """Ends subscriptions of these kinds (all when None). Events already received stay queued."""
        fields: Dict[str, Any] = {}
        if events is not None:
            fields["events"] = events if events == "all" else [events] if isinstance(events, str) else list(events)
        self.request("unsubscribe", **fields)

    def wait_for(self, kind: Optional[str], timeout: float = 5.0, **match: Any) -> Event:
        """The first event of this kind (None: any) whose fields equal the keywords, taken from the queue: one
        that came earlier (while an answer was awaited) counts. A keyword's value may be a predicate
        (``code=lambda c: c >= 0x3000``); a trailing underscore is dropped (``from_="STOPPED"`` for ``from``).
        Events that do not match stay queued. Raises ControlTimeout after timeout seconds."""
        wanted = {(k[:-1] if k.endswith("_") else k): v for k, v in match.items()}
        deadline = time.monotonic() + timeout
        seen: Dict[str, int] = {}
        with self._lock:
            found = self._take_matching(kind, wanted)
            while found is None:
                msg = self._receive(deadline)
                if msg is None:
                    others = ", ".join(f"{n} {k}" for k, n in sorted(seen.items())) or "none"
                    raise ControlTimeout(f"no {kind or 'any'} event with {wanted} within {timeout} s "
                                         f"(other events meanwhile: {others})")
                if "event" not in msg:
                    self.stale_answers += 1
                    continue
                self._queue(msg)
                seen[str(msg.get("event"))] = seen.get(str(msg.get("event")), 0) + 1
                found = self._take_matching(kind, wanted)
            return found

    def events(self, timeout: Optional[float] = None) -> Iterator[Event]:
        """The events as they come, queued ones first; ends after timeout seconds (None: never) or when the
        connection ends. Events not taken from the iterator stay queued."""
        deadline = None if timeout is None else time.monotonic() + timeout
        while True:
            with self._lock:
                ev: Optional[Event] = self._pending.popleft() if self._pending else None
                while ev is None:
                    try:
                        msg = self._receive(deadline)
                    except ConnectionClosed:
                        return
                    if msg is None:
                        return
                    if "event" in msg:
                        ev = msg
                        self._history.append(msg)
                    else:
                        self.stale_answers += 1
            yield ev

    def drain_events(self) -> List[Event]:
        """Every event received and not taken yet, after reading what has already arrived (without waiting); the
        queue is empty afterwards."""
        with self._lock:
            self._read_available()
            taken = list(self._pending)
            self._pending.clear()
            return taken

    @property
    def pending_events(self) -> int:
        """How many received events wait in the queue (not counting any still in the socket)."""
        return len(self._pending)

    @property
    def recent_events(self) -> List[Event]:
        """The last events received (taken or not), oldest first: what a failure report shows."""
        return list(self._history)

    # --- internals --------------------------------------------------------------------------------------------

    def _take_matching(self, kind: Optional[str], wanted: Mapping[str, Any]) -> Optional[Event]:
        for i, ev in enumerate(self._pending):
            if _matches(ev, kind, wanted):
                del self._pending[i]
                return ev
        return None

    def _queue(self, event: Event) -> None:
        self._history.append(event)
        if len(self._pending) >= self._max_pending:
            self._pending.popleft()
            self.events_dropped += 1
        self._pending.append(event)

    def _send(self, data: bytes, request: Mapping[str, Any]) -> None:
        sock = self._require_socket()
        sock.settimeout(self.timeout)
        try:
            sock.sendall(data)
        except (BrokenPipeError, ConnectionResetError) as e:
            refusal = self._last_words()
            self.close()
            if refusal is not None:
                # It said why before it closed (a 65th client): that is the answer.
                raise ControlError(str(refusal.get("error", "")), request, (), refusal) from e
            raise ConnectionClosed(f"the emulator closed the control connection ({e})") from e

    def _last_words(self) -> Optional[Dict[str, Any]]:
        """A refusal (``"id": null``) the emulator sent before it closed the connection, if it can still be read."""
        sock = self._require_socket()
        try:
            sock.settimeout(0)
            while True:
                chunk = sock.recv(65536)
                if not chunk:
                    break
                self._buf += chunk
        except OSError:
            pass
        for line in self._buf.split(b"\n"):
            try:
                msg = json.loads(line)
            except ValueError:
                continue
            if isinstance(msg, dict) and msg.get("id") is None and msg.get("ok") is False:
                return msg
        return None

    def _require_socket(self) -> socket.socket:
        if self._sock is None:
            raise ConnectionClosed("the control connection is closed")
        return self._sock

    def _receive(self, deadline: Optional[float]) -> Optional[Dict[str, Any]]:
        """The next JSON object from the emulator; None when the deadline passed first."""
        while b"\n" not in self._buf:
            sock = self._require_socket()
            if deadline is None:
                sock.settimeout(None)
            else:
                left = deadline - time.monotonic()
                if left <= 0:
                    return None
                sock.settimeout(left)
            try:
                chunk = sock.recv(65536)
            except socket.timeout:
                return None
            except ConnectionResetError as e:
                self.close()
                raise ConnectionClosed(f"the emulator closed the control connection ({e})") from e
            if not chunk:
                self.close()
                raise ConnectionClosed("the emulator closed the control connection"
                                       + (f" (unread: {self._buf[:200]!r})" if self._buf else ""))
            self._buf += chunk
        line, self._buf = self._buf.split(b"\n", 1)
        return _parse(line)

    def _read_available(self) -> None:
        """Queues the events that have arrived, without waiting for more."""
        while True:
            while b"\n" in self._buf:
                line, self._buf = self._buf.split(b"\n", 1)
                msg = _parse(line)
                if "event" in msg:
                    self._queue(msg)
                else:
                    self.stale_answers += 1
            if self._sock is None or not select.select([self._sock], [], [], 0)[0]:
                return
            self._sock.settimeout(0)
            try:
                chunk = self._sock.recv(65536)
            except (BlockingIOError, socket.timeout):
                return
            except ConnectionResetError:
                chunk = b""
            if not chunk:
                self.close()
                return
            self._buf += chunk


def _parse(line: bytes) -> Dict[str, Any]:
    try:
        msg = json.loads(line)
    except ValueError as e:
        raise ProtocolError(f"not a JSON line of the control protocol: {line[:200]!r} ({e})") from e
    if not isinstance(msg, dict):
        raise ProtocolError(f"not a JSON object of the control protocol: {line[:200]!r}")
    return msg


def _matches(event: Event, kind: Optional[str], wanted: Mapping[str, Any]) -> bool:
    if kind is not None and event.get("event") != kind:
        return False
    for key, expected in wanted.items():
        if key not in event:
            return False
        if callable(expected):
            if not expected(event[key]):
                return False
        elif event[key] != expected:
            return False
    return True


def _node_info(n: Mapping[str, Any]) -> NodeInfo:
    return NodeInfo(node=n["node"], device=n["device"], variant=n["variant"], started_as=n["started_as"],
                    state=n["state"], bus=n["bus"], bus_kind=n.get("bus_kind"))


def _node_status(n: Mapping[str, Any]) -> NodeStatus:
    return NodeStatus(node=n["node"], device=n["device"], variant=n["variant"], started_as=n["started_as"],
                      state=n["state"], bus=n["bus"], bus_kind=n.get("bus_kind"), error_register=n["error_register"],
                      errors=tuple(ActiveError(e["code"], e["register"], bytes.fromhex(e["info"]))
                                   for e in n["errors"]),
                      tx_frames=n["tx_frames"], rx_frames=n["rx_frames"], tx_dropped=n["tx_dropped"],
                      device_type=n["device_type"], heartbeat_ms=n["heartbeat_ms"],
                      last_heartbeat_us=n["last_heartbeat_us"], faults=tuple(n["faults"]),
                      last_emcy=None if n["last_emcy"] is None else LastEmcy(
                          n["last_emcy"]["code"], n["last_emcy"]["register"], bytes.fromhex(n["last_emcy"]["info"]),
                          n["last_emcy"]["time_us"]))


def _entry(answer: Mapping[str, Any]) -> Entry:
    return Entry(node=answer["node"], object=answer["object"], value=decode_value(answer["value"], answer["type"]),
                 type=answer["type"], name=answer.get("name", ""), unit=answer.get("unit"))


def _object_info(o: Mapping[str, Any]) -> ObjectInfo:
    def typed(key: str) -> Optional[Value]:
        return decode_value(o[key], o["type"]) if key in o else None
    return ObjectInfo(object=o["object"], name=o["name"], type=o["type"], access=o["access"], tpdo=o["tpdo"],
                      rpdo=o["rpdo"], stored=o["stored"], unit=o.get("unit"), low=typed("low"), high=typed("high"),
                      value=typed("value"), error=o.get("error"), object_name=o.get("object_name"))
