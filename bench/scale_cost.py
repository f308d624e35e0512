#!/usr/bin/env python3
"""Instructions per event of the whole emulator by number of nodes and by watcher (issue 36): canopen-emu-fakecan
(its CAN channel a Unix socket to this script: tests/native/socketcan_unix.c) with N Bürkert flow controllers under
`valgrind --tool=callgrind`, twice per set-up: once with the events, once without, otherwise the same steps. Each
run is cut into phases by `callgrind_control --dump`, so one pair of runs gives every row of a set-up:
Ir per event = (Ir of the phase with events - Ir of the phase without) / (events - events).

    scale_cost.py --emu PATH --work DIR --out FILE [--quick] [--only SETUP ...]

Set-ups: 1, 32, 64 and 127 nodes with no watcher; 127 nodes with a control-socket client subscribed to every
frame; 127 nodes with a web session tracing every frame (docs/web.md: the trace's subscription), which also gives
the idle exchange. Phases, in this order in every run:

- setup: start, every boot-up, 0x1017 = 0 on every node, the watcher connected and subscribed (never compared);
- sdo: expedited SDO requests, uploads of 0x1018:01 and downloads of 0x1017 = 0 alternating, to the nodes in turn,
  each after the last one's answer and a 3 ms pause, so that every request is one wake-up of the emulator;
- frame: frames no node takes (COB-ID 0x7F0, 8 bytes), 3 ms apart, then one SDO upload so that all were read;
- heartbeat: 0x1017 = 10 ms x N on every node, written 10 ms apart (100 heartbeats a second in all, evenly; the
  run without writes 0 instead), a dump, the hold (the phase compared; the events are the heartbeats this script
  received in it), a dump, then 0x1017 = 0 on every node;
- web: (web only) HTTP exchanges that carry nothing, what a page without its WebSocket or stream makes every 250 ms;
- web_message: (web only) empty messages on the session's WebSocket, 3 ms apart (a message with nothing to ask);
- web_request: (web only) requests on the WebSocket, a `get` of one object (0x1017 of node 1) each, the next after
  the answer came on it: what the page's views send every 250 ms.

A web session takes its events from its WebSocket (docs/web.md), as the page does, read by a thread; a control-socket
client is read by a thread too (the bus and the watchers: bench/scale_clients.py). So the difference of a phase is
the events' own cost, their delivery included.
Standard library only.
"""
import argparse
import json
import os
import re
import shutil
import signal
import subprocess
import sys
import time

from scale_clients import BenchError, ControlWatcher, FakeBus, WebWatcher, download_u16, free_port, upload

NOBODY = 0x7F0  # a COB-ID no node of the Bürkert flow controller takes
GAP_S = 0.003
EXCHANGE_EVERY = 25  # steps of a phase between two exchanges of the web session
SIZES = {"full": dict(sdo=1000, frame=1000, hold_s=5.0, web=200),
         "quick": dict(sdo=100, frame=100, hold_s=3.0, web=40)}  # web: also the messages and requests
SETUPS = {  # name: (nodes, watcher)
    "n1": (1, None), "n32": (32, None), "n64": (64, None), "n127": (127, None),
    "n127_control": (127, "control"), "n127_web": (127, "web"),
}
COMPARED = ("sdo", "frame", "heartbeat", "web", "web_message", "web_request")  # the phases whose difference is a row


def callgrind_totals(path):
    with open(path) as f:
        for line in f:
            m = re.match(r"(?:totals|summary):\s+(\d+)", line)
            if m:
                return int(m.group(1))
    raise BenchError(f"no totals in {path}")


class Run:
    """One emulator run under callgrind with its phases; with=False: the same steps without the events."""

    def __init__(self, emu, work, name, nodes, watcher, with_events, sz):
        self.emu, self.nodes, self.watcher_kind, self.with_events, self.sz = emu, nodes, watcher, with_events, sz
        self.out = os.path.join(work, f"callgrind.{name}")
        self.dir = os.path.join(work, name)
        shutil.rmtree(self.dir, ignore_errors=True)  # a run of its own: no NVM file or socket of an earlier one
        os.makedirs(self.dir)
        for fn in os.listdir(work):
            if fn == os.path.basename(self.out) or fn.startswith(os.path.basename(self.out) + "."):
                os.remove(os.path.join(work, fn))
        self.dumps = []  # (phase, events)
        self.took = {}  # phase: seconds from the end of the last dump to this one's
        self.paced = {}  # the run without: each phase lasts as long as in the run with (set by measure)
        self.last = time.monotonic()
        self.watcher = None
        self.proc = None
        self.command = None

    def start(self):
        bus_path = os.path.join(self.dir, "bus")
        self.bus = FakeBus(bus_path)
        extra = []
        if self.watcher_kind == "control":
            extra = ["--control-socket", os.path.join(self.dir, "ctl.sock")]
        elif self.watcher_kind == "web":
            self.port = free_port()
            extra = ["--web", f"127.0.0.1:{self.port}"]
        specs = [f"buerkert:{n}" for n in range(1, self.nodes + 1)]
        argv = ["valgrind", "--tool=callgrind", f"--callgrind-out-file={self.out}", self.emu, "-i", "fakecan0",
                "--nvm-dir", os.path.join(self.dir, "nvm"), "-q"] + extra + specs
        shown = specs if len(specs) <= 2 else [specs[0], "...", specs[-1]]
        self.command = " ".join(argv[:len(argv) - len(specs)] + shown)
        self.proc = subprocess.Popen(argv, env=dict(os.environ, CO_FAKECAN_SOCKET=bus_path),
                                     stdout=subprocess.DEVNULL, stderr=subprocess.PIPE, text=True)
        self.bus.accept()

    def dump(self, phase, events):
        """Everything counted since the last dump becomes the next dump file, this phase's."""
        self.bus.sdo(1, upload(0x1018, 1))  # the same last wake-up in both runs, so the phase ends alike
        subprocess.run(["callgrind_control", f"--dump={phase}", str(self.proc.pid)], check=True,
                       stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL, timeout=120)
        self.dumps.append((phase, events))
        now = time.monotonic()
        self.took[phase] = now - self.last
        self.last = now

    def pace(self, phase, step, steps):
        """The run without: step k of a phase waits until k/steps of the time the phase took in the run with. The
        program's own timers (a Bürkert node stores its operating time once a minute, at its own phase) then fall
        alike into both runs' phases."""
        if phase in self.paced:
            time.sleep(max(0.0, self.last + self.paced[phase] * step / steps - time.monotonic()))

    def setup(self):
        deadline = time.monotonic() + 300
        while len(self.bus.boot_ups) < self.nodes:
            if time.monotonic() > deadline or self.proc.poll() is not None:
                why = self.proc.stderr.read()[-2000:] if self.proc.poll() is not None else "still waiting after 300 s"
                raise BenchError(f"{len(self.bus.boot_ups)} of {self.nodes} boot-ups: {why}")
            time.sleep(0.05)
        for node in range(1, self.nodes + 1):
            self.bus.sdo(node, download_u16(0x1017, 0, 0))
        if self.watcher_kind == "control":
            self.watcher = ControlWatcher(os.path.join(self.dir, "ctl.sock"))
        elif self.watcher_kind == "web":
            self.watcher = WebWatcher(self.port)
        self.dump("setup", 0)

    def tick(self, step):
        if self.watcher is not None and step % EXCHANGE_EVERY == 0:
            self.watcher.tick()

    def sdo_phase(self):
        n = self.sz["sdo"] if self.with_events else 0
        for k in range(self.sz["sdo"]):
            if k < n:
                node = k // 2 % self.nodes + 1
                self.bus.sdo(node, upload(0x1018, 1) if k % 2 == 0 else download_u16(0x1017, 0, 0))
                time.sleep(GAP_S)
            self.pace("sdo", k + 1, self.sz["sdo"])
            self.tick(k)
        self.dump("sdo", n)

    def frame_phase(self):
        n = self.sz["frame"] if self.with_events else 0
        for k in range(self.sz["frame"]):
            if k < n:
                self.bus.send(NOBODY, bytes(range(8)))
                time.sleep(GAP_S)
            self.pace("frame", k + 1, self.sz["frame"])
            self.tick(k)
        self.dump("frame", n)

    def heartbeat_phase(self):
        """The writes of 0x1017 are phases of their own (hb_on, hb_off: never compared), so that only the hold,
        idle in the run without, is: the SDO writes to 127 nodes cost more than their heartbeats, and vary."""
        period = 10 * self.nodes if self.with_events else 0
        start = time.monotonic()
        for node in range(1, self.nodes + 1):
            # 10 ms apart: the heartbeats come evenly, one every 10 ms, each one wake-up; written as fast as the
            # answers come, a slowed-down program finds several due at once, and how many depends on its speed
            time.sleep(max(0.0, start + (node - 1) * 0.010 - time.monotonic()))
            self.bus.sdo(node, download_u16(0x1017, 0, period))
        self.dump("hb_on", 0)
        before = self.bus.heartbeats
        start = time.monotonic()
        for i in range(int(self.sz["hold_s"] / 0.25)):
            time.sleep(max(0.0, start + (i + 1) * 0.25 - time.monotonic()))
            if self.watcher is not None:
                self.watcher.tick()
        self.dump("heartbeat", self.bus.heartbeats - before)
        for node in range(1, self.nodes + 1):
            self.bus.sdo(node, download_u16(0x1017, 0, 0))
        self.dump("hb_off", 0)

    def web_phase(self):
        n = self.sz["web"] if self.with_events else 0
        for k in range(self.sz["web"]):
            if k < n:
                self.watcher.exchange("")
            self.pace("web", k + 1, self.sz["web"])
        self.dump("web", n)
        for k in range(self.sz["web"]):
            if k < n:
                self.watcher.send("")
                time.sleep(GAP_S)
            self.pace("web_message", k + 1, self.sz["web"])
        self.dump("web_message", n)
        for k in range(self.sz["web"]):
            if k < n:
                ident = 1000 + k
                self.watcher.request(ident, f'{{"id":{ident},"cmd":"get","node":1,"object":"0x1017"}}')
            self.pace("web_request", k + 1, self.sz["web"])
        self.dump("web_request", n)

    def finish(self):
        self.proc.send_signal(signal.SIGTERM)
        try:
            _, err = self.proc.communicate(timeout=300)
        except subprocess.TimeoutExpired:
            self.proc.kill()
            raise BenchError("canopen-emu did not stop under callgrind within 300 s") from None
        if self.proc.returncode != 0:
            raise BenchError(f"canopen-emu: exit {self.proc.returncode}\n{err[-2000:]}")
        if self.watcher is not None:
            self.watcher.close()
        self.bus.close()
        res = {}
        for i, (phase, events) in enumerate(self.dumps, start=1):
            res[phase] = {"ir": callgrind_totals(f"{self.out}.{i}"), "events": events, "dump": f"{self.out}.{i}"}
        if self.watcher is not None:
            res["watcher_frame_events"] = self.watcher.events
        return res

    def run(self):
        self.start()
        try:
            self.setup()
            self.sdo_phase()
            self.frame_phase()
            self.heartbeat_phase()
            if self.watcher_kind == "web":
                self.web_phase()
            return self.finish()
        finally:
            if self.proc.poll() is None:
                self.proc.kill()
                self.proc.wait()


def measure(emu, work, name, sz, log=print):
    nodes, watcher = SETUPS[name]
    t0 = time.monotonic()
    runs = {}
    for with_events in (True, False):
        tag = f"{name}_{'k' if with_events else '0'}"
        r = Run(emu, work, tag, nodes, watcher, with_events, sz)
        if not with_events:
            r.paced = {p: took for p, took in paced.items() if p in ("sdo", "frame", "web", "web_message", "web_request")}
        runs[with_events] = r.run()
        paced = r.took
        command = r.command
    rows = {}
    for phase in COMPARED:
        a, b = runs[True].get(phase), runs[False].get(phase)
        if a is None:
            continue
        events = a["events"] - b["events"]
        rows[phase] = {"events": events, "ir_k": a["ir"], "ir_0": b["ir"],
                       "ir_per_event": (a["ir"] - b["ir"]) / events if events > 0 else None,
                       "dump_k": a["dump"], "dump_0": b["dump"]}
    res = {"nodes": nodes, "watcher": watcher, "rows": rows, "seconds": time.monotonic() - t0, "command": command,
           "watcher_frame_events": runs[True].get("watcher_frame_events")}
    log(f"scale: {name}: " + ", ".join(f"{p} {fmt(r['ir_per_event'])} Ir x {r['events']}" for p, r in rows.items())
        + f" ({res['seconds']:.0f} s)")
    return res


def fmt(x):
    return "–" if x is None else f"{x:,.0f}"


def costs(path, inclusive=False):
    """Ir per function of one dump (callgrind_annotate), by name ("file:function", the library added when it is
    not the program); self cost, or inclusive. The functions on the stack through the whole phase (main, the loop)
    come out of a dump taken mid-run with the phase's total whatever the option: they are left out."""
    text = subprocess.run(["callgrind_annotate", "--auto=no", "--threshold=100",
                           f"--inclusive={'yes' if inclusive else 'no'}", path], check=True,
                          stdout=subprocess.PIPE, stderr=subprocess.DEVNULL, text=True).stdout
    total = None
    out = {}
    for line in text.splitlines():
        m = re.match(r"^\s*([\d,]+)\s+(?:\([^)]*\)\s+)?(\S.*?)(?:\s+\[(.*)\])?$", line)
        if not m:
            continue
        ir = int(m.group(1).replace(",", ""))
        if "PROGRAM TOTALS" in line:
            total = ir
            continue
        if ":" not in m.group(2) or ir == total:
            continue
        where, _, fn = m.group(2).rpartition(":")
        name = fn if where in ("", "???") else f"{os.path.basename(where)}:{fn}"
        lib = os.path.basename(m.group(3) or "")
        if lib and not lib.startswith("canopen-emu"):
            name += f" ({lib})"
        out[name] = out.get(name, 0) + ir
    return out


def breakdown(row, top=12):
    """Where an event's instructions go: the functions whose cost differs most between the phase with events and
    without, per event; self cost (the rest summed), and inclusive for the program's own functions."""
    if shutil.which("callgrind_annotate") is None or not row.get("events"):
        return None

    def per_event(inclusive):
        a, b = costs(row["dump_k"], inclusive), costs(row["dump_0"], inclusive)
        # inclusive: the program's own functions only (a Release build has no file names: "file:" is a library's)
        per = sorted((((a.get(k, 0) - b.get(k, 0)) / row["events"]), k) for k in set(a) | set(b)
                     if not (inclusive and ("(" in k or ":" in k)))
        per.reverse()
        return [(k, v) for v, k in per[:top] if v >= 0.5]

    own = per_event(False)
    own.append(("everything else", row["ir_per_event"] - sum(v for _, v in own)))
    return {"self": own, "inclusive": per_event(True)}


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--emu", required=True, help="canopen-emu-fakecan")
    ap.add_argument("--work", required=True)
    ap.add_argument("--out", required=True, help="the figures, JSON")
    ap.add_argument("--quick", action="store_true", help="fewer events: a look, not the figures")
    ap.add_argument("--only", nargs="+", choices=list(SETUPS), help="these set-ups alone")
    ap.add_argument("--breakdown", nargs="*", default=["n127", "n127_control"],
                    help="set-ups whose SDO, frame and heartbeat rows get a breakdown by function")
    args = ap.parse_args()
    sz = SIZES["quick" if args.quick else "full"]
    res = {"sizes": sz, "setups": {}}
    for name in args.only or list(SETUPS):
        try:
            res["setups"][name] = m = measure(os.path.abspath(args.emu), args.work, name, sz,
                                              log=lambda s: print(s, file=sys.stderr, flush=True))
        except (BenchError, OSError, subprocess.SubprocessError) as e:
            print(f"scale: {name}: {e}", file=sys.stderr)
            return 1
        if name in args.breakdown:
            for phase in ("sdo", "frame", "heartbeat"):
                if phase in m["rows"]:
                    m["rows"][phase]["breakdown"] = breakdown(m["rows"][phase])
    with open(args.out, "w") as f:
        json.dump(res, f, indent=1)
    return 0


if __name__ == "__main__":
    sys.exit(main())
