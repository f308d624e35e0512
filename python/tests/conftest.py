"""Tests of the installed canopen_emu package against the real canopen-emu on vcan0/vcan1 (and, marked netns, on
udp_multicast inside a network namespace of their own).

python/run-tests.sh runs them in a fresh venv where ./python was pip-installed as a user installs it: the
canopen_emu imported here is the installed one, and the plugin's fixtures (canopen_emu, canopen_emu_factory...)
come from its pytest11 entry point; nothing here imports the plugin. The program is $CANOPEN_EMU; the source tree
(for include/co/co_version.h) is $CO_SOURCE_DIR."""
import os
from pathlib import Path
from typing import Callable, Iterator, List

import can
import canopen
import pytest

pytest_plugins = ("pytester",)


def pytest_configure(config):
    # run-tests.sh's second pass runs these alone, inside tests/udp/netns-run (a network namespace whose only
    # interface is lo); its first pass, on vcan, leaves them out
    config.addinivalue_line("markers", "netns: runs on udp_multicast inside a network namespace of its own (only lo)")

SOURCE_DIR = Path(os.environ.get("CO_SOURCE_DIR") or Path(__file__).resolve().parents[2])
EDS = {"pro-ionizer": SOURCE_DIR / "od/pro-ionizer.eds", "sds": SOURCE_DIR / "od/sds.eds",
       "buerkert": SOURCE_DIR / "od/buerkert-flow-controller.eds"}


@pytest.fixture
def can_bus() -> Iterator[Callable[[str], can.BusABC]]:
    """can_bus("vcan1"): a python-can socket on that interface, shut at the end of the test."""
    opened: List[can.BusABC] = []

    def open_bus(channel: str = "vcan0") -> can.BusABC:
        bus = can.Bus(channel=channel, interface="socketcan", receive_own_messages=False)
        opened.append(bus)
        return bus

    yield open_bus
    for bus in opened:
        bus.shutdown()


@pytest.fixture
def network() -> Iterator[canopen.Network]:
    """python-canopen as the master on vcan0."""
    net = canopen.Network()
    net.connect(interface="socketcan", channel="vcan0")
    yield net
    net.disconnect()


def remote(network: canopen.Network, device: str, node_id: int) -> canopen.RemoteNode:
    node = canopen.RemoteNode(node_id, str(EDS[device]))
    # User-Mode Linux shares one CPU between the emulator, this master and its receive thread: the default
    # 0.3 s can pass before the receive thread runs although the answer is on the bus.
    node.sdo.RESPONSE_TIMEOUT = 5.0
    network.add_node(node)
    return node
