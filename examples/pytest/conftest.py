"""Fixtures of the example suite. The emulator comes from the canopen_emu pytest plugin (pip install ./python):
``canopen_emu`` starts the nodes of a test's ``@pytest.mark.canopen_emu_nodes(...)`` marker and stops them at its
end, and a failed test's report shows the emulator's log. Here: the master under test on the same bus, and the
protocol faults, which skip a test when the emulator has none."""
import os
from pathlib import Path
from typing import Iterator, List, Union

import canopen
import pytest

from canopen_emu import ControlError, Emulator
from line_master import LineMaster

# The object dictionaries of the emulated devices: the repository's od/ (an installed canopen-emu has them in
# share/canopen-emu/eds/; point CANOPEN_EMU_EDS_DIR there).
EDS_DIR = Path(os.environ.get("CANOPEN_EMU_EDS_DIR") or Path(__file__).resolve().parents[2] / "od")
EDS = {"pro-ionizer": EDS_DIR / "pro-ionizer.eds", "sds": EDS_DIR / "sds.eds",
       "buerkert": EDS_DIR / "buerkert-flow-controller.eds"}


@pytest.fixture
def network(canopen_emu_network: canopen.Network) -> canopen.Network:
    """python-canopen on the emulators' bus, whatever its kind: the plugin's canopen_emu_network, on the bus its
    --canopen-emu-bus chose (auto: vcan0 where it is up, else a udp_multicast group of this session's own)."""
    return canopen_emu_network


@pytest.fixture
def master(network: canopen.Network) -> Iterator[LineMaster]:
    """The master under test. The emulator answers SDO within milliseconds, but python-canopen's receive thread
    can run late on a loaded machine (User-Mode Linux has one CPU for the emulator, the master and pytest): 2 s
    per attempt keeps the timeout cases short and the others free of false timeouts."""
    line = LineMaster(network, sdo_timeout=2.0, sdo_attempts=2)
    yield line
    line.close()


class Faults:
    """The emulator's protocol faults (docs/emulator.md "Protocol faults") for a test: inject(node, kind, args...)
    returns the reply lines; the test is skipped when the emulator answers that `fault` is an unknown command (an
    emulator from before fault injection)."""

    def __init__(self, emulator: Emulator) -> None:
        self.client = emulator.client

    def inject(self, node: int, kind: str, *args: Union[int, str]) -> List[str]:
        try:
            return self.client.inject_fault(node, kind, *args)
        except ControlError as e:
            if e.error.startswith("unknown command 'fault'"):
                pytest.skip(f"this canopen-emu has no protocol fault injection: it answered {e.error!r}")
            raise

    def clear(self, node: int, kind: str = "all") -> List[str]:
        return self.client.clear_fault(node, kind)

    def listing(self, node: int) -> List[str]:
        return self.client.faults(node)


@pytest.fixture
def faults(canopen_emu: Emulator) -> Faults:
    return Faults(canopen_emu)
