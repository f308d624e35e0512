"""Virtual buses (-i virtual:NAME, docs/buses.md): no medium, the nodes of one bus hear each other and nothing else;
two virtual buses are apart. A heartbeat consumer (the Buerkert's 0x1016) shows it: it starts watching a producer
when it first hears its heartbeat, and reports the heartbeat missing once the producer stops."""
from udp_support import Emulator


def consumer_watches_producer(emu):
    c = emu.control
    c.request("set", node=16, object="0x1017", value=100)                    # sds: heartbeat every 100 ms
    c.request("set", node=18, object="0x1016:01", value=(16 << 16) | 400)    # buerkert: expects it within 400 ms
    c.request("subscribe", events=["heartbeat"])
    assert [e for e in c.drain(1.0) if e["event"] == "heartbeat"] == []
    c.request("fault", node=16, args=["heartbeat-stop"])
    return c


def test_nodes_on_a_virtual_bus_hear_each_other(tmp_path):
    emu = Emulator(tmp_path, "-i", "virtual:plant", "sds:16", "buerkert:18@plant")
    c = consumer_watches_producer(emu)
    event = c.event("heartbeat", timeout=3, node=18, producer=16)
    assert event["bus"] == "plant"
    assert [n["bus"] for n in c.request("list")["nodes"]] == ["plant", "plant"]
    log = emu.stop()
    assert "plant: a virtual bus inside this process: its nodes hear each other and nothing else" in log, log


def test_two_virtual_buses_are_apart(tmp_path):
    emu = Emulator(tmp_path, "-i", "virtual:plant", "-i", "virtual:other", "sds:16", "buerkert:18@virtual:other")
    c = consumer_watches_producer(emu)
    # the consumer never heard the producer, so it never started watching it: nothing to miss
    assert [e for e in c.drain(1.5) if e["event"] == "heartbeat"] == []
    assert [(n["node"], n["bus"]) for n in c.request("list")["nodes"]] == [(16, "plant"), (18, "other")]
    emu.stop()
