"""The pytest plugin of canopen_emu, registered through the ``pytest11`` entry point: installing the package is
enough (``pytest --trace-config`` lists it as ``canopen_emu``).

Options (command line, or the ini file):

- ``--canopen-emu PATH`` / ini ``canopen_emu``: the program (default ``$CANOPEN_EMU``, else ``canopen-emu`` on
  PATH);
- ``--canopen-emu-bus BUS`` (repeatable) / ini ``canopen_emu_bus``: the bus(es) of the emulators, as canopen-emu's
  ``-i`` names them (``vcan0``, ``socketcan:can1``, ``udp_multicast:239.74.163.2:43113``, docs/buses.md), or ``auto``
  (the default): vcan0 where it exists and is up, else a udp_multicast group and port of this session's own, TTL 0
  (canopen_emu.buses.session_udp_bus: two sessions on one machine, pytest-xdist's workers too, never share it),
  or ``socketcand``: a virtual bus in each emulator, served on a loopback port of its own by its ``--socketcand``,
  which the master joins with python-can's ``socketcand`` interface (canopen_emu.buses.socketcand_bus);
  ``--canopen-emu-interface`` / ini ``canopen_emu_interface`` are its older names;
- ``--canopen-emu-web HOST:PORT`` / ini ``canopen_emu_web``: every emulator the fixtures start serves the live view
  in the browser there (``127.0.0.1:0``: a free port each); its address is written to the terminal and into a
  failed test's report;
- ini ``canopen_emu_session_nodes``: the nodes of ``canopen_emu_session``; ini ``canopen_emu_log_lines`` /
  ``canopen_emu_event_lines``: how much of the log and of the events a failed test's report shows.

Fixtures: ``canopen_emu_factory`` (start emulators in a test; all stopped at its end), ``canopen_emu`` (one
emulator with the nodes of ``@pytest.mark.canopen_emu_nodes(...)``), ``canopen_emu_session`` (one for the whole
session), ``canopen_emu_network`` (a python-canopen Network on the emulators' bus, whatever its kind, for the
master under test), ``canopen_emu_bus`` (that bus: canopen_emu.Bus, its ``can_kwargs()`` for python-can). A
failed test's report gets, for each emulator it used, a section with the end of its log and one with the last events
its clients received."""
from __future__ import annotations

import json
import os
from dataclasses import dataclass
from typing import Any, Generator, Iterator, List, Optional, Sequence, Union

import pytest

from ._version import __version__
from .buses import Bus, choose_bus, interface_is_up
from .client import Event
from .emulator import Emulator, PathLike, find_executable
from .errors import EmulatorError

MARKER = "canopen_emu_nodes"


@dataclass(frozen=True)
class Settings:
    """The plugin's options, resolved once per run."""
    executable: Optional[str]   # None: $CANOPEN_EMU, else canopen-emu on PATH (looked up at each start)
    buses: List[Bus]            # auto resolved: the buses every emulator of the run is started on
    chosen_by: str              # how: "" when named, else what auto found
    web: Optional[str]          # HOST:PORT of the emulators' web view; None: none
    log_lines: int
    event_lines: int


SETTINGS = pytest.StashKey[Settings]()
EMULATORS = pytest.StashKey[List[Emulator]]()      # on an item: the emulators its test started
SESSION_EMULATOR = pytest.StashKey[Emulator]()     # on the config: canopen_emu_session's emulator


def pytest_addoption(parser: pytest.Parser) -> None:
    group = parser.getgroup("canopen-emu", "canopen-emu (emulated CANopen devices)")
    group.addoption("--canopen-emu", dest="canopen_emu", metavar="PATH", default=None,
                    help="the canopen-emu program (default: ini canopen_emu, $CANOPEN_EMU, canopen-emu on PATH)")
    group.addoption("--canopen-emu-bus", dest="canopen_emu_bus", metavar="auto|BUS", action="append",
                    default=None, help="bus of the emulators, as canopen-emu's -i names it (vcan0, "
                                       "udp_multicast:GROUP:PORT, ...), or auto: vcan0 when it is up, else a "
                                       "udp_multicast group of this session's own, or socketcand: a virtual bus "
                                       "served by each emulator's socketcand server on loopback (default: ini "
                                       "canopen_emu_bus, else auto); give it again for more buses")
    group.addoption("--canopen-emu-interface", dest="canopen_emu_interface", metavar="IFACE", action="append",
                    default=None, help="the older name of --canopen-emu-bus")
    group.addoption("--canopen-emu-web", dest="canopen_emu_web", metavar="HOST:PORT", default=None,
                    help="serve each emulator's live view in the browser there (127.0.0.1:0: a free port each; "
                         "default: ini canopen_emu_web, else none)")
    parser.addini("canopen_emu", "the canopen-emu program (relative to the ini file's directory)", default="")
    parser.addini("canopen_emu_web", "HOST:PORT of the emulators' live view in the browser (none when empty)",
                  default="")
    parser.addini("canopen_emu_bus", "bus(es) of the emulators, separated by blanks: auto (the default) or as "
                  "canopen-emu's -i names them", type="args", default=[])
    parser.addini("canopen_emu_interface", "the older name of canopen_emu_bus", type="args", default=[])
    parser.addini("canopen_emu_session_nodes", "nodes of the canopen_emu_session fixture (\"sds:16 buerkert:17\")",
                  type="args", default=[])
    parser.addini("canopen_emu_log_lines", "log lines of each emulator in a failed test's report", default="60")
    parser.addini("canopen_emu_event_lines", "events of each emulator in a failed test's report", default="20")


def pytest_configure(config: pytest.Config) -> None:
    config.addinivalue_line(
        "markers", f"{MARKER}(*nodes, interface=None, nvm_dir=None, extra_args=(), start_timeout=10.0): the "
                   "nodes of the canopen_emu fixture's emulator (\"sds:16\", \"buerkert:0x11@vcan1\")")
    executable: Optional[str] = config.getoption("canopen_emu")
    if not executable:
        ini = str(config.getini("canopen_emu"))
        if ini and os.sep in ini and config.inipath is not None:
            ini = str(config.inipath.parent / ini)
        executable = ini or None
    choices = (config.getoption("canopen_emu_bus") or config.getoption("canopen_emu_interface")
               or list(config.getini("canopen_emu_bus")) or list(config.getini("canopen_emu_interface")) or ["auto"])
    try:
        buses = [choose_bus(str(choice)) for choice in choices]
    except (ValueError, OSError) as e:
        raise pytest.UsageError(f"--canopen-emu-bus: {e}") from None
    chosen_by = ""
    if "auto" in choices:
        chosen_by = ("auto: vcan0 is up" if interface_is_up("vcan0") else
                     "auto: no vcan0 up, so a group of this session's own, TTL 0 (never leaves the machine)")
    web = config.getoption("canopen_emu_web") or str(config.getini("canopen_emu_web")) or None
    config.stash[SETTINGS] = Settings(executable=executable, buses=buses, chosen_by=chosen_by, web=web,
                                      log_lines=int(config.getini("canopen_emu_log_lines")),
                                      event_lines=int(config.getini("canopen_emu_event_lines")))


def pytest_report_header(config: pytest.Config) -> str:
    settings = config.stash[SETTINGS]
    try:
        program = find_executable(settings.executable)
    except EmulatorError as e:
        program = f"not usable ({e})"
    buses = ", ".join(bus.label for bus in settings.buses)
    return (f"canopen-emu plugin {__version__}: {program} on {buses}"
            + (f", chosen by {settings.chosen_by}" if settings.chosen_by else ""))


class EmulatorFactory:
    """What ``canopen_emu_factory`` gives: call it with nodes to start an emulator on the plugin's interface(s);
    keyword arguments as Emulator's. Every emulator it started is stopped at the end of the test."""

    def __init__(self, config: pytest.Config, started: List[Emulator]) -> None:
        self.config = config
        self.settings = config.stash[SETTINGS]
        self.started = started

    def __call__(self, *nodes: str, interface: Union[None, str, Sequence[str]] = None,
                 nvm_dir: Optional[PathLike] = None, extra_args: Sequence[str] = (),
                 executable: Optional[PathLike] = None, start_timeout: float = 10.0) -> Emulator:
        if not nodes:
            raise ValueError("canopen_emu_factory needs the nodes: canopen_emu_factory(\"sds:16\", ...)")
        emu = Emulator(interface if interface is not None else self.settings.buses, list(nodes), nvm_dir,
                       executable if executable is not None else self.settings.executable, extra_args,
                       start_timeout=start_timeout, web=self.settings.web)
        self.started.append(emu)
        announce_web(self.config, emu)
        return emu

    def stop_all(self) -> List[str]:
        """Stops them; the problems: each that ended with a status other than 0 without being asked to stop."""
        problems = []
        for emu in self.started:
            asked = emu.stop_requested
            status = emu.stop()
            if status != 0 and not asked:
                problems.append(f"canopen-emu ({' '.join(emu.node_args)}) ended by itself with status {status}:\n"
                                f"{emu.describe(self.settings.log_lines)}")
        return problems


@pytest.fixture
def canopen_emu_factory(request: pytest.FixtureRequest) -> Iterator[EmulatorFactory]:
    """Starts emulators: ``emu = canopen_emu_factory("sds:16", "buerkert:17")``. All are stopped at the end of
    the test; one that ended by itself with a status other than 0 makes the teardown fail."""
    started = request.node.stash.setdefault(EMULATORS, [])
    factory = EmulatorFactory(request.config, started)
    yield factory
    problems = factory.stop_all()
    if problems:
        pytest.fail("\n\n".join(problems), pytrace=False)


@pytest.fixture
def canopen_emu(request: pytest.FixtureRequest, canopen_emu_factory: EmulatorFactory) -> Emulator:
    """An emulator with the nodes of the test's ``@pytest.mark.canopen_emu_nodes("sds:16", ...)`` marker (its
    keywords as canopen_emu_factory's), started and booted; ``canopen_emu.client`` is connected."""
    marker = request.node.get_closest_marker(MARKER)
    if marker is None or not marker.args:
        pytest.fail(f"the canopen_emu fixture needs the nodes: @pytest.mark.{MARKER}(\"sds:16\", ...)",
                    pytrace=False)
    return canopen_emu_factory(*marker.args, **marker.kwargs)


@pytest.fixture(scope="session")
def canopen_emu_session_nodes(pytestconfig: pytest.Config) -> List[str]:
    """The nodes of canopen_emu_session: the ini value canopen_emu_session_nodes; override this fixture in a
    conftest.py to choose them in Python."""
    nodes = [str(n) for n in pytestconfig.getini("canopen_emu_session_nodes")]
    if not nodes:
        pytest.fail("canopen_emu_session needs nodes: set canopen_emu_session_nodes in the ini file, or override "
                    "the canopen_emu_session_nodes fixture", pytrace=False)
    return nodes


@pytest.fixture(scope="session")
def canopen_emu_session(request: pytest.FixtureRequest, canopen_emu_session_nodes: List[str]) -> Iterator[Emulator]:
    """One emulator for the whole session, shared by the tests that use it (they see each other's changes)."""
    settings = request.config.stash[SETTINGS]
    emu = Emulator(settings.buses, canopen_emu_session_nodes, executable=settings.executable, web=settings.web)
    request.config.stash[SESSION_EMULATOR] = emu
    announce_web(request.config, emu)
    yield emu
    asked = emu.stop_requested
    status = emu.stop()
    del request.config.stash[SESSION_EMULATOR]
    if status != 0 and not asked:
        pytest.fail(f"canopen-emu ({' '.join(emu.node_args)}) of the session ended by itself with status "
                    f"{status}:\n{emu.describe(settings.log_lines)}", pytrace=False)


@pytest.fixture(scope="session")
def canopen_emu_bus(pytestconfig: pytest.Config) -> Bus:
    """The emulators' (first) bus, as --canopen-emu-bus chose it: its ``kind``, ``name`` and ``can_kwargs()``
    (``can.Bus(**canopen_emu_bus.can_kwargs())`` joins it with python-can)."""
    return pytestconfig.stash[SETTINGS].buses[0]


@pytest.fixture
def canopen_emu_network(request: pytest.FixtureRequest, canopen_emu_bus: Bus) -> Iterator[Any]:
    """A python-canopen ``Network`` connected to the emulators' bus, whatever its kind (vcan0, the session's
    udp_multicast group...), disconnected at the end of the test: hand it to the master under test. Needs the
    ``canopen`` package (and ``msgpack`` for udp_multicast: ``pip install canopen-emu[udp]``). A bus served by
    socketcand is inside one emulator: the test's ``canopen_emu`` (else ``canopen_emu_session``), started first."""
    try:
        if canopen_emu_bus.socketcand is not None:
            emulator = next((request.getfixturevalue(name) for name in ("canopen_emu", "canopen_emu_session")
                             if name in request.fixturenames), None)
            if emulator is None:
                raise ValueError(f"{canopen_emu_bus.label} is inside each emulator: a test that starts its own with "
                                 "canopen_emu_factory joins it with emulator.network()")
            net = emulator.network()
        else:
            net = canopen_emu_bus.network()
    except (ImportError, ValueError, OSError) as e:
        pytest.fail(f"canopen_emu_network: {e}", pytrace=False)
    yield net
    net.disconnect()


def announce_web(config: pytest.Config, emu: Emulator) -> None:
    """With --canopen-emu-web: the address of the emulator's live view on the terminal, as it starts."""
    if "--web" not in emu.args:
        return
    line = f"canopen-emu ({' '.join(emu.node_args)}): live view at {emu.web_url()}"
    reporter = config.pluginmanager.get_plugin("terminalreporter")
    capture = config.pluginmanager.get_plugin("capturemanager")
    if reporter is None:
        return
    if capture is None:
        reporter.write_line(line)
        return
    with capture.global_and_fixture_disabled():  # a fixture's output is captured: this line is for the user now
        reporter.write_line(line)


def format_events(events: List[Event]) -> str:
    """Events one a line: the emulator's time in seconds, then the event as it came."""
    return "\n".join(f"{int(ev.get('time_us', 0)) / 1e6:12.6f}  {json.dumps(ev, separators=(',', ':'))}"
                     for ev in events)


def emulators_of(item: pytest.Item) -> List[Emulator]:
    """The emulators a test used: the session's (if it asked for it), then those it started."""
    used: List[Emulator] = []
    session = item.config.stash.get(SESSION_EMULATOR, None)
    if session is not None and "canopen_emu_session" in getattr(item, "fixturenames", ()):
        used.append(session)
    started: List[Emulator] = item.stash.get(EMULATORS, [])
    used.extend(started)
    return used


@pytest.hookimpl(hookwrapper=True)
def pytest_runtest_makereport(item: pytest.Item, call: "pytest.CallInfo[None]") -> Generator[None, Any, None]:
    """A failed test's report shows each emulator it used (the last three: a test may restart many): its state
    and the end of its log, and the last events its clients received. A CI run is seen only through its output,
    and a frame that never came is explained by what the emulator did meanwhile."""
    outcome = yield
    report = outcome.get_result()
    if not report.failed:
        return
    settings = item.config.stash[SETTINGS]
    used = emulators_of(item)
    for number, emu in list(enumerate(used, 1))[-3:]:
        emu.flush_log()  # the lines of what the test saw last may still be on their way to the file
        title = f"canopen-emu #{number} of {len(used)}"
        report.sections.append((f"{title}: log", emu.describe(settings.log_lines)))
        events = emu.recent_events[-settings.event_lines:] if settings.event_lines > 0 else []
        report.sections.append((f"{title}: last {len(events)} event(s) its clients received",
                                format_events(events) if events else "(none: no subscription, or nothing came)"))
