"""canopen-check (canopen_emu.check, docs/conformance.md) against canopen-emu: the three built-in devices pass every
check, with --write too; a node made wrong on purpose (protocol faults, a file device whose EDS says another value)
fails the check that should catch it, with the frames; the command line's exit status and JUnit XML; the EDS reader.

On the session's bus (udp_multicast inside tests/udp/netns-run in run-tests.sh's udp pass)."""
import re
import shutil
import subprocess
import threading
import sys
import xml.etree.ElementTree as ET
from concurrent.futures import ThreadPoolExecutor
from pathlib import Path

import pytest

import can

from canopen_emu import Emulator, socketcand_bus
from canopen_emu.check import CHECKS, Status, eds as eds_module, run
from canopen_emu.check.frames import FrameLog
from canopen_emu.check.sdo import SdoClient
from canopen_emu.check.testing import assert_result, check_names, run_on

from conftest import EDS, SOURCE_DIR

BUILT_IN = (("sds", 16), ("buerkert", 17), ("pro-ionizer", 18))
#: Not applicable on each device, and why: the Eltex devices' SDO server is expedited only and their values fit
#: in 4 bytes (sds.eds "Comments", pro-ionizer.eds), they have no node guarding (no 0x100C/0x100D) and their PDO
#: mappings are static (read-only); the Bürkert
#: device has no write-only entry and keeps no error history (no 0x1003).
ELTEX = {"sdo.segmented-upload", "sdo.upload-toggle-error", "sdo.block-upload", "sdo.segmented-download",
         "sdo.download-toggle-error", "nmt.node-guarding", "pdo.mapping-procedure",
         "sdo.server-timeout", "sdo.block-download", "sdo.block-sequence-error"}
NOT_APPLICABLE = {"sds": ELTEX, "buerkert": {"od.write-only-refuses-read", "emcy.error-history"}, "pro-ionizer": ELTEX}
#: The Eltex devices' RPDO maps a write-only entry (0x6200:01, the HV release: not read back, nor sent with its own
#: value) and their TPDOs have no inhibit time (no sub-index 3).
ELTEX |= {"pdo.rpdo-write-read", "pdo.rpdo-length-error", "pdo.tpdo-inhibit-time"}


@pytest.fixture
def three_devices(canopen_emu_factory):
    return canopen_emu_factory(*(f"{device}:{node}" for device, node in BUILT_IN))


#: Where a built-in device knowingly differs from its EDS (a recorded decision), the check that finds it and the entries
#: it names. docs/devices/pro-ionizer.md #36: the EDS's limits of the E-field sensor settings are the union of the two
#: sensor types' (an EDS has one range), the device keeps the range of the type selected (0x2002:31/36).
DEVIATIONS = {
    ("pro-ionizer", "od.takes-limits"): {f"0x2002:{sub:02X}" for sub in (0x32, 0x33, 0x34, 0x35, 0x37, 0x38, 0x39, 0x3A)},
}


def test_the_built_in_devices_pass_every_check(three_devices, canopen_emu_bus):
    # one run per node, at the same time (each its own python-can bus): the SDS's heartbeat is 5 s; LSS after,
    # one node at a time: its answers do not say which node gave them
    with ThreadPoolExecutor(len(BUILT_IN)) as pool:
        reports = dict(zip((d for d, _ in BUILT_IN), pool.map(
            lambda dn: run(canopen_emu_bus.can_kwargs(), dn[1], EDS[dn[0]], write=True, heartbeat_intervals=2,
                           skip=["lss"]), BUILT_IN)))
    for device, node in BUILT_IN:
        reports[device].results += run(canopen_emu_bus.can_kwargs(), node, EDS[device], only=["lss"]).results
    for device, report in reports.items():
        failed = "\n".join(f"{r.name}: {r.message}" for r in report.failed if (device, r.name) not in DEVIATIONS)
        assert not failed, f"{device}:\n{failed}"
        for (d, name), entries in DEVIATIONS.items():
            if d == device:  # a recorded decision: the check finds it, and nothing else
                result = report[name]
                named = set(re.findall(r"0x[0-9A-F]{4}:[0-9A-F]{2}", result.message))
                assert result.status is Status.FAILED and named == entries, result.message
        assert {r.name for r in report.results if r.status is Status.NOT_APPLICABLE} == NOT_APPLICABLE[device]
        assert [r.name for r in report.results] == check_names()
    # what they looked at: every readable entry of the Bürkert's 341 sections, its 12-byte device name segmented
    assert reports["buerkert"]["od.readable-entries"].message == "307 entries"
    assert "0x1008:00" in reports["buerkert"]["sdo.segmented-upload"].message
    assert "(12 bytes, with CRC)" in reports["buerkert"]["sdo.block-upload"].message
    assert "with CRC)" in reports["buerkert"]["sdo.block-download"].message
    # canopen-emu's server gives up 1 s (CO_SDO_TIMEOUT_US) after the client's last frame
    timeout = reports["buerkert"]["sdo.server-timeout"].message
    timed_out = re.search(r"aborted with 0x05040000 ([0-9.]+) s after", timeout)
    assert timed_out and 0.9 <= float(timed_out.group(1)) <= 1.5, timeout


def test_read_only_runs_send_no_download_and_no_nmt_command(three_devices, canopen_emu_bus):
    report = run(canopen_emu_bus.can_kwargs(), 17, EDS["buerkert"], skip=["heartbeat"])
    assert report.ok
    writers = {name for name in check_names() if CHECKS[name].writes}
    assert writers and {r.name for r in report.results if r.status is Status.NOT_APPLICABLE} >= writers
    assert all(r.message == "changes the device: needs --write" for r in report.results if r.name in writers)
    # and the node did not move: still pre-operational, nothing written
    assert three_devices.client.nodes()[1].state == "PRE-OPERATIONAL"


def test_an_sdo_abort_fault_fails_the_object_dictionary_checks_with_the_frames(three_devices, canopen_emu_bus):
    three_devices.client.inject_fault(17, "sdo-abort", "0x1018:01", "0x06020000")
    report = run(canopen_emu_bus.can_kwargs(), 17, EDS["buerkert"], only=["od"])
    failed = {r.name: r for r in report.failed}
    # 0x1018:01 is mandatory, readable, and read-only with a value in the EDS
    assert set(failed) == {"od.mandatory-objects", "od.readable-entries", "od.default-values"}, failed
    result = failed["od.readable-entries"]
    assert result.message.startswith("1 of 307 readable entries wrong: 0x1018:01 'Vendor ID' (UNSIGNED32, ro): "
                                      "aborted with 0x06020000"), result.message
    assert "0x06020000 (object does not exist in the object dictionary)" in result.message
    # the frames that show it: the request and the abort in the node's place
    assert [(f.can_id, f.data.hex()) for f in result.frames] == [
        (0x611, "4018100100000000"), (0x591, "8018100100000206")]


class NeverTimingOutServer:
    """An SDO server of node 5 on python-can's virtual bus, wrong on purpose: it serves uploads (0x1000
    expedited, any other entry segmented, b"0123456789") and answers a block download initiate, but never times
    out a transfer and takes a block segment with sequence number 0 silently."""

    NODE, VALUE = 5, b"0123456789"

    def __init__(self, channel):
        self.bus = can.Bus(interface="virtual", channel=channel)
        self.position = 0
        self.running = True
        self.thread = threading.Thread(target=self.serve, daemon=True)
        self.thread.start()

    def answer(self, data):
        self.bus.send(can.Message(arbitration_id=0x580 + self.NODE, data=bytes(data).ljust(8, b"\0"),
                                  is_extended_id=False))

    def serve(self):
        while self.running:
            request = self.bus.recv(0.05)
            if request is None or request.arbitration_id != 0x600 + self.NODE:
                continue
            command, mux = request.data[0], bytes(request.data[1:4])
            if command == 0x40 and mux == b"\x00\x10\x00":
                self.answer(b"\x43" + mux + (0x20192).to_bytes(4, "little"))
            elif command == 0x40:
                self.position = 0
                self.answer(b"\x41" + mux + len(self.VALUE).to_bytes(4, "little"))
            elif command & 0xEF == 0x60:  # an upload segment request
                chunk = self.VALUE[self.position:self.position + 7]
                self.position += len(chunk)
                last = self.position >= len(self.VALUE)
                self.answer(bytes([command & 0x10 | (7 - len(chunk)) << 1 | last]) + chunk)
            elif command & 0xE1 == 0xC0:  # a block download initiate: block size 127
                self.answer(b"\xa4" + mux + b"\x7f")

    def close(self):
        self.running = False
        self.thread.join()
        self.bus.shutdown()


def minimal_with_label(value):
    """tests/eds/files/minimal.eds with 0x2000 'Label', a rw VISIBLE_STRING of this value."""
    minimal = (SOURCE_DIR / "tests/eds/files/minimal.eds").read_text()
    return minimal.replace("[OptionalObjects]\nSupportedObjects=1\n1=0x1017\n",
                           "[OptionalObjects]\nSupportedObjects=2\n1=0x1017\n2=0x2000\n") + (
        "\n[2000]\nParameterName=Label\nObjectType=0x7\nDataType=0x0009\nAccessType=rw\nDefaultValue="
        f"{value}\nPDOMapping=0\n")


def test_a_server_without_a_timeout_nor_a_sequence_check_fails_those_checks(tmp_path):
    device = tmp_path / "never-times-out.eds"
    device.write_text(minimal_with_label("0123456789"))
    server = NeverTimingOutServer("never-times-out")
    check_bus = can.Bus(interface="virtual", channel="never-times-out")
    try:
        report = run(check_bus, 5, device, only=["sdo.server-timeout", "sdo.block-sequence-error"], write=True,
                     timeout=0.3)
    finally:
        check_bus.shutdown()
        server.close()
    timeout = report["sdo.server-timeout"]
    assert timeout.status is Status.FAILED
    assert timeout.message.startswith("0x2000:00 'Label' (VISIBLE_STRING, rw): a segmented upload left open after "
                                      "its initiate was not aborted by the server within 5.3 s: expected abort "
                                      "0x05040000 (SDO protocol timed out)"), timeout.message
    # the initiate, its answer, and the abort this side sent when it gave up
    assert [f.data.hex() for f in timeout.frames] == ["4000200000000000", "410020000a000000", "8000200000000405"]
    sequence = report["sdo.block-sequence-error"]
    assert sequence.status is Status.FAILED
    assert "a block download segment with sequence number 0 was not answered within 0.3 s, expected abort " \
           "0x05040003 (invalid sequence number)" in sequence.message
    assert [f.data.hex() for f in sequence.frames] == [
        "c60020000a000000", "a40020007f000000", "0030313233343536", "8000200003000405"]


def test_a_value_of_more_than_one_block_goes_by_block_both_ways(canopen_emu_factory, canopen_emu_bus, tmp_path):
    # 1000 bytes, longer than canopen-emu's SDO buffer: a large object, taken in blocks of 127 segments (889 bytes)
    value = "".join(chr(0x41 + i % 26) for i in range(1000)).encode()
    device = tmp_path / "long-label.eds"
    device.write_text(minimal_with_label(value.decode()))
    canopen_emu_factory(f"{device}:0x63")  # not a node-ID of file_devices, which may be on the bus
    report = run(canopen_emu_bus.can_kwargs(), 0x63, device, write=True,
                 only=["sdo.block-upload", "sdo.block-download", "sdo.block-sequence-error", "sdo.server-timeout"])
    assert report.ok, [(r.name, r.message) for r in report.failed]
    assert report["sdo.block-download"].message == "0x2000:00 'Label' (VISIBLE_STRING, rw) (1000 bytes, with CRC)"
    # the check's client, with another value: 143 segments in two blocks, each confirmed whole (ackseq 127, 16)
    bus = can.Bus(**canopen_emu_bus.can_kwargs())
    try:
        client = SdoClient(FrameLog(bus), 0x63)
        assert client.block_download(0x2000, 0, value[::-1]) is True
        assert [f.data[:3].hex() for f in client.frames if not f.sent and f.data[0] == 0xA2] == ["a27f7f", "a2107f"]
        assert client.upload(0x2000, 0) == value[::-1]
    finally:
        bus.shutdown()


def test_a_wrong_state_in_the_heartbeat_fails_the_heartbeat_and_nmt_checks(three_devices, canopen_emu_bus):
    client = three_devices.client
    client.inject_fault(17, "heartbeat-state", "0x12")
    report = run(canopen_emu_bus.can_kwargs(), 17, EDS["buerkert"], only=["heartbeat.state"])
    assert report["heartbeat.state"].status is Status.FAILED
    assert "state 0x12, not 0x04, 0x05 or 0x7F" in report["heartbeat.state"].message
    assert all(f.can_id == 0x711 and f.data == b"\x12" for f in report["heartbeat.state"].frames)
    # a valid state, but always operational: only the NMT commands show it is not the node's
    client.inject_fault(17, "heartbeat-state", "0x05")
    report = run(canopen_emu_bus.can_kwargs(), 17, EDS["buerkert"], only=["heartbeat.state", "nmt.state-changes"],
                 write=True)
    assert report["heartbeat.state"].status is Status.PASSED
    assert report["nmt.state-changes"].status is Status.FAILED
    assert "after NMT stop: no heartbeat with state 0x04 (stopped)" in report["nmt.state-changes"].message


def test_a_jittered_heartbeat_fails_the_period_check(three_devices, canopen_emu_bus):
    # each heartbeat 0..400 ms late (0x1017 = 500 ms): an interval within +-50 ms of 500 has a chance of 23 %, six
    # in a row 0.02 %
    three_devices.client.inject_fault(17, "heartbeat-jitter", 400)
    report = run(canopen_emu_bus.can_kwargs(), 17, EDS["buerkert"], only=["heartbeat.period"], heartbeat_intervals=6)
    assert report["heartbeat.period"].status is Status.FAILED
    assert "0x1017 = 500 ms, allowed +-50 ms" in report["heartbeat.period"].message
    assert len(report["heartbeat.period"].frames) == 7  # the heartbeats judged


def test_a_stopped_heartbeat_fails_the_period_and_guarding_checks(three_devices, canopen_emu_bus):
    assert run(canopen_emu_bus.can_kwargs(), 17, EDS["buerkert"], only=["nmt.node-guarding"], write=True).ok
    three_devices.client.inject_fault(17, "heartbeat-stop")  # no heartbeat, nor node-guarding answer
    report = run(canopen_emu_bus.can_kwargs(), 17, EDS["buerkert"], only=["heartbeat.period", "nmt.node-guarding"],
                 write=True)
    assert report["heartbeat.period"].status is Status.FAILED
    assert report["heartbeat.period"].message.startswith("no heartbeat within")
    assert report["nmt.node-guarding"].message.startswith(
        "1 wrong guarding answers: the first request: no answer to the guard request")
    three_devices.client.clear_fault(17)
    assert three_devices.client.get(17, "0x1017") == 500  # put back after the check set it to 0


def test_a_tpdo_of_the_wrong_length_fails_the_tpdo_check(three_devices, canopen_emu_bus):
    three_devices.client.inject_fault(18, "tpdo-length", 2, 3)
    report = run(canopen_emu_bus.can_kwargs(), 18, EDS["pro-ionizer"], only=["pdo"], write=True)
    assert report["pdo.mappings"].status is Status.PASSED  # the mapping is right, the frame is not
    result = report["pdo.tpdo-frames"]
    assert result.status is Status.FAILED
    assert "TPDO 0x1801 on 0x292 (remote request): 3 byte(s), its mapping has" in result.message
    assert [(f.can_id, len(f.data)) for f in result.frames] == [(0x292, 3)]
    assert three_devices.client.nodes()[2].state == "PRE-OPERATIONAL"  # put back as it was found


def test_a_node_silent_to_lss_fails_the_lss_checks(three_devices, canopen_emu_bus):
    three_devices.client.inject_fault(17, "lss-silent")
    report = run(canopen_emu_bus.can_kwargs(), 17, EDS["buerkert"], only=["lss"], timeout=0.3)
    assert [r.name for r in report.failed] == ["lss.identify-remote-slave", "lss.inquire-identity"]
    assert report["lss.inquire-identity"].message.startswith("no answer to switch state selective")
    assert {f.can_id for f in report["lss.inquire-identity"].frames} == {0x7E5}  # asked, never answered


def test_an_error_register_without_its_generic_bit_fails_the_check(three_devices, canopen_emu_bus):
    # the emulator's emcy command sets the generic bit as a device does; a raw set of 0x1001 does not
    three_devices.client.set(17, "0x1001", 0x04)  # voltage, and the generic bit 0 not set
    report = run(canopen_emu_bus.can_kwargs(), 17, EDS["buerkert"], only=["emcy.error-register"])
    assert report["emcy.error-register"].message == "0x1001 = 0x04: an error bit without the generic error bit 0"
    assert [(f.can_id, f.data.hex()) for f in report["emcy.error-register"].frames] == [
        (0x611, "4001100000000000"), (0x591, "4f01100004000000")]


def test_the_mapping_procedure_puts_the_pdo_back(three_devices, canopen_emu_bus):
    client = three_devices.client
    pdo = ["0x1800:01", "0x1A00:00", "0x1A00:01", "0x1A00:02", "0x1A00:03"]
    before = client.get_many(17, pdo)
    report = run(canopen_emu_bus.can_kwargs(), 17, EDS["buerkert"], only=["pdo.mapping-procedure"], write=True)
    assert report.ok, report["pdo.mapping-procedure"].message
    assert report["pdo.mapping-procedure"].message == (
        "TPDO 0x1800/0x1A00; valid: refused with 0x06010000 (unsupported access to an object)")
    assert client.get_many(17, pdo) == before
    # the aborts were asked for and given: not mappable, too long
    aborts = [line for line in three_devices.log_lines() if "SDO abort 0x0604004" in line]
    assert any("0x06040041 on 0x1A00:01" in line for line in aborts), aborts
    assert any("0x06040042" in line for line in aborts), aborts


def test_an_eds_whose_default_differs_from_the_device_fails_default_values(canopen_emu_factory, canopen_emu_bus,
                                                                          tmp_path):
    device = SOURCE_DIR / "tests/eds/files/minimal.eds"
    canopen_emu_factory(f"{device}:0x61")  # not a node-ID of file_devices, which may be on the bus
    assert run(canopen_emu_bus.can_kwargs(), 0x61, device, only=["od"]).ok
    wrong = tmp_path / "minimal-wrong.eds"
    wrong.write_text(device.read_text().replace("DefaultValue=0x00000ABC", "DefaultValue=0x00000ABD"))
    report = run(canopen_emu_bus.can_kwargs(), 0x61, wrong, only=["od"])
    assert [r.name for r in report.failed] == ["od.default-values"]
    assert ("0x1018:01 'Vendor-ID' (UNSIGNED32, ro): holds 2748 (0xABC), the EDS says '0x00000ABD' = 2749 (0xABD)"
            in report["od.default-values"].message)


FILE_DEVICES = sorted(p.name for p in (SOURCE_DIR / "tests/eds/files").iterdir() if p.suffix in (".eds", ".dcf"))


@pytest.fixture(scope="module")
def file_devices(canopen_emu_bus):
    """Every file of tests/eds/files as a node of one emulator, node-IDs 20 and up in the files' order."""
    nodes = [f"{SOURCE_DIR / 'tests/eds/files' / name}:{20 + i}" for i, name in enumerate(FILE_DEVICES)]
    with Emulator(interface=canopen_emu_bus, nodes=nodes) as emu:
        yield emu


@pytest.mark.parametrize("name", FILE_DEVICES)
def test_every_file_device_passes(file_devices, canopen_emu_bus, name):
    # the files the EDS reader's tests hold to canopen-emu's reader: the check reads them as the emulator does
    report = run(canopen_emu_bus.can_kwargs(), 20 + FILE_DEVICES.index(name), SOURCE_DIR / "tests/eds/files" / name,
                 write=True, heartbeat_intervals=2)
    assert report.ok, "\n".join(f"{r.name}: {r.message}" for r in report.failed)


def test_a_device_that_takes_a_value_past_the_eds_limit_fails_write_limits(canopen_emu_factory, canopen_emu_bus,
                                                                          tmp_path):
    device = SOURCE_DIR / "tests/eds/files/limits.eds"
    emu = canopen_emu_factory(f"{device}:0x60")  # not a node-ID of file_devices, which may be on the bus
    before = emu.client.get(0x60, "0x2000")
    stricter = tmp_path / "limits-stricter.eds"  # the EDS says 40, the device takes up to 50
    stricter.write_text(device.read_text().replace("HighLimit=50", "HighLimit=40"))
    report = run(canopen_emu_bus.can_kwargs(), 0x60, stricter, only=["od.write-limits", "od.write-sizes"], write=True)
    assert report["od.write-sizes"].status is Status.PASSED, report["od.write-sizes"].message
    result = report["od.write-limits"]
    assert result.status is Status.FAILED
    assert ("0x2000:00 'Empty default with limits' (UNSIGNED16, rw): 41 (above HighLimit 40): taken, expected "
            "0x06090031 (value of parameter written too high (download only)) (its value put back)") in result.message
    assert [f.data.hex() for f in result.frames] == ["2b00200029000000", "6000200000000000"]
    assert emu.client.get(0x60, "0x2000") == before


def test_the_mpdo_variant_passes(canopen_emu_factory, canopen_emu_bus):
    # a SAM-MPDO (0x1A03:00 = 0xFE): its mapping is no list of entries, its frame always 8 bytes
    variant = SOURCE_DIR / "od/variants"
    canopen_emu_factory(f"{variant / 'buerkert-mpdo.eds'}:0x62",
                        extra_args=["--rules", str(variant / "buerkert-mpdo.yaml")])
    report = run(canopen_emu_bus.can_kwargs(), 0x62, variant / "buerkert-mpdo.eds", write=True, heartbeat_intervals=2)
    assert report.ok, "\n".join(f"{r.name}: {r.message}" for r in report.failed)
    assert report["pdo.mappings"].message.endswith("MPDO: 0x1A03 SAM-MPDO")
    assert "0x1803" in report["pdo.tpdo-frames"].message


def canopen_check_program():
    found = Path(sys.executable).parent / "canopen-check"  # installed with the package, beside its python
    return str(found) if found.exists() else shutil.which("canopen-check")


def test_the_command_line_exit_status_and_junit_xml(three_devices, canopen_emu_bus, tmp_path):
    program = canopen_check_program()
    assert program, "the canopen-check console script is not installed"
    kwargs = canopen_emu_bus.can_kwargs()
    if kwargs["interface"] != "udp_multicast":
        pytest.skip("the command line is exercised on udp_multicast (the udp pass)")
    bus = ["--interface", "udp_multicast", "--bus", kwargs["channel"], "--port", str(kwargs["port"])]
    junit = tmp_path / "check.xml"
    good = subprocess.run([program, *bus, "--node", "17", str(EDS["buerkert"]), "--only", "od", "sdo",
                           "--junit", str(junit)], capture_output=True, text=True, timeout=60)
    assert good.returncode == 0, good.stdout + good.stderr
    assert "PASS  od.readable-entries" in good.stdout and "0 failed" in good.stdout
    suite = ET.parse(junit).getroot().find("testsuite")
    assert suite is not None and suite.get("failures") == "0" and int(suite.get("tests")) == len(check_names(only=["od", "sdo"]))
    assert suite.find("testcase[@name='sdo.expedited-download']/skipped") is not None  # read-only: n/a

    three_devices.client.inject_fault(17, "sdo-abort", "0x1000", "0x08000000")
    bad = subprocess.run([program, *bus, "--node", "17", str(EDS["buerkert"]), "--only", "od.readable-entries",
                          "--junit", str(junit)], capture_output=True, text=True, timeout=60)
    assert bad.returncode == 1, bad.stdout + bad.stderr
    assert "FAIL  od.readable-entries" in bad.stdout and "tx  611  [8]  40 00 10 00" in bad.stdout
    failure = ET.parse(junit).getroot().find("testsuite/testcase[@name='od.readable-entries']/failure")
    assert failure is not None and "0x08000000 (general error)" in failure.get("message") + failure.text

    unusable = subprocess.run([program, *bus, "--node", "17", str(tmp_path / "none.eds")], capture_output=True,
                              text=True, timeout=60)
    assert unusable.returncode == 2 and "cannot read the EDS" in unusable.stderr
    typo = subprocess.run([program, *bus, "--node", "17", str(EDS["buerkert"]), "--only", "od.nonsense"],
                          capture_output=True, text=True, timeout=60)
    assert typo.returncode == 2 and "no check is named 'od.nonsense'" in typo.stderr


@pytest.fixture(scope="module")
def pro_ionizer_report(canopen_emu_bus):
    """The documented way to make each check a test of its own (canopen_emu.check.testing), on an emulator of the
    module."""
    with Emulator(interface=canopen_emu_bus, nodes=["pro-ionizer:18"]) as emu:
        yield run_on(emu, 18, EDS["pro-ionizer"], skip=["heartbeat.period"])


@pytest.mark.parametrize("name", check_names(skip=["heartbeat.period"]))
def test_each_check_as_a_test(pro_ionizer_report, name):
    assert_result(pro_ionizer_report[name])


def test_the_eds_reader(tmp_path):
    eds = tmp_path / "device.eds"
    eds.write_text("\ufeff[DeviceInfo]\nLSS_Supported=1\n[OptionalObjects]\nSupportedObjects=2\n1=0x1014\n2=0x2000\n"
                   "[1014]\nParameterName=COB-ID EMCY\nDataType=0x0007\nAccessType=RO\nDefaultValue=$NODEID+0x80\n"
                   "[2000]\nParameterName=Gain\nObjectType=0x8\nDataType=0x0002\nAccessType=rw\n"
                   "DefaultValue=0xFD ; minus three\nCompactSubObj=2\n[2000Name]\nNrOfEntries=1\n1=Left\n"
                   "[2000Value]\nNrOfEntries=1\n2=010\n", encoding="utf-8")
    model = eds_module.load(eds, 5)
    assert model.info_flag("LSS_Supported")
    cob = model.entry(0x1014)
    assert (cob.value, cob.node_relative, cob.access) == (0x85, True, "ro")
    gain = model.objects[0x2000]
    assert [(e.sub, e.name, e.value) for e in gain.entries.values()] == [
        (0, "Highest sub-index supported", 2), (1, "Left", -3), (2, "Gain2", 8)]  # 0xFD of an INTEGER8; 010 octal


def test_a_virtual_bus_served_by_socketcand():
    # run_on an Emulator whose bus is inside it: the check joins through python-can's socketcand interface
    with Emulator(interface=socketcand_bus(), nodes=["buerkert:17"]) as emu:
        report = run_on(emu, 17, EDS["buerkert"], only=["od", "sdo", "heartbeat.state"])
    assert report.ok, [(r.name, r.message) for r in report.failed]
    assert report.bus.startswith("canopen-emu (socketcand, host=127.0.0.1, port=")


def test_the_block_transfer_crc_is_cia_301s():
    from canopen_emu.check.sdo import sdo_crc
    assert sdo_crc(b"123456789") == 0x31C3 and sdo_crc(b"") == 0  # CRC-16-CCITT, start value 0 (§7.2.4.3.16)


# --- PDO, EMCY and store checks with --write (RPDO written and read back, its length error, the TPDO inhibit
# time, 0x1010/0x1011) ---

def test_an_rpdo_is_written_and_read_back_and_its_length_error_answered(three_devices, canopen_emu_bus):
    client = three_devices.client
    before = client.get(17, "0x2540:01")
    report = run(canopen_emu_bus.can_kwargs(), 17, EDS["buerkert"],
                 only=["pdo.rpdo-write-read", "pdo.rpdo-length-error", "pdo.tpdo-inhibit-time"], write=True)
    assert report.ok, "\n".join(f"{r.name}: {r.message}" for r in report.failed)
    assert report["pdo.rpdo-write-read"].message == "0x1400 (0x2540:01 changed)"
    # the short frame (3 of 4 bytes), EMCY 0x8210 with the communication and generic bits, then the error reset
    assert report["pdo.rpdo-length-error"].message.startswith(
        "RPDO 0x1400 on 0x211: EMCY 10 82 11 04 00 00 00 00, then 00 00 00 04 00 00 00 00; no 0x1003")
    assert "inhibit time 200 ms, event timer 50 ms: intervals" in report["pdo.tpdo-inhibit-time"].message
    # put back: the set-point, the TPDO's inhibit time and timer, the NMT state
    assert client.get(17, "0x2540:01") == before
    assert [r.value for r in client.get_many(17, ["0x1800:03", "0x1800:05"])] == [5000, 1000]
    assert client.nodes()[1].state == "PRE-OPERATIONAL"


def test_an_rpdo_not_read_back_and_an_error_history_that_lacks_the_error_fail(three_devices, canopen_emu_bus,
                                                                            tmp_path):
    # the EDS says the node keeps an error history (0x1003), which the Bürkert device has not
    with_history = tmp_path / "buerkert-history.eds"
    with_history.write_text(EDS["buerkert"].read_text(encoding="latin-1").replace(
        "[OptionalObjects]\nSupportedObjects=29\n", "[OptionalObjects]\nSupportedObjects=30\n30=0x1003\n") + (
        "\n[1003]\nParameterName=Pre-defined Error Field\nObjectType=0x8\nSubNumber=2\n\n[1003sub0]\n"
        "ParameterName=Number of Errors\nObjectType=0x7\nDataType=0x0005\nAccessType=rw\nDefaultValue=0\n"
        "PDOMapping=0\n\n[1003sub1]\nParameterName=Standard Error Field\nObjectType=0x7\nDataType=0x0007\n"
        "AccessType=ro\nDefaultValue=0\nPDOMapping=0\n"), encoding="latin-1")
    report = run(canopen_emu_bus.can_kwargs(), 17, with_history, only=["pdo.rpdo-length-error"], write=True)
    result = report["pdo.rpdo-length-error"]
    assert result.status is Status.FAILED
    assert "0x1003 (the EDS lists it): aborted with 0x06020000" in result.message, result.message
    # a set-point the node does not give back over SDO
    three_devices.client.inject_fault(17, "sdo-abort", "0x2540:01", "0x08000000")
    report = run(canopen_emu_bus.can_kwargs(), 17, EDS["buerkert"], only=["pdo.rpdo-write-read"], write=True)
    assert report["pdo.rpdo-write-read"].status is Status.FAILED
    assert "0x08000000" in report["pdo.rpdo-write-read"].message
    assert three_devices.client.nodes()[1].state == "PRE-OPERATIONAL"


def test_store_and_restore_leave_the_values_the_node_runs_with_for_the_next_power_on(three_devices,
                                                                                   canopen_emu_bus):
    client = three_devices.client
    client.set(17, "0x1017", 700)  # not the default 500: a restore left as it is would bring 500 back
    report = run(canopen_emu_bus.can_kwargs(), 17, EDS["buerkert"], only=["store"], write=True)
    assert report.ok, "\n".join(f"{r.name}: {r.message}" for r in report.failed)
    assert report["store.save"].message == ("0x1010:01 = 0x00000001; wrong signature refused with 0x08000020; saved")
    assert report["store.restore"].message == ("wrong signature refused with 0x08000020; restored, then saved again")
    client.power_cycle(17)
    assert client.get(17, "0x1017") == 700
    # a node whose store fails (0x06060000: the port's error) fails the save
    client.inject_fault(17, "sdo-abort", "0x1010:01", "0x06060000")
    report = run(canopen_emu_bus.can_kwargs(), 17, EDS["buerkert"], only=["store"], write=True)
    assert report["store.save"].status is Status.FAILED
    assert "aborted with 0x06060000" in report["store.save"].message
    # and the restore is not tried: it could not be saved over again
    assert report["store.restore"].status is Status.FAILED
    assert "0x1010:01 = 'save': aborted with 0x06060000" in report["store.restore"].message


class TpdoWithoutInhibitTime:
    """Node 6 on python-can's virtual bus, wrong on purpose: its TPDO 0x1800 (event-driven, on 0x186) takes an
    inhibit time and an event timer over SDO but goes out every 50 ms in Operational whatever they say. Expedited
    SDO, NMT, a 100 ms heartbeat."""

    NODE = 6

    def __init__(self, channel):
        import threading  # noqa: PLC0415
        import can  # noqa: PLC0415
        self.values = {(0x1000, 0): (0x20192, 4), (0x1017, 0): (100, 2), (0x1800, 1): (0x186, 4),
                       (0x1800, 2): (254, 1), (0x1800, 3): (0, 2), (0x1800, 5): (0, 2), (0x1A00, 0): (0, 1)}
        self.state = 0x7F
        self.bus = can.Bus(interface="virtual", channel=channel)
        self.running = True
        self.thread = threading.Thread(target=self.serve, daemon=True)
        self.thread.start()

    def send(self, can_id, data):
        import can  # noqa: PLC0415
        self.bus.send(can.Message(arbitration_id=can_id, data=bytes(data), is_extended_id=False))

    def serve(self):
        import time
        next_heartbeat = next_tpdo = time.monotonic()
        while self.running:
            now = time.monotonic()
            if now >= next_heartbeat:
                self.send(0x700 + self.NODE, [self.state])
                next_heartbeat = now + 0.1
            if now >= next_tpdo and self.state == 0x05:
                self.send(0x186, [0x2A])
                next_tpdo = now + 0.05
            frame = self.bus.recv(0.005)
            if frame is None:
                continue
            if frame.arbitration_id == 0 and frame.data[1] in (0, self.NODE):
                self.state = {0x01: 0x05, 0x02: 0x04, 0x80: 0x7F}.get(frame.data[0], self.state)
            elif frame.arbitration_id == 0x600 + self.NODE:
                key = (int.from_bytes(frame.data[1:3], "little"), frame.data[3])
                if frame.data[0] == 0x40 and key in self.values:
                    value, size = self.values[key]
                    self.send(0x580 + self.NODE, bytes([0x43 | (4 - size) << 2]) + frame.data[1:4]
                              + value.to_bytes(4, "little"))
                elif frame.data[0] & 0xE3 == 0x23 and key in self.values:  # an expedited download, size given
                    size = 4 - (frame.data[0] >> 2 & 3)
                    self.values[key] = (int.from_bytes(frame.data[4:4 + size], "little"), self.values[key][1])
                    self.send(0x580 + self.NODE, b"\x60" + frame.data[1:4] + bytes(4))
                else:
                    self.send(0x580 + self.NODE, b"\x80" + frame.data[1:4] + (0x06020000).to_bytes(4, "little"))

    def close(self):
        self.running = False
        self.thread.join()
        self.bus.shutdown()


def test_a_tpdo_closer_than_its_inhibit_time_fails_the_inhibit_check(tmp_path):
    import can  # noqa: PLC0415
    minimal = (SOURCE_DIR / "tests/eds/files/minimal.eds").read_text()
    sub = "[1800sub{}]\nParameterName=Sub {}\nObjectType=0x7\nDataType={}\nAccessType={}\nDefaultValue={}\nPDOMapping=0\n\n"
    device = minimal.replace("[OptionalObjects]\nSupportedObjects=1\n1=0x1017\n",
                             "[OptionalObjects]\nSupportedObjects=3\n1=0x1017\n2=0x1800\n3=0x1A00\n") + (
        "\n[1800]\nParameterName=TPDO 1\nObjectType=0x9\nSubNumber=5\n\n"
        + sub.format(0, 0, "0x0005", "ro", 5) + sub.format(1, 1, "0x0007", "rw", "$NODEID+0x180")
        + sub.format(2, 2, "0x0005", "rw", 254) + sub.format(3, 3, "0x0006", "rw", 0)
        + sub.format(5, 5, "0x0006", "rw", 0)
        + "[1A00]\nParameterName=TPDO 1 mapping\nObjectType=0x7\nDataType=0x0005\nAccessType=rw\nDefaultValue=0\n"
          "PDOMapping=0\n")
    (tmp_path / "no-inhibit.eds").write_text(device)
    node = TpdoWithoutInhibitTime("no-inhibit")
    check_bus = can.Bus(interface="virtual", channel="no-inhibit")
    try:
        report = run(check_bus, 6, tmp_path / "no-inhibit.eds", only=["pdo.tpdo-inhibit-time"], write=True,
                     timeout=0.3)
    finally:
        check_bus.shutdown()
        node.close()
    result = report["pdo.tpdo-inhibit-time"]
    assert result.status is Status.FAILED, result.message
    assert result.message.startswith("TPDO 0x1800 on 0x186: inhibit time 200 ms, event timer 50 ms: frames "), \
        result.message
    assert [f.can_id for f in result.frames] == [0x186, 0x186]
    assert result.frames[1].time - result.frames[0].time < 0.18  # the inhibit time less the allowance
    # put back: the inhibit time and timer as found, pre-operational
    assert node.values[(0x1800, 3)][0] == 0 and node.values[(0x1800, 5)][0] == 0 and node.state == 0x7F


def test_a_device_that_refuses_its_eds_limit_fails_takes_limits(canopen_emu_factory, canopen_emu_bus, tmp_path):
    """od.takes-limits: each limit of the EDS written and taken, the value put back; an EDS that allows more than the
    device (HighLimit 60, the device keeps 50) fails it with the abort, and the value is as before."""
    device = SOURCE_DIR / "tests/eds/files/limits.eds"
    emu = canopen_emu_factory(f"{device}:0x61")  # not a node-ID of file_devices, which may be on the bus
    before = emu.client.get(0x61, "0x2000")
    report = run(canopen_emu_bus.can_kwargs(), 0x61, device, only=["od.takes-limits"], write=True)
    result = report["od.takes-limits"]
    assert result.status is Status.PASSED, result.message
    assert result.message.startswith("4 limits taken"), result.message  # those of 0x2000 and 0x2002 (UNSIGNED64)
    assert emu.client.get(0x61, "0x2000") == before
    wider = tmp_path / "limits-wider.eds"
    wider.write_text(device.read_text().replace("HighLimit=50", "HighLimit=60"))
    result = run(canopen_emu_bus.can_kwargs(), 0x61, wider, only=["od.takes-limits"], write=True)["od.takes-limits"]
    assert result.status is Status.FAILED
    assert ("0x2000:00 'Empty default with limits' (UNSIGNED16, rw): its HighLimit 60 refused with 0x06090031 "
            "(value of parameter written too high (download only))") in result.message, result.message
    assert emu.client.get(0x61, "0x2000") == before
    result = run(canopen_emu_bus.can_kwargs(), 0x61, device, only=["od.takes-limits"])["od.takes-limits"]
    assert result.status is Status.NOT_APPLICABLE  # it writes: only with --write


def test_the_rpdo_length_error_is_logged_in_the_error_history(canopen_emu_factory, canopen_emu_bus, tmp_path):
    # the SDS's RPDO maps its write-only 0x6200:01; as a file device whose EDS makes it rw, both RPDO checks apply,
    # and the SDS keeps an error history
    readable = tmp_path / "sds-rw.eds"
    text = EDS["sds"].read_text(encoding="latin-1")
    hv_release = "ParameterName=Write HV Release\nObjectType=0x7\nDataType=0x0005\nAccessType=wo\n"
    assert hv_release in text
    readable.write_text(text.replace(hv_release, hv_release.replace("=wo", "=rw")), encoding="latin-1")
    emu = canopen_emu_factory(f"{readable}:0x63")  # not a node-ID of file_devices, which may be on the bus
    report = run(canopen_emu_bus.can_kwargs(), 0x63, readable, only=["pdo.rpdo-write-read", "pdo.rpdo-length-error"],
                 write=True)
    assert report.ok, "\n".join(f"{r.name}: {r.message}" for r in report.failed)
    assert report["pdo.rpdo-write-read"].message == "0x1400 (0x6200:01 changed)"
    assert report["pdo.rpdo-length-error"].message == (
        "RPDO 0x1400 on 0x263: EMCY 10 82 11 04 00 00 00 00, then 00 00 00 04 00 00 00 00; 0x1003:01 = 0x00048210")
    # the history keeps the check's error; the output is put back
    assert [r.value for r in emu.client.get_many(0x63, ["0x1003:00", "0x1003:01", "0x6200:01"])] == [1, 0x48210, 0]
