"""The web view's HTTP side under load of its own kind (docs/web.md, "Limits"): the request headers one connection's
memory holds (a browser's, with cookies, fit; more gets 431 and a log line), and the answers of the exchanges an
idle page makes four times a second, one after another on one connection and across connections (the empty answer
is made once and handed out again, an API request's state is reused: neither may carry anything of an earlier
request). Against canopen-emu-fakecan, in the plain and in the ASan+UBSan build (test_web_native.py's program).

Environment (tests/native/CMakeLists.txt): CO_SOURCE_DIR, CO_EMU_FAKECAN, CO_SANITIZED.
"""

import http.client
import socket

import pytest

from test_web_native import CSP, WebEmulator, assert_security_headers

# What headless Chromium 156 sends with the page's exchange (measured: 17 lines, 668 bytes with the request line).
BROWSER_HEADERS = {
    "Connection": "keep-alive",
    "sec-ch-ua-platform": '"Linux"',
    "User-Agent": "Mozilla/5.0 (X11; Linux x86_64) AppleWebKit/537.36 (KHTML, like Gecko) HeadlessChrome/156.0.0.0 "
                  "Safari/537.36",
    "sec-ch-ua": '"Not:A-Brand";v="8", "Chromium";v="156"',
    "Content-Type": "application/x-ndjson",
    "sec-ch-ua-mobile": "?0",
    "Accept": "*/*",
    "Sec-Fetch-Site": "same-origin",
    "Sec-Fetch-Mode": "cors",
    "Sec-Fetch-Dest": "empty",
    "Accept-Encoding": "gzip, deflate, br, zstd",
    "Accept-Language": "en-US,en;q=0.9",
}
HEADER_ROOM = 2000  # bytes of cookies beside a browser's own headers that must fit (docs/web.md)
TOO_LARGE = 9000  # bytes of one header that must not (more than a connection's memory, WEB_CONNECTION_MEMORY)


@pytest.fixture
def emu(tmp_path):
    e = WebEmulator(tmp_path)
    yield e
    if e.proc.poll() is None:
        assert e.quit() == 0, e.log()[-3000:]


def browser_headers(emu, cookie_bytes):
    """A browser's headers with cookies of another local program (a host's cookies go to every port)."""
    cookies = "; ".join(f"other{k}={'v' * 90}" for k in range(cookie_bytes // 100))
    return dict(BROWSER_HEADERS, Origin=f"http://127.0.0.1:{emu.port}", Cookie=cookies)


def test_a_browsers_headers_with_cookies_fit(emu):
    headers = browser_headers(emu, HEADER_ROOM)
    assert len(headers["Cookie"]) >= HEADER_ROOM - 100
    page = emu.request("GET", "/", headers=headers)
    assert page.status == 200, page.body[:200]
    session = emu.request("POST", "/api/session", headers=headers, token=emu.token())
    assert session.status == 200, session.body
    answer = emu.request("POST", f"/api/session/{session.json()['session']}", body=b'{"id":1,"cmd":"hello"}\n',
                         headers=headers, token=emu.token())
    assert answer.status == 200, answer.body
    assert [(m["id"], m["ok"]) for m in answer.lines()] == [(1, True)]


@pytest.mark.parametrize("name", ["Cookie", "X-Padding"])
def test_headers_beyond_the_connections_memory_get_431_and_are_logged(emu, name):
    with socket.create_connection(("127.0.0.1", emu.port), timeout=10) as raw:
        raw.sendall(f"GET /app.js HTTP/1.1\r\nHost: 127.0.0.1:{emu.port}\r\n{name}: {'x' * TOO_LARGE}\r\n\r\n".encode())
        answer = b""
        while b"\r\n" not in answer:
            piece = raw.recv(65536)
            if not piece:
                break
            answer += piece
    assert answer.startswith(b"HTTP/1.1 431 "), answer[:200]
    emu.wait_log("431")
    assert emu.request("GET", "/app.js").status == 200  # the server is unharmed


def exchange(conn, emu, session, body=b""):
    conn.request("POST", f"/api/session/{session}", body=body,
                 headers={"Host": f"127.0.0.1:{emu.port}", "X-Canopen-Emu": emu.token()})
    answer = conn.getresponse()
    return answer.status, dict(answer.headers), answer.read()


def test_idle_exchanges_get_the_same_empty_answer_with_every_header(emu):
    session = emu.open_session()
    conns = [http.client.HTTPConnection("127.0.0.1", emu.port, timeout=10) for _ in range(2)]
    try:
        seen = []
        for k in range(12):  # keep-alive: each connection carries several, the two take turns
            status, headers, body = exchange(conns[k % 2], emu, session)
            assert (status, body) == (200, b""), (k, status, body)
            seen.append(headers)
            if k == 5:  # an answer with something in it between the empty ones
                status, headers, body = exchange(conns[0], emu, session, b'{"id":7,"cmd":"hello"}\n')
                assert status == 200 and b'"id":7' in body, body
                assert headers["Content-Type"] == "application/x-ndjson" and headers["Cache-Control"] == "no-store"
        for headers in seen:
            assert headers["Content-Type"] == "application/x-ndjson"
            assert headers["Content-Length"] == "0"
            assert headers["Content-Security-Policy"] == CSP
            assert headers["X-Content-Type-Options"] == "nosniff"
            assert headers["Referrer-Policy"] == "no-referrer"
            assert headers["Cache-Control"] == "no-store"
        assert {tuple(sorted((n, v) for n, v in h.items() if n != "Date")) for h in seen} == \
            {tuple(sorted((n, v) for n, v in seen[0].items() if n != "Date"))}
    finally:
        for conn in conns:
            conn.close()


def test_a_request_takes_nothing_of_the_one_before(emu):
    session = emu.open_session()
    conn = http.client.HTTPConnection("127.0.0.1", emu.port, timeout=10)
    try:
        answers = []
        for n in (1, 2, 3):  # each body alone: never appended to the one before
            status, _, body = exchange(conn, emu, session, b'{"id":%d,"cmd":"hello"}\n' % n)
            assert status == 200, body
            answers.append(body.count(b'"id":'))
            assert b'"id":%d,' % n in body, body
        assert answers == [1, 1, 1]
    finally:
        conn.close()
    # A body that was too large (refused, its connection closed): the next request is read as a fresh one.
    too_large = emu.request("POST", f"/api/session/{session}", body=b"\n" * 20000, token=emu.token(), chunked=True)
    assert too_large.status == 413
    assert_security_headers(too_large, api=True)
    answer = emu.exchange(session, '{"id":4,"cmd":"hello"}')
    assert answer.status == 200, answer.body
    assert [m["id"] for m in answer.lines()] == [4]
