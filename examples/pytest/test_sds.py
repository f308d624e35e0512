"""The master against the emulated Eltex SDS (docs/devices/sds-behaviour.md): identity, heartbeat, and a
pollution warning: the master's safe state, an acknowledgement refused while the bar is still dirty, accepted
once it is clean."""
import pytest

from conftest import EDS
from line_master import DeviceRefused, Identity, eltex_emcy, ionizer_safe_state

NODE = 0x21
pytestmark = pytest.mark.canopen_emu_nodes(f"sds:{NODE}")


def test_identity_and_heartbeat(canopen_emu, master):
    master.add(NODE, EDS["sds"])
    assert master.read_identity(NODE) == Identity(vendor_id=0x24E, product_code=0x1235, revision=0x00010000,
                                                  serial=0x00ABCDF0 + NODE, device_name="SDS")
    assert master.read_u16(NODE, 0x1017) == 5000  # "in 5-second intervals"
    assert master.configure_heartbeat(NODE, 1000) == 1000
    assert canopen_emu.client.get(NODE, "0x1017") == 1000


def test_pollution_warning_safe_state_and_acknowledgement(canopen_emu, master):
    c = canopen_emu.client
    master.add(NODE, EDS["sds"], safe_state=ionizer_safe_state)
    master.start(NODE)
    master.write(NODE, 0x6200, 1, b"\x0F")  # HV on: the bar measures pollution only with HV
    c.subscribe(["emcy"], nodes=[NODE])
    c.command(NODE, "pollution", 85)  # above the warning level (80 % of the pollution factor)
    assert c.wait_for("emcy", node=NODE, timeout=5)["code"] == 0x2300
    emergency = master.next_emergency()
    assert (emergency.code, emergency.register, eltex_emcy(emergency)) == (0x2300, 0x03, ("warning", 1))
    assert emergency.action == "safe state"
    assert c.get(NODE, "0x6000:01") & 0x01 == 0  # HV off: the master's reaction
    with pytest.raises(DeviceRefused) as e:
        master.acknowledge_eltex(NODE, "warning", 1)
    assert e.value.abort_code == 0x08000022  # the cause is still there
    c.command(NODE, "pollution", 0)
    master.acknowledge_eltex(NODE, "warning", 1)
    assert master.next_emergency().code == 0x0000  # the confirmation (error reset)
    assert c.get(NODE, "0x6000:01") & 0x04 == 0  # no warning active
