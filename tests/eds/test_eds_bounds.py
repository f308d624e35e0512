"""What the EDS/DCF reader (eds/, through canopen-eds) takes of time and memory, and what it says about a DCF
that is not as written: time and memory grow with the file's size and no faster, up to the largest file it reads
(16 MiB); a section defined twice and a NodeID outside 1..127 are told; the writer refuses a file name a line cannot
hold (the refusal of such values is tests/eds/test_eds_write.c)."""
import json
import os
import subprocess
import sys
import time
from pathlib import Path

import pytest

SRC = Path(os.environ.get("CO_SOURCE_DIR", Path(__file__).resolve().parents[2]))
TOOL = os.environ.get("CO_EDS_TOOL", "canopen-eds")
FILES = SRC / "tests" / "eds" / "files"
LIMIT = 16 * 1024 * 1024  # EDS_MAX_FILE_BYTES
MINIMAL = (FILES / "minimal.eds").read_text()


# Runs canopen-eds and prints its exit status, CPU seconds and peak memory. A process of its own: a child's peak
# memory includes what its parent had when it forked (this test's process holds the large files it wrote).
MEASURE = """
import json, os, subprocess, sys, time
timeout = float(sys.argv[1])
with open(sys.argv[2], "wb") as err:
    p = subprocess.Popen(sys.argv[3:], stdout=subprocess.DEVNULL, stderr=err)
start = time.monotonic()
while True:
    pid, status, usage = os.wait4(p.pid, os.WNOHANG)
    if pid != 0:
        break
    if time.monotonic() - start > timeout:
        p.kill()
        pid, status, usage = os.wait4(p.pid, 0)
        break
    time.sleep(0.01)
p.returncode = os.waitstatus_to_exitcode(status)
print(json.dumps([p.returncode, usage.ru_utime + usage.ru_stime, usage.ru_maxrss * 1024]))
"""


def measured(tmp_path, *args, timeout=60):
    """Runs canopen-eds: (exit status, stderr, CPU seconds, peak memory in bytes); fails after timeout seconds.
    CPU time, not the clock: a loaded machine stretches the clock more than a process's own time."""
    err = tmp_path / "stderr"
    start = time.monotonic()
    r = subprocess.run([sys.executable, "-c", MEASURE, str(timeout), err, TOOL, *map(str, args)],
                       capture_output=True, text=True, timeout=timeout + 60)
    assert r.returncode == 0, r.stderr
    if time.monotonic() - start > timeout:
        pytest.fail(f"canopen-eds {' '.join(map(str, args))} took more than {timeout} s")
    rc, seconds, memory = json.loads(r.stdout)
    return rc, err.read_text(errors="replace"), seconds, memory


def fill(parts, limit=LIMIT):
    """The device of minimal.eds and then as many of the parts as fit below the size limit."""
    text, size = [MINIMAL], len(MINIMAL)
    for part in parts:
        if size + len(part) > limit:
            break
        text.append(part)
        size += len(part)
    return "".join(text)


def named_sections():
    i = 0
    while True:
        yield f"[Extra{i}]\nKey=1\n"
        i += 1


def array_objects():
    """ARRAYs of 254 UNSIGNED32 entries, one after the other from 0x2000."""
    for index in range(0x2000, 0x6000):
        yield (f"[{index:04X}]\nParameterName=a\nObjectType=0x8\nSubNumber=255\n"
               f"[{index:04X}sub0]\nParameterName=n\nDataType=0x0005\nAccessType=ro\nDefaultValue=254\n" +
               "".join(f"[{index:04X}sub{s:X}]\nParameterName=e\nDataType=0x0007\nAccessType=rw\nDefaultValue=0\n"
                       for s in range(1, 255)))


def test_the_largest_file_of_named_sections_is_read_at_once(tmp_path):
    """16 MiB of one-key named sections (some 1.3 million): each named section was looked up by a scan of all of
    them for each key of the file, quadratic time (40,000 sections: 10 s; 16 MiB: hours)."""
    path = tmp_path / "named.eds"
    path.write_text(fill(named_sections()))
    rc, err, seconds, memory = measured(tmp_path, "check", path)
    assert rc == 0, err
    assert memory < 32 * LIMIT  # some 20 times the file's size


def test_pdo_objects_left_out_cost_no_more_than_reading_them(tmp_path):
    """2048 PDO objects that are left out (their types are wrong) in front of 16 MiB of entries: each one left out
    moved every entry after it (11 s against 0.5 s for the same entries without them). Best of three, CPU time."""
    pdos = "".join(f"[{i:04X}]\nObjectType=0x9\n[{i:04X}sub1]\nDataType=0x0005\nAccessType=rw\n"
                   for i in range(0x1400, 0x1C00))
    entries = fill(array_objects(), LIMIT - len(pdos))
    plain, with_pdos = tmp_path / "plain.eds", tmp_path / "pdos.eds"
    plain.write_text(entries)
    with_pdos.write_text(entries + pdos)

    def best(path):
        runs = [measured(tmp_path, "check", path) for _ in range(3)]
        assert all(rc == 0 for rc, *_ in runs), runs[0][1]
        return min(seconds for _, _, seconds, _ in runs)

    base = best(plain)
    assert best(with_pdos) < 4 * base + 0.2


def test_a_long_compact_default_is_read_once(tmp_path):
    """A CompactSubObj=254 object whose DefaultValue is a 1 MiB string: the default was read (and copied) for each
    of its sub-indices, 254 copies (a 16 MiB file took 4 GB)."""
    path = tmp_path / "compact.eds"
    device = MINIMAL.replace("[ManufacturerObjects]\nSupportedObjects=0\n",
                             "[ManufacturerObjects]\nSupportedObjects=1\n1=0x2000\n")
    assert "1=0x2000" in device
    path.write_text(device + "[2000]\nParameterName=c\nObjectType=0x8\nCompactSubObj=254\nDataType=0x0009\n"
                    "AccessType=rw\nDefaultValue=" + "a" * (1024 * 1024) + "\n")
    rc, err, _, memory = measured(tmp_path, "check", path)
    assert rc == 0, err
    assert memory < 40 * 1024 * 1024  # 254 copies: 270 MB


def test_a_section_defined_twice_is_told(tmp_path):
    """A DCF with a [2006] inside another value (as a string with line breaks written raw made one): the second
    definition and the key it repeats are warned about, with their lines."""
    dcf = tmp_path / "device.dcf"
    assert subprocess.run([TOOL, "convert", "--dcf", "--node-id", "5", FILES / "all-types.eds", dcf]).returncode == 0
    lines = dcf.read_text().splitlines()
    at = next(i for i, line in enumerate(lines) if line.startswith("ParameterValue=") and i > lines.index("[2008]"))
    lines[at:at + 1] = ["ParameterValue=x", "[2006]", "ParameterValue=7"]
    dcf.write_text("\n".join(lines) + "\n")
    first = lines.index("[2006]") + 1
    r = subprocess.run([TOOL, "check", dcf], capture_output=True, text=True, timeout=60)
    assert f"device.dcf:{at + 2}: warning: section [2006] appears again (first at line {first}); its keys are " \
           f"merged into it" in r.stderr
    assert "warning: key ParameterValue appears again in [2006]" in r.stderr


@pytest.mark.parametrize("value", ["0", "255", "128", "0x100", "five"])
def test_a_node_id_outside_1_to_127_is_told(tmp_path, value):
    dcf = tmp_path / "device.dcf"
    dcf.write_text(MINIMAL + f"[DeviceComissioning]\nNodeID={value}\nBaudrate=250\n")
    line = MINIMAL.count("\n") + 2
    r = subprocess.run([TOOL, "check", dcf], capture_output=True, text=True, timeout=60)
    assert r.returncode == 0
    assert r.stderr.splitlines() == [f"{dcf}:{line}: warning: [DeviceComissioning] NodeID={value} is not a node-ID "
                                     f"(1..127); ignored"]


def test_a_dcf_without_a_node_id_is_not_warned(tmp_path):
    dcf = tmp_path / "device.dcf"
    dcf.write_text(MINIMAL + "[DeviceComissioning]\nBaudrate=250\n")
    r = subprocess.run([TOOL, "check", dcf], capture_output=True, text=True, timeout=60)
    assert r.returncode == 0 and r.stderr == ""


def test_convert_refuses_a_file_name_a_line_cannot_hold(tmp_path):
    out = tmp_path / "x\n[2006]\nParameterValue=7.dcf"
    r = subprocess.run([TOOL, "convert", "--dcf", "--node-id", "5", FILES / "all-types.eds", out],
                       capture_output=True, text=True, timeout=60)
    assert r.returncode == 2
    assert "the file name has a line break, which a line of a CiA 306 file cannot hold; nothing written" in r.stderr
    assert list(tmp_path.iterdir()) == []
