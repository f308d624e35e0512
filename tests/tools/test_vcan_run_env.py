"""tools/vcan-run passes a chosen set of the caller's variables into User-Mode Linux (docs/vcan.md): among them
CANOPEN_EMU, CANOPEN_EMU_* and PYTEST_ADDOPTS, which the testing guide's steps (docs/testing-with-canopen-emu.md)
need when pytest runs in there; without CANOPEN_EMU the package said "canopen-emu not found" inside."""

import os
import subprocess
from pathlib import Path

import pytest

REPO = Path(os.environ.get("CO_SOURCE_DIR") or Path(__file__).resolve().parents[2])
VCAN_RUN = REPO / "tools" / "vcan-run"

# Each variable on a line of its own, "unset" for one that did not arrive.
SHOW = 'for v in "$@"; do eval "printf \'%s=%s\\n\' \\"\\$v\\" \\"\\${$v-unset}\\""; done'


def run_in_uml(env_vars, names):
    env = {k: v for k, v in os.environ.items()
           if not k.startswith(("CANOPEN_EMU", "VCAN_RUN_", "PYTEST_ADDOPTS", "CO_PASSED", "CO_NOT_PASSED"))}
    # Always User-Mode Linux (the filter is its own; a native vcan0 takes the whole environment), never an install.
    env.update(env_vars, VCAN_RUN_MODE="uml", VCAN_RUN_NO_INSTALL="1", VCAN_RUN_TIMEOUT="300")
    r = subprocess.run([str(VCAN_RUN), "sh", "-c", SHOW, "sh", *names], env=env, stdin=subprocess.DEVNULL,
                       capture_output=True, text=True, timeout=400)
    if r.returncode == 77:
        pytest.skip("no User-Mode Linux here: " + r.stderr.strip().splitlines()[0])
    assert r.returncode == 0, r.stderr
    return r.stdout


def test_the_program_and_the_plugins_variables_arrive_and_others_do_not():
    passed = {
        "CANOPEN_EMU": "/opt/it's here/bin/canopen-emu",         # a blank and a quote survive
        "CANOPEN_EMU_EDS_DIR": "/usr/share/canopen-emu/eds",
        "PYTEST_ADDOPTS": "--canopen-emu-bus vcan0 -k 'not slow'",
        "VCAN_RUN_PASS_ENV": "MY_CI_VAR",                        # the names listed there still arrive
        "MY_CI_VAR": "listed",
    }
    names = ["CANOPEN_EMU", "CANOPEN_EMU_EDS_DIR", "PYTEST_ADDOPTS", "MY_CI_VAR", "CANOPEN_EMULATOR", "NOT_LISTED"]
    out = run_in_uml({**passed, "CANOPEN_EMULATOR": "x", "NOT_LISTED": "y"}, names)
    assert out.splitlines() == [
        "CANOPEN_EMU=/opt/it's here/bin/canopen-emu",
        "CANOPEN_EMU_EDS_DIR=/usr/share/canopen-emu/eds",
        "PYTEST_ADDOPTS=--canopen-emu-bus vcan0 -k 'not slow'",
        "MY_CI_VAR=listed",
        "CANOPEN_EMULATOR=unset",   # the prefix is CANOPEN_EMU_, not CANOPEN_EMU
        "NOT_LISTED=unset",         # and nothing else: this ran inside User-Mode Linux, through the filter
    ]
