"""The bus the package and the plugin choose (canopen_emu.buses, --canopen-emu-bus): the buses by canopen-emu's -i
names, how python-can joins each, auto (vcan0 where it is up, else a udp_multicast group and port of the session's
own), and, marked netns (run-tests.sh's second pass, inside tests/udp/netns-run), whole sessions on udp_multicast:
the plugin's emulators and its python-canopen Network on one group, two sessions at once on buses of their own."""
import os
import socket
import subprocess
import sys

import pytest

from canopen_emu import Bus, Emulator, choose_bus, session_udp_bus, socketcand_bus
from canopen_emu.buses import SESSION_PORTS, interface_is_up, port_is_free
from conftest import EDS


def test_buses_by_the_emulators_names_and_how_python_can_joins_them():
    vcan = Bus.parse("vcan1")
    assert (vcan.kind, vcan.name, vcan.label) == ("socketcan", "vcan1", "vcan1 (socketcan)")
    assert vcan.can_kwargs() == {"interface": "socketcan", "channel": "vcan1"}
    assert Bus.parse("socketcan:can0").name == "can0"
    udp = Bus.parse("udp_multicast")  # python-can's IPv4 default group and port, TTL 1
    assert (udp.kind, udp.name, udp.label) == ("udp_multicast", "udp_multicast:239.74.163.2:43113",
                                               "udp_multicast:239.74.163.2:43113")
    assert udp.can_kwargs() == {"interface": "udp_multicast", "channel": "239.74.163.2", "port": 43113,
                                "hop_limit": 1}
    six = Bus.parse("udp_multicast:[ff15:7079:7468:6f6e:6465:6d6f:6d63:6173]:43114,ttl=3")
    assert six.name == "udp_multicast:[ff15:7079:7468:6f6e:6465:6d6f:6d63:6173]:43114"
    assert six.can_kwargs() == {"interface": "udp_multicast", "channel": "ff15:7079:7468:6f6e:6465:6d6f:6d63:6173",
                                "port": 43114, "hop_limit": 3}
    assert Bus.parse("udp_multicast:239.1.2.3").port == 43113
    plant = Bus.parse("virtual:plant")
    assert (plant.kind, plant.name, plant.label) == ("virtual", "plant", "plant (virtual)")
    with pytest.raises(ValueError, match="no python-can master can join it"):
        plant.can_kwargs()
    for bad in ("udp_multicast:10.0.0.1", "udp_multicast:239.1.2.3:0", "udp_multicast,ttl=256", "virtual:",
                "vcan0 x", "udp_multicast:[ff15::1"):
        with pytest.raises(ValueError):
            Bus.parse(bad)


def test_auto_is_vcan0_when_it_is_up_else_a_udp_multicast_group_of_the_sessions_own():
    asked = []

    def up(name):
        asked.append(name)
        return True

    assert choose_bus("auto", is_up=up) == Bus.parse("vcan0") and asked == ["vcan0"]
    bus = choose_bus("auto", is_up=lambda name: False)  # vcan0 down or missing
    assert bus.kind == "udp_multicast" and bus.ttl == 0 and bus.spec == bus.name + ",ttl=0", bus
    assert bus.group.startswith("239.74.") and bus.port in SESSION_PORTS, bus
    own_port = SESSION_PORTS.start + os.getpid() % len(SESSION_PORTS)  # the pid's, unless something has it
    assert bus.port == own_port or not port_is_free(own_port), bus
    assert choose_bus("udp_multicast:239.9.9.9:40000", is_up=up).name == "udp_multicast:239.9.9.9:40000"
    # this machine as ip sees it: vcan0 up (the first pass, on vcan) gives vcan0; none (the netns pass) a group
    links = {line.split(": ")[1].split("@")[0]: line.split("<")[1].split(">")[0].split(",")
             for line in subprocess.run(["ip", "-o", "link", "show"], check=True, capture_output=True,
                                        text=True).stdout.splitlines()}
    assert interface_is_up("lo") == ("UP" in links["lo"]) and not interface_is_up("nosuch0")
    assert (choose_bus("auto").kind == "socketcan") == ("UP" in links.get("vcan0", []))


def test_two_sessions_never_share_a_port_and_a_port_in_use_is_passed_over():
    assert session_udp_bus(pid=4242, probe=False).port != session_udp_bus(pid=4243, probe=False).port
    for pid in range(1000, 1100):  # a pid whose port is free here, then taken as a multicast listener takes it
        start = SESSION_PORTS.start + pid % len(SESSION_PORTS)
        if port_is_free(start) and port_is_free(start + 1):
            break
    with socket.socket(socket.AF_INET, socket.SOCK_DGRAM) as listener:
        listener.setsockopt(socket.SOL_SOCKET, socket.SO_REUSEADDR, 1)  # as python-can and canopen-emu bind
        listener.bind(("", start))
        assert not port_is_free(start)
        assert session_udp_bus(pid=pid).port == start + 1
    assert session_udp_bus(pid=pid).port == start


# --- whole sessions on udp_multicast, inside a network namespace of their own ----------------------------------


@pytest.fixture
def own_namespace():
    names = [name for _, name in socket.if_nameindex()]
    if names != ["lo"]:
        pytest.fail(f"the netns tests run only inside their own network namespace (tests/udp/netns-run), not with "
                    f"interfaces {names}: multicast must not reach this machine's network", pytrace=False)


SESSION_TEST = """
import time
from pathlib import Path

import pytest

@pytest.mark.canopen_emu_nodes("sds:{node}")
def test_session(canopen_emu, canopen_emu_network, canopen_emu_bus):
    name = canopen_emu_bus.name
    Path("bus").write_text(name)
    hello = canopen_emu.client.hello()
    assert hello.buses == (name,) and hello.bus_kinds == {{name: "udp_multicast"}}
    assert [(n.bus, n.bus_kind) for n in canopen_emu.client.nodes()] == [(name, "udp_multicast")]
    # the plugin's master on the same group: SDO both ways, and the heartbeat it sets
    node = canopen_emu_network.add_node({node}, {eds!r})
    node.sdo.RESPONSE_TIMEOUT = 5.0
    node.sdo.download(0x1017, 0, (100).to_bytes(2, "little"))
    assert int.from_bytes(node.sdo.upload(0x1017, 0), "little") == 100
    node.nmt.wait_for_heartbeat(timeout=2.0)
    # Emulator.network(): another master on the emulator's bus, disconnected by stop()
    other = canopen_emu.network()
    remote = other.add_node({node}, {eds!r})
    remote.sdo.RESPONSE_TIMEOUT = 5.0
    assert remote.sdo.upload(0x1018, 1) == node.sdo.upload(0x1018, 1)
    # {seconds} s of the other session's heartbeats, had it been on this bus: none heard
    time.sleep({seconds})
    assert canopen_emu.client.heard() == []
    canopen_emu.stop()
    assert other.bus is None
"""


def session(directory, node, seconds, *args):
    directory.mkdir()
    (directory / "test_session.py").write_text(SESSION_TEST.format(node=node, eds=str(EDS["sds"]), seconds=seconds))
    return subprocess.Popen([sys.executable, "-m", "pytest", "-p", "no:cacheprovider", "-v", *args], cwd=directory,
                            stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True)


@pytest.mark.netns
def test_a_named_udp_multicast_bus_carries_the_emulator_and_the_plugins_network(own_namespace, tmp_path):
    bus = "udp_multicast:239.74.163.77:43177"
    proc = session(tmp_path / "named", 16, 0.5, "--canopen-emu-bus", bus)
    out = proc.communicate(timeout=300)[0]
    assert proc.returncode == 0, out
    assert f"on {bus}\n" in out, out  # the header: the bus as named, no auto
    assert (tmp_path / "named" / "bus").read_text() == bus


@pytest.mark.netns
def test_auto_gives_two_sessions_at_once_a_udp_multicast_bus_each(own_namespace, tmp_path):
    # both run a node with a 100 ms heartbeat for 2 s at the same time: neither hears the other's
    sessions = [session(tmp_path / "a", 16, 2.0), session(tmp_path / "b", 17, 2.0)]
    outs = [proc.communicate(timeout=300)[0] for proc in sessions]
    assert [proc.returncode for proc in sessions] == [0, 0], outs
    for out in outs:
        assert ", chosen by auto: no vcan0 up, so a group of this session's own, TTL 0 (never leaves the machine)\n" in out, out
    buses = [Bus.parse((tmp_path / d / "bus").read_text()) for d in ("a", "b")]
    assert all(b.kind == "udp_multicast" for b in buses) and buses[0].port != buses[1].port, buses


def test_socketcand_is_a_virtual_bus_served_on_loopback():
    bus = choose_bus("socketcand")
    assert bus == socketcand_bus() and (bus.spec, bus.kind, bus.name) == ("virtual:canopen-emu", "virtual", "canopen-emu")
    assert bus.socketcand == "127.0.0.1:0" and str(bus) == "virtual:canopen-emu"
    assert bus.label == "canopen-emu (virtual, served by socketcand on 127.0.0.1:0)"
    with pytest.raises(ValueError, match="the port is the emulator's; its network"):
        bus.can_kwargs()  # the port is each emulator's own: Emulator.network() joins it
    with pytest.raises(ValueError, match="no python-can master can join it"):
        Bus.parse("virtual:plant").can_kwargs()


def test_an_emulator_serves_a_socketcand_bus_and_its_network_joins_it_with_python_can():
    with Emulator(interface=socketcand_bus("plant"), nodes=["sds:16"]) as emu:
        assert "--socketcand" in emu.args and emu.args[emu.args.index("--socketcand") + 1] == "127.0.0.1:0"
        host, port = emu.socketcand_address()
        assert host == "127.0.0.1" and port > 0
        assert emu.client.hello().bus_kinds == {"plant": "virtual"}
        net = emu.network()
        assert net.bus.__class__.__name__ == "SocketCanDaemonBus"  # python-can's own socketcand interface
        node = net.add_node(16, str(EDS["sds"]))
        node.sdo.RESPONSE_TIMEOUT = 5.0
        node.sdo.download(0x1017, 0, (1200).to_bytes(2, "little"))
        assert emu.client.get(16, "0x1017") == 1200
        assert node.sdo.upload(0x1018, 1) == emu.client.get(16, "0x1018:01").to_bytes(4, "little")
    assert net.bus is None  # stop() disconnected it
    with pytest.raises(ValueError, match="one address"):
        Emulator(interface=socketcand_bus("a"), socketcand="127.0.0.1:1", nodes=["sds:16"])


def test_the_plugins_socketcand_bus_hands_each_test_a_network_on_its_emulator(pytester):
    pytester.makepyfile(f"""
        import pytest

        @pytest.mark.canopen_emu_nodes("sds:16")
        def test_master(canopen_emu_network, canopen_emu):
            node = canopen_emu_network.add_node(16, {str(EDS["sds"])!r})
            node.sdo.RESPONSE_TIMEOUT = 5.0
            node.sdo.download(0x1017, 0, (1300).to_bytes(2, "little"))
            assert canopen_emu.client.get(16, "0x1017") == 1300

        def test_factory_only(canopen_emu_factory, canopen_emu_network):
            pass
    """)
    result = pytester.runpytest_subprocess("-p", "no:cacheprovider", "--canopen-emu-bus", "socketcand", timeout=300)
    result.assert_outcomes(passed=1, errors=1)
    result.stdout.fnmatch_lines([
        "canopen-emu plugin *: * on canopen-emu (virtual, served by socketcand on 127.0.0.1:0)",
        "*canopen_emu_network: canopen-emu (virtual, served by socketcand on 127.0.0.1:0) is inside each emulator: a "
        "test that starts its own with canopen_emu_factory joins it with emulator.network()",
    ])
