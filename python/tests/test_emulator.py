"""The launcher: it returns once every node has booted, stops with status 0 (or by signals when quit is not
possible), reports a failed start with the log, finds its program, runs several buses, keeps nvm_dir."""
import os
import tempfile
import re
import shutil
import signal
import struct
import time
import urllib.request

import pytest

from canopen_emu import ConnectionClosed, ControlError, Emulator, EmulatorError, find_executable

from conftest import remote

EMU = os.environ["CANOPEN_EMU"]


def test_the_launcher_returns_once_every_node_has_booted(can_bus, canopen_emu_bus):
    bus = can_bus()  # open before the start: it sees the boot-ups
    with Emulator(interface=canopen_emu_bus, nodes=["sds:16", "buerkert:17", "pro-ionizer:0x20"]) as emu:
        assert [(n.node, n.state) for n in emu.client.nodes()] == [
            (16, "PRE-OPERATIONAL"), (17, "PRE-OPERATIONAL"), (0x20, "PRE-OPERATIONAL")]
        for node, device in ((16, "sds"), (17, "buerkert"), (32, "pro-ionizer")):
            emu.wait_log(f"node {node} ({device}): NMT INITIALISING -> PRE-OPERATIONAL")
        # the boot-ups were on the bus before the constructor returned
        boot_ups = set()
        while (msg := bus.recv(0.5)) is not None:
            if msg.data == bytearray(b"\x00"):
                boot_ups.add(msg.arbitration_id)
            if boot_ups == {0x710, 0x711, 0x720}:
                break
        assert boot_ups == {0x710, 0x711, 0x720}
        assert emu.client.drain_events() == []  # the launcher's own boot events are not left for the test
        assert emu.executable == EMU and emu.interfaces == [str(canopen_emu_bus)]
    assert emu.returncode == 0


@pytest.mark.vcan
def test_the_default_interface_is_vcan0():
    with Emulator(nodes=["sds:16"]) as emu:
        assert emu.interfaces == ["vcan0"] and emu.client.hello().buses == ("vcan0",)


def test_stop_quits_with_status_0_and_cleans_up(canopen_emu_bus):
    emu = Emulator(interface=canopen_emu_bus, nodes=["sds:16"])
    socket_path, workdir = emu.socket_path, emu.workdir
    assert socket_path.exists() and emu.running
    assert emu.stop() == 0
    assert not emu.running and emu.returncode == 0
    assert not socket_path.exists() and not workdir.exists()
    assert emu.client.closed
    log = emu.log_lines()
    assert log[-2].endswith("] stopping"), log  # by quit: "stopping (signal)" after SIGTERM
    assert "frame(s) sent, 0 dropped" in log[-1]
    assert emu.stop() == 0  # again: the same status, nothing more happens
    with pytest.raises(ConnectionClosed):
        emu.client.get(16, "0x1017")


def test_stop_without_a_socket_sends_sigterm(canopen_emu_bus):
    emu = Emulator(interface=canopen_emu_bus, nodes=["sds:16"])
    emu.client.close()
    os.unlink(emu.socket_path)  # quit cannot be asked any more
    start = time.monotonic()
    assert emu.stop(timeout=2) == 0  # canopen-emu ends with 0 on SIGTERM
    assert time.monotonic() - start < 2  # no quit was sent, so none was waited for
    assert emu.log_lines()[-2].endswith("] stopping (signal)")


def test_stop_of_a_hung_emulator_ends_with_sigkill(canopen_emu_bus):
    emu = Emulator(interface=canopen_emu_bus, nodes=["sds:16"])
    os.kill(emu.pid, signal.SIGSTOP)  # answers nothing, and SIGTERM waits for a SIGCONT that never comes
    start = time.monotonic()
    assert emu.stop(timeout=0.3) == -signal.SIGKILL
    assert time.monotonic() - start >= 0.6  # quit, then SIGTERM, each waited for
    assert not emu.workdir.exists()


@pytest.mark.parametrize("nodes, interface, status, message", [
    (["nosuch:5"], "vcan0", 2, "canopen-emu: unknown device 'nosuch'; known devices:"),
    pytest.param(["sds:16"], "vcan9", 1, "canopen-emu: interface vcan9 does not exist; create a virtual one with:",
                 marks=pytest.mark.vcan),
])
def test_a_failed_start_raises_with_the_log(nodes, interface, status, message, monkeypatch):
    # The launcher's work directory in a folder of the test's own, never the shared temporary directory's listing;
    # a fresh one there rather than tmp_path, which can be too long for the control socket (107 bytes).
    own = tempfile.mkdtemp(prefix="t")
    try:
        monkeypatch.setattr(tempfile, "tempdir", own)
        with pytest.raises(EmulatorError) as e:
            Emulator(interface=interface, nodes=nodes)
        assert e.value.returncode == status
        assert message in e.value.log
        assert f"canopen-emu exited with status {status} before its control socket answered" in str(e.value)
        assert message in str(e.value)
        assert os.listdir(own) == []  # its directory went with it
    finally:
        shutil.rmtree(own)


def test_the_program_comes_from_the_argument_the_variable_or_path(monkeypatch, tmp_path, canopen_emu_bus):
    assert find_executable() == EMU  # $CANOPEN_EMU
    monkeypatch.delenv("CANOPEN_EMU")
    (tmp_path / "bin").mkdir()
    os.symlink(EMU, tmp_path / "bin" / "canopen-emu")
    monkeypatch.setenv("PATH", str(tmp_path / "bin"))
    assert find_executable() == str(tmp_path / "bin" / "canopen-emu")
    with Emulator(interface=canopen_emu_bus, nodes=["sds:16"]) as emu:
        assert emu.executable == str(tmp_path / "bin" / "canopen-emu")
        assert emu.client.get(16, "0x1017") == 5000
    monkeypatch.setenv("PATH", str(tmp_path))
    with pytest.raises(EmulatorError) as e:
        find_executable()
    assert str(e.value) == ("canopen-emu not found: pass executable=..., set $CANOPEN_EMU, or put canopen-emu on "
                            "PATH")
    not_executable = tmp_path / "emu"
    not_executable.write_text("")
    with pytest.raises(EmulatorError) as e:
        Emulator(interface=canopen_emu_bus, nodes=["sds:16"], executable=not_executable)
    assert str(e.value) == f"{not_executable} is not an executable file"


@pytest.mark.vcan
def test_several_interfaces(canopen_emu_factory, can_bus):
    vcan1 = can_bus("vcan1")
    emu = canopen_emu_factory("sds:16", "sds:16@vcan1", "buerkert:17@vcan1", interface=["vcan0", "vcan1"])
    c = emu.client
    assert c.hello().buses == ("vcan0", "vcan1")
    assert [(n.node, n.device, n.bus) for n in c.nodes()] == [(16, "sds", "vcan0"), (16, "sds", "vcan1"),
                                                               (17, "buerkert", "vcan1")]
    assert "-i vcan0 -i vcan1" in " ".join(emu.args)
    with pytest.raises(ControlError) as e:
        c.get(16, "0x1017")
    assert e.value.error == "node 16 is on vcan0 and on vcan1: say 16@vcan0"
    assert c.set("16@vcan1", "0x1017", 100) == 100
    assert c.get("16@vcan0", "0x1017") == 5000
    # node 16 of vcan1 now beats every 100 ms, on vcan1 only
    c.subscribe("frame", frames=0x710)
    # heartbeats in pre-operational (7F): the boot-up (00) may come after the subscription on a loaded machine, and
    # did, 9 ms before the first heartbeat
    beats = [c.wait_for("frame", bus="vcan1", data=lambda d: d.lower() == "7f") for _ in range(3)]
    assert all(450_000 > b["time_us"] - a["time_us"] > 50_000 for a, b in zip(beats, beats[1:])), beats
    seen = set()
    deadline = time.monotonic() + 3
    while seen != {0x710, 0x711} and time.monotonic() < deadline:
        msg = vcan1.recv(0.5)
        if msg is not None:
            seen.add(msg.arbitration_id)
    assert seen == {0x710, 0x711}


def test_nvm_dir_keeps_what_was_stored(canopen_emu_factory, network, tmp_path, canopen_emu_bus):
    nvm = tmp_path / "nvm"
    first = canopen_emu_factory("sds:16", nvm_dir=nvm)
    first.wait_log(f"node 16 (sds) on {canopen_emu_bus.name}, NVM {nvm}/sds-16.*")
    node = remote(network, "sds", 16)
    node.sdo.download(0x1017, 0, struct.pack("<H", 1200))
    node.sdo.download(0x1010, 1, b"save")
    assert first.stop() == 0
    assert (nvm / "sds-16.params").is_file()
    second = canopen_emu_factory("sds:16", nvm_dir=nvm)
    assert second.client.get(16, "0x1017") == 1200
    fresh = canopen_emu_factory("sds:18")  # no nvm_dir: a fresh one
    assert fresh.client.get(18, "0x1017") == 5000


def test_the_web_view_is_served_where_web_url_says(canopen_emu_bus):
    with Emulator(interface=canopen_emu_bus, nodes=["sds:16"], web="127.0.0.1:0") as emu:
        url = emu.web_url()
        assert re.fullmatch(r"http://127\.0\.0\.1:\d+/", url), url
        assert url != "http://127.0.0.1:0/"
        with urllib.request.urlopen(url, timeout=5) as page:
            html = page.read().decode()
        assert page.status == 200 and "<title>canopen-emu</title>" in html
        assert re.search(r'name="canopen-emu-token" content="[0-9a-f]{32}"', html), html[:500]
    with Emulator(interface=canopen_emu_bus, nodes=["sds:16"]) as plain, pytest.raises(ValueError, match="without the web view"):
        plain.web_url()
