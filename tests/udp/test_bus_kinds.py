"""Each bus by its name and its kind in the control protocol (docs/control-protocol.md): hello's bus_kinds, list's and
show's bus_kind, show all's heard nodes' bus_kind, on a udp_multicast bus and a virtual bus in one emulator. Every
answer is checked against docs/control-protocol.schema.json as well."""
import sys
import time

import can

from udp_support import GROUP, SRC, Emulator

sys.path.insert(0, str(SRC / "tests/support"))
from control_schema import check_schema  # noqa: E402

PORT = 43121  # apart from the other udp tests' port: a heartbeat sent here reaches this emulator only
UDP_BUS = f"udp_multicast:{GROUP}:{PORT}"


def test_hello_list_and_show_name_each_bus_and_its_kind(tmp_path):
    emu = Emulator(tmp_path, "-i", f"udp_multicast:{GROUP}:{PORT}", "-i", "virtual:plant", "sds:16",
                   "buerkert:18@plant")
    try:
        c = emu.control
        hello = c.request("hello")
        check_schema(hello, "hello")
        assert hello["buses"] == [UDP_BUS, "plant"], hello  # as before: the names, in the order of -i
        assert hello["bus_kinds"] == {UDP_BUS: "udp_multicast", "plant": "virtual"}, hello

        listed = c.request("list")
        check_schema(listed, "list")
        assert [(n["node"], n["bus"], n["bus_kind"]) for n in listed["nodes"]] == [
            (16, UDP_BUS, "udp_multicast"), (18, "plant", "virtual")]

        # a node the emulator does not emulate, heard on the udp_multicast bus by its heartbeat
        with can.Bus(interface="udp_multicast", channel=GROUP, port=PORT) as master:
            master.send(can.Message(arbitration_id=0x705, data=[0x05], is_extended_id=False))
            end = time.monotonic() + 5
            while True:
                shown = c.request("show", node="all")
                if shown.get("heard"):
                    break
                assert time.monotonic() < end, f"node 5's heartbeat was not heard: {shown}"
                time.sleep(0.05)
        check_schema(shown, "show")
        assert [(n["node"], n["bus_kind"]) for n in shown["nodes"]] == [(16, "udp_multicast"), (18, "virtual")]
        assert [(h["node"], h["bus"], h["bus_kind"]) for h in shown["heard"]] == [(5, UDP_BUS, "udp_multicast")]
    finally:
        emu.stop()
