"""Events: subscribe/wait_for with the emulator's time stamps, events that come while an answer is awaited
(queued, never lost), the iterator, unsubscribe, and events a master causes."""
import itertools
import re

import can
import pytest
from canopen.sdo.exceptions import SdoAbortedError

from canopen_emu import ControlError, ControlTimeout, ExtendedId

from conftest import remote

pytestmark = pytest.mark.canopen_emu_nodes("sds:16", "buerkert:17")


def log_time(emu, text):
    """The time (s) of the log line with text: the log's clock is the events' one. The line may reach the file
    after the event reached the socket (each output has its own buffer): wait for it."""
    line = emu.wait_log(text)
    match = re.fullmatch(r"\[\s*(\d+\.\d{3})\] .*", line)
    assert match, line
    return float(match.group(1))


def test_nmt_events_with_the_emulators_time(canopen_emu, can_bus, canopen_emu_bus):
    c = canopen_emu.client
    assert c.subscribe(["nmt", "boot-up"]) == ["nmt", "boot-up"]
    can_bus().send(can.Message(arbitration_id=0x000, data=[0x01, 0x00], is_extended_id=False))  # start all
    sds = c.wait_for("nmt", node=16, to="OPERATIONAL")
    assert {k: sds[k] for k in ("event", "node", "device", "bus", "from", "to", "text")} == {
        "event": "nmt", "node": 16, "device": "sds", "bus": canopen_emu_bus.name, "from": "PRE-OPERATIONAL",
        "to": "OPERATIONAL", "text": "NMT PRE-OPERATIONAL -> OPERATIONAL"}
    mfc = c.wait_for("nmt", node=17, from_="PRE-OPERATIONAL")  # from_: 'from' is a Python keyword
    assert mfc["to"] == "OPERATIONAL"
    # One NMT frame started both, in one pass of the emulator's loop: the same moment on its clock (each event
    # reads the clock when it is sent out, so allow for a busy machine's preemption).
    assert isinstance(sds["time_us"], int) and 0 <= mfc["time_us"] - sds["time_us"] < 100_000, (sds, mfc)
    # the clock of the log lines (which read it themselves, a moment apart)
    assert abs(log_time(canopen_emu, "node 16 (sds): NMT PRE-OPERATIONAL -> OPERATIONAL")
               - sds["time_us"] / 1e6) < 0.05
    # a predicate instead of a value
    c.power_cycle(17)
    boot = c.wait_for("boot-up", node=lambda n: n in (16, 17))
    assert boot["node"] == 17 and boot["time_us"] > mfc["time_us"]


def test_frame_events_show_the_heartbeat_period(canopen_emu, canopen_emu_bus):
    c = canopen_emu.client
    assert c.subscribe("frame", frames=0x711) == ["frame"]  # the Bürkert node's heartbeat, every 500 ms
    beats = [c.wait_for("frame", timeout=3) for _ in range(4)]
    assert all((b["dir"], b["node"], b["id"], b["data"], b["bus"]) == ("tx", 17, 0x711, "7F", canopen_emu_bus.name)
               for b in beats), beats
    stamps = [b["time_us"] for b in beats]
    # the emulator's clock: what the node did, however late this process read it
    assert all(450_000 < b - a < 550_000 for a, b in zip(stamps, stamps[1:])), stamps


def test_frame_events_of_several_filters(canopen_emu, can_bus):
    c = canopen_emu.client
    bus = can_bus()
    assert c.subscribe("frame", frames=[(0x120, 0x7F0), 0x7FF, "0x711"]) == ["frame"]
    for cob_id in (0x125, 0x135, 0x7FF):
        bus.send(can.Message(arbitration_id=cob_id, data=[1], is_extended_id=False))
    got = [c.wait_for("frame", timeout=3) for _ in range(3)]
    ids = sorted(ev["id"] for ev in got)
    assert 0x125 in ids and 0x7FF in ids and 0x135 not in ids, got  # 0x135 & 0x7F0 is 0x130: no filter takes it


def test_extended_frames_say_eff_and_only_extended_filters_take_them(canopen_emu, can_bus):
    c = canopen_emu.client
    bus = can_bus()
    base = canopen_emu.connect()  # a second client: the 11-bit filter alone
    try:
        assert base.subscribe("frame", frames=0x181) == ["frame"]
        assert c.subscribe("frame", frames=[0x181, ExtendedId(0x181), ExtendedId(0x18FF0000, 0x1FFF0000)]) == ["frame"]
        with pytest.raises(ControlError):
            c.subscribe("frame", frames=0x18FF1234)  # above 11 bits: an extended one must say so
        # the extended frames first: an event of one taken wrongly would come before the 11-bit frame's
        bus.send(can.Message(arbitration_id=0x181, data=[0x11, 0x22], is_extended_id=True))
        bus.send(can.Message(arbitration_id=0x18FF1234, data=[0x44], is_extended_id=True))
        bus.send(can.Message(arbitration_id=0x181, data=[0x33], is_extended_id=False))
        got = [c.wait_for("frame", timeout=3) for _ in range(3)]
        assert [(ev["id"], ev["data"], ev.get("eff", False), ev["text"]) for ev in got] == [
            (0x181, "1122", True, "rx 00000181#1122"), (0x18FF1234, "44", True, "rx 18FF1234#44"),
            (0x181, "33", False, "rx 181#33")], got
        only = base.wait_for("frame", timeout=3)
        assert (only["data"], "eff" in only) == ("33", False), only  # TPDO1 of node 1, not the extended 0x181
    finally:
        base.close()
    assert str(ExtendedId(0x181)) == "0x00000181x/0x1FFFFFFF"


def test_events_that_come_during_requests_are_queued_not_lost(canopen_emu, can_bus, canopen_emu_bus):
    c = canopen_emu.client
    bus = can_bus()
    c.subscribe(["frame"], frames=(0x123, 0x7FF))
    for i in range(40):
        bus.send(can.Message(arbitration_id=0x123, data=[i], is_extended_id=False))
        assert c.get(16, "0x1017") == 5000  # the frame's event may come while this waits: it must be queued
    assert c.pending_events > 0  # the requests read events and queued them
    last = c.wait_for("frame", data="27")  # the 40th (0x27); the others stay queued, in their order
    rest = c.drain_events()
    assert [int(ev["data"], 16) for ev in rest] == list(range(39))
    assert all(ev["dir"] == "rx" and ev["id"] == 0x123 and ev["bus"] == canopen_emu_bus.name for ev in rest + [last])
    stamps = [ev["time_us"] for ev in rest + [last]]
    assert stamps == sorted(stamps)


def test_events_before_an_answer_are_kept_in_order(canopen_emu):
    # An EMCY command sends its event before its answer, on the same connection: each request reads one.
    c = canopen_emu.client
    c.subscribe(["emcy"])
    codes = [0x1000, 0x2310, 0x3120, 0x4210, 0x5000]
    for code in codes:
        c.emcy(16, code)
    assert c.pending_events == len(codes)
    queued = c.drain_events()
    assert [ev["code"] for ev in queued] == codes
    assert [ev["node"] for ev in queued] == [16] * 5
    assert queued[-1]["text"] == "EMCY 0x5000, error register 0x01"


def test_wait_for_leaves_other_events_queued_and_times_out_with_what_came(canopen_emu):
    c = canopen_emu.client
    c.subscribe(["emcy"], nodes=[17])
    c.emcy(17, 0x1000)
    c.emcy(17, 0x2000)
    assert c.wait_for("emcy", code=0x2000)["code"] == 0x2000
    with pytest.raises(ControlTimeout) as e:
        c.wait_for("emcy", timeout=0.2, code=0x9999)
    assert "no emcy event with {'code': 39321} within 0.2 s" in str(e.value)
    assert c.wait_for("emcy")["code"] == 0x1000  # still there
    c.emcy(16, 0x3000)  # node 16 is filtered out
    c.emcy(17, 0x4000)
    assert [ev["code"] for ev in c.drain_events()] == [0x4000]


def test_the_event_iterator(canopen_emu):
    c = canopen_emu.client
    c.subscribe(["boot-up"])
    c.power_cycle(16)
    c.power_cycle(17)
    got = list(itertools.islice(c.events(timeout=5), 2))
    assert [(ev["event"], ev["node"]) for ev in got] == [("boot-up", 16), ("boot-up", 17)]
    assert list(c.events(timeout=0.1)) == []


def test_unsubscribe_ends_the_events(canopen_emu):
    c = canopen_emu.client
    c.subscribe("all")
    c.unsubscribe()
    c.emcy(16, 0x5000)  # its event would come before this answer
    assert c.drain_events() == []
    assert c.subscribe("all") == ["nmt", "boot-up", "emcy", "sdo-abort", "store", "nvm", "lss", "heartbeat",
                                  "guarding", "interface", "fault", "message"]
    c.unsubscribe(["emcy"])
    c.emcy(16, 0x5000)
    assert c.drain_events() == []


def test_an_sdo_abort_a_master_gets_is_an_event(canopen_emu, network):
    c = canopen_emu.client
    c.subscribe(["sdo-abort"], nodes=[16])
    node = remote(network, "sds", 16)
    with pytest.raises(SdoAbortedError) as e:
        node.sdo.upload(0x5555, 0)
    assert e.value.code == 0x06020000
    event = c.wait_for("sdo-abort", node=16)
    assert (event["index"], event["sub"], event["abort_code"]) == (0x5555, 0, 0x06020000)
    assert event["text"].startswith("SDO abort 0x06020000 on 0x5555:00")
