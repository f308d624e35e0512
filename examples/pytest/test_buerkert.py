"""The master against the emulated Bürkert mass flow controller (docs/devices/buerkert-behaviour.md): identity
(segmented upload), a TPDO the master maps itself (dynamic mapping), the flow following the set-point, SDO abort
codes, and the master closing the valve on an under-voltage EMCY."""
import math
import struct

import pytest

from conftest import EDS
from line_master import DeviceRefused, Identity, eventually, flow_controller_safe_state

NODE = 0x22
pytestmark = pytest.mark.canopen_emu_nodes(f"buerkert:{NODE}")


def test_identity(canopen_emu, master):
    master.add(NODE, EDS["buerkert"])
    assert master.read_identity(NODE) == Identity(vendor_id=0x39, product_code=0x1, revision=0x00010000,
                                                  serial=0x1 + NODE, device_name="Buerkert MFC")


def map_status_and_flow(master):
    # TPDO2 is disabled in the device's defaults: the master maps the NE 107 status and the flow into it
    master.map_tpdo(NODE, 2, [(0x2004, 1), (0x2500, 1)], event_timer_ms=100)
    master.start(NODE)


def test_mapped_tpdo_follows_the_set_point(canopen_emu, master):
    master.add(NODE, EDS["buerkert"])
    map_status_and_flow(master)
    assert canopen_emu.client.get(NODE, "0x1801:01") == 0x280 + NODE  # valid now (bit 31 clear)
    assert canopen_emu.client.get(NODE, "0x1A01:00") == 2
    master.write_rpdo(NODE, 1, 0x2540, 1, 40.0)  # RPDO1 carries the set-point
    # the flow settles on 40.0 (a first-order response, tau 200 ms, resolution 0.01)
    eventually(lambda: master.tpdo_value(NODE, 2, 0x2500, 1) == 40.0, timeout=5)
    assert master.tpdo_value(NODE, 2, 0x2004, 1) == 0x00  # NE 107: normal, auto
    assert master.read_real32(NODE, 0x2540, 1) == 40.0


def test_abort_codes_become_the_masters_errors(canopen_emu, master):
    master.add(NODE, EDS["buerkert"])
    with pytest.raises(DeviceRefused) as e:
        master.write(NODE, 0x2500, 1, struct.pack("<f", 5.0))  # the measurement
    assert (e.value.index, e.value.sub, e.value.abort_code) == (0x2500, 1, 0x08000021)
    with pytest.raises(DeviceRefused) as e:
        master.write(NODE, 0x2540, 1, struct.pack("<f", math.nan))
    assert e.value.abort_code == 0x06090030
    with pytest.raises(DeviceRefused) as e:
        master.read(NODE, 0x1018, 9)
    assert e.value.abort_code == 0x06090011  # no such sub-index


def test_under_voltage_emcy_closes_the_valve(canopen_emu, master):
    c = canopen_emu.client
    master.add(NODE, EDS["buerkert"], safe_state=flow_controller_safe_state)
    map_status_and_flow(master)
    master.write(NODE, 0x2540, 1, struct.pack("<f", 60.0))
    eventually(lambda: master.tpdo_value(NODE, 2, 0x2500, 1) > 30.0, timeout=5)
    assert c.command(NODE, "supply", 20) != []  # 20 V: below 24 V - 10 %
    emergency = master.next_emergency()
    assert (emergency.code, emergency.register, emergency.action) == (0x3120, 0x05, "safe state")
    assert emergency.data == bytes([0x00, 0x00, 0x03, 0x00, 0x00])  # NE 107 state 3 after the change
    assert c.get(NODE, "0x2540:01") == 0.0  # the master closed it
    eventually(lambda: master.tpdo_value(NODE, 2, 0x2500, 1) == 0.0, timeout=5)
    assert master.tpdo_value(NODE, 2, 0x2004, 1) == 0x03  # out of specification
