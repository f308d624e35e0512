"""The control sockets' guards against what is not a control client (docs/control-protocol.md, "Who may connect",
and docs/robustness.md): a browser's HTTP request on a control socket runs nothing, a TCP socket with a token takes
nothing before it, refusals are logged at a bounded rate, and an answer of megabytes is streamed to a client that
reads it, whatever its size. canopen-emu-fakecan (no CAN needed), also under ASan+UBSan."""
import json
import re
import socket
import threading
import time

import pytest

from test_emulator_native import SANITIZER_MARKS, start_program

TOKEN = "s3cret-T0ken-of-the-test-0123456789"
HTTP_REFUSED = "closed: its first line is an HTTP request: a control socket takes control lines only"


class Program:
    """canopen-emu-fakecan with args; its log read as it comes."""

    def __init__(self, tmp_path, *args, accept=True):
        self.tmp_path = tmp_path
        self.bus, self.proc = start_program(tmp_path, "--nvm-dir", str(tmp_path / "nvm"), *args)
        self.err_lines = []
        self.readers = [threading.Thread(target=lambda: self.err_lines.extend(self.proc.stderr), daemon=True),
                        threading.Thread(target=lambda: [None for _ in self.proc.stdout], daemon=True)]
        for reader in self.readers:
            reader.start()
        if accept:
            self.bus.accept()

    def exit_status(self, timeout=20):
        """The program's exit status once it has ended and all it wrote has been read (the readers are threads:
        without the join, the log of a program that has just exited may still be on its way)."""
        status = self.proc.wait(timeout=timeout)
        for reader in self.readers:
            reader.join(timeout=timeout)
        return status

    def log(self):
        return "".join(self.err_lines)

    def wait_log(self, pattern, timeout=10.0):
        end = time.monotonic() + timeout
        while time.monotonic() < end:
            for line in list(self.err_lines):
                m = re.search(pattern, line)
                if m:
                    return m
            if self.proc.poll() is not None:
                break
            time.sleep(0.02)
        raise AssertionError(f"no log line matching {pattern!r}; status {self.proc.poll()}; log:\n{self.log()[-4000:]}")

    def tcp_port(self):
        return int(self.wait_log(r"control: listening on tcp 127\.0\.0\.1:(\d+)").group(1))

    def quit(self):
        try:
            self.proc.stdin.write("quit\n")
            self.proc.stdin.flush()
            self.exit_status()
        finally:
            if self.proc.poll() is None:
                self.proc.kill()
                self.exit_status()
            self.bus.close() if hasattr(self.bus, "close") else None
        log = self.log()
        assert not any(mark in log for mark in SANITIZER_MARKS), log[-6000:]
        assert self.proc.returncode == 0, log[-3000:]
        return log


def connect(address):
    if isinstance(address, int):
        return socket.create_connection(("127.0.0.1", address), timeout=10)
    s = socket.socket(socket.AF_UNIX)
    s.settimeout(10)
    s.connect(str(address))
    return s


def read_until_closed(s, limit=1 << 20):
    got = b""
    while len(got) < limit:
        piece = s.recv(65536)
        if not piece:
            return got
        got += piece
    raise AssertionError(f"still open after {len(got)} bytes")


def ask(address, *lines):
    """Sends lines on a connection of its own, returns the answer lines (one per line sent)."""
    with connect(address) as s:
        s.sendall("".join(line + "\n" for line in lines).encode())
        s.shutdown(socket.SHUT_WR)
        return read_until_closed(s).decode().splitlines()


@pytest.fixture
def sockets(tmp_path):
    ctl = tmp_path / "ctl.sock"
    program = Program(tmp_path, "--control-socket", str(ctl), "--control-tcp", "127.0.0.1:0", "sds:17")
    program.ctl = ctl
    program.port = program.tcp_port()
    yield program
    program.quit()


def heartbeat_time(address):
    answer = json.loads(ask(address, '{"id":1,"cmd":"get","node":17,"object":"0x1017"}')[0])
    assert answer["ok"] is True, answer
    return answer["value"]


def test_an_http_request_runs_nothing_on_either_socket(sockets):
    """A browser's "simple" cross-origin POST (text/plain, no preflight) from any page: its header lines and its
    body, control lines of the page's choosing, reach the port. The connection is closed at its first line, with no
    answer; nothing of it runs (0x1017 stays, the emulator goes on after the body's `quit`)."""
    before = heartbeat_time(sockets.ctl)
    body = ('set 17 0x1017 1234\n{"cmd":"set","node":17,"object":"0x1017","value":999}\n'
            '{"cmd":"emcy","node":17,"args":["0x3210",5]}\nquit\n')
    for address in (sockets.port, sockets.ctl):
        with connect(address) as s:
            s.sendall(f"POST /x HTTP/1.1\r\nHost: 127.0.0.1\r\nOrigin: https://evil.example\r\n"
                      f"Content-Type: text/plain\r\nContent-Length: {len(body)}\r\n\r\n{body}".encode())
            assert read_until_closed(s) == b""  # closed, not one byte of answer
    time.sleep(0.3)
    assert sockets.proc.poll() is None
    assert heartbeat_time(sockets.port) == before
    assert "EMCY" not in sockets.log()
    sockets.wait_log(r"control: client \d+ \(tcp\) " + re.escape(HTTP_REFUSED))
    sockets.wait_log(r"control: client \d+ \(unix\) " + re.escape(HTTP_REFUSED))
    # the same words later in a session are only a line the command language does not know: no refusal
    answer = ask(sockets.ctl, "list", "GET / HTTP/1.1")
    assert answer[1].startswith("error: ") and len(answer) == 2, answer


def test_http_like_first_lines_that_are_not_requests_run(sockets):
    """Only a request line (METHOD SP TARGET SP HTTP/x) is refused: a control line is never one."""
    assert ask(sockets.ctl, "list HTTP/1.1")[0].startswith("node 17: ")
    assert json.loads(ask(sockets.port, '{"id":"GET / HTTP/1.1","cmd":"hello"}')[0])["ok"] is True
    assert HTTP_REFUSED not in sockets.log()


def test_refusals_are_logged_at_a_bounded_rate(sockets):
    """40 HTTP connections from one looping client: 3 log lines, then the count once the 5 s window ended."""
    for _ in range(40):
        with connect(sockets.port) as s:
            s.sendall(b"GET / HTTP/1.1\r\nHost: 127.0.0.1\r\n\r\n")
            assert read_until_closed(s) == b""
    time.sleep(0.5)
    assert sockets.log().count(HTTP_REFUSED) == 3, sockets.log()[-3000:]
    time.sleep(5.0)
    heartbeat_time(sockets.ctl)  # a pass of the loop after the window
    sockets.wait_log(r"37 more refused or closed control connections in 5 s \(not shown one by one\)")


def test_too_many_clients_are_refused_with_a_bounded_log(sockets):
    held = [connect(sockets.ctl) for _ in range(64)]
    try:
        for _ in range(30):
            with connect(sockets.ctl) as s:
                answer = json.loads(read_until_closed(s))
                assert answer == {"id": None, "ok": False, "error": "too many control clients (at most 64)"}
        time.sleep(0.3)
        assert sockets.log().count("client refused: 64 are connected already") == 3
    finally:
        for s in held:
            s.close()


@pytest.fixture
def token_file(tmp_path):
    f = tmp_path / "token"
    f.write_text(TOKEN + "\n")
    f.chmod(0o600)
    return f


def test_a_tcp_socket_with_a_token_takes_nothing_before_it(tmp_path, token_file):
    ctl = tmp_path / "ctl.sock"
    program = Program(tmp_path, "--control-socket", str(ctl), "--control-tcp", "127.0.0.1:0",
                      "--control-token-file", str(token_file), "sds:17")
    try:
        port = int(program.wait_log(r"listening on tcp 127\.0\.0\.1:(\d+) \(clients give the token first\)").group(1))
        before = heartbeat_time(ctl)  # the Unix socket (mode 0600) needs none
        needs = ("this control connection needs the token first: hello TOKEN, or "
                 '{"cmd":"hello","token":"TOKEN"} (the token of --control-token-file)')
        # no token: the first line is answered with the refusal, nothing more runs, the connection ends
        assert ask(port, "set 17 0x1017 1234", "set 17 0x1017 4321") == [f"error: {needs}"]
        assert ask(port, '{"id":1,"cmd":"set","node":17,"object":"0x1017","value":999}') == [
            json.dumps({"id": None, "ok": False, "error": needs}, separators=(",", ":"))]
        assert ask(port, "hello wrong-token-0123456789", "set 17 0x1017 1234") == [f"error: {needs}"]
        assert ask(port, '{"id":1,"cmd":"hello","token":"' + TOKEN[:-1] + '"}', "list") == [
            json.dumps({"id": None, "ok": False, "error": needs}, separators=(",", ":"))]
        assert heartbeat_time(ctl) == before
        program.wait_log(r"control: client \d+ \(tcp\) closed: it did not give the token first")
        # with it, in either framing
        text = ask(port, f"hello {TOKEN}", "set 17 0x1017 2000")
        assert text[0] == "hello: authenticated" and len(text) == 2, text
        assert heartbeat_time(ctl) == 2000
        answers = [json.loads(line) for line in ask(port, json.dumps({"id": 1, "cmd": "hello", "token": TOKEN}),
                                                     '{"id":2,"cmd":"set","node":17,"object":"0x1017","value":3000}')]
        assert answers[0]["ok"] is True and answers[0]["program"] == "canopen-emu" and answers[1]["ok"] is True
        assert heartbeat_time(ctl) == 3000
    finally:
        log = program.quit()
    assert TOKEN not in log  # the token is never logged


def test_a_remote_tcp_socket_needs_a_token(tmp_path, token_file):
    program = Program(tmp_path, "--control-tcp", "0.0.0.0:0", "sds:17", accept=False)
    assert program.exit_status() == 1
    assert ("--control-tcp 0.0.0.0:" in program.log() and "is not a loopback address: give --control-token-file FILE"
            in program.log()), program.log()
    program = Program(tmp_path, "--control-tcp", "0.0.0.0:0", "--control-token-file", str(token_file), "sds:17")
    program.wait_log(r"control: warning: tcp 0\.0\.0\.0:\d+ is not a loopback address: whoever has the token controls")
    program.quit()


@pytest.mark.parametrize("content, why", [
    ("short\n", "the token must be one line of 16 to 256 printable characters without spaces"),
    ("a token with spaces in it\n", "the token must be one line of 16 to 256 printable characters without spaces"),
    ("x" * 300, "the token must be one line of 16 to 256 printable characters without spaces"),
    (None, "No such file or directory"),
])
def test_a_bad_token_file_stops_the_start(tmp_path, content, why):
    f = tmp_path / "token"
    if content is not None:
        f.write_text(content)
    program = Program(tmp_path, "--control-tcp", "127.0.0.1:0", "--control-token-file", str(f), "sds:17", accept=False)
    assert program.exit_status() == 1
    assert f"--control-token-file {f}: " in program.log() and why in program.log(), program.log()


def test_a_token_file_without_a_tcp_socket_is_an_error(tmp_path, token_file):
    program = Program(tmp_path, "--control-token-file", str(token_file), "sds:17", accept=False)
    assert program.exit_status() == 1
    assert "--control-token-file is the token of --control-tcp, which is not given" in program.log()


def big_eds(path, entries):
    """An EDS of the mandatory objects, a heartbeat of 100 ms and `entries` UNSIGNED32 parameters."""
    head = """[FileInfo]
FileName=big.eds
FileVersion=1
EDSVersion=4.0
[DeviceInfo]
VendorName=Test Vendor
VendorNumber=0x00000ABC
ProductName=Big Device
ProductNumber=0x00000002
RevisionNumber=0x00010000
BaudRate_125=1
Granularity=8
NrOfRXPDO=0
NrOfTXPDO=0
LSS_Supported=0
[MandatoryObjects]
SupportedObjects=3
1=0x1000
2=0x1001
3=0x1018
[1000]
ParameterName=Device type
ObjectType=0x7
DataType=0x0007
AccessType=ro
DefaultValue=0
[1001]
ParameterName=Error register
ObjectType=0x7
DataType=0x0005
AccessType=ro
DefaultValue=0
[1018]
ParameterName=Identity object
ObjectType=0x9
SubNumber=2
[1018sub0]
ParameterName=Highest sub-index supported
ObjectType=0x7
DataType=0x0005
AccessType=ro
DefaultValue=1
[1018sub1]
ParameterName=Vendor-ID
ObjectType=0x7
DataType=0x0007
AccessType=ro
DefaultValue=0x00000ABC
[OptionalObjects]
SupportedObjects=1
1=0x1017
[1017]
ParameterName=Producer heartbeat time
ObjectType=0x7
DataType=0x0006
AccessType=rw
DefaultValue=100
"""
    lines = [head, f"[ManufacturerObjects]\nSupportedObjects={entries}\n"]
    lines += [f"{k + 1}=0x{0x2000 + k:04X}\n" for k in range(entries)]
    for k in range(entries):
        lines.append(f"[{0x2000 + k:04X}]\nParameterName=Parameter number {k} of the big device\nObjectType=0x7\n"
                     f"DataType=0x0007\nAccessType=rw\nDefaultValue={k}\n")
    path.write_text("".join(lines))
    return entries + 5  # rows: 0x1000, 0x1001, 0x1018 (2 subs), 0x1017, and the parameters


def test_an_answer_of_megabytes_is_streamed_to_a_slow_reader(tmp_path):
    """`objects` of a device of 12,000 entries is some 2 MB with values: more than a client may leave unread
    (1 MiB), and it is no reason to disconnect one that reads, however slowly. The line comes whole and is the same
    as the one stdin gets at once (the same code builds both); events meanwhile follow it."""
    eds = tmp_path / "big.eds"
    rows = big_eds(eds, 12000)
    ctl = tmp_path / "ctl.sock"
    program = Program(tmp_path, "--control-socket", str(ctl), f"{eds}:5", "sds:17")
    try:
        program.wait_log(r"control: listening on unix")
        with connect(ctl) as s:
            s.sendall(b'{"id":1,"cmd":"subscribe","events":["nmt"]}\n{"id":2,"cmd":"objects","node":5,"values":true}\n'
                      b'{"id":3,"cmd":"hello"}\n')
            got = b""
            time.sleep(0.5)  # its answer waits unread meanwhile: no disconnection
            program.bus.send(0x000, bytes([0x81, 17]))  # a reset of node 17 while the answer is being written
            while got.count(b"\n") < 4:
                piece = s.recv(8192)
                assert piece, "closed"
                got += piece
                time.sleep(0.0005)
        lines = got.split(b"\n")
        assert json.loads(lines[0])["id"] == 1
        answer = json.loads(lines[1])
        assert len(lines[1]) > 1024 * 1024
        assert answer["id"] == 2 and answer["ok"] is True and answer["node"] == 5 and len(answer["objects"]) == rows
        assert answer["objects"][-1]["object"] == "0x4EDF:00" and answer["objects"][-1]["value"] == 11999
        rest = [json.loads(line) for line in lines[2:] if line]
        assert rest[0]["event"] == "nmt" and rest[0]["node"] == 17, rest  # held during the stream, right after it
        assert rest[1]["id"] == 3  # the next line ran after the stream: lines run in order
        assert "disconnected" not in program.log()
    finally:
        program.quit()
