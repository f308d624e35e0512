"""export-dcf of a device read from an EDS, when an SDO master wrote a string a CiA 306 line cannot hold, and a DCF
whose NodeID is out of range (issue 32: N9 and the small one). canopen-emu-fakecan, also under ASan+UBSan."""
import os
import subprocess

from test_emulator_native import EMU, FakeBus
from test_text_native import TextEmulator, sdo_download

SRC = os.environ.get("CO_SOURCE_DIR", os.path.join(os.path.dirname(__file__), "..", ".."))
ALL_TYPES = os.path.join(SRC, "tests", "eds", "files", "all-types.eds")


def test_a_string_with_a_line_break_is_refused_by_export_dcf(tmp_path):
    """A value with a line break, written over SDO, injected a [2006] section into the exported DCF (on reload 0x2006
    was the page's value, without a word). Now the export is refused naming the entry, and nothing is written; a
    clean value exports."""
    emu = TextEmulator(tmp_path, f"{ALL_TYPES}:5")
    emu.bus.expect(lambda i, d: i == 0x705 and d == b"\0", 10.0, "boot-up of node 5")
    sdo_download(emu.bus, 5, 0x2008, 0, b"x\n[2006]\nDefaultValue=7")
    dcf = tmp_path / "node5.dcf"
    emu.command(f"export-dcf 5 {dcf}")
    emu.command('{"id":1,"cmd":"get","node":5,"object":"0x2008"}')  # the answers above are in before the quit
    clean = tmp_path / "clean.dcf"
    out, _ = emu.quit()
    text = out.decode()
    assert ("0x2008:00: its VISIBLE_STRING value has a line break (at byte 1), which a line of a CiA 306 file cannot "
            "hold; nothing written") in text, text
    assert not dcf.exists() and not (tmp_path / "node5.dcf.tmp").exists()
    emu = TextEmulator(tmp_path, f"{ALL_TYPES}:5")
    emu.bus.expect(lambda i, d: i == 0x705 and d == b"\0", 10.0, "boot-up of node 5")
    sdo_download(emu.bus, 5, 0x2008, 0, b"fine value")
    emu.command(f"export-dcf 5 {clean}")
    emu.quit()
    assert "ParameterValue=fine value" in clean.read_text()


def test_a_dcf_with_a_node_id_out_of_range_says_so(tmp_path):
    for value in ("0", "255"):
        dcf = tmp_path / f"node-{value}.dcf"
        text = open(ALL_TYPES).read() + f"\n[DeviceComissioning]\nNodeID={value}\nBaudrate=250\n"
        dcf.write_text(text)
        bus = FakeBus(tmp_path / f"bus-{value}")
        env = dict(os.environ, CO_FAKECAN_SOCKET=bus.listener.getsockname())
        r = subprocess.run([EMU, "-i", "fakecan0", "--nvm-dir", str(tmp_path / "nvm"), str(dcf)], env=env,
                           capture_output=True, text=True, timeout=30)
        assert r.returncode == 2, r.stderr
        assert f"NodeID={value} is not a node-ID (1..127); ignored" in r.stderr, r.stderr
        assert "the file has no [DeviceComissioning] NodeID in 1..127" in r.stderr, r.stderr
