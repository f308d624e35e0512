"""canopen-check: a conformance check of any CANopen node, real or emulated, against its EDS and CiA 301/305
(docs/conformance.md lists every check with its clause).

Needs python-can (``pip install canopen-emu[check]``); the rest of canopen_emu does not.

- ``canopen-check --bus vcan0 --node 5 device.eds`` (cli.py): the command line; exit status 0 when nothing failed.
- ``run(bus, node, eds, write=False, only=(), skip=())`` (runner.py): the same from Python, a Report of Results.
- testing.py: each check as a pytest test (``canopen_check_results`` / ``assert_result``).

The layout, for whoever adds checks: registry.py (``@check``, Result, Failed, NotApplicable), frames.py (the bus with
every frame recorded), sdo.py (an SDO client that builds its frames itself), eds.py (the EDS reader), report.py
(text and JUnit XML), one module per group of checks: od.py, sdo_protocol.py, nmt.py, pdo.py, emcy.py, lss.py."""
from .registry import CHECKS, Check, Failed, NotApplicable, Result, Status
from .runner import Context, Options, Report, SetupError, run, select

__all__ = ["CHECKS", "Check", "Context", "Failed", "NotApplicable", "Options", "Report", "Result", "SetupError",
           "Status", "run", "select"]
