"""Device variants read from their EDS (od/variants/): each file is what its script writes from the base device's
EDS, reads without a warning, and python-canopen imports it with the layout its documentation gives."""
import os
import subprocess
import sys
from pathlib import Path

import canopen

SRC = Path(os.environ.get("CO_SOURCE_DIR", Path(__file__).resolve().parents[2]))
MPDO_EDS = SRC / "od" / "variants" / "buerkert-mpdo.eds"


def test_buerkert_mpdo_eds_is_what_its_script_writes():
    r = subprocess.run([sys.executable, str(SRC / "tools" / "buerkert-mpdo-eds.py"), "--check"],
                       capture_output=True, text=True)
    assert r.returncode == 0, r.stderr


def test_buerkert_mpdo_eds_reads_clean():
    r = subprocess.run([os.environ["CO_EDS_TOOL"], "check", "--strict", str(MPDO_EDS)], capture_output=True,
                       text=True)
    assert r.returncode == 0, r.stdout + r.stderr


def test_buerkert_mpdo_layout_through_python_canopen():
    od = canopen.import_od(str(MPDO_EDS), node_id=0x14)
    assert [od[0x1A00 + n][0].default for n in range(4)] == [2, 2, 2, 0xFE]
    assert [od[0x1A00 + n][s].default for n in range(3) for s in (1, 2)] == [
        0x25000120, 0x25010120, 0x25020120, 0x25030120, 0x25040120, 0x25050120]
    assert [od[0x1800 + n][1].default for n in range(4)] == [0x194, 0x294, 0x394, 0x494]
    scanner = od[0x1FA0]
    assert [scanner[s].default for s in range(4)] == [3, 0x01250601, 0x01250701, 0x01250801]
    assert [od[0x2500 + i][3].default for i in range(9)][6:] == ["Supply voltage", "Device temperature",
                                                                  "Operating time"]
