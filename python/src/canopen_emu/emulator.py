"""The launcher: starts canopen-emu with a control socket of its own, waits until every node has booted, hands
out connected clients, keeps the log, and stops it again (quit, then SIGTERM, then SIGKILL)."""
from __future__ import annotations

import os
import shutil
import subprocess
import tempfile
import time
import weakref
from pathlib import Path
from typing import Any, List, Optional, Sequence, Tuple, Union

from .buses import NOTIFIER_CYCLE_S, Bus
from .client import Client, Event, connect
from .errors import CanopenEmuError, ConnectionClosed, ControlTimeout, EmulatorError

#: The nodes an Emulator runs when none are named.
DEFAULT_NODES = ("sds:16", "buerkert:17")
#: The variable naming the canopen-emu program when none is given.
EXECUTABLE_VARIABLE = "CANOPEN_EMU"

PathLike = Union[str, "os.PathLike[str]"]


def find_executable(executable: Optional[PathLike] = None) -> str:
    """The canopen-emu program to run: ``executable`` if given, else ``$CANOPEN_EMU``, else ``canopen-emu`` on
    PATH. A name without a slash is looked up on PATH."""
    candidate = os.fspath(executable) if executable is not None else os.environ.get(EXECUTABLE_VARIABLE) or ""
    if not candidate:
        found = shutil.which("canopen-emu")
        if found is None:
            raise EmulatorError(f"canopen-emu not found: pass executable=..., set ${EXECUTABLE_VARIABLE}, or put "
                                "canopen-emu on PATH")
        return found
    if os.sep not in candidate:
        found = shutil.which(candidate)
        if found is None:
            raise EmulatorError(f"{candidate!r} is not a program on PATH")
        return found
    if not (os.path.isfile(candidate) and os.access(candidate, os.X_OK)):
        raise EmulatorError(f"{candidate} is not an executable file")
    return candidate


def _cleanup(proc: "subprocess.Popen[bytes]", workdir: str) -> None:
    # An Emulator dropped without stop() (or a test run interrupted): no process and no directory stay behind.
    if proc.poll() is None:
        proc.kill()
        proc.wait()
    shutil.rmtree(workdir, ignore_errors=True)


class Emulator:
    """canopen-emu running the given nodes, started by the constructor and ready when it returns.

    ``interface``: one bus or several, as canopen-emu's ``-i`` names them (``"vcan0"``, ``["vcan0", "vcan1"]``,
    ``"udp_multicast:239.74.163.2:43113"``, ``"virtual:plant"``, docs/buses.md) or as Bus objects (``choose_bus()``);
    nodes go to the first unless named ``DEVICE:ID@BUS``. ``nodes``: the emulator's device arguments (``"sds:16"``,
    ``"pro-ionizer/efield:0x20"``). ``nvm_dir``: where stored parameters live (default: a fresh directory, removed
    by stop()). ``executable``: default ``$CANOPEN_EMU``, else ``canopen-emu`` on PATH. ``extra_args``: more options
    (``["-v"]``). ``web``:
    ``HOST:PORT`` of the live view in the browser (``--web``; ``"127.0.0.1:0"`` takes a free port), its address then
    from ``web_url()``. ``socketcand``: ``HOST:PORT`` where it serves its buses over socketcand (``--socketcand``;
    port 0: a free one, from ``socketcand_address()``); a Bus of socketcand_bus() asks for it too.

    The constructor returns once the control socket answers ``hello`` with protocol 1 and ``list`` shows every node
    out of INITIALISING (the boot-up sent); it raises EmulatorError, with the log, when that does not happen
    within ``start_timeout`` seconds or the program exits. ``client`` is then a connected Client."""

    def __init__(self, interface: Union[str, Bus, Sequence[Union[str, Bus]]] = "vcan0",
                 nodes: Sequence[str] = DEFAULT_NODES,
                 nvm_dir: Optional[PathLike] = None, executable: Optional[PathLike] = None,
                 extra_args: Sequence[str] = (), *, start_timeout: float = 10.0, client_timeout: float = 5.0,
                 wait_boot: bool = True, web: Optional[str] = None, socketcand: Optional[str] = None) -> None:
        given = [interface] if isinstance(interface, (str, Bus)) else list(interface)
        # canopen-emu's -i texts: a Bus (choose_bus()) gives its spec
        self.interfaces: List[str] = [str(i) for i in given]
        self._given_buses = {str(i): i for i in given if isinstance(i, Bus)}
        served = {b.socketcand for b in self._given_buses.values() if b.socketcand is not None} | (
            {socketcand} if socketcand is not None else set())
        if len(served) > 1:
            raise ValueError(f"an emulator serves socketcand at one address, not at {', '.join(sorted(served))}")
        self.socketcand: Optional[str] = served.pop() if served else None
        self.node_args: List[str] = [nodes] if isinstance(nodes, str) else list(nodes)
        if not self.interfaces:
            raise ValueError("an emulator needs at least one interface")
        if not self.node_args:
            raise ValueError("an emulator needs at least one node (\"sds:16\")")
        self.executable = find_executable(executable)
        self.client_timeout = client_timeout
        # A directory of its own for the socket and the log: short (a Unix socket path holds 107 bytes, a pytest
        # tmp_path can be longer) and private.
        self.workdir = Path(tempfile.mkdtemp(prefix="canopen-emu-"))
        self.socket_path = self.workdir / "ctl.sock"
        self.log_path = self.workdir / "emulator.log"
        self.nvm_dir = Path(nvm_dir) if nvm_dir is not None else self.workdir / "nvm"
        self.args: List[str] = [self.executable]
        for name in self.interfaces:
            self.args += ["-i", name]
        self.args += ["--nvm-dir", str(self.nvm_dir), "--control-socket", str(self.socket_path),
                      *(["--web", web] if web is not None else []),
                      *(["--socketcand", self.socketcand] if self.socketcand is not None else []),
                      *extra_args, *self.node_args]
        self.stop_requested = False  # stop() was called (by the test, not found dead at the end)
        self._clients: List[Client] = []
        self._networks: List[Any] = []  # python-canopen Networks of network(), disconnected by stop()
        self._status: Optional[int] = None
        self._final_log: Optional[str] = None
        try:
            with open(self.log_path, "ab") as log:
                # stdout too: with a socket no reply goes there, but --help, --version and usage errors do.
                self.proc = subprocess.Popen(self.args, stdin=subprocess.DEVNULL, stdout=log,
                                             stderr=subprocess.STDOUT)
        except OSError as e:
            shutil.rmtree(self.workdir, ignore_errors=True)
            raise EmulatorError(f"cannot run {self.executable}: {e}") from e
        self._finalizer = weakref.finalize(self, _cleanup, self.proc, str(self.workdir))
        try:
            self.client = self._wait_ready(start_timeout, wait_boot)
        except BaseException:
            self._finish(kill=True)
            raise

    # --- start ------------------------------------------------------------------------------------------------

    def _wait_ready(self, start_timeout: float, wait_boot: bool) -> Client:
        deadline = time.monotonic() + start_timeout
        client = None
        while client is None:
            status = self.proc.poll()
            if status is not None:
                raise EmulatorError(f"canopen-emu exited with status {status} before its control socket answered; "
                                    f"{self._log_report()}", status, self.log_text())
            if self.socket_path.exists():
                try:
                    client = connect(self.socket_path, timeout=self.client_timeout)
                except (ConnectionRefusedError, FileNotFoundError, ConnectionClosed):
                    # The file is there, the listen() not yet; or the program is ending (it opens the socket
                    # before it looks at the interfaces): the next look at its status says.
                    client = None
            if client is None:
                if time.monotonic() > deadline:
                    raise EmulatorError(f"canopen-emu did not open its control socket within {start_timeout} s; "
                                        f"{self._log_report()}", None, self.log_text())
                time.sleep(0.01)  # a socket file appearing gives nothing to wait on: look again shortly
        self._clients.append(client)
        if wait_boot:
            try:
                self._wait_boot(client, deadline, start_timeout)
            except ConnectionClosed as e:
                try:
                    ended: Optional[int] = self.proc.wait(1.0)
                except subprocess.TimeoutExpired:
                    ended = None
                raise EmulatorError(f"canopen-emu closed its control socket while starting (status {ended}); "
                                    f"{self._log_report()}", ended, self.log_text()) from e
        return client

    def _wait_boot(self, client: Client, deadline: float, start_timeout: float) -> None:
        # Subscribed before looking, so a boot-up between the look and the wait wakes the wait.
        client.subscribe(["nmt"])
        while True:
            nodes = client.nodes()
            if len(nodes) != len(self.node_args):
                raise EmulatorError(f"canopen-emu runs {len(nodes)} node(s), not the {len(self.node_args)} asked for "
                                    f"({' '.join(self.node_args)}); {self._log_report()}", None, self.log_text())
            booting = [n.node for n in nodes if n.state == "INITIALISING"]
            if not booting:
                break
            left = deadline - time.monotonic()
            if left <= 0:
                raise EmulatorError(f"node(s) {booting} still INITIALISING {start_timeout} s after the start; "
                                    f"{self._log_report()}", None, self.log_text())
            try:
                client.wait_for("nmt", timeout=left, from_="INITIALISING")
            except ControlTimeout:
                pass  # looked at again above, and reported there
        client.unsubscribe(["nmt"])
        client.drain_events()  # the boot's own events: the test has not asked for any yet

    # --- while it runs ----------------------------------------------------------------------------------------

    @property
    def pid(self) -> int:
        return self.proc.pid

    @property
    def running(self) -> bool:
        return self.proc.poll() is None

    @property
    def returncode(self) -> Optional[int]:
        """The exit status once it has exited (negative: killed by that signal), else None."""
        return self.proc.poll()

    @property
    def clients(self) -> List[Client]:
        """``client`` and every client made by connect()."""
        return list(self._clients)

    def connect(self, timeout: Optional[float] = None) -> Client:
        """Another connection to this emulator (a session of its own: its own subscriptions and events)."""
        client = connect(self.socket_path, timeout=self.client_timeout if timeout is None else timeout)
        self._clients.append(client)
        return client

    @property
    def buses(self) -> List[Bus]:
        """The buses as given (``interface``), each with its kind and the emulator's name of it (canopen_emu.Bus)."""
        return [self._given_buses.get(name) or Bus.parse(name) for name in self.interfaces]

    def network(self, bus: Union[None, str, Bus] = None) -> Any:
        """A python-canopen ``Network`` connected to a bus of this emulator (default: its first; or one of
        ``buses`` by its name or ``-i`` text), disconnected by stop(): the master's side of the test, on whatever
        kind of bus the emulator runs (``Bus.can_kwargs()``); a virtual bus through the emulator's socketcand server
        (python-can's ``socketcand`` interface). Needs the ``canopen`` package, and for udp_multicast ``msgpack``
        (``pip install canopen-emu[udp]``)."""
        buses = self.buses
        if bus is None:
            chosen = buses[0]
        else:
            wanted = bus.name if isinstance(bus, Bus) else str(bus)
            found = [b for b in buses if wanted in (b.name, b.spec)]
            if not found:
                raise ValueError(f"{wanted!r} is not a bus of this emulator ({', '.join(b.name for b in buses)})")
            chosen = found[0]
        if chosen.kind == "virtual" and self.socketcand is not None:
            try:
                import canopen  # not a dependency of this package: only a test with a master needs it
            except ImportError as e:
                raise ImportError("a python-canopen Network needs the canopen package: pip install canopen") from e
            host, port = self.socketcand_address()
            net = canopen.Network()
            net.NOTIFIER_CYCLE = NOTIFIER_CYCLE_S
            net.connect(interface="socketcand", channel=chosen.name, host=host, port=port)
        else:
            net = chosen.network()
        self._networks.append(net)
        return net

    def socketcand_address(self, timeout: float = 5.0) -> Tuple[str, int]:
        """(host, port) of its socketcand server as the log says it (``socketcand=``; port 0 replaced by the port
        it got)."""
        if self.socketcand is None:
            raise ValueError("this emulator was started without socketcand (socketcand=\"127.0.0.1:0\")")
        line = self.wait_log("socketcand: listening on ", timeout)
        address = line.split("socketcand: listening on ", 1)[1].split(": ", 1)[0].strip()
        host, port = address.rsplit(":", 1)
        return host.strip("[]"), int(port)

    def log_text(self) -> str:
        """The log (stderr) so far, or all of it after stop()."""
        if self._final_log is not None:
            return self._final_log
        try:
            return self.log_path.read_text(errors="replace")
        except FileNotFoundError:
            return ""

    def log_lines(self) -> List[str]:
        return self.log_text().splitlines()

    def flush_log(self, timeout: float = 1.0) -> None:
        """Makes sure the log file holds what the emulator did until now. Its log and its answers go out through
        buffers of their own, so a line can reach the file just after the event that goes with it reached a
        client; one round trip on a connection of its own lets it finish that pass of its loop. Nothing happens
        when it has stopped or does not answer within timeout."""
        if not self.running:
            return
        try:
            with connect(self.socket_path, timeout=timeout, check_protocol=False) as probe:
                probe.request("hello")
        except (CanopenEmuError, OSError):
            pass

    def wait_log(self, text: str, timeout: float = 5.0) -> str:
        """The first log line containing ``text``, waiting up to timeout seconds for it."""
        deadline = time.monotonic() + timeout
        while True:
            alive = self.running  # looked at before reading: an exited emulator's file is complete
            for line in self.log_lines():
                if text in line:
                    return line
            if not alive or time.monotonic() > deadline:
                raise ControlTimeout(f"no log line with {text!r} within {timeout} s; {self._log_report()}")
            time.sleep(0.02)  # a file gives nothing to wait on

    def tcp_address(self, timeout: float = 5.0) -> str:
        """``HOST:PORT`` of the ``--control-tcp`` socket (given in extra_args), as the log says it (port 0 is
        replaced by the port it got)."""
        if "--control-tcp" not in self.args:
            raise ValueError("this emulator was started without --control-tcp HOST:PORT")
        line = self.wait_log("control: listening on tcp ", timeout)
        return line.split("control: listening on tcp ", 1)[1].split()[0]  # "(clients give the token first)" after

    def web_url(self, timeout: float = 5.0) -> str:
        """The address of the live view (``http://127.0.0.1:8080/``) as the log says it (``--web``, from ``web=``
        or extra_args; port 0 replaced by the port it got)."""
        if "--web" not in self.args:
            raise ValueError("this emulator was started without the web view (web=\"127.0.0.1:8080\")")
        line = self.wait_log("web: listening on ", timeout)
        return line.split("web: listening on ", 1)[1].strip()

    @property
    def recent_events(self) -> List[Event]:
        """The last events its clients received, by the emulator's time."""
        events = [ev for c in self._clients for ev in c.recent_events]
        return sorted(events, key=lambda ev: int(ev.get("time_us", 0)))

    def describe(self, lines: int = 60) -> str:
        """For a failure report: the command line, whether it runs, and the end of its log."""
        log = self.log_lines()
        tail = log[-lines:] if lines > 0 else []
        head = f"log (last {len(tail)} of {len(log)} lines)" if len(tail) < len(log) else "log"
        status = self.returncode
        state = "running" if status is None else f"exited with status {status}"
        return "\n".join([" ".join(self.args), f"{state}; {head}:"] + tail)

    def _log_report(self, lines: int = 20) -> str:
        tail = self.log_lines()[-lines:]
        return "log:\n" + "\n".join(tail) if tail else "nothing logged"

    # --- stop -------------------------------------------------------------------------------------------------

    def stop(self, timeout: float = 5.0) -> int:
        """Stops it and returns its exit status (0 after a clean quit; negative: killed by that signal): ``quit``
        over the control socket, then SIGTERM, then SIGKILL, each given timeout seconds. Closes the clients and
        removes its directory; log_text() still works. A second call returns the same status."""
        self.stop_requested = True
        if self._status is None:
            if self.proc.poll() is None:
                try:
                    if not self._ask_to_quit(timeout):
                        raise subprocess.TimeoutExpired(self.args, 0)  # not asked: nothing to wait for
                    self.proc.wait(timeout)
                except subprocess.TimeoutExpired:
                    self.proc.terminate()
                    try:
                        self.proc.wait(timeout)
                    except subprocess.TimeoutExpired:
                        self.proc.kill()
                        self.proc.wait()
            self._finish(kill=False)
        assert self._status is not None
        return self._status

    def _ask_to_quit(self, timeout: float) -> bool:
        """Sends quit; False when it could not be sent or was not answered (the signals come next)."""
        try:
            client = next((c for c in self._clients if not c.closed), None)
            if client is None:
                client = connect(self.socket_path, timeout=timeout, check_protocol=False)
            client.quit(timeout=timeout)
            return True
        except (CanopenEmuError, OSError):
            return False

    def _finish(self, kill: bool) -> None:
        if kill and self.proc.poll() is None:
            self.proc.kill()
        self.proc.wait()
        for client in self._clients:
            client.close()
        for net in self._networks:
            if net.bus is not None:  # not disconnected by the test already
                net.disconnect()
        self._networks.clear()
        self._final_log = self.log_text()
        self._status = self.proc.returncode
        self._finalizer()  # removes the directory (the process has ended)

    def __enter__(self) -> "Emulator":
        return self

    def __exit__(self, *exc: object) -> None:
        self.stop()

    def __repr__(self) -> str:
        state = "running" if self._status is None and self.running else f"status {self.returncode}"
        return f"<canopen_emu.Emulator {' '.join(self.node_args)} on {','.join(self.interfaces)}, {state}>"
