"""canopen_emu: drive canopen-emu, the emulator of CANopen devices on Linux SocketCAN, from Python and pytest.

- connect(): a client of the control socket (docs/control-protocol.md): typed get/set, device commands, faults,
  events.
- Emulator: starts canopen-emu, waits until its nodes have booted, stops it; Emulator.network(): a python-canopen
  Network on its bus.
- Bus, choose_bus(): the buses by canopen-emu's -i names (socketcan, udp_multicast, virtual), "auto" (vcan0 where it
  is up, else a udp_multicast group of the session's own), and how python-can joins each (Bus.can_kwargs()).
- the pytest plugin (canopen_emu.pytest_plugin, registered through the pytest11 entry point): fixtures
  canopen_emu, canopen_emu_factory, canopen_emu_session, canopen_emu_network, canopen_emu_bus, option
  --canopen-emu-bus, and the emulator's log in a failed test's report.
"""
from ._version import __version__
from .buses import BUS_KINDS, Bus, choose_bus, session_udp_bus, socketcand_bus
from .client import (PROTOCOL_VERSION, ActiveError, Address, Client, Entry, Event, ExtendedId, FaultKind,
                     FrameFilter, HeardNode, LastEmcy, NodeInfo, NodeRef, NodeStatus, ObjectInfo, ObjectRef, Reading,
                     ServerInfo, Tables, Value, connect, decode_value, encode_value)
from .emulator import DEFAULT_NODES, Emulator, find_executable
from .errors import (CanopenEmuError, ConnectionClosed, ControlError, ControlTimeout, EmulatorError,
                     ProtocolError)


__all__ = [
    "__version__", "PROTOCOL_VERSION", "DEFAULT_NODES",
    "connect", "Client", "Emulator", "find_executable", "decode_value", "encode_value",
    "Bus", "BUS_KINDS", "choose_bus", "session_udp_bus", "socketcand_bus",
    "ServerInfo", "NodeInfo", "NodeStatus", "HeardNode", "ActiveError", "LastEmcy", "Entry", "ObjectInfo", "Reading",
    "Address", "NodeRef", "ObjectRef", "Value", "Event", "ExtendedId", "FrameFilter", "Tables", "FaultKind",
    "CanopenEmuError", "ControlError", "ProtocolError", "ControlTimeout", "ConnectionClosed", "EmulatorError",
]
