"""The master against the emulated Eltex PRO IONIZER (docs/devices/pro-ionizer-behaviour.md): identity, heartbeat
configuration and its refusals, NMT start, the HV release with its status in TPDO1, and the master's reaction to
an EMCY (the HV switched off) and its acknowledgement through 0x2003."""
import pytest

from conftest import EDS
from line_master import DeviceRefused, Identity, eltex_emcy, eventually, ionizer_safe_state

NODE = 0x20
pytestmark = pytest.mark.canopen_emu_nodes(f"pro-ionizer:{NODE}")


def test_identity(canopen_emu, master):
    master.add(NODE, EDS["pro-ionizer"])
    identity = master.read_identity(NODE)
    # docs/devices/pro-ionizer.md: Eltex's vendor-ID, the chosen product code and revision, the EDS serial plus
    # the node-ID
    assert identity == Identity(vendor_id=0x24E, product_code=0x1234, revision=0x00010002,
                                serial=0x00ABCDEF + NODE, device_name="ES61")
    assert identity.serial == canopen_emu.client.get(NODE, "0x1018:04")


def test_heartbeat_and_start(canopen_emu, master):
    c = canopen_emu.client
    master.add(NODE, EDS["pro-ionizer"])
    assert master.read_u16(NODE, 0x1017) == 1000  # the manual's default
    assert master.configure_heartbeat(NODE, 200) == 200
    c.subscribe(["nmt"], nodes=[NODE])
    c.subscribe("frame", frames=0x700 + NODE)
    master.start(NODE)
    assert c.wait_for("nmt", node=NODE)["to"] == "OPERATIONAL"
    beats = [c.wait_for("frame", data="05", timeout=2) for _ in range(3)]
    stamps = [b["time_us"] for b in beats]
    assert all(180_000 <= b - a <= 220_000 for a, b in zip(stamps, stamps[1:])), stamps
    assert [n.state for n in c.nodes()] == ["OPERATIONAL"]


@pytest.mark.parametrize("period, abort", [(150, 0x06090030), (50, 0x06090032), (60100, 0x06090031)])
def test_heartbeat_values_the_device_refuses(canopen_emu, master, period, abort):
    master.add(NODE, EDS["pro-ionizer"])
    with pytest.raises(DeviceRefused) as e:
        master.configure_heartbeat(NODE, period)
    assert (e.value.index, e.value.sub, e.value.abort_code) == (0x1017, 0, abort)
    assert canopen_emu.client.get(NODE, "0x1017") == 1000  # unchanged


def release_hv(master):
    master.write(NODE, 0x2002, 2, b"\x06")  # release by HMI and CANopen (bit 2)
    master.start(NODE)
    master.write(NODE, 0x6200, 1, b"\x0F")
    # TPDO1 (0x6000:01-06, every 0x2002:01 = 500 ms) shows HV on (bit 0) and the software release (bit 5)
    return eventually(lambda: master.tpdo_value(NODE, 1, 0x6000, 1) & 0x21 == 0x21, timeout=5)


def test_hv_release_shows_in_tpdo1(canopen_emu, master):
    master.add(NODE, EDS["pro-ionizer"])
    release_hv(master)
    assert canopen_emu.client.get(NODE, "0x6000:01") & 0x21 == 0x21


def test_an_emcy_switches_the_hv_off_and_is_acknowledged(canopen_emu, master):
    c = canopen_emu.client
    master.add(NODE, EDS["pro-ionizer"], safe_state=ionizer_safe_state)
    release_hv(master)
    # warning 3 (temperature above 60 C) does not switch the HV off by itself: the master must
    assert c.command(NODE, "warning", 3) == [
        f"node {NODE}: pro-ionizer: warning 3 raised: device temperature high (> 60 C): power derated to 50 %"]
    emergency = master.next_emergency()
    assert (emergency.node_id, emergency.code, emergency.register) == (NODE, 0x4210, 0x09)
    assert eltex_emcy(emergency) == ("warning", 3)
    assert emergency.action == "safe state"
    assert c.get(NODE, "0x6000:01") & 0x25 == 0x04  # HV (bit 0) and release (5) off, the warning (2) on
    master.acknowledge_eltex(NODE, "warning", 3)
    reset = master.next_emergency()
    assert (reset.code, reset.action) == (0x0000, "none (error reset)")
    with pytest.raises(DeviceRefused) as e:
        master.acknowledge_eltex(NODE, "warning", 3)  # no longer active
    assert e.value.abort_code == 0x08000024
