"""What the udp tests share: the guard that they run in a network namespace of their own (netns-run), canopen-emu
started with a control socket, and a JSON control client.

Environment (tests/udp/CMakeLists.txt): CO_SOURCE_DIR, CO_EMU (the program), CO_UDP_DATAGRAM_TOOL."""
import json
import os
import socket
import subprocess
import time
from pathlib import Path

import pytest

SRC = Path(os.environ.get("CO_SOURCE_DIR") or Path(__file__).resolve().parents[2])
EMU = os.environ.get("CO_EMU", "")
GROUP = "239.74.163.2"                                # python-can's default IPv4 group and port
GROUP6 = "ff15:7079:7468:6f6e:6465:6d6f:6d63:6173"    # ... and IPv6 group
PORT = 43113


def require_own_namespace():
    """Fails unless lo is the only interface: multicast from these tests must never reach a real network."""
    names = [name for _, name in socket.if_nameindex()]
    if names != ["lo"]:
        pytest.fail(f"the udp tests run only inside their own network namespace (tests/udp/netns-run), "
                    f"not with interfaces {names}", pytrace=False)


class Control:
    """A JSON control connection to canopen-emu's --control-socket."""

    def __init__(self, path, timeout=5.0):
        self.sock = socket.socket(socket.AF_UNIX, socket.SOCK_STREAM)
        self.sock.settimeout(timeout)
        self.sock.connect(str(path))
        self.buf = b""
        self.events = []
        self.next_id = 1

    def line(self, timeout=5.0):
        end = time.monotonic() + timeout
        while b"\n" not in self.buf:
            left = end - time.monotonic()
            if left <= 0:
                raise AssertionError(f"no line within {timeout} s; have {self.buf[:200]!r}")
            self.sock.settimeout(left)
            try:
                chunk = self.sock.recv(65536)
            except socket.timeout:
                continue
            if not chunk:
                raise AssertionError("control connection closed")
            self.buf += chunk
        line, self.buf = self.buf.split(b"\n", 1)
        return json.loads(line)

    def request(self, cmd, **fields):
        req = {"id": self.next_id, "cmd": cmd, **fields}
        self.next_id += 1
        self.sock.sendall(json.dumps(req).encode() + b"\n")
        while True:
            msg = self.line()
            if "event" in msg:
                self.events.append(msg)
                continue
            assert msg.get("ok"), f"{req}: {msg}"
            return msg

    def event(self, kind, timeout=5.0, **match):
        end = time.monotonic() + timeout
        while True:
            while self.events:
                msg = self.events.pop(0)
                if msg.get("event") == kind and all(msg.get(k) == v for k, v in match.items()):
                    return msg
            left = end - time.monotonic()
            if left <= 0:
                raise AssertionError(f"no {kind} event {match} within {timeout} s")
            try:
                self.events.append(self.line(left))
            except AssertionError:
                continue

    def drain(self, seconds):
        """Every event that comes within `seconds`."""
        end = time.monotonic() + seconds
        while True:
            left = end - time.monotonic()
            if left <= 0:
                out, self.events = self.events, []
                return out
            try:
                self.events.append(self.line(left))
            except AssertionError:
                pass

    def close(self):
        self.sock.close()


class Emulator:
    """canopen-emu with a control socket and its own NVM directory; its log collected when it stops."""

    def __init__(self, tmp_path, *args, name="emu"):
        if not EMU:
            pytest.fail("CO_EMU is not set (the test is run by ctest: tests/udp/CMakeLists.txt)", pytrace=False)
        self.socket_path = tmp_path / f"{name}.sock"
        self.proc = subprocess.Popen([EMU, "--nvm-dir", str(tmp_path / f"{name}-nvm"), "--control-socket",
                                      str(self.socket_path), *args],
                                     stdin=subprocess.DEVNULL, stdout=subprocess.PIPE, stderr=subprocess.STDOUT,
                                     text=True)
        self.log = ""
        end = time.monotonic() + 10
        while not self.socket_path.exists():
            if self.proc.poll() is not None:
                raise AssertionError(f"canopen-emu ended with {self.proc.returncode}:\n{self.proc.stdout.read()}")
            assert time.monotonic() < end, "canopen-emu made no control socket within 10 s"
            time.sleep(0.02)
        while True:  # the file is there a moment before the socket listens
            try:
                self.control = Control(self.socket_path)
                break
            except ConnectionRefusedError:
                assert time.monotonic() < end, "canopen-emu's control socket took no connection within 10 s"
                time.sleep(0.02)

    def stop(self):
        """Stops it (SIGTERM) and returns its whole log; fails if it did not exit cleanly."""
        if self.proc.poll() is None:
            self.control.close()
            self.proc.terminate()
        try:
            self.log = self.proc.communicate(timeout=10)[0]
        except subprocess.TimeoutExpired:
            self.proc.kill()
            self.log = self.proc.communicate()[0]
            raise AssertionError("canopen-emu did not stop within 10 s:\n" + self.log)
        assert self.proc.returncode == 0, f"canopen-emu ended with {self.proc.returncode}:\n{self.log}"
        return self.log

    def kill(self):
        if self.proc.poll() is None:
            self.proc.kill()
            self.proc.communicate()
