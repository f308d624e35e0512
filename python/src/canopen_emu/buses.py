"""The buses canopen-emu runs on, as its ``-i`` names them (docs/buses.md), and how a python-can master joins each:
``Bus.parse("vcan0")``, ``Bus.parse("udp_multicast:239.74.163.2:43113")``, ``choose_bus("auto")``.

``auto`` is vcan0 where it exists and is up, else a udp_multicast group and port of this process's own
(session_udp_bus()): no root, no kernel module, and two test sessions on one machine never share a bus.
``socketcand`` is a virtual bus inside each emulator, served over TCP on loopback by its ``--socketcand``
(socketcand_bus()): the master reaches it with python-can's stock ``socketcand`` interface."""
from __future__ import annotations

import fcntl
import ipaddress
import os
import socket
import struct
from dataclasses import dataclass
from typing import Any, Callable, Dict, Optional

#: How long python-canopen's receive thread waits for a frame at a time: its disconnect() waits for the wait to end,
#: a whole second with python-canopen's default (1.0), at the end of every test with a master; 0.1 s costs nothing.
NOTIFIER_CYCLE_S = 0.1
#: The kinds of bus, by python-can's interface names (hello's ``bus_kinds``, list's ``bus_kind``).
BUS_KINDS = ("socketcan", "udp_multicast", "virtual")
#: python-can's udp_multicast defaults (and canopen-emu's ``-i udp_multicast``): IPv4 group and port.
DEFAULT_UDP_GROUP = "239.74.163.2"
DEFAULT_UDP_PORT = 43113
#: The ports a session's own udp_multicast bus is taken from: below Linux's ephemeral ports (32768 and up), so no
#: socket of another program is given one by the kernel meanwhile.
SESSION_PORTS = range(20000, 30000)
_IFF_UP = 0x1
_SIOCGIFFLAGS = 0x8913  # <linux/sockios.h>


@dataclass(frozen=True)
class Bus:
    """One bus: ``spec``, the text given to canopen-emu's ``-i``; ``kind`` (``"socketcan"``, ``"udp_multicast"``,
    ``"virtual"``); ``name``, the emulator's name of it (``"vcan0"``, ``"udp_multicast:239.74.163.2:43113"``,
    ``"plant"``: what ``NODE@BUS``, list's ``bus`` and the log show); for udp_multicast its ``group``, ``port``,
    ``ttl`` and ``iface`` (None: the route's); ``socketcand``: the ``HOST:PORT`` the emulator serves its buses at
    (canopen-emu's ``--socketcand``; port 0: a free one, told by its log), None when it does not."""
    spec: str
    kind: str
    name: str
    group: Optional[str] = None
    port: Optional[int] = None
    ttl: int = 1
    iface: Optional[str] = None
    socketcand: Optional[str] = None

    @classmethod
    def parse(cls, text: str) -> "Bus":
        """A bus from canopen-emu's ``-i`` text: ``IFACE``, ``socketcan:IFACE``,
        ``udp_multicast[:GROUP[:PORT]][,ttl=N][,iface=NAME]`` or ``virtual:NAME``. ValueError when it is none."""
        if text.startswith("udp_multicast") and text[len("udp_multicast"):][:1] in ("", ":", ","):
            return _parse_udp(text)
        if text.startswith("virtual:"):
            name = text[len("virtual:"):]
            if not name or len(name) > 47 or any(c in name for c in "/@,"):
                raise ValueError(f"virtual:NAME takes a name of 1..47 characters without '/', '@' or ',', not {text!r}")
            return cls(text, "virtual", name)
        iface = text[len("socketcan:"):] if text.startswith("socketcan:") else text
        if not iface or len(iface) > 15 or ":" in iface or "/" in iface or any(c.isspace() for c in iface):
            raise ValueError(f"not a bus: {text!r} (an interface name, socketcan:IFACE, "
                             "udp_multicast[:GROUP[:PORT]][,ttl=N][,iface=NAME] or virtual:NAME)")
        return cls(text, "socketcan", iface)

    @property
    def label(self) -> str:
        """The name with the kind where the name does not say it: ``"vcan0 (socketcan)"``, ``"plant (virtual)"``,
        ``"udp_multicast:239.74.163.2:43113"``."""
        if self.socketcand is not None:
            return f"{self.name} ({self.kind}, served by socketcand on {self.socketcand})"
        return self.name if self.name.startswith(self.kind + ":") else f"{self.name} ({self.kind})"

    def can_kwargs(self) -> Dict[str, Any]:
        """The arguments of ``can.Bus(**kwargs)`` and of python-canopen's ``Network.connect(**kwargs)`` that join
        this bus: ``{"interface": "socketcan", "channel": "vcan0"}``, ``{"interface": "udp_multicast", "channel":
        GROUP, "port": PORT, "hop_limit": TTL}`` (python-can's udp_multicast needs the ``msgpack`` package: ``pip
        install canopen-emu[udp]``). A virtual bus has no medium a master could join: ValueError."""
        if self.kind == "socketcan":
            return {"interface": "socketcan", "channel": self.name}
        if self.kind == "udp_multicast":
            # python-can joins on the interface of the route to the group: with iface= the emulator may be elsewhere
            return {"interface": "udp_multicast", "channel": self.group, "port": self.port, "hop_limit": self.ttl}
        if self.socketcand is not None:
            raise ValueError(f"{self.label}: the port is the emulator's; its network() joins the bus (python-can's "
                             "socketcand interface)")
        raise ValueError(f"{self.label} is inside the emulator: no python-can master can join it (use a socketcan or "
                         "udp_multicast bus, or serve it with socketcand)")

    def network(self) -> Any:
        """A python-canopen ``Network`` connected to this bus (``network.disconnect()`` when done). Needs the
        ``canopen`` package."""
        try:
            import canopen  # not a dependency of this package: only a test with a master needs it
        except ImportError as e:
            raise ImportError("a python-canopen Network needs the canopen package: pip install canopen") from e
        net = canopen.Network()
        net.NOTIFIER_CYCLE = NOTIFIER_CYCLE_S
        net.connect(**self.can_kwargs())
        return net

    def __str__(self) -> str:
        return self.spec


def _parse_udp(text: str) -> Bus:
    head, *options = text.split(",")
    rest = head[len("udp_multicast"):]
    group, port = DEFAULT_UDP_GROUP, DEFAULT_UDP_PORT
    if rest.startswith(":"):
        rest = rest[1:]
        port_text: Optional[str] = None
        if rest.startswith("["):
            close = rest.find("]")
            if close < 0 or rest[close + 1:][:1] not in ("", ":"):
                raise ValueError(f"udp_multicast: an IPv6 group goes in brackets: [ff15::1]:43113, not {text!r}")
            group, port_text = rest[1:close], rest[close + 2:] if rest[close + 1:] else None
        elif rest.count(":") == 1:
            group, port_text = rest.split(":")
        elif rest:
            group = rest
        if port_text is not None:
            if not port_text.isdigit() or not 1 <= int(port_text) <= 65535:
                raise ValueError(f"udp_multicast: the port is 1..65535, not {port_text!r}")
            port = int(port_text)
        group = group or DEFAULT_UDP_GROUP
    try:
        address = ipaddress.ip_address(group)
    except ValueError:
        raise ValueError(f"udp_multicast: {group!r} is not an IP address") from None
    if not address.is_multicast:
        raise ValueError(f"udp_multicast: {group} is not a multicast group (224.0.0.0/4, ff00::/8)")
    ttl, iface = 1, None
    for option in options:
        key, _, value = option.partition("=")
        if key == "ttl" and value.isdigit() and int(value) <= 255:
            ttl = int(value)
        elif key == "iface" and value:
            iface = value
        else:
            raise ValueError(f"udp_multicast: options are ttl=0..255 and iface=NAME, not {option!r}")
    group = address.compressed
    name = f"udp_multicast:[{group}]:{port}" if address.version == 6 else f"udp_multicast:{group}:{port}"
    return Bus(text, "udp_multicast", name, group, port, ttl, iface)


def interface_is_up(name: str) -> bool:
    """Whether the network interface exists in this process's network namespace and is administratively up
    (IFF_UP, asked with SIOCGIFFLAGS: /sys/class/net shows the namespace sysfs was mounted in, not necessarily this
    one, and a vcan's operstate says ``unknown`` when it is up)."""
    if len(name.encode()) >= 16:
        return False
    with socket.socket(socket.AF_INET, socket.SOCK_DGRAM) as sock:
        try:
            ifreq = fcntl.ioctl(sock.fileno(), _SIOCGIFFLAGS, struct.pack("16sH22x", name.encode(), 0))
        except OSError:  # ENODEV: no such interface here
            return False
    return struct.unpack_from("16sH", ifreq)[1] & _IFF_UP != 0


def port_is_free(port: int) -> bool:
    """Whether no UDP socket of this machine (of this network namespace) is bound to the port: a bind without
    SO_REUSEADDR fails beside any other socket on it, a multicast listener's included."""
    with socket.socket(socket.AF_INET, socket.SOCK_DGRAM) as probe:
        try:
            probe.bind(("", port))
        except OSError:
            return False
    return True


def session_udp_bus(pid: Optional[int] = None, *, probe: bool = True) -> Bus:
    """A udp_multicast bus of this process's own, TTL 0 (its datagrams are delivered on this machine and never sent
    out on a link: a test session's bus stays on the machine that runs it): port 20000 + pid % 10000 (the next free one when that is
    taken), so that two sessions on one machine never share it (python-can's sockets bind the port, not the group,
    and take every group joined on it), and a group 239.74.X.Y of the pid and random bits, so that sessions on two
    machines of one link seldom share one."""
    pid = os.getpid() if pid is None else pid
    start = SESSION_PORTS.start + pid % len(SESSION_PORTS)
    port = start
    if probe:
        for step in range(len(SESSION_PORTS)):
            port = SESSION_PORTS.start + (start - SESSION_PORTS.start + step) % len(SESSION_PORTS)
            if port_is_free(port):
                break
        else:
            raise OSError("no free UDP port in 20000..29999 for the session's udp_multicast bus")
    salt = int.from_bytes(os.urandom(2), "big")
    x, y = ((pid >> 8) ^ (salt >> 8)) & 0xFF, (pid ^ salt) & 0xFF
    return Bus.parse(f"udp_multicast:239.74.{x}.{y}:{port},ttl=0")


def socketcand_bus(name: str = "canopen-emu", address: str = "127.0.0.1:0") -> Bus:
    """A virtual bus NAME that the emulator serves with ``--socketcand ADDRESS`` (default loopback and a free port
    of each emulator's own, so that emulators of parallel tests never share one): a master joins it with python-can's
    ``socketcand`` interface (``Emulator.network()``), as it would join a SocketCAN interface of another machine."""
    bus = Bus.parse(f"virtual:{name}")
    return Bus(bus.spec, bus.kind, bus.name, socketcand=address)


def choose_bus(choice: str = "auto", is_up: Callable[[str], bool] = interface_is_up) -> Bus:
    """The bus ``--canopen-emu-bus`` names: ``auto`` is vcan0 where it exists and is up (``is_up``), else
    session_udp_bus(); ``socketcand`` is socketcand_bus(); anything else is parsed as canopen-emu's ``-i``
    (Bus.parse)."""
    if choice == "auto":
        return Bus.parse("vcan0") if is_up("vcan0") else session_udp_bus()
    if choice == "socketcand":
        return socketcand_bus()
    return Bus.parse(choice)
