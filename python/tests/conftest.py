"""Tests of the installed canopen_emu package against the real canopen-emu, on the bus the plugin's auto chooses:
run-tests.sh runs those marked vcan (several SocketCAN interfaces, SocketCAN's own messages) on vcan0/vcan1, and all
others on udp_multicast inside a network namespace of their own (only lo), where auto takes a group of the session's.

python/run-tests.sh runs them in a fresh venv where ./python was pip-installed as a user installs it: the
canopen_emu imported here is the installed one, and the plugin's fixtures (canopen_emu, canopen_emu_factory...)
come from its pytest11 entry point; nothing here imports the plugin. The program is $CANOPEN_EMU; the source tree
(for include/co/co_version.h) is $CO_SOURCE_DIR."""
import os
from pathlib import Path
from typing import Callable, Iterator, List, Optional

import can
import canopen
import pytest

pytest_plugins = ("pytester",)


def pytest_configure(config):
    # run-tests.sh's vcan pass runs the tests marked vcan only; its udp pass, inside tests/udp/netns-run (a network
    # namespace whose only interface is lo), all others (netns: those that need to be there)
    config.addinivalue_line("markers", "vcan: needs SocketCAN interfaces (vcan0, vcan1): run in the vcan pass")
    config.addinivalue_line("markers", "netns: runs on udp_multicast inside a network namespace of its own (only lo)")

SOURCE_DIR = Path(os.environ.get("CO_SOURCE_DIR") or Path(__file__).resolve().parents[2])
EDS = {"pro-ionizer": SOURCE_DIR / "od/pro-ionizer.eds", "sds": SOURCE_DIR / "od/sds.eds",
       "buerkert": SOURCE_DIR / "od/buerkert-flow-controller.eds"}


@pytest.fixture
def can_bus(canopen_emu_bus) -> Iterator[Callable[..., can.BusABC]]:
    """can_bus(): a python-can bus on the session's bus (the plugin's choice); can_bus("vcan1"): on that SocketCAN
    interface. Shut at the end of the test."""
    opened: List[can.BusABC] = []

    def open_bus(channel: Optional[str] = None) -> can.BusABC:
        bus = (can.Bus(**canopen_emu_bus.can_kwargs()) if channel is None else
               can.Bus(channel=channel, interface="socketcan", receive_own_messages=False))
        opened.append(bus)
        return bus

    yield open_bus
    for bus in opened:
        bus.shutdown()


@pytest.fixture
def network(canopen_emu_bus) -> Iterator[canopen.Network]:
    """python-canopen as the master on the session's bus."""
    net = canopen_emu_bus.network()
    yield net
    net.disconnect()


def remote(network: canopen.Network, device: str, node_id: int) -> canopen.RemoteNode:
    node = canopen.RemoteNode(node_id, str(EDS[device]))
    # User-Mode Linux shares one CPU between the emulator, this master and its receive thread: the default
    # 0.3 s can pass before the receive thread runs although the answer is on the bus.
    node.sdo.RESPONSE_TIMEOUT = 5.0
    network.add_node(node)
    return node
