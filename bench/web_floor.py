#!/usr/bin/env python3
"""libmicrohttpd's floor under the web view's idle exchange (issue 36; docs/decisions.md, "The idle web
exchange"): Ir per request of bench/web_floor.c (a daemon as the emulator starts its own, answering every request
with one empty response made at start) under `valgrind --tool=callgrind`, by connection memory
(MHD_OPTION_CONNECTION_MEMORY_LIMIT, WEB_CONNECTION_MEMORY in emu/web/emu_web.h). The requests are the bench's
empty exchanges (bench/scale_clients.py: an empty POST with the token header on one keep-alive connection) and
the same with what headless Chromium sends (BROWSER_HEADERS).

    web_floor.py [--requests N] [--memory BYTES ...]

Per request = Ir between two dumps / N (the daemon does nothing else: no timer falls due in between). Needs cc,
libmicrohttpd's headers and valgrind. Standard library only.
"""
import argparse
import http.client
import os
import re
import socket
import subprocess
import sys
import tempfile
import time

HERE = os.path.dirname(os.path.abspath(__file__))
TOKEN = "0123456789abcdef0123456789abcdef"
PATH = f"/api/session/{TOKEN}"
# What headless Chromium 156 sends with the page's exchange beside Host, Content-Length and the token (measured;
# the same list as tests/native/test_web_http_native.py's, which checks that it fits the connection memory).
BROWSER_HEADERS = {
    "Connection": "keep-alive",
    "sec-ch-ua-platform": '"Linux"',
    "User-Agent": "Mozilla/5.0 (X11; Linux x86_64) AppleWebKit/537.36 (KHTML, like Gecko) HeadlessChrome/156.0.0.0 "
                  "Safari/537.36",
    "sec-ch-ua": '"Not:A-Brand";v="8", "Chromium";v="156"',
    "Content-Type": "application/x-ndjson",
    "sec-ch-ua-mobile": "?0",
    "Accept": "*/*",
    "Origin": "http://127.0.0.1:8080",
    "Sec-Fetch-Site": "same-origin",
    "Sec-Fetch-Mode": "cors",
    "Sec-Fetch-Dest": "empty",
    "Accept-Encoding": "gzip, deflate, br, zstd",
    "Accept-Language": "en-US,en;q=0.9",
}


def build(work):
    exe = os.path.join(work, "web_floor")
    flags = subprocess.run(["pkg-config", "--cflags", "--libs", "libmicrohttpd"], check=True,
                           stdout=subprocess.PIPE, text=True).stdout.split()
    subprocess.run(["cc", "-std=c99", "-O2", "-Wall", "-Wextra", "-Wpedantic", "-Wconversion", "-Werror", "-o", exe,
                    os.path.join(HERE, "web_floor.c")] + flags, check=True)
    return exe


def totals(path):
    out = subprocess.run(["callgrind_annotate", path], check=True, stdout=subprocess.PIPE, text=True).stdout
    return int(re.search(r"([\d,]+)\s+\(100\.0%\)\s+PROGRAM TOTALS", out).group(1).replace(",", ""))


def measure(exe, work, memory, headers, n):
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        port = s.getsockname()[1]
    out = os.path.join(work, f"callgrind.{memory}")
    for fn in os.listdir(work):
        if fn.startswith(os.path.basename(out)):
            os.remove(os.path.join(work, fn))
    proc = subprocess.Popen(["valgrind", "--tool=callgrind", f"--callgrind-out-file={out}", exe, str(port),
                             str(memory)], stderr=subprocess.DEVNULL)
    try:
        headers = dict(headers, **{"X-Canopen-Emu": TOKEN})
        deadline = time.monotonic() + 60
        while True:
            try:
                conn = http.client.HTTPConnection("127.0.0.1", port, timeout=60)
                conn.request("POST", PATH, body=b"", headers=headers)
                break
            except OSError:
                if time.monotonic() > deadline:
                    raise
                time.sleep(0.1)
        answer = conn.getresponse()
        answer.read()
        if answer.status != 200:
            raise SystemExit(f"web_floor: HTTP {answer.status} at {memory} bytes of connection memory")

        def dump():
            subprocess.run(["callgrind_control", "--dump", str(proc.pid)], check=True, stdout=subprocess.DEVNULL,
                           stderr=subprocess.DEVNULL, timeout=120)
        dump()
        for _ in range(n):
            conn.request("POST", PATH, body=b"", headers=headers)
            conn.getresponse().read()
        dump()
        conn.close()
    finally:
        proc.terminate()
        proc.wait(timeout=120)
    return totals(out + ".2") / n


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--requests", type=int, default=200)
    ap.add_argument("--memory", type=int, nargs="+", default=[4096, 8192, 16384, 32768, 65536])
    args = ap.parse_args()
    with tempfile.TemporaryDirectory(prefix="co-web-floor.") as work:
        exe = build(work)
        print("| connection memory | Ir per request, the bench's client | Ir per request, Chromium's headers |")
        print("|--:|--:|--:|")
        for memory in args.memory:
            bench = measure(exe, work, memory, {}, args.requests)
            chromium = measure(exe, work, memory, BROWSER_HEADERS, args.requests)
            print(f"| {memory:,} | {bench:,.0f} | {chromium:,.0f} |", flush=True)
    return 0


if __name__ == "__main__":
    sys.exit(main())
