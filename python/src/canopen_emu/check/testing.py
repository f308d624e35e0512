"""canopen-check in a pytest suite: each check one test, passed / failed (with the frames) / skipped (not
applicable).

A suite that runs its own nodes (canopen-emu's, through the plugin's fixtures, or real ones)::

    import pytest
    from canopen_emu.check.testing import assert_result, check_names, run_on

    @pytest.fixture(scope="module")
    def conformance(canopen_emu_session, canopen_emu_bus):
        return run_on(canopen_emu_bus, 16, "od/sds.eds", write=True)   # once for all the tests below

    @pytest.mark.parametrize("name", check_names())
    def test_conformance(conformance, name):
        assert_result(conformance[name])

``run_on`` takes a canopen_emu.Bus (the plugin's ``canopen_emu_bus``), an Emulator (its first bus, a socketcand
one included) or anything ``run()`` takes (a python-can bus, its keyword arguments)."""
from __future__ import annotations

from pathlib import Path
from typing import Any, Dict, List, Sequence, Union

from .registry import CHECKS, Result, Status
from .report import result_details
from .runner import Report, run, select


def check_names(*, only: Sequence[str] = (), skip: Sequence[str] = ()) -> List[str]:
    """The checks' names, in the order they run (``only``/``skip`` as run()'s): the parameters of a test."""
    return [c.name for c in select(only, skip)] if only or skip else list(CHECKS)


def bus_arguments(target: Any) -> Union[Dict[str, Any], Any]:
    """What run() takes as its bus for a canopen_emu.Bus or Emulator; anything else as it is."""
    from ..buses import Bus
    from ..emulator import Emulator
    if isinstance(target, Emulator):
        bus = target.buses[0]
        if bus.kind == "virtual" and target.socketcand is not None:
            host, port = target.socketcand_address()
            return {"interface": "socketcand", "channel": bus.name, "host": host, "port": port}
        return bus.can_kwargs()
    if isinstance(target, Bus):
        return target.can_kwargs()
    return target


def run_on(target: Any, node: int, eds: Union[str, Path], **options: Any) -> Report:
    """run() on a canopen_emu.Bus, an Emulator's first bus, or what run() takes; ``options`` as run()'s."""
    return run(bus_arguments(target), node, eds, **options)


def assert_result(result: Result) -> None:
    """Passes for a passed check; pytest.skip for one not applicable; pytest.fail with the message, the clause
    and the frames for a failed one."""
    import pytest
    if result.status is Status.NOT_APPLICABLE:
        pytest.skip(f"{result.name}: {result.message}")
    if result.failed:
        first = result.message.splitlines()[0] if result.message else ""
        pytest.fail(f"{result.name}: {first}\n{result_details(result)}", pytrace=False)
