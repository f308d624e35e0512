"""The master's error handling against protocol faults the emulator injects (docs/emulator.md "Protocol faults"):
an SDO request left unanswered (timeout, retry, giving up), an object answered with an abort code, a heartbeat
that stops, a TPDO that freezes, an EMCY flood. Marked `faults`: skipped when the emulator has no fault injection;
deselect them with -m "not faults"."""
import time

import pytest

from conftest import EDS
from line_master import (PRE_OPERATIONAL, SDO_TIMEOUT, DeviceNotResponding, DeviceRefused, Identity,
                         eventually, flow_controller_safe_state)

pytestmark = pytest.mark.faults

SDS, MFC = 0x21, 0x22


@pytest.mark.canopen_emu_nodes(f"sds:{SDS}")
def test_an_unanswered_request_is_retried_then_given_up(canopen_emu, master, faults):
    c = canopen_emu.client
    master.add(SDS, EDS["sds"])
    c.subscribe("frame", frames=0x600 + SDS)  # what the master sends to the node
    assert faults.inject(SDS, "sdo-ignore", 1) == [
        f"node {SDS}: fault sdo-ignore: the next 1 SDO request(s) get no answer"]
    # one request lost: the master's second attempt gets the answer
    assert master.read_u16(SDS, 0x1017) == 5000
    assert master.timeouts == 1
    # python-canopen told the node it gave up on the first one: abort 0x05040000 (SDO protocol timed out)
    abort = c.wait_for("frame", data=lambda d: d.startswith("80"))
    assert bytes.fromhex(abort["data"])[4:] == SDO_TIMEOUT.to_bytes(4, "little")
    # two lost: the master gives up with its own error
    faults.inject(SDS, "sdo-ignore", 2)
    with pytest.raises(DeviceNotResponding) as e:
        master.read_identity(SDS)
    assert (e.value.index, e.value.sub, e.value.attempts) == (0x1018, 1, 2)
    assert "abort 0x05040000 sent" in str(e.value)
    assert master.read_u32(SDS, 0x1018, 1) == 0x24E  # the fault is over by itself


@pytest.mark.canopen_emu_nodes(f"sds:{SDS}")
def test_an_abort_code_reaches_the_caller(canopen_emu, master, faults):
    master.add(SDS, EDS["sds"])
    assert faults.inject(SDS, "sdo-abort", "0x1018:04", "0x06040047") == [
        f"node {SDS}: fault sdo-abort: requests for 0x1018:04 answered with abort 0x06040047"]
    with pytest.raises(DeviceRefused) as e:
        master.read_identity(SDS)
    assert (e.value.index, e.value.sub, e.value.abort_code) == (0x1018, 4, 0x06040047)
    faults.clear(SDS, "sdo-abort")
    assert master.read_identity(SDS) == Identity(0x24E, 0x1235, 0x00010000, 0x00ABCDF0 + SDS, "SDS")


@pytest.mark.canopen_emu_nodes(f"sds:{SDS}")
def test_a_stopped_heartbeat_is_noticed_and_its_return_too(canopen_emu, master, faults):
    master.add(SDS, EDS["sds"])
    assert master.configure_heartbeat(SDS, 100) == 100
    monitor = master.watch_heartbeat(SDS, consumer_time=0.5)  # five periods
    master.nodes[SDS].nmt.wait_for_heartbeat(2)
    injected = time.monotonic()
    assert faults.inject(SDS, "heartbeat-stop") == [
        f"node {SDS}: fault heartbeat-stop: no heartbeat (nor node-guarding answer)"]
    assert monitor.lost.wait(3), "the master did not notice the missing heartbeat"
    assert monitor.lost_at is not None and monitor.lost_at > injected, "a loss before the fault: the bus stalled"
    # noticed after its consumer time, and soon after (a stall of this process may add to it)
    assert monitor.lost_after is not None and 0.5 < monitor.lost_after < 2.0
    assert canopen_emu.client.nodes()[0].state == "PRE-OPERATIONAL"  # the node itself goes on
    faults.clear(SDS, "heartbeat-stop")
    assert monitor.recovered.wait(3), "the master did not see the heartbeat come back"
    assert monitor.states[-1] == PRE_OPERATIONAL


@pytest.mark.canopen_emu_nodes(f"buerkert:{MFC}")
def test_a_frozen_tpdo_fails_the_plausibility_check(canopen_emu, master, faults):
    c = canopen_emu.client
    master.add(MFC, EDS["buerkert"])
    master.start(MFC)
    master.write_rpdo(MFC, 1, 0x2540, 1, 40.0)
    eventually(lambda: master.tpdo_value(MFC, 1, 0x2500, 1) == 40.0, timeout=5)
    assert not master.tpdo_is_stale(MFC, 1, 0x2500, 1, tolerance=0.5)
    assert faults.inject(MFC, "tpdo-freeze", 1) == [
        f"node {MFC}: fault tpdo-freeze: TPDO1 keeps the data it had (from its next frame)"]
    assert master.tpdo_value(MFC, 1, 0x2500, 1) == 40.0  # that next frame: what TPDO1 sends from now on
    master.write_rpdo(MFC, 1, 0x2540, 1, 10.0)
    eventually(lambda: c.get(MFC, "0x2500:01") == 10.0, timeout=5)  # the device's flow moved
    assert master.tpdo_value(MFC, 1, 0x2500, 1) == 40.0  # its TPDO did not
    assert master.tpdo_is_stale(MFC, 1, 0x2500, 1, tolerance=0.5)
    faults.clear(MFC, "tpdo-freeze")
    eventually(lambda: not master.tpdo_is_stale(MFC, 1, 0x2500, 1, tolerance=0.5), timeout=5)


@pytest.mark.canopen_emu_nodes(f"buerkert:{MFC}")
def test_an_emcy_flood_is_handled_frame_by_frame(canopen_emu, master, faults):
    master.add(MFC, EDS["buerkert"], safe_state=flow_controller_safe_state)
    assert faults.inject(MFC, "emcy-burst", 5, "0x5000") == [
        f"node {MFC}: fault emcy-burst: 5 of 5 EMCY frame(s) 0x5000 sent"]
    handled = [master.next_emergency() for _ in range(5)]
    assert [(e.code, e.data[0], e.action) for e in handled] == [(0x5000, i, "safe state") for i in range(5)]
    assert canopen_emu.client.get(MFC, "0x2540:01") == 0.0

