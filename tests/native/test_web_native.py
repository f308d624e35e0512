"""The web view (--web HOST:PORT, docs/web.md) without a browser: the page and its files, the HTTP API's sessions
(a control session per browser: requests in, answers and events out), and the checks every request passes (Host,
token, method, path, size), against canopen-emu-fakecan (the whole program, its CAN channel a test double: see
test_emulator_native.py), in the plain and in the ASan+UBSan build.

Environment (tests/native/CMakeLists.txt): CO_SOURCE_DIR, CO_EMU_FAKECAN (the program), CO_SANITIZED.
"""

import http.client
import json
import re
import socket
import struct
import subprocess
import sys
import threading
import time

import pytest

from test_emulator_native import EMU, SANITIZER_MARKS, SRC, start_program, upload

sys.path.insert(0, str(SRC / "tests/support"))
from control_schema import check_schema  # noqa: E402

NODES = ("pro-ionizer:16", "sds:17")
CSP = "default-src 'self'; frame-ancestors 'none'"
PLACEHOLDER = b"@CANOPEN_EMU_TOKEN@"
REFUSED_QUIT = "quit is refused in a web session: it stops the emulator"
REFUSED_EXIT = "exit is refused in a web session: it stops the emulator"
REFUSED_EXPORT = "export-dcf is refused in a web session: it writes a file"
NO_SESSION = {"error": "no such session (expired or dropped): open a new one"}

class Answer:
    def __init__(self, status, headers, body):
        self.status, self.headers, self.body = status, headers, body

    def json(self):
        return json.loads(self.body)

    def lines(self):
        """An exchange's lines: JSON objects as dicts, the command language's text lines as strings."""
        text = self.body.decode()
        assert text == "" or text.endswith("\n"), text
        return [json.loads(line) if line.startswith("{") else line for line in text.splitlines()]


class WebEmulator:
    """canopen-emu-fakecan with --web (and --control - for the test's quit): its port from the log, as a user reads
    it; requests with a Host header and token of the test's choosing."""

    def __init__(self, tmp_path, web="127.0.0.1:0", nodes=NODES):
        self.bus, self.proc = start_program(tmp_path, "--nvm-dir", str(tmp_path / "nvm"), "--web", web, *nodes)
        self.err_lines, self.out_lines = [], []
        self.readers = [threading.Thread(target=lambda s=stream, l=lines: l.extend(s), daemon=True)
                        for stream, lines in ((self.proc.stderr, self.err_lines), (self.proc.stdout, self.out_lines))]
        for reader in self.readers:
            reader.start()
        self.bus.accept()
        line = self.wait_log("web: listening on http://")
        self.address, port = re.search(r"web: listening on http://(.+):(\d+)/$", line).groups()
        self.port = int(port)
        self._token = None

    def log(self):
        return "".join(self.err_lines)

    def wait_log(self, text, timeout=10.0):
        end = time.monotonic() + timeout
        while time.monotonic() < end:
            found = [line for line in list(self.err_lines) if text in line]
            if found:
                return found[0].rstrip("\n")
            if self.proc.poll() is not None:
                break
            time.sleep(0.02)
        raise AssertionError(f"no log line with {text!r}; status {self.proc.poll()}; log:\n{self.log()[-4000:]}")

    def request(self, method, path, body=None, headers=None, host=True, token=None, chunked=False):
        """One request on a connection of its own. host: True = 127.0.0.1:PORT, a string = that, None = no Host
        header. token: the X-Canopen-Emu header (None: none)."""
        conn = http.client.HTTPConnection("127.0.0.1", self.port, timeout=10)
        try:
            conn.putrequest(method, path, skip_host=True, skip_accept_encoding=True)
            if host is not None:
                conn.putheader("Host", f"127.0.0.1:{self.port}" if host is True else host)
            if token is not None:
                conn.putheader("X-Canopen-Emu", token)
            for name, value in (headers or {}).items():
                conn.putheader(name, value)
            if chunked:
                conn.putheader("Transfer-Encoding", "chunked")
            elif body is not None:
                conn.putheader("Content-Length", str(len(body)))
            conn.endheaders()
            if body is not None:
                if chunked:
                    for k in range(0, len(body), 4096):
                        piece = body[k:k + 4096]
                        conn.send(b"%x\r\n%s\r\n" % (len(piece), piece))
                    conn.send(b"0\r\n\r\n")
                else:
                    conn.send(body)
            resp = conn.getresponse()
            return Answer(resp.status, resp.headers, resp.read())
        finally:
            conn.close()

    def token(self):
        if self._token is None:
            page = self.request("GET", "/")
            assert page.status == 200, page.status
            self._token = re.search(rb'<meta name="canopen-emu-token" content="([0-9a-f]{32})">', page.body).group(1).decode()
        return self._token

    def open_session(self):
        answer = self.request("POST", "/api/session", token=self.token())
        assert answer.status == 200, (answer.status, answer.body)
        return answer.json()["session"]

    def exchange(self, session, *lines):
        body = "".join(line + "\n" for line in lines).encode()
        return self.request("POST", f"/api/session/{session}", body=body, token=self.token())

    def quit(self, timeout=20.0):
        """quit on stdin (a web session may not); returns the exit status; fails on any sanitizer report."""
        try:
            self.proc.stdin.write("quit\n")
            self.proc.stdin.flush()
            self.proc.wait(timeout=timeout)
        except (subprocess.TimeoutExpired, BrokenPipeError):
            self.proc.kill()
            self.proc.wait()
            raise AssertionError("canopen-emu did not end after quit:\n" + self.log()[-3000:])
        finally:
            self.bus.close()
        for reader in self.readers:  # the last lines, read once the program has ended
            reader.join(timeout=timeout)
        assert not any(mark in self.log() for mark in SANITIZER_MARKS), self.log()[-6000:]
        return self.proc.returncode


@pytest.fixture
def emu(tmp_path):
    e = WebEmulator(tmp_path)
    yield e
    if e.proc.poll() is None:
        assert e.quit() == 0, e.log()[-3000:]


def assert_security_headers(answer, api):
    assert answer.headers["Content-Security-Policy"] == CSP
    assert answer.headers["X-Content-Type-Options"] == "nosniff"
    assert answer.headers["Referrer-Policy"] == "no-referrer"
    if api:
        assert answer.headers["Cache-Control"] == "no-store"


def heartbeat_times(bus, node, count, timeout=5.0):
    return [bus.expect(lambda i, d: i == 0x700 + node and len(d) == 1, timeout, f"heartbeat of node {node}")[0]
            for _ in range(count)]


# ---- the page and its files -------------------------------------------------------------------------------------

def test_page_is_served_with_the_token_and_the_security_headers(emu):
    """/ and /index.html are web/index.html with this run's token in the placeholder's place; the other files are
    served byte for byte with their type and ETag (304 when the browser has them); every answer carries the CSP."""
    source = (SRC / "web/index.html").read_bytes()
    assert source.count(PLACEHOLDER) == 1
    for path in ("/", "/index.html", "/index.html?reload=1"):
        page = emu.request("GET", path)
        assert page.status == 200, (path, page.status)
        assert page.headers["Content-Type"] == "text/html; charset=utf-8"
        assert page.headers["Cache-Control"] == "no-store"
        assert_security_headers(page, api=False)
        token = re.search(rb'content="([0-9a-f]{32})"', page.body).group(1)
        assert page.body == source.replace(PLACEHOLDER, token)
        assert token.decode() == emu.token()
    files = [(name, "text/javascript; charset=utf-8") for name in ("app.js", "api.js", "format.js", "nodes.js",
                                                                    "overview.js")]
    for name, mime in files + [("style.css", "text/css; charset=utf-8"), ("icon.svg", "image/svg+xml")]:
        answer = emu.request("GET", "/" + name)
        assert answer.status == 200
        assert answer.headers["Content-Type"] == mime
        assert answer.body == (SRC / "web" / name).read_bytes()
        assert_security_headers(answer, api=False)
        etag = answer.headers["ETag"]
        assert re.fullmatch(r'"[0-9a-f]{16}"', etag), etag
        again = emu.request("GET", "/" + name, headers={"If-None-Match": etag})
        assert (again.status, again.body, again.headers["ETag"]) == (304, b"", etag)
        other = emu.request("GET", "/" + name, headers={"If-None-Match": '"0000000000000000"'})
        assert (other.status, other.body) == (200, answer.body)


def test_unknown_paths_are_404_and_nothing_is_read_from_disk(emu):
    for path in ("/nope", "/index.htm", "/INDEX.HTML", "/index.html/", "//index.html", "/web/index.html",
                 "/../etc/passwd", "/%2e%2e/etc/passwd", "/..%2f..%2fetc%2fpasswd", "/./index.html",
                 "/etc/passwd", "/CMakeLists.txt", "/package.json", "/api.mjs"):
        answer = emu.request("GET", path)
        assert (answer.status, answer.body) == (404, b"not found\n"), path
        assert answer.headers["Content-Type"] == "text/plain; charset=utf-8"
        assert_security_headers(answer, api=False)
    token = emu.token()
    for path in ("/api", "/api/", "/api/sessions", "/api/session/", "/api/session/xyz", "/api/session/" + "A" * 32,
                 "/api/session/" + "0" * 31, "/api/session/../session"):
        answer = emu.request("POST", path, body=b"", token=token)
        assert (answer.status, answer.json()) == (404, {"error": "no such API path"}), path
        assert_security_headers(answer, api=True)
    answer = emu.request("POST", "/api/session/" + "0" * 32, body=b"", token=token)
    assert (answer.status, answer.json()) == (404, NO_SESSION)


def test_only_get_for_files_and_post_for_the_api(emu):
    token = emu.token()
    session = emu.open_session()
    for method, path in (("POST", "/"), ("PUT", "/index.html"), ("DELETE", "/app.js"), ("HEAD", "/")):
        answer = emu.request(method, path, body=b"" if method in ("POST", "PUT") else None)
        body = b"" if method == "HEAD" else b"only GET\n"  # a HEAD answer has no body
        assert (answer.status, answer.headers["Allow"], answer.body) == (405, "GET", body), (method, path)
    for method, path in (("GET", "/api/session"), ("GET", f"/api/session/{session}"), ("PUT", "/api/session"),
                         ("DELETE", f"/api/session/{session}")):
        answer = emu.request(method, path, token=token)
        assert (answer.status, answer.headers["Allow"]) == (405, "POST"), (method, path)
        assert answer.json() == {"error": "the API takes POST only"}
        assert_security_headers(answer, api=True)
    assert emu.exchange(session).status == 200  # the session is still there: DELETE removed nothing


# ---- the checks of every request -------------------------------------------------------------------------------

def test_host_header_must_name_this_server(emu):
    """Against DNS rebinding: a page of another site that makes its name point here sends its own name."""
    port = emu.port
    for host in (f"localhost:{port}", f"LocalHost:{port}", f"127.0.0.1:{port}", f"[::1]:{port}"):
        assert emu.request("GET", "/", host=host).status == 200, host
        assert emu.request("POST", "/api/session", host=host, token=emu.token()).status == 200, host
    for host in (f"evil.example:{port}", f"localhost.evil.example:{port}", f"127.0.0.1.nip.io:{port}",
                 f"localhost:{port + 1}", "localhost", f"localhost:{port}x", f"[::1]x:{port}", f":{port}", ""):
        answer = emu.request("GET", "/", host=host)
        assert (answer.status, answer.body) == (421, b"the Host header does not name this server\n"), host
        assert_security_headers(answer, api=False)
        api = emu.request("POST", "/api/session", host=host, token=emu.token())
        assert (api.status, api.json()) == (421, {"error": "the Host header does not name this server"}), host
    with socket.create_connection(("127.0.0.1", port), timeout=10) as raw:  # HTTP/1.0: no Host header at all
        raw.sendall(b"GET / HTTP/1.0\r\n\r\n")
        reply = b""
        while chunk := raw.recv(65536):
            reply += chunk
    assert reply.startswith(b"HTTP/1.0 421 ") or reply.startswith(b"HTTP/1.1 421 "), reply[:200]


def test_api_needs_the_token_of_the_page(emu):
    """Another site's page cannot send the custom header without a CORS preflight, which is never answered; a
    program that did not load the page has no token."""
    expected = {"error": "missing or wrong X-Canopen-Emu token: load the page again"}
    real = emu.token()
    for token in (None, "", "0" * 32, real[:-1], real + "0", real.upper(), real[:16], real + real):
        answer = emu.request("POST", "/api/session", token=token)
        assert (answer.status, answer.json()) == (403, expected), token
        assert_security_headers(answer, api=True)
    session = emu.open_session()
    answer = emu.request("POST", f"/api/session/{session}", body=b'{"id":1,"cmd":"hello"}\n', token="f" * 32)
    assert (answer.status, answer.json()) == (403, expected)
    assert emu.exchange(session).lines() == []  # the refused request did not run: nothing waits


# ---- sessions --------------------------------------------------------------------------------------------------

def test_session_round_trip_reaches_the_bus(emu):
    """hello, list and set in one exchange, answered in order; the set of 0x1017 changes node 16's heartbeat period
    on the bus and reads back over SDO and with get."""
    session_answer = emu.request("POST", "/api/session", token=emu.token())
    assert session_answer.status == 200
    assert session_answer.headers["Content-Type"] == "application/json"
    assert_security_headers(session_answer, api=True)
    session = session_answer.json()["session"]
    assert re.fullmatch(r"[0-9a-f]{32}", session), session
    before = heartbeat_times(emu.bus, 16, 3)
    assert 1.5 <= before[2] - before[0] <= 2.6, before  # the default: 1000 ms
    answer = emu.exchange(session, '{"id":1,"cmd":"hello"}', '{"id":2,"cmd":"list"}',
                          '{"id":3,"cmd":"set","node":16,"object":"0x1017","value":500}')
    assert answer.status == 200
    assert answer.headers["Content-Type"] == "application/x-ndjson"
    assert_security_headers(answer, api=True)
    hello, nodes, written = answer.lines()
    for msg, cmd in ((hello, "hello"), (nodes, "list"), (written, "set")):
        check_schema(msg, cmd)
    assert (hello["id"], hello["ok"], hello["program"], hello["protocol"], hello["buses"], hello["bus_kinds"]) == \
        (1, True, "canopen-emu", 1, ["fakecan0"], {"fakecan0": "socketcan"})
    assert nodes == {"id": 2, "ok": True, "nodes": [
        {"node": 16, "device": "pro-ionizer", "variant": "full", "started_as": 16, "state": "PRE-OPERATIONAL",
         "bus": "fakecan0", "bus_kind": "socketcan"},
        {"node": 17, "device": "sds", "variant": "N", "started_as": 17, "state": "PRE-OPERATIONAL", "bus": "fakecan0",
         "bus_kind": "socketcan"}]}
    assert written == {"id": 3, "ok": True, "node": 16, "object": "0x1017:00", "value": 500, "type": "UNSIGNED16",
                       "name": "Producer heartbeat time"}
    emu.bus.expect(lambda i, d: i == 0x710, 3.0, "a first heartbeat after the set")
    after = heartbeat_times(emu.bus, 16, 3)
    assert 0.7 <= after[2] - after[0] <= 1.4, after  # two periods of 500 ms (the default would give 2 s)
    assert emu.bus.sdo(16, upload(0x1017, 0))[4:6] == struct.pack("<H", 500)
    got = emu.exchange(session, '{"id":4,"cmd":"get","node":16,"object":"0x1017"}', "get 16 0x1017").lines()
    check_schema(got[0], "get")
    assert got[0] == {"id": 4, "ok": True, "node": 16, "object": "0x1017:00", "value": 500, "type": "UNSIGNED16",
                      "name": "Producer heartbeat time"}
    assert got[1].startswith("node 16: 0x1017:00 = 500 "), got
    assert emu.exchange(session).lines() == []  # everything was delivered once


def test_subscribed_events_come_with_a_later_exchange(emu):
    """Events that happen between exchanges wait in the session and come with the next one, however it was caused:
    an NMT start from the bus; an EMCY a command raised comes with that command's answer or later."""
    session = emu.open_session()
    answer = emu.exchange(session, '{"id":1,"cmd":"subscribe","events":["nmt","emcy"],"nodes":[16]}').lines()
    assert answer == [{"id": 1, "ok": True, "events": ["nmt", "emcy"]}]
    emu.bus.send(0x000, bytes([0x01, 16]))  # NMT start node 16
    emu.bus.expect(lambda i, d: i == 0x710 and d == b"\x05", 5.0, "heartbeat of node 16 in Operational")
    events = emu.exchange(session).lines()
    for event in events:
        check_schema(event, None)
    assert [{k: e[k] for k in ("event", "node", "device", "bus", "from", "to")} for e in events] == [
        {"event": "nmt", "node": 16, "device": "pro-ionizer", "bus": "fakecan0", "from": "PRE-OPERATIONAL",
         "to": "OPERATIONAL"}]
    lines = emu.exchange(session, '{"id":2,"cmd":"emcy","node":16,"args":["0x3210","0x05"]}').lines()
    assert [m["ok"] for m in lines if m.get("id") == 2] == [True], lines
    _, _, frame = emu.bus.expect(lambda i, d: i == 0x090, 5.0, "EMCY of node 16")
    assert frame[:3] == bytes([0x10, 0x32, 0x05]), frame.hex()
    end = time.monotonic() + 5.0
    while not any(isinstance(m, dict) and m.get("event") == "emcy" for m in lines) and time.monotonic() < end:
        lines += emu.exchange(session).lines()
        time.sleep(0.05)
    emcy = [m for m in lines if isinstance(m, dict) and m.get("event") == "emcy"]
    assert len(emcy) == 1, lines
    check_schema(emcy[0], None)
    assert {k: emcy[0][k] for k in ("node", "device", "code", "register", "info")} == \
        {"node": 16, "device": "pro-ionizer", "code": 0x3210, "register": 0x05, "info": "0000000000"}
    emu.bus.send(0x000, bytes([0x01, 17]))  # node 17 is not subscribed to
    emu.bus.sdo(17, upload(0x1001, 0))  # answered after the NMT frame before it was handled
    assert emu.exchange(session).lines() == []


def test_show_answers_with_the_events_clock(emu):
    """show's time_us is the events' clock when it answered: after the event that came before it, and it advances
    as the host's clock does (a page tells the age of a heartbeat from it)."""
    session = emu.open_session()
    assert emu.exchange(session, '{"id":1,"cmd":"subscribe","events":["nmt"]}').lines()[0]["ok"] is True
    emu.bus.send(0x000, bytes([0x01, 16]))  # NMT start node 16
    emu.bus.expect(lambda i, d: i == 0x710 and d == b"\x05", 5.0, "heartbeat of node 16 in Operational")
    (event,) = emu.exchange(session).lines()
    first = emu.exchange(session, '{"id":2,"cmd":"show","node":16}').lines()[0]
    asked = time.monotonic()
    check_schema(first, "show")
    assert event["time_us"] <= first["time_us"] < event["time_us"] + 5_000_000, (event, first)
    assert first["nodes"][0]["last_heartbeat_us"] <= first["time_us"], first
    time.sleep(0.5)  # a span of the host's clock to compare with
    second = emu.exchange(session, '{"id":3,"cmd":"show","node":16}').lines()[0]
    span = time.monotonic() - asked
    assert 500_000 <= second["time_us"] - first["time_us"] <= span * 1e6 + 100_000, (first["time_us"], second, span)


def test_show_all_lists_the_nodes_heard_on_the_bus(emu):
    """show all has the other node-IDs heard on the bus (heartbeat, boot-up, guarding answer), not the emulated ones
    and not guard requests (RTR) or extended frames; one node's show has no list."""
    session = emu.open_session()
    emu.bus.send(0x705, b"\x05")  # node 5: heartbeat, Operational
    emu.bus.send(0x709, b"\x00")  # node 9: boot-up
    emu.bus.send(0x70A, b"\x84")  # node 10: guarding answer, toggle bit set, Stopped
    emu.bus.send(0x40000000 | 0x70B, b"")  # a guard request (RTR) to node 11: nothing heard from 11
    emu.bus.send(0x80000000 | 0x70C, b"\x05")  # an extended frame: not CANopen's heartbeat of node 12
    emu.bus.send(0x711, b"\x7f")  # node 17 is emulated here (a duplicate node-ID on the bus): not "heard"
    emu.bus.send(0x70D, b"\x03")  # node 13: a state byte no state has
    deadline = time.monotonic() + 5
    while True:
        answer = emu.exchange(session, '{"id":1,"cmd":"show","node":"all"}').lines()[0]
        if len(answer["heard"]) == 4 or time.monotonic() > deadline:
            break
        time.sleep(0.05)
    check_schema(answer, "show")
    heard = [(h["node"], h["bus"], h["state"], h["boot_up"]) for h in answer["heard"]]
    assert heard == [(5, "fakecan0", "OPERATIONAL", False), (9, "fakecan0", "PRE-OPERATIONAL", True),
                     (10, "fakecan0", "STOPPED", False), (13, "fakecan0", "UNKNOWN", False)], answer["heard"]
    assert all(0 < h["last_heartbeat_us"] <= answer["time_us"] for h in answer["heard"]), answer
    assert [n["node"] for n in answer["nodes"]] == [16, 17]
    emu.bus.send(0x709, b"\x05")  # node 9 started by its master: its state follows
    deadline = time.monotonic() + 5
    while True:
        later = emu.exchange(session, '{"id":2,"cmd":"show","node":"all@fakecan0"}').lines()[0]
        if later["heard"][1]["state"] == "OPERATIONAL" or time.monotonic() > deadline:
            break
        time.sleep(0.05)
    assert later["heard"][1] == {"node": 9, "bus": "fakecan0", "bus_kind": "socketcan", "state": "OPERATIONAL",
                                 "boot_up": False, "last_heartbeat_us": later["heard"][1]["last_heartbeat_us"]}, later["heard"]
    assert later["heard"][1]["last_heartbeat_us"] > answer["heard"][1]["last_heartbeat_us"]
    one = emu.exchange(session, '{"id":3,"cmd":"show","node":16}').lines()[0]
    check_schema(one, "show")
    assert "heard" not in one


def test_get_of_several_objects_answers_with_the_time_they_were_read(emu):
    """get with "objects" answers with time_us, the events' clock when it read them: after an event that came before
    it, advancing as the host's clock does (the plots put each sample at that time, whenever its answer arrives)."""
    session = emu.open_session()
    assert emu.exchange(session, '{"id":1,"cmd":"subscribe","events":["nmt"]}').lines()[0]["ok"] is True
    emu.bus.send(0x000, bytes([0x01, 16]))  # NMT start node 16
    emu.bus.expect(lambda i, d: i == 0x710 and d == b"\x05", 5.0, "heartbeat of node 16 in Operational")
    (event,) = emu.exchange(session).lines()
    ask = '{"id":%d,"cmd":"get","node":16,"objects":["0x6401:01","0x1017"]}'
    first = emu.exchange(session, ask % 2).lines()[0]
    asked = time.monotonic()
    check_schema(first, "get")
    assert [v["object"] for v in first["values"]] == ["0x6401:01", "0x1017:00"], first
    assert event["time_us"] <= first["time_us"] < event["time_us"] + 5_000_000, (event, first)
    time.sleep(0.5)
    second = emu.exchange(session, ask % 3).lines()[0]
    span = time.monotonic() - asked
    assert 500_000 <= second["time_us"] - first["time_us"] <= span * 1e6 + 100_000, (first["time_us"], second, span)


def test_quit_exit_and_export_dcf_are_refused_in_both_framings(emu, tmp_path):
    session = emu.open_session()
    dcf = tmp_path / "node16.dcf"
    answer = emu.exchange(session, "quit", "exit", f"export-dcf 16 {dcf}", '{"id":1,"cmd":"quit"}',
                          '{"id":2,"cmd":"exit"}', f'{{"id":3,"cmd":"export-dcf","node":16,"args":["{dcf}"]}}')
    assert answer.lines() == [
        f"error: {REFUSED_QUIT}", f"error: {REFUSED_EXIT}", f"error: {REFUSED_EXPORT}",
        {"id": 1, "ok": False, "error": REFUSED_QUIT}, {"id": 2, "ok": False, "error": REFUSED_EXIT},
        {"id": 3, "ok": False, "error": REFUSED_EXPORT}]
    assert not dcf.exists()
    time.sleep(0.3)
    assert emu.proc.poll() is None
    assert emu.exchange(session, '{"id":4,"cmd":"list"}').lines()[0]["ok"] is True


def test_at_most_eight_sessions(emu):
    sessions = [emu.open_session() for _ in range(8)]
    assert len(set(sessions)) == 8
    refused = emu.request("POST", "/api/session", token=emu.token())
    assert (refused.status, refused.json()) == (503, {"error": "too many web sessions (at most 8)"})
    assert_security_headers(refused, api=True)
    emu.wait_log("web: a session refused: 8 are open already")
    for k, session in enumerate(sessions):  # each one is its own: the answer goes to the session that asked
        assert emu.exchange(session, f'{{"id":{k},"cmd":"hello"}}').lines()[0]["id"] == k


def test_a_session_whose_browser_does_not_ask_pauses_and_loses_nothing(emu):
    """80 requests of ~25 kB answers each (2 MB): an exchange answers what it ran at once; the rest run only while
    less than a quarter of WEB_OUTPUT_MAX waits for the browser, so a browser that does not ask costs no work and
    is not dropped; the next exchanges bring every answer, whole, in order."""
    session = emu.open_session()
    request = '{"id":1,"cmd":"objects","node":16,"values":true}'
    first = emu.exchange(session, *[request] * 80)
    assert first.status == 200
    time.sleep(1.0)  # many passes of the main loop: the session runs until its output waits, then pauses
    second = emu.exchange(session)
    assert second.status == 200
    assert 256 * 1024 <= len(second.body) < 256 * 1024 + 64 * 1024, len(second.body)  # paused at the mark
    text = first.body + second.body
    for _ in range(200):
        if text.count(b"\n") == 80:
            break
        answer = emu.exchange(session)
        assert answer.status == 200
        text += answer.body
    lines = text.split(b"\n")
    assert lines[-1] == b"" and len(lines) == 81
    rows = [json.loads(line) for line in lines[:-1]]
    assert all(m["id"] == 1 and m["ok"] is True and m["node"] == 16 for m in rows)
    assert all(m["objects"] == rows[0]["objects"] or len(m["objects"]) == len(rows[0]["objects"]) for m in rows)
    assert "dropped" not in emu.log()


def test_a_session_overflowing_its_buffer_with_events_is_dropped(emu):
    """Events are not paused: a session subscribed to every frame whose browser does not ask for them is dropped
    once more than WEB_OUTPUT_MAX bytes wait (logged); a new one works."""
    session = emu.open_session()
    subscribed = emu.exchange(session, '{"id":1,"cmd":"subscribe","events":["frame"],"frames":"0x000/0x000"}')
    assert subscribed.lines()[0]["ok"] is True
    for k in range(30000):  # ~110 bytes of JSON event each
        emu.bus.send(0x7E0, k.to_bytes(4, "little"))
    emu.wait_log("web: web session 1 dropped: more than 1048576 bytes waited for its next exchange")
    gone = emu.exchange(session)
    assert (gone.status, gone.json()) == (404, NO_SESSION)
    assert emu.exchange(emu.open_session(), '{"id":2,"cmd":"hello"}').lines()[0]["id"] == 2


def test_body_limits(emu):
    session = emu.open_session()
    too_large = {"error": "a request body has at most 16384 bytes"}
    answer = emu.request("POST", f"/api/session/{session}", body=b"\n" * 16384, token=emu.token())
    assert (answer.status, answer.body) == (200, b"")  # 16384 empty lines: accepted, nothing to answer
    answer = emu.request("POST", f"/api/session/{session}", body=b"\n" * 16385, token=emu.token())
    assert (answer.status, answer.json()) == (413, too_large)
    assert_security_headers(answer, api=True)
    answer = emu.request("POST", f"/api/session/{session}", body=b"\n" * 20000, token=emu.token(), chunked=True)
    assert (answer.status, answer.json()) == (413, too_large)
    with socket.create_connection(("127.0.0.1", emu.port), timeout=10) as raw:  # announced, never sent
        raw.sendall(f"POST /api/session/{session} HTTP/1.1\r\nHost: 127.0.0.1:{emu.port}\r\n"
                    f"X-Canopen-Emu: {emu.token()}\r\nContent-Length: 1000000\r\n\r\n".encode())
        assert raw.recv(65536).startswith(b"HTTP/1.1 413 ")
    # The session is unharmed. Its hello waits behind what is left of the 16384 lines (512 bytes run a pass; on a
    # loaded machine the passes so far may not have run them all): its answer comes with this or a later exchange.
    lines = emu.exchange(session, '{"id":1,"cmd":"hello"}').lines()
    end = time.monotonic() + 5.0
    while not lines and time.monotonic() < end:
        time.sleep(0.02)
        lines = emu.exchange(session).lines()
    assert [(m["id"], m["ok"], m["program"]) for m in lines] == [(1, True, "canopen-emu")], lines


def test_a_session_without_exchange_for_10_s_is_removed(emu):
    kept, idle = emu.open_session(), emu.open_session()
    start = time.monotonic()
    while time.monotonic() - start < 8.0:
        assert emu.exchange(kept).status == 200
        time.sleep(1.0)
    assert "removed: no exchange" not in emu.log()
    while time.monotonic() - start < 11.0:
        assert emu.exchange(kept).status == 200
        time.sleep(1.0)
    emu.wait_log("web: web session 2 removed: no exchange for 10 s", timeout=2.0)
    assert "web session 1 removed" not in emu.log()
    gone = emu.exchange(idle, '{"id":1,"cmd":"hello"}')
    assert (gone.status, gone.json()) == (404, NO_SESSION)
    assert emu.exchange(kept, '{"id":2,"cmd":"hello"}').lines()[0]["id"] == 2


def test_quit_on_stdin_ends_the_program_at_once_on_a_quiet_bus(tmp_path):
    """A node whose heartbeat is off and a web session open: the loop's next deadline is the session's expiry, 10 s
    away. quit on stdin ended the program only then (the loop went back to sleep after taking the command); it must
    end it at once."""
    emu = WebEmulator(tmp_path, nodes=("buerkert:18",))
    emu.proc.stdin.write("set 18 0x1017 0\n")
    emu.proc.stdin.flush()
    end = time.monotonic() + 10.0
    while not any("0x1017" in line for line in list(emu.out_lines)):  # its answer: no heartbeat from now on
        assert time.monotonic() < end, emu.out_lines
        time.sleep(0.02)
    emu.open_session()
    time.sleep(0.5)  # the loop asleep, no frame or timer due before the session's expiry
    start = time.monotonic()
    assert emu.quit() == 0, emu.log()[-3000:]
    assert time.monotonic() - start < 3.0, emu.log()[-3000:]  # 10 s before the fix; a few ms after it


# ---- addresses ---------------------------------------------------------------------------------------------------

def test_loopback_is_not_warned_about(emu):
    assert emu.address == "127.0.0.1"
    assert "warning" not in emu.log()


def test_a_non_loopback_address_is_warned_about(tmp_path):
    emu = WebEmulator(tmp_path, web="0.0.0.0:0")
    try:
        assert emu.address == "0.0.0.0"
        emu.wait_log(f"web: warning: 0.0.0.0:{emu.port} is not a loopback address: anyone who reaches it can change "
                     "the devices (the page hands its token to whoever loads it)")
        assert emu.request("GET", "/", host=f"localhost:{emu.port}").status == 200
        assert emu.request("GET", "/", host=f"0.0.0.0:{emu.port}").status == 200  # the address named
        assert emu.request("GET", "/", host=f"evil.example:{emu.port}").status == 421
    finally:
        assert emu.quit() == 0, emu.log()[-3000:]


@pytest.mark.parametrize("arg", ["nonsense", "127.0.0.1", "127.0.0.1:65536", ":8080", "127.0.0.1:-1"])
def test_a_bad_web_argument_is_refused_before_anything_starts(tmp_path, arg):
    if not EMU:
        pytest.fail("CO_EMU_FAKECAN is not set", pytrace=False)
    r = subprocess.run([EMU, "--nvm-dir", str(tmp_path), "--web", arg, "sds:17"], capture_output=True, text=True,
                       timeout=30)
    assert r.returncode == 2, r.stderr
    assert r.stderr.startswith(f"canopen-emu: --web takes HOST:PORT (127.0.0.1:8080, [::1]:8080, localhost:0; "
                               f"port 0: any free one), not '{arg}'\n"), r.stderr
