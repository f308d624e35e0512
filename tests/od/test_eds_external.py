"""The device EDS files are read by three independent parsers, as a user's master or tool would:
python-canopen's import_od, eds-utils' eds-validate and objdictgen's odg (list and C generation).
Also checks the anchor values the object-dictionary issue names, through python-canopen."""
import os
import re
import subprocess
import sys
from pathlib import Path

import canopen
import pytest

SRC = Path(os.environ.get("CO_SOURCE_DIR", Path(__file__).resolve().parents[2]))
EDS = sorted((SRC / "od").glob("*.eds"))
BIN = Path(sys.executable).parent
DIAGNOSTIC = re.compile(r"^\s*(WARNING|ERROR|CRITICAL)\b|Traceback", re.MULTILINE | re.IGNORECASE)


def test_every_device_has_an_eds():
    assert [p.name for p in EDS] == ["buerkert-flow-controller.eds", "pro-ionizer.eds", "sds.eds"]


@pytest.mark.parametrize("eds", EDS, ids=lambda p: p.name)
def test_python_canopen_imports(eds):
    od = canopen.import_od(str(eds), node_id=5)
    assert 0x1000 in od and 0x1018 in od
    for obj in od.values():
        variables = obj.values() if hasattr(obj, "values") else [obj]
        for var in variables:
            if var.default is not None and var.data_type not in (canopen.objectdictionary.VISIBLE_STRING,
                                                                  canopen.objectdictionary.OCTET_STRING):
                var.encode_raw(var.default)  # representable in its type


@pytest.mark.parametrize("eds", EDS, ids=lambda p: p.name)
def test_eds_validate_accepts(eds):
    r = subprocess.run([str(BIN / "eds-validate"), str(eds)], capture_output=True, text=True, timeout=60)
    assert r.returncode == 0, r.stdout + r.stderr
    assert r.stdout.strip() == "" and r.stderr.strip() == "", r.stdout + r.stderr


@pytest.mark.parametrize("eds", EDS, ids=lambda p: p.name)
def test_objdictgen_lists_and_generates(eds, tmp_path):
    r = subprocess.run([str(BIN / "odg"), "--no-color", "list", str(eds)], capture_output=True, text=True, timeout=120)
    assert r.returncode == 0, r.stdout + r.stderr
    assert not DIAGNOSTIC.search(r.stdout + r.stderr), r.stdout + r.stderr
    out = tmp_path / "od.c"
    r = subprocess.run([str(BIN / "odg"), "--no-color", "convert", str(eds), str(out)], capture_output=True,
                       text=True, timeout=120)
    assert r.returncode == 0, r.stdout + r.stderr
    assert not DIAGNOSTIC.search(r.stdout + r.stderr), r.stdout + r.stderr
    assert out.stat().st_size > 0


def default(od, index, sub=None):
    obj = od[index]
    return (obj[sub] if sub is not None else obj).default


def test_pro_ionizer_anchors():
    od = canopen.import_od(str(SRC / "od/pro-ionizer.eds"), node_id=5)
    assert default(od, 0x1000) == 0x000F0191
    assert default(od, 0x1008) == "ES61"
    assert default(od, 0x1018, 1) == 0x0000024E
    assert [default(od, 0x1600, s) for s in range(1, 2)] == [0x62000108]
    assert [default(od, 0x1A00, s) for s in range(1, 7)] == [0x60000108 + (s << 8) for s in range(6)]
    assert [default(od, 0x1A01, s) for s in range(1, 5)] == [0x64010110 + (s << 8) for s in range(4)]
    assert [default(od, 0x1A02, s) for s in range(1, 5)] == [0x64010510 + (s << 8) for s in range(4)]
    assert default(od, 0x2002, 0) == 0x3B
    assert [default(od, 0x2002, s) for s in (1, 2, 3, 4, 6, 7)] == [500, 2, 0, 0, 99, 4]
    assert [default(od, 0x1800 + n, 1) for n in range(3)] == [0x185, 0x285, 0x385]
    assert default(od, 0x1400, 1) == 0x205 and default(od, 0x1014) == 0x85


def test_sds_anchors():
    od = canopen.import_od(str(SRC / "od/sds.eds"), node_id=5)
    assert default(od, 0x1000) == 0x191
    assert default(od, 0x1008) == "SDS"
    assert default(od, 0x1018, 1) == 0x0000024E
    assert [i for i in (0x1800, 0x1801, 0x1802) if i in od] == [0x1800, 0x1801]
    assert default(od, 0x2002, 0) == 9 and len([s for s in od[0x2002] if s != 0]) == 9
    assert [default(od, 0x1A00, s) for s in range(1, 6)] == [0x60000108 + (s << 8) for s in range(5)]
    assert [default(od, 0x1A01, s) for s in range(1, 4)] == [0x64010110 + (s << 8) for s in range(3)]


def test_buerkert_anchors():
    od = canopen.import_od(str(SRC / "od/buerkert-flow-controller.eds"), node_id=5)
    assert default(od, 0x1018, 1) == 0x39
    assert default(od, 0x1017) == 500
    assert len([s for s in od[0x1016] if s != 0]) == 127
    assert [s for s in od[0x1200]] == [0, 1, 2, 3]
    for n in range(4):
        assert 0x1400 + n in od and 0x1600 + n in od and 0x1800 + n in od and 0x1A00 + n in od
    assert [default(od, 0x1800, s) for s in (2, 3, 5)] == [0xFE, 5000, 1000]
    assert od[0x2500][1].data_type == canopen.objectdictionary.REAL32 and od[0x2500][1].pdo_mappable
    assert od[0x2540][1].data_type == canopen.objectdictionary.REAL32 and od[0x2540][1].pdo_mappable
    assert default(od, 0x1A00, 1) == 0x25000120 and default(od, 0x1600, 1) == 0x25400120
    for index in (0x1005, 0x1006, 0x100C, 0x100D, 0x1014, 0x2000, 0x2001, 0x2002, 0x2004):
        assert index in od, hex(index)
