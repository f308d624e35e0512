#!/usr/bin/env python3
"""The bus half of tools/bench: runs where vcan0 is up (inside one `tools/vcan-run` call) and writes one
JSON file with every figure. Standard library only.

    run_bus.py --bin DIR --emu PATH --work DIR --out FILE [--mode full|quick|smoke] [--only SECTION]
    run_bus.py --clients-table LABEL=FILE [LABEL=FILE ...]    (on the host: the `clients` tables, Markdown)
    run_bus.py --table udp|socketcand FILE                     (on the host: that section's tables, Markdown)

Sections (docs/performance.md explains each): SDO round trip against bench-echo (the floor) and
canopen-emu; heartbeat/TPDO periods next to the ideal generator; the heartbeat while a control client floods
the control socket; instructions per SDO request, heartbeat
and TPDO of canopen-emu under callgrind (difference of runs); 127 nodes: CPU share, period error, highest
lossless SDO rate. Any program failing (non-zero status, unparsable output) fails the whole run.

The sections `udp` and `socketcand` run only when asked (`--only udp`, `--only socketcand`; tools/bench does not
run them, docs/performance.md keeps their hand-measured sections): `udp` the 127 nodes' heartbeats at 10 ms on a
udp_multicast bus, sent against received and where frames were lost; it runs only in a network namespace whose
only interface is lo (tests/udp/netns-run), never where multicast could leave the machine. `socketcand` the round
trip of an SDO upload through `--socketcand` against a raw SocketCAN socket's, in one run (inside vcan-run).

The section `clients` runs only when asked (`--only clients`; tools/bench does not show it): the heartbeat at
100 ms while 64 control clients keep the emulator busy (issue 32, N2), idle and under three loads, one emulator run
per phase. --emu picks the program, so that the same section measures an older build next to the current one.
"""
import argparse
import json
import statistics
import os
import re
import signal
import subprocess
import sys
import threading
import time

IFACE = "vcan0"
NODE = 1  # the Bürkert flow controller's own default node-ID

# Sizes per mode. full: the figures of docs/performance.md; quick: a fast look (not full figures);
# smoke: the ctest, only proves every program still runs and parses.
SIZES = {
    "full": dict(rtt_n=5000, period_s=12, cg_n=2000, cg_hold_s=5, scale_window_s=30, scale_rounds=3, rate_step_ms=2000,
                 rates=[250, 500, 1000, 1500, 2000, 3000, 4000, 6000, 8000, 12000],
                 callgrind=True, clients_s=10, udp_window_s=20, scd_n=2000),
    "quick": dict(rtt_n=500, period_s=3, cg_n=200, cg_hold_s=1, scale_window_s=6, scale_rounds=3, rate_step_ms=500,
                  rates=[500, 1000, 2000, 4000, 8000, 16000, 32000], callgrind=True, clients_s=5, udp_window_s=5,
                  scd_n=500),
    "smoke": dict(rtt_n=20, period_s=1, cg_n=0, cg_hold_s=0, scale_window_s=1, scale_rounds=1, rate_step_ms=200,
                  rates=[100, 200], callgrind=False, clients_s=2, udp_window_s=1, scd_n=20),
}


class BenchError(Exception):
    pass


class Runner:
    def __init__(self, args):
        self.bin = args.bin
        self.emu_path = args.emu
        self.work = args.work
        self.commands = []  # (section, argv) for the document
        self.emu_runs = 0

    def show(self, argv):
        """A command as the document shows it: build paths replaced by names."""
        out = []
        for a in argv:
            a = a.replace(self.bin + "/", "")
            a = a.replace(self.emu_path, "canopen-emu")
            a = a.replace(self.work, "$WORK")
            a = a.replace(os.path.abspath(__file__), "bench/run_bus.py").replace(sys.executable, "python3")
            out.append(a)
        return " ".join(out)

    def prog(self, name):
        return os.path.join(self.bin, name)

    def run_json(self, section, argv, timeout=600):
        self.commands.append((section, self.show(argv)))
        p = subprocess.run(argv, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True, timeout=timeout)
        if p.returncode != 0:
            raise BenchError(f"{self.show(argv)}: exit {p.returncode}\n{p.stderr}{p.stdout}")
        try:
            return json.loads(p.stdout.strip().splitlines()[-1])
        except (ValueError, IndexError) as e:
            raise BenchError(f"{self.show(argv)}: output not JSON ({e}): {p.stdout!r}") from e

    def start(self, section, argv, stdout=subprocess.PIPE, stdin=None):
        self.commands.append((section, self.show(argv)))
        return subprocess.Popen(argv, stdin=stdin, stdout=stdout, stderr=subprocess.PIPE, text=True)

    def stop(self, proc, what, timeout=120):
        """SIGTERM and wait; the program must exit 0 (canopen-emu and bench-echo do on SIGTERM)."""
        if proc.poll() is None:
            proc.send_signal(signal.SIGTERM)
        try:
            out, err = proc.communicate(timeout=timeout)
        except subprocess.TimeoutExpired:
            proc.kill()
            out, err = proc.communicate()
            raise BenchError(f"{what} did not stop within {timeout} s")
        if proc.returncode != 0:
            raise BenchError(f"{what}: exit {proc.returncode}\n{err}")
        return out, err

    def emu(self, section, specs, valgrind_out=None, extra=(), iface=IFACE, quiet=True):
        self.emu_runs += 1
        nvm = os.path.join(self.work, f"nvm{self.emu_runs}")
        os.makedirs(nvm, exist_ok=True)
        argv = [self.emu_path, "-i", iface, "--nvm-dir", nvm] + (["-q"] if quiet else []) + list(extra) + specs
        if valgrind_out:
            argv = ["valgrind", "--tool=callgrind", f"--callgrind-out-file={valgrind_out}"] + argv
        show_specs = specs if len(specs) <= 3 else [specs[0], "...", specs[-1]]
        shown = (argv[: len(argv) - len(specs)]) + show_specs
        self.commands.append((section, self.show(shown)))
        return subprocess.Popen(argv, stdout=subprocess.DEVNULL, stderr=subprocess.PIPE, text=True)


def loadavg():
    with open("/proc/loadavg") as f:
        return " ".join(f.read().split()[:3])


def cpu_ticks(pid):
    with open(f"/proc/{pid}/stat") as f:
        fields = f.read().rsplit(")", 1)[1].split()
    return int(fields[11]), int(fields[12])  # utime, stime (fields 14, 15)


def tpdo_setup(node, event_ms):
    """TPDO1 of a Bürkert node: invalid, no inhibit time (only writable while invalid), event timer, valid."""
    return ["w", str(node), "0x1800:1", "4", hex(0x80000180 + node), "w", str(node), "0x1800:3", "2", "0",
            "w", str(node), "0x1800:5", "2", str(event_ms), "w", str(node), "0x1800:1", "4", hex(0x180 + node)]


RTT_ROUNDS = 5
# bench-record reads what arrived every 20 ms instead of waking for each frame (bench_record.c: woken 2,540
# times a second it took User-Mode Linux's one CPU from the 127-node emulator in the middle of its bursts).
RECORD_BATCH_MS = 20


def merge_rounds(rounds):
    """Per request kind: the median of the rounds' p50 and p99 (robust against one disturbed round), the largest max,
    the summed n, the n-weighted mean, and each round's p50."""
    out = dict(rounds[0])
    results = []
    for i, first in enumerate(rounds[0]["results"]):
        stats = [rd["results"][i]["rtt_us"] for rd in rounds]
        n = sum(st["n"] for st in stats)
        merged = {"n": n, "mean": sum(st["mean"] * st["n"] for st in stats) / n if n else 0.0,
                  "p50": statistics.median(st["p50"] for st in stats),
                  "p99": statistics.median(st["p99"] for st in stats),
                  "max": max(st["max"] for st in stats),
                  "rounds_p50": [st["p50"] for st in stats]}
        results.append(dict(first, rtt_us=merged))
    out["results"] = results
    return out


def sdo_rtt(r, sz):
    """Round trip: the same client, the same requests, against the echo floor and against canopen-emu, in alternating
    rounds with both servers running (the echo on another node-ID), so that both see the same machine state: inside
    User-Mode Linux the wake-up latency of an idle guest drifts by a factor of ten between minutes."""
    per_round = max(1, sz["rtt_n"] // RTT_ROUNDS)
    echo_node = NODE + 1

    def ops(node):
        return ["up", str(node), "0x1018:1", str(per_round), "down", str(node), "0x1017", "2", "0", str(per_round)]

    res = {}
    echo = r.start("rtt", [r.prog("bench-echo"), "-i", IFACE, str(echo_node)])
    emu = r.emu("rtt", [f"buerkert:{NODE}"])
    floor_rounds, emu_rounds = [], []
    try:
        # 0x1017 = 0 first: no heartbeat between the measured frames.
        r.run_json("rtt", [r.prog("bench-sdo"), "-i", IFACE, "ready", str(NODE), "w", str(NODE), "0x1017", "2", "0"])
        for _ in range(RTT_ROUNDS):
            floor_rounds.append(r.run_json("rtt", [r.prog("bench-sdo"), "-i", IFACE, "--any-reply"] + ops(echo_node)))
            emu_rounds.append(r.run_json("rtt", [r.prog("bench-sdo"), "-i", IFACE] + ops(NODE)))
    finally:
        r.stop(emu, "canopen-emu")
        r.stop(echo, "bench-echo")
    res["floor"] = merge_rounds(floor_rounds)
    res["emu"] = merge_rounds(emu_rounds)
    res["n"] = per_round * RTT_ROUNDS
    res["rounds"] = RTT_ROUNDS
    return res


def periods(r, sz):
    """Heartbeat and event-timer TPDO at 10 ms, recorded next to the ideal generator at 10 ms."""
    period_us = 10000
    d = sz["period_s"]
    emu = r.emu("periods", [f"buerkert:{NODE}"])
    try:
        r.run_json("periods", [r.prog("bench-sdo"), "-i", IFACE, "ready", str(NODE), "w", str(NODE), "0x1017", "2", "10"]
                   + tpdo_setup(NODE, 10) + ["nmt", "1", str(NODE), "sleep", "200"])
        rec = r.start("periods", [r.prog("bench-record"), "-i", IFACE, "-b", str(RECORD_BATCH_MS), "-p", str(period_us),
                                  "-d", str(d),
                                  f"heartbeat=0x{0x700 + NODE:03X}", f"tpdo=0x{0x180 + NODE:03X}", "ideal=0x7F0"])
        gen = r.start("periods", [r.prog("bench-gen"), "-i", IFACE, "-p", str(period_us), "-d", str(d + 1), "0x7F0"])
        rec_out, rec_err = rec.communicate(timeout=d + 60)
        gen_out, gen_err = gen.communicate(timeout=d + 60)
        if rec.returncode != 0 or gen.returncode != 0:
            raise BenchError(f"bench-record/bench-gen failed: {rec_err}{gen_err}")
    finally:
        r.stop(emu, "canopen-emu")
    return {"period_us": period_us, "seconds": d, "record": json.loads(rec_out), "gen": json.loads(gen_out)}


FLOOD_IN_FLIGHT = 64  # requests a flooding client keeps on the way: it never waits for one answer at a time


def flood_client(path, stop, counts):
    """A control client that sends JSON get requests as fast as the emulator takes them, FLOOD_IN_FLIGHT at a time,
    and checks every answer. counts: answered, wrong."""
    import socket
    request = (json.dumps({"cmd": "get", "node": NODE, "object": "0x1018:01"}) + "\n").encode()
    s = socket.socket(socket.AF_UNIX)
    s.connect(path)
    buf, in_flight = b"", 0
    while not stop.is_set():
        if in_flight < FLOOD_IN_FLIGHT:
            s.sendall(request * (FLOOD_IN_FLIGHT - in_flight))
            in_flight = FLOOD_IN_FLIGHT
        buf += s.recv(1 << 16)
        *lines, buf = buf.split(b"\n")
        for line in lines:
            in_flight -= 1
            answer = json.loads(line)
            counts["answered" if answer.get("ok") and answer.get("value") is not None else "wrong"] += 1
    s.close()


def control_flood(r, sz):
    """Heartbeat at 10 ms next to the ideal generator, recorded twice in one emulator run: with its control socket
    idle, then while one client floods the socket with pipelined JSON requests. What the flood costs the bus side."""
    import threading
    period_us = 10000
    d = sz["period_s"]
    path = os.path.join(r.work, "ctl.sock")
    emu = r.emu("flood", [f"buerkert:{NODE}"], extra=["--control-socket", path])
    res = {"period_us": period_us, "seconds": d, "in_flight": FLOOD_IN_FLIGHT}
    try:
        r.run_json("flood", [r.prog("bench-sdo"), "-i", IFACE, "ready", str(NODE), "w", str(NODE), "0x1017", "2", "10"])
        for phase in ("idle", "flood"):
            stop, counts = threading.Event(), {"answered": 0, "wrong": 0}
            client = threading.Thread(target=flood_client, args=(path, stop, counts))
            if phase == "flood":
                client.start()
                time.sleep(0.5)  # the flood is on before the recording starts
            t0, cpu0 = time.monotonic(), cpu_ticks(emu.pid)
            rec = r.start("flood", [r.prog("bench-record"), "-i", IFACE, "-b", str(RECORD_BATCH_MS), "-p", str(period_us),
                                    "-d", str(d), f"heartbeat=0x{0x700 + NODE:03X}", "ideal=0x7F0"])
            gen = r.start("flood", [r.prog("bench-gen"), "-i", IFACE, "-p", str(period_us), "-d", str(d + 1), "0x7F0"])
            rec_out, rec_err = rec.communicate(timeout=d + 60)
            gen_out, gen_err = gen.communicate(timeout=d + 60)
            t1, cpu1 = time.monotonic(), cpu_ticks(emu.pid)
            answered_in_window = counts["answered"]
            stop.set()
            if phase == "flood":
                client.join(timeout=10)
            if rec.returncode != 0 or gen.returncode != 0:
                raise BenchError(f"bench-record/bench-gen failed: {rec_err}{gen_err}")
            if counts["wrong"]:
                raise BenchError(f"{counts['wrong']} wrong answers to the flooding client")
            hz = os.sysconf("SC_CLK_TCK")
            res[phase] = {"record": json.loads(rec_out), "requests": answered_in_window,
                          "requests_per_s": answered_in_window / (t1 - t0),
                          "cpu_share": (sum(cpu1) - sum(cpu0)) / hz / (t1 - t0)}
    finally:
        r.stop(emu, "canopen-emu (control socket)")
    return res


# ---- 64 busy control clients (issue 32, N2)
CLIENTS = 64  # the control socket's most clients at once (MAX_CLIENTS, emu/control/emu_socket.h)
CLIENTS_PERIOD_US = 100000
CLIENT_REQUESTS = {"objects": b'{"cmd":"objects","node":1,"values":true}\n', "hello": b'{"cmd":"hello"}\n'}
CLIENT_IN_FLIGHT = (2, 4)  # a reading client asks again when only 2 answers are due, up to 4 again
SILENT_REQUESTS = 100  # what a client that never reads sends, at once
# The phases: what the 64 clients do (none, reading `objects` answers, never reading them, `hello`).
CLIENT_PHASES = (("idle", None), ("objects", "objects"), ("silent", "objects"), ("hello", "hello"))
CLIENTS_LEAD_S = 1  # the recording runs this long before the clients begin: a stall they cause at once is inside it


def client_load(phase, path, n_clients):
    """The 64 clients of one phase, in a process of their own (`run_bus.py client-load PHASE PATH N`): one poll()
    over all sockets, no busy waiting (User-Mode Linux has one CPU for them and the emulator). Prints "ready" once
    all are connected, and begins to ask when a line comes on stdin; the counts are noted then and on SIGUSR1 (the
    recorded window's end); SIGTERM ends it and prints the notes as JSON. A reading client counts answers by their
    line ends and checks its first answer whole; a silent client only sends, and is watched for being closed by the
    emulator."""
    import select
    import socket
    kind = dict(CLIENT_PHASES)[phase]
    request = CLIENT_REQUESTS[kind]
    reading = phase != "silent"
    socks = []
    deadline = time.monotonic() + 10
    while len(socks) < n_clients:
        s = socket.socket(socket.AF_UNIX)
        try:
            s.connect(path)
        except OSError:
            s.close()
            if socks or time.monotonic() > deadline:
                raise
            time.sleep(0.05)  # the socket is not there yet
            continue
        socks.append(s)
    by_fd = {s.fileno(): s for s in socks}
    due = {fd: 0 for fd in by_fd}  # answers asked for and not yet received
    out = {fd: b"" for fd in by_fd}  # requests not yet taken by the socket
    first = {fd: b"" for fd in by_fd}  # the first answer, until whole
    counts = {"answers": 0, "bytes": 0, "refused": 0, "closed_by_emulator": 0}
    poller = select.poll()
    marks, stop = [], []

    def mark(*_):
        t = os.times()
        marks.append({"t": time.monotonic(), "cpu_s": t.user + t.system, **counts})

    signal.signal(signal.SIGUSR1, mark)
    signal.signal(signal.SIGTERM, lambda *_: stop.append(1))
    print("ready", flush=True)
    sys.stdin.readline()  # go
    mark()
    for fd, s in by_fd.items():
        if reading:
            due[fd] = CLIENT_IN_FLIGHT[1]
            out[fd] = request * CLIENT_IN_FLIGHT[1]
        else:
            s.sendall(request * SILENT_REQUESTS)
        s.setblocking(False)

    def flush(fd):
        try:
            n = by_fd[fd].send(out[fd])
        except BlockingIOError:
            n = 0
        out[fd] = out[fd][n:]
        poller.modify(fd, select.POLLIN | (select.POLLOUT if out[fd] else 0))

    for fd in by_fd:
        poller.register(fd, select.POLLIN if reading else select.POLLRDHUP)
        if reading:
            flush(fd)
    while not stop:
        try:
            events = poller.poll(200)
        except InterruptedError:
            continue
        for fd, ev in events:
            s = by_fd[fd]
            if not reading:  # only a hang-up wakes a silent client
                counts["closed_by_emulator"] += 1
                poller.unregister(fd)
                continue
            if ev & select.POLLOUT:
                flush(fd)
            if not ev & (select.POLLIN | select.POLLHUP | select.POLLERR):
                continue
            try:
                data = s.recv(1 << 18)
            except BlockingIOError:
                continue
            except OSError:
                data = b""
            if not data:
                counts["closed_by_emulator"] += 1
                poller.unregister(fd)
                continue
            lines = data.count(b"\n")
            counts["answers"] += lines
            counts["bytes"] += len(data)
            counts["refused"] += data.count(b'"ok":false')
            if first[fd] is not None:
                first[fd] += data
                if b"\n" in first[fd]:
                    answer = json.loads(first[fd].split(b"\n", 1)[0])
                    if not answer.get("ok") or (kind == "objects" and not answer.get("objects")):
                        raise BenchError(f"client-load: a wrong first answer: {str(answer)[:300]}")
                    first[fd] = None
            due[fd] -= lines
            if due[fd] <= CLIENT_IN_FLIGHT[0]:
                out[fd] += request * (CLIENT_IN_FLIGHT[1] - due[fd])
                due[fd] = CLIENT_IN_FLIGHT[1]
                flush(fd)
    mark()
    for s in socks:
        s.close()
    print(json.dumps({"clients": n_clients, "marks": marks}), flush=True)
    return 0


def clients_phase(r, phase, d):
    """One emulator run: heartbeat 100 ms; the heartbeat and the ideal generator recorded for d seconds, the phase's
    clients connected before and asking from CLIENTS_LEAD_S on (a stall that began before the window would not be
    an interval of it). Recorded twice at once: against the period (deviation, intervals over 1.5 periods) and
    against a period of 1 µs, whose deviations are the intervals themselves (the largest gap, the p99 interval)."""
    path = os.path.join(r.work, f"ctl-{phase}.sock")
    emu = r.emu("clients", [f"buerkert:{NODE}"], extra=["--control-socket", path])
    load = None
    rd = {"phase": phase}
    try:
        r.run_json("clients", [r.prog("bench-sdo"), "-i", IFACE, "ready", str(NODE), "w", str(NODE), "0x1017", "2",
                               str(CLIENTS_PERIOD_US // 1000)])
        if dict(CLIENT_PHASES)[phase]:
            load = r.start("clients", [sys.executable, os.path.abspath(__file__), "client-load", phase, path,
                                       str(CLIENTS)], stdin=subprocess.PIPE)
            if load.stdout.readline().strip() != "ready":
                load.wait(timeout=30)
                raise BenchError(f"client-load {phase}: {load.stderr.read()}")
        hb, ideal = f"heartbeat=0x{0x700 + NODE:03X}", "ideal=0x7F0"
        rec = r.start("clients", [r.prog("bench-record"), "-i", IFACE, "-b", str(RECORD_BATCH_MS), "-p",
                                  str(CLIENTS_PERIOD_US), "-d", str(d), hb, ideal])
        gaps = r.start("clients", [r.prog("bench-record"), "-i", IFACE, "-b", str(RECORD_BATCH_MS), "-p", "1",
                                   "-d", str(d), hb, ideal])
        gen = r.start("clients", [r.prog("bench-gen"), "-i", IFACE, "-p", str(CLIENTS_PERIOD_US), "-d", str(d + 1),
                                  "0x7F0"])
        time.sleep(CLIENTS_LEAD_S)
        t0, wall0, cpu0 = time.monotonic(), time.time(), cpu_ticks(emu.pid)
        if load is not None:
            load.stdin.write("go\n")
            load.stdin.flush()
        outs = {}
        for name, proc in (("record", rec), ("gaps", gaps), ("gen", gen)):
            out, err = proc.communicate(timeout=d + 60)
            if proc.returncode != 0:
                raise BenchError(f"bench-{name}: exit {proc.returncode}: {err}")
            outs[name] = json.loads(out)
        t1, wall1, cpu1 = time.monotonic(), time.time(), cpu_ticks(emu.pid)
        if load is not None:
            load.send_signal(signal.SIGUSR1)
            time.sleep(0.3)  # the mark is taken before the end
            out, err = r.stop(load, f"client-load {phase}")
            marks = json.loads(out.strip().splitlines()[-1])["marks"]
            a, b = marks[0], marks[1]
            dt = b["t"] - a["t"]
            rd["load"] = {"answers": b["answers"] - a["answers"], "answers_per_s": (b["answers"] - a["answers"]) / dt,
                          "bytes_per_s": (b["bytes"] - a["bytes"]) / dt, "refused": marks[-1]["refused"],
                          "closed_by_emulator": marks[-1]["closed_by_emulator"],
                          "cpu_share": (b["cpu_s"] - a["cpu_s"]) / dt}
            load = None
        tck = os.sysconf("SC_CLK_TCK")
        rd.update({"load_s": t1 - t0, "wall": [wall0, wall1], "loadavg_window": loadavg(),
                   "emu_cpu_share": (sum(cpu1) - sum(cpu0)) / tck / (t1 - t0),
                   "record": outs["record"], "gaps": outs["gaps"], "gen": outs["gen"]})
    finally:
        if load is not None and load.poll() is None:
            load.kill()
            load.communicate()
        _, err = r.stop(emu, f"canopen-emu (control socket, {phase})")
        rd["emu_stderr"] = err.strip()[-1000:]
    return rd


def busy_clients(r, sz):
    """The heartbeat (100 ms) beside the ideal generator while 64 control clients: do nothing; ask `objects` with
    values as fast as they read the answers (2-4 on the way each); send 100 such requests each and never read;
    send `hello` as fast as answered. Before issue 32's fix, a pass of the emulator's loop ran every client's
    waiting lines and the heartbeat waited for all of them."""
    d = sz["clients_s"]
    return {"period_us": CLIENTS_PERIOD_US, "seconds": d, "lead_s": CLIENTS_LEAD_S, "clients": CLIENTS,
            "in_flight": list(CLIENT_IN_FLIGHT),
            "silent_requests": SILENT_REQUESTS, "emu": r.emu_path,
            "phases": [clients_phase(r, phase, d) for phase, _ in CLIENT_PHASES]}


def stream_cells(res, rd, stream):
    """A stream's cells of the `clients` table: frames received of those due in the window, intervals over 1.5
    periods, the largest gap (ms, the 1 µs recording's largest interval), p99 and max deviation from the period."""
    g, iv = rd["record"]["groups"][stream], rd["gaps"]["groups"][stream]["abs_dev_us"]
    due = res["seconds"] * 1000000 // res["period_us"]
    return [f"{g['frames']}/{due}", str(g["missing"]), f"{iv['max'] / 1000:,.0f}",
            f"{g['abs_dev_us']['p99'] / 1000:,.1f}", f"{g['abs_dev_us']['max'] / 1000:,.1f}"]


CLIENTS_WHAT = {"idle": "none", "objects": "64 reading `objects`", "silent": "64 never reading",
                "hello": "64 sending `hello`"}


def clients_table(labelled):
    """The `clients` tables (Markdown), one JSON file of run_bus.py per label (runs of an older and of the current
    program), grouped by phase: the heartbeat's timing next to the ideal generator's, then what the clients got and
    what it cost."""
    runs = []
    for label, path in labelled:
        with open(path) as f:
            runs.append((label, json.load(f)["clients"]))
    phases = [rd["phase"] for rd in runs[0][1]["phases"]]
    lines = ["| clients | program | heartbeat frames | over 1.5 periods | largest gap ms | p99 dev ms | max dev ms "
             "| ideal frames | over 1.5 periods | largest gap ms | p99 dev ms | max dev ms |",
             "|---|---|" + "--:|" * 10]
    for k, phase in enumerate(phases):
        for label, res in runs:
            rd = res["phases"][k]
            lines.append(f"| {CLIENTS_WHAT[phase]} | {label} | " + " | ".join(stream_cells(res, rd, "heartbeat"))
                         + " | " + " | ".join(stream_cells(res, rd, "ideal")) + " |")
    lines += ["", "| clients | program | answers/s | MB/s read | closed by the emulator | canopen-emu CPU "
              "| clients' CPU | load average (UML) |", "|---|---|--:|--:|--:|--:|--:|---|"]
    for k, phase in enumerate(phases[1:], 1):
        for label, res in runs:
            rd = res["phases"][k]
            ld = rd["load"]
            lines.append(f"| {CLIENTS_WHAT[phase]} | {label} | {ld['answers_per_s']:,.0f} | "
                         f"{ld['bytes_per_s'] / 1e6:.1f} | {ld['closed_by_emulator']} "
                         f"| {rd['emu_cpu_share'] * 100:.0f}% | {ld['cpu_share'] * 100:.0f}% | {rd['loadavg_window']} |")
    return "\n".join(lines)

def callgrind_total(path):
    total = None
    with open(path) as f:
        for line in f:
            m = re.match(r"(?:totals|summary):\s+(\d+)", line)
            if m:
                total = int(m.group(1))
    if total is None:
        raise BenchError(f"no totals in {path}")
    return total


def cg_run(r, name, client_cmds):
    out = os.path.join(r.work, f"callgrind.{name}")
    emu = r.emu("callgrind", [f"buerkert:{NODE}"], valgrind_out=out)
    try:
        # Long timeout and drain: under valgrind in UML the server starts and answers slowly.
        # --gap-ms: one request per wake-up of the server (see bench_sdo.c), as with a master that is not
        # sending back to back; otherwise valgrind's slowness batches requests and the count depends on speed.
        res = r.run_json("callgrind", [r.prog("bench-sdo"), "-i", IFACE, "--timeout-ms", "20000", "--gap-ms", "3",
                                       "ready", str(NODE),
                                       "1000"] + client_cmds, timeout=900)
    finally:
        r.stop(emu, "canopen-emu under callgrind", timeout=300)
    res["ir"] = callgrind_total(out)
    return res


def callgrind(r, sz):
    """Instructions of canopen-emu per SDO request, heartbeat and TPDO: runs that differ only in the
    number of those events (heartbeat off, node otherwise idle), Ir difference / event difference."""
    n = str(sz["cg_n"])
    hold = str(sz["cg_hold_s"] * 1000)
    quiet = ["w", str(NODE), "0x1017", "2", "0"]
    res = {"n": sz["cg_n"], "hold_ms": int(hold)}
    a = cg_run(r, "sdo_n", quiet + ["up", str(NODE), "0x1018:1", n, "down", str(NODE), "0x1017", "2", "0", n])
    b = cg_run(r, "sdo_0", quiet)
    res["sdo"] = {"ir_n": a["ir"], "ir_0": b["ir"], "answers_n": a["sdo_answers"], "answers_0": b["sdo_answers"]}
    hb = f"0x{0x700 + NODE:03X}"
    a = cg_run(r, "hb_k", quiet + ["w", str(NODE), "0x1017", "2", "10", "sleep", hold] + quiet)
    b = cg_run(r, "hb_0", quiet + quiet + ["sleep", hold] + quiet)
    res["heartbeat"] = {"ir_n": a["ir"], "ir_0": b["ir"], "frames_n": a["frames"].get(hb, 0),
                        "frames_0": b["frames"].get(hb, 0)}
    tp = f"0x{0x180 + NODE:03X}"
    off = ["w", str(NODE), "0x1800:5", "2", "0"]
    a = cg_run(r, "tpdo_k", quiet + tpdo_setup(NODE, 10) + ["nmt", "1", str(NODE), "sleep", hold] + off)
    b = cg_run(r, "tpdo_0", quiet + tpdo_setup(NODE, 0) + ["nmt", "1", str(NODE), "sleep", hold] + off)
    res["tpdo"] = {"ir_n": a["ir"], "ir_0": b["ir"], "frames_n": a["frames"].get(tp, 0), "frames_0": b["frames"].get(tp, 0)}
    for k in ("sdo", "heartbeat", "tpdo"):
        d = res[k]
        events = (d["answers_n"] - d["answers_0"]) if k == "sdo" else (d["frames_n"] - d["frames_0"])
        d["events"] = events
        d["ir_per_event"] = (d["ir_n"] - d["ir_0"]) / events if events > 0 else None
    return res


WEB_PORT = 18080  # the web view of the 127-node run (inside the vcan-run guest: nothing else listens there)


class PageLoad:
    """What the web view's page asks of the emulator, as a thread: one web session (docs/web.md "HTTP API"), an
    exchange every 250 ms, `show all` once a second, the overview's events, and the trace's subscription to every
    frame; plus a batched `get` of 8 process values of one node per exchange (a plot). Counts exchanges, their bytes
    and their round-trip times, and the frame events received."""

    def __init__(self, port):
        import http.client  # only this section talks HTTP
        self.http = http.client
        self.port = port
        self.stop = False
        self.exchanges, self.sizes, self.rtts, self.frames, self.errors = 0, [], [], 0, []
        conn = self.http.HTTPConnection("127.0.0.1", port, timeout=10)
        conn.request("GET", "/")
        page = conn.getresponse().read().decode()
        self.token = re.search(r'name="canopen-emu-token" content="([0-9a-f]+)"', page).group(1)
        self.conn = conn
        self.session = self.post("/api/session", "")["session"]

    def post(self, path, body):
        self.conn.request("POST", path, body=body.encode(), headers={"X-Canopen-Emu": self.token})
        answer = self.conn.getresponse()
        data = answer.read()
        if answer.status != 200:
            raise BenchError(f"web: {path}: HTTP {answer.status}: {data[:200]!r}")
        return json.loads(data) if path == "/api/session" else data

    def run(self):
        lines = ['{"id":1,"cmd":"subscribe","events":["nmt","boot-up","emcy","fault"]}',
                 '{"id":2,"cmd":"subscribe","events":["frame"],"frames":"0x000/0x000"}']
        plot = json.dumps({"id": 3, "cmd": "get", "node": 1, "objects": ["0x2500:01", "0x2500:02", "0x2500:03",
                           "0x2500:04", "0x2500:05", "0x2500:06", "0x2500:07", "0x1001"]})
        last_show = 0.0
        next_at = time.monotonic()
        try:
            while not self.stop:
                now = time.monotonic()
                if now - last_show >= 1.0:
                    lines.append('{"id":4,"cmd":"show","node":"all"}')
                    last_show = now
                lines.append(plot)
                t0 = time.monotonic()
                data = self.post(f"/api/session/{self.session}", "\n".join(lines))
                self.rtts.append(time.monotonic() - t0)
                lines = []
                self.exchanges += 1
                self.sizes.append(len(data))
                self.frames += data.count(b'"event":"frame"')
                next_at += 0.25
                time.sleep(max(0.0, next_at - time.monotonic()))
        except (OSError, BenchError, ValueError) as e:
            self.errors.append(str(e))

    def restart_counts(self):
        """The window starts: what came before (the subscriptions settling) is not counted."""
        self.exchanges, self.sizes, self.rtts, self.frames = 0, [], [], 0

    def figures(self, seconds):
        rtts = sorted(self.rtts)
        return {"exchanges": self.exchanges, "errors": self.errors, "frame_events_per_s": self.frames / seconds,
                "bytes_mean": statistics.mean(self.sizes) if self.sizes else 0, "bytes_max": max(self.sizes, default=0),
                "rtt_ms_p50": 1000 * rtts[len(rtts) // 2] if rtts else None,
                "rtt_ms_p99": 1000 * rtts[min(len(rtts) - 1, int(len(rtts) * 0.99))] if rtts else None}


def scale_round(r, emu, w):
    """One window of the 127-node run: the streams recorded beside the ideal generator, the emulator's CPU share."""
    tck = os.sysconf("SC_CLK_TCK")
    rec = r.start("scale", [r.prog("bench-record"), "-i", IFACE, "-b", str(RECORD_BATCH_MS), "-p", "100000",
                            "-d", str(w), "heartbeat=0x701-0x77F", "tpdo=0x181-0x1FF", "ideal=0x7F0"])
    gen = r.start("scale", [r.prog("bench-gen"), "-i", IFACE, "-p", "100000", "-d", str(w + 1), "0x7F0"])
    u0, s0 = cpu_ticks(emu.pid)
    t0, wall0 = time.monotonic(), time.time()
    rec_out, rec_err = rec.communicate(timeout=w + 120)
    u1, s1 = cpu_ticks(emu.pid)
    dt, wall1 = time.monotonic() - t0, time.time()
    gen_out, gen_err = gen.communicate(timeout=w + 60)
    if rec.returncode != 0 or gen.returncode != 0:
        raise BenchError(f"bench-record/bench-gen: {rec_err}{gen_err}")
    rd = {"wall": [wall0, wall1],  # realtime: tools/bench matches it with the host's steal time
          "window_s": dt, "cpu_user": (u1 - u0) / tck / dt, "cpu_sys": (s1 - s0) / tck / dt,
          "loadavg_window": loadavg(), "record": json.loads(rec_out)}
    rd["cpu_share"] = rd["cpu_user"] + rd["cpu_sys"]
    g = rd["record"]["groups"]
    rd["missing"] = g["heartbeat"]["missing"] + g["tpdo"]["missing"]
    return rd


def scale(r, sz):
    """127 Bürkert nodes in one canopen-emu: heartbeat 100 ms and TPDO1 every 100 ms each."""
    nodes = range(1, 128)
    emu = r.emu("scale", [f"buerkert:{n}" for n in nodes], extra=("--web", f"127.0.0.1:{WEB_PORT}"))
    res = {"nodes": len(nodes)}
    try:
        cmds = ["ready", "1-127", "300"]
        for n in nodes:
            cmds += ["w", str(n), "0x1017", "2", "100"] + tpdo_setup(n, 100)
        cmds += ["nmt", "1", "0", "sleep", "1000"]
        t0 = time.monotonic()
        r.run_json("scale", [r.prog("bench-sdo"), "-i", IFACE] + cmds)
        res["config_s"] = time.monotonic() - t0
        # Rounds of the window, each with the ideal generator's stream recorded next to the emulator's: what the
        # machine itself did to a 100 ms period meanwhile (a stall of the whole guest shows there too, a fault of
        # the emulator does not). In User-Mode Linux on a shared host the figures of one window swing by a factor
        # of ten from minute to minute; the document shows every round and takes the median one.
        rounds = sz["scale_rounds"]
        w = max(1, sz["scale_window_s"] // rounds)
        res["rounds"] = [scale_round(r, emu, w) for _ in range(rounds)]
        median = sorted(res["rounds"], key=lambda x: x["missing"])[len(res["rounds"]) // 2]
        for k in ("window_s", "cpu_user", "cpu_sys", "cpu_share", "loadavg_window", "record"):
            res[k] = median[k]
        res["median_round"] = res["rounds"].index(median)
        # The same window with the web view's page open on it (overview, trace of every frame, one plot): what a
        # browser beside a test run costs the emulator, and whether the streams keep their periods meanwhile.
        page = PageLoad(WEB_PORT)
        thread = threading.Thread(target=page.run, daemon=True)
        thread.start()
        time.sleep(1.0)  # its subscriptions are in place
        page.restart_counts()
        t0 = time.monotonic()
        res["web"] = scale_round(r, emu, w)
        page.stop = True
        thread.join(timeout=15)
        res["web"]["page"] = page.figures(time.monotonic() - t0)
        if page.errors:
            raise BenchError(f"web: {page.errors[0]}")
        res["rate"] = r.run_json("scale", [r.prog("bench-rate"), "-i", IFACE, "--pid", str(emu.pid), "--step-ms",
                                           str(sz["rate_step_ms"]), "--nodes", "1-127"] + [str(x) for x in sz["rates"]],
                                 timeout=1200)
    finally:
        _, err = r.stop(emu, "canopen-emu (127 nodes)")
    res["emu_stderr"] = err.strip()[-2000:]  # with its exit summary when anything was lost (-q)
    return res


# ---- udp_multicast: 127 nodes, heartbeats at 10 ms (issue 33, section 5)
UDP_GROUP = "239.74.163.2"
UDP_PORT = 43119  # not python-can's default: nothing else in the namespace shares it
UDP_PERIOD_US = 10000


def udp_counters():
    """The namespace's UDP counters (/proc/net/snmp, per network namespace), by name."""
    with open("/proc/net/snmp") as f:
        rows = [line.split() for line in f if line.startswith("Udp:")]
    return {k: int(v) for k, v in zip(rows[0][1:], rows[1][1:])}


def udp_namespace_only():
    """True where lo is the only network interface: a namespace of tests/udp/netns-run (/proc/net/dev is the
    namespace's; /sys/class/net would be the host's unless sysfs were mounted again)."""
    with open("/proc/net/dev") as f:
        return [line.split(":")[0].strip() for line in f if ":" in line] == ["lo"]


def udp(r, sz):
    """127 Bürkert nodes on a udp_multicast bus with TTL 0, heartbeat 10 ms each (12,700 frames/s). Two receivers
    (bench-record on the group): one over the emulator's whole life, whose frame count is compared with the
    emulator's own count of frames sent (its exit summary), and one for the measured window (heartbeats received
    per node, missing periods). Where a frame is lost: the receivers' own socket overflows (SO_RXQ_OVFL, per
    socket), the namespace's UDP RcvbufErrors (every socket, the emulator's own receiving socket included: it
    reads its own datagrams back from the loop and skips them), the emulator's refused sends (its summary)."""
    if not udp_namespace_only():
        raise BenchError("udp: run in tests/udp/netns-run (a network namespace with only lo): multicast must not "
                         "leave the machine")
    bus = f"udp_multicast:{UDP_GROUP}:{UDP_PORT}"
    w = sz["udp_window_s"]
    nodes = range(1, 128)
    res = {"group": f"{UDP_GROUP}:{UDP_PORT}", "nodes": len(nodes), "period_us": UDP_PERIOD_US, "window_s": w}
    snmp0 = udp_counters()
    # The whole-run receiver joins the group before the emulator starts: the boot-ups come at once.
    whole_d = w + 12  # configuration, the window, the stop, with room: it ends after the emulator
    whole = r.start("udp", [r.prog("bench-record"), "-i", bus, "-b", "2", "-p", str(UDP_PERIOD_US), "-d", str(whole_d),
                            "emu=0x080-0x5FF", "nodes=0x700-0x77F"])
    time.sleep(0.5)
    t_whole = time.monotonic()
    # The emulator without -q: its exit summary (frames sent) is always printed then.
    emu = r.emu("udp", [f"buerkert:{n}" for n in nodes], iface=f"{bus},ttl=0", quiet=False)
    try:
        cmds = ["ready", "1-127", "300"]
        for n in nodes:
            cmds += ["w", str(n), "0x1017", "2", str(UDP_PERIOD_US // 1000)]
        cmds += ["sleep", "500"]
        t0 = time.monotonic()
        r.run_json("udp", [r.prog("bench-sdo"), "-i", bus] + cmds)
        res["config_s"] = time.monotonic() - t0
        snmp1 = udp_counters()
        tck = os.sysconf("SC_CLK_TCK")
        rec = r.start("udp", [r.prog("bench-record"), "-i", bus, "-b", "2", "-p", str(UDP_PERIOD_US), "-d", str(w),
                              "heartbeat=0x701-0x77F"])
        u0, s0 = cpu_ticks(emu.pid)
        t0 = time.monotonic()
        rec_out, rec_err = rec.communicate(timeout=w + 60)
        u1, s1 = cpu_ticks(emu.pid)
        dt = time.monotonic() - t0
        snmp2 = udp_counters()
        if rec.returncode != 0:
            raise BenchError(f"bench-record: {rec_err}")
        res["window"] = {"seconds": dt, "cpu_user": (u1 - u0) / tck / dt, "cpu_sys": (s1 - s0) / tck / dt,
                         "loadavg": loadavg(), "record": json.loads(rec_out),
                         "snmp": {k: snmp2[k] - snmp1[k] for k in snmp2}}
        res["window"]["cpu_share"] = res["window"]["cpu_user"] + res["window"]["cpu_sys"]
    finally:
        _, err = r.stop(emu, "canopen-emu (udp_multicast, 127 nodes)")
    res["emu_life_s"] = time.monotonic() - t_whole
    summary = [ln for ln in err.splitlines() if "frame(s) sent" in ln]
    m = re.search(r"(\d+) frame\(s\) sent, (\d+) dropped; (\d+) received frame\(s\) lost", summary[-1] if summary else "")
    if not m:
        raise BenchError(f"udp: no exit summary from canopen-emu: {err[-500:]}")
    res["emu_sent"], res["emu_dropped"], res["emu_rx_lost"] = (int(x) for x in m.groups())
    res["emu_summary"] = summary[-1].split("] ", 1)[-1]
    whole_out, whole_err = whole.communicate(timeout=whole_d + 60)
    if whole.returncode != 0:
        raise BenchError(f"bench-record (whole run): {whole_err}")
    res["whole"] = json.loads(whole_out)
    g = res["whole"]["groups"]
    res["whole_received"] = g["emu"]["frames"] + g["nodes"]["frames"]
    res["snmp_run"] = {k: v - snmp0[k] for k, v in udp_counters().items()}
    return res


# ---- socketcand against SocketCAN: the round trip of one SDO upload (issue 33, section 5)
SCD_PORT = 29536
SCD_ROUNDS = 10


def socketcand(r, sz):
    """canopen-emu on vcan0 serving it with --socketcand; the same expedited upload (0x1018:01) N times, closed loop,
    from a raw SocketCAN socket and from a socketcand client (bench-sdo over TCP, rawmode), in alternating rounds in
    one emulator run. The socketcand client can only take the arrival time after its read returns, so the raw
    socket is measured that way too (--user-time) for the ratio; its kernel-time-stamp figure is shown beside."""
    per_round = max(1, sz["scd_n"] // SCD_ROUNDS)
    emu = r.emu("socketcand", [f"buerkert:{NODE}"], extra=["--socketcand", f"127.0.0.1:{SCD_PORT}"])
    scd = f"socketcand:127.0.0.1:{SCD_PORT}:{IFACE}"
    up = ["up", str(NODE), "0x1018:1", str(per_round)]
    kinds = (("raw_kernel", ["-i", IFACE]), ("raw", ["-i", IFACE, "--user-time"]), ("socketcand", ["-i", scd]))
    rounds = {k: [] for k, _ in kinds}
    try:
        r.run_json("socketcand", [r.prog("bench-sdo"), "-i", IFACE, "ready", str(NODE), "w", str(NODE), "0x1017", "2",
                                  "0"])
        for _ in range(SCD_ROUNDS):
            for k, opts in kinds:
                # ready first: the server holds a new rawmode client's frames for 100 ms (docs/buses.md)
                rounds[k].append(r.run_json("socketcand", [r.prog("bench-sdo")] + opts + ["ready", str(NODE), "200"] + up))
    finally:
        r.stop(emu, "canopen-emu (socketcand)")
    res = {k: merge_rounds(v) for k, v in rounds.items()}
    res["n"] = per_round * SCD_ROUNDS
    res["rounds"] = SCD_ROUNDS
    a, b = res["socketcand"]["results"][0]["rtt_us"], res["raw"]["results"][0]["rtt_us"]
    res["ratio_p50"] = a["p50"] / b["p50"]
    res["ratio_p99"] = a["p99"] / b["p99"]
    # Per round (the two clients a few seconds apart): inside User-Mode Linux the idle guest's wake-up drifts
    # between rounds by more than the difference measured, so the median of the rounds' ratios is the steadier one.
    res["round_ratios_p50"] = [x["results"][0]["rtt_us"]["p50"] / y["results"][0]["rtt_us"]["p50"]
                               for x, y in zip(rounds["socketcand"], rounds["raw"])]
    res["round_ratio_p50"] = statistics.median(res["round_ratios_p50"])
    return res


def udp_table(res):
    """The udp section's figures, Markdown (the hand-measured section of docs/performance.md)."""
    win, hb = res["window"], res["window"]["record"]["groups"]["heartbeat"]
    due = res["nodes"] * win["record"]["seconds"] * 1000000 // res["period_us"]
    lines = ["| what | count | per second |", "|---|--:|--:|",
             f"| heartbeats due in the window ({res['nodes']} nodes x {win['record']['seconds']} s / 10 ms) | {due:,} | "
             f"{due / win['record']['seconds']:,.0f} |",
             f"| heartbeats received in the window | {hb['frames']:,} | {hb['frames'] / win['seconds']:,.0f} |",
             f"| intervals over 1.5 periods (a missing heartbeat) | {hb['missing']:,} | |",
             f"| window receiver's socket drops (SO_RXQ_OVFL) | {win['record']['rx_drops']:,} | |",
             f"| namespace UDP RcvbufErrors in the window (all sockets) | {win['snmp']['RcvbufErrors']:,} | |",
             f"| frames canopen-emu sent, whole run (exit summary) | {res['emu_sent']:,} | |",
             f"| frames the whole-run receiver got from it | {res['whole_received']:,} | |",
             f"| whole-run receiver's socket drops | {res['whole']['rx_drops']:,} | |",
             f"| canopen-emu's refused sends (dropped) / its receive socket's losses | {res['emu_dropped']:,} / "
             f"{res['emu_rx_lost']:,} | |",
             f"| namespace UDP RcvbufErrors, whole run | {res['snmp_run']['RcvbufErrors']:,} | |"]
    a = hb["abs_dev_us"]
    lines += ["", f"canopen-emu CPU share in the window: {win['cpu_share'] * 100:.1f}% (user {win['cpu_user'] * 100:.1f}%, "
              f"system {win['cpu_sys'] * 100:.1f}%); heartbeat period deviation p50 {a['p50']:,.0f} µs, p99 "
              f"{a['p99']:,.0f} µs, max {a['max']:,.0f} µs, mean error {hb['mean_error_us']:+.1f} µs; receiver buffer "
              f"{win['record']['rcvbuf']:,} bytes; load average after the window {win['loadavg']}; configuration "
              f"{res['config_s']:.1f} s."]
    return "\n".join(lines)


def socketcand_table(res):
    lines = ["| client | arrival time | p50 µs | p99 µs | max µs | p50 per round (µs) |", "|---|---|--:|--:|--:|---|"]
    for k, label, when in (("raw_kernel", "SocketCAN raw socket", "kernel time stamp"),
                           ("raw", "SocketCAN raw socket", "after read()"),
                           ("socketcand", "socketcand (TCP, rawmode)", "after read()")):
        st = res[k]["results"][0]["rtt_us"]
        lines.append(f"| {label} | {when} | {st['p50']:,.0f} | {st['p99']:,.0f} | {st['max']:,.0f} | "
                     + ", ".join(f"{x:,.0f}" for x in st["rounds_p50"]) + " |")
    lines += ["", f"socketcand / SocketCAN (both after read()): p50 **{res['ratio_p50']:.2f}**, "
              f"p99 **{res['ratio_p99']:.2f}** (medians of the rounds' figures); the p50 ratio per round: "
              + ", ".join(f"{x:.2f}" for x in res["round_ratios_p50"])
              + f", median **{res['round_ratio_p50']:.2f}**."]
    return "\n".join(lines)


def main():
    if sys.argv[1:2] == ["--table"]:  # on the host: the udp or socketcand section's table from a JSON file
        with open(sys.argv[3]) as f:
            data = json.load(f)
        print({"udp": udp_table, "socketcand": socketcand_table}[sys.argv[2]](data[sys.argv[2]]))
        return 0
    if sys.argv[1:2] == ["client-load"]:  # the clients of a `clients` phase, started by clients_phase()
        phase, path, n = sys.argv[2:5]
        return client_load(phase, path, int(n))
    if sys.argv[1:2] == ["--clients-table"]:
        print(clients_table([a.split("=", 1) for a in sys.argv[2:]]))
        return 0
    ap = argparse.ArgumentParser()
    ap.add_argument("--bin", required=True)
    ap.add_argument("--emu", required=True)
    ap.add_argument("--work", required=True)
    ap.add_argument("--out", required=True)
    ap.add_argument("--mode", choices=sorted(SIZES), default="full")
    ap.add_argument("--only", choices=("rtt", "periods", "flood", "callgrind", "scale", "clients", "udp", "socketcand"),
                    help="run this section alone (tools/bench --emu-instructions: callgrind); clients, udp and "
                         "socketcand run only so")
    args = ap.parse_args()
    args.bin = os.path.abspath(args.bin)
    args.emu = os.path.abspath(args.emu)
    args.work = os.path.abspath(args.work)
    os.makedirs(args.work, exist_ok=True)
    sz = SIZES[args.mode]
    r = Runner(args)
    res = {"mode": args.mode, "sizes": sz, "inside": {"kernel": os.uname().release, "cpus": os.cpu_count(),
                                                      "loadavg_before": loadavg()}}
    started = time.monotonic()
    steps = [("rtt", sdo_rtt), ("periods", periods), ("flood", control_flood)]
    if sz["callgrind"]:
        steps.append(("callgrind", callgrind))
    steps.append(("scale", scale))
    if args.only == "clients":
        steps.append(("clients", busy_clients))
    if args.only == "udp":
        steps.append(("udp", udp))
    if args.only == "socketcand":
        steps.append(("socketcand", socketcand))
    if args.only:
        steps = [(name, fn) for name, fn in steps if name == args.only]
    try:
        for name, fn in steps:
            t0 = time.monotonic()
            print(f"bench: {name} ...", file=sys.stderr, flush=True)
            res[name] = fn(r, sz)
            res[name]["elapsed_s"] = time.monotonic() - t0
            res[name]["loadavg_after"] = loadavg()
    except (BenchError, subprocess.TimeoutExpired, OSError) as e:
        print(f"bench: FAILED: {e}", file=sys.stderr)
        return 1
    res["inside"]["loadavg_after"] = loadavg()
    res["inside"]["elapsed_s"] = time.monotonic() - started
    res["commands"] = r.commands
    with open(args.out, "w") as f:
        json.dump(res, f, indent=1)
    return 0


if __name__ == "__main__":
    sys.exit(main())
