#!/usr/bin/env python3
"""Many buses in one process (issue 36): one canopen-emu with B udp_multicast buses of N Bürkert flow controllers
each (8 x 127 in full), every node with a 100 ms heartbeat and two TPDOs with 50 ms event timers; the frames of
every bus recorded with kernel time stamps, the emulator's CPU share, and in a run under callgrind its
instructions per second. Runs only inside tests/udp/netns-run (a network namespace whose only interface is lo:
multicast never leaves the machine). Standard library only; the recorder is bench-record (C: 50,800 frames a second
are more than a Python reader keeps up with).

    scale_buses.py --bin DIR --emu PATH --work DIR --out FILE [--buses B] [--nodes N] [--seconds S]
                   [--callgrind-seconds S] [--late-ms MS] [--aligned] [--nvm-tmpfs DIR]

Steps of a run:
- canopen-emu -i udp_multicast:239.74.164.K:4314K,ttl=0 (K = 1..B; a group and a port per bus) with
  buerkert:1@BUS ... buerkert:N@BUS and --control-socket;
- over the control socket (JSON `set`, as the device itself writes: no SDO), every node's TPDO1 (0x2500:01, the
  flow, pre-mapped) and TPDO2 (disabled by default; mapped to 0x2004:01, the NAMUR status byte): inhibit time 0,
  event timer 50 ms, both left invalid; then 0x1017 = 100 ms, node n of every bus (n-1)/N of 100 ms after node 1;
  NMT start all on every bus (bench-sdo); then the TPDOs made valid, node n (n-1)/N of 50 ms after node 1. So each
  bus's streams come spread over their periods, as unsynchronised devices send them. --aligned adds a run whose
  TPDOs are valid before NMT start all: every TPDO of a bus due at the same instant, 254 frames in one burst;
- after 2 s of settling, one bench-record per bus for S seconds (heartbeats 0x701-0x77F at 100 ms, TPDO1
  0x181-0x1FF and TPDO2 0x281-0x2FF at 50 ms), and bench-gen on the first bus, the ideal 50 ms sender (absolute
  deadlines): what the machine itself did to a period meanwhile;
- the emulator's utime + stime (/proc/PID/stat) over the window's wall time: its share of one core.
The first run keeps the nodes' stored parameters in --work; --nvm-tmpfs DIR adds a run with them in DIR, and puts
the aligned and callgrind runs' there too (a Bürkert node saves its operating time once a minute, with fsync: 1,016
nodes save 17 times a second, in the emulator's loop). The callgrind run repeats the set-up under valgrind
--tool=callgrind, zeroes the counts once the streams run (callgrind_control --zero), records for its own window and
dumps: Ir of the window / its wall time.

A deadline is judged per stream (one COB-ID) from the kernel arrival times of consecutive frames: lateness =
interval - period. Missed: lateness > --late-ms (default 10 ms; docs/performance.md says why), and, as bench-record
counts it, missing: an interval over 1.5 periods.
"""
import argparse
import json
import os
import re
import signal
import socket
import subprocess
import sys
import time

from run_bus import BenchError, cpu_ticks, loadavg, udp_counters, udp_namespace_only

HEARTBEAT_MS = 100
TPDO_MS = 50
LATE_MS = 10
IDEAL_COB = 0x7F0  # a COB-ID no Bürkert node takes
SETTLE_S = 2.0
STREAMS = (("heartbeat", "0x701-0x77F", HEARTBEAT_MS), ("tpdo1", "0x181-0x1FF", TPDO_MS),
           ("tpdo2", "0x281-0x2FF", TPDO_MS))


def bus_name(k):
    """Bus k (0-based): a group and a port of its own, so no bus's socket gets another bus's datagrams."""
    return f"udp_multicast:239.74.164.{k + 1}:{43141 + k}"


def node_settings(n):
    """The `set`s of node n's TPDOs, both left invalid (tpdo_valid makes them valid), in CiA 301's order: inhibit
    time and mapping only while the PDO is invalid."""
    return [("0x1800:01", hex(0x80000180 + n)), ("0x1800:03", "0"), ("0x1800:05", str(TPDO_MS)),
            ("0x1A01:01", "0x20040108"), ("0x1A01:00", "1"), ("0x1801:03", "0"), ("0x1801:05", str(TPDO_MS))]


def tpdo_valid(n):
    return [("0x1800:01", hex(0x180 + n)), ("0x1801:01", hex(0x280 + n))]


class Control:
    """A control-socket client speaking JSON lines (docs/control-protocol.md): requests with ids, at most WINDOW of
    them unanswered (the answers are read as they come, so neither side's buffer fills)."""
    WINDOW = 32

    def __init__(self, path, emu, timeout_s):
        self.deadline = time.monotonic() + timeout_s
        self.sock = socket.socket(socket.AF_UNIX, socket.SOCK_STREAM)
        while True:
            try:
                self.sock.connect(path)
                break
            except OSError:
                if emu.poll() is not None or time.monotonic() > self.deadline:
                    raise BenchError(f"no control socket at {path}")
                time.sleep(0.1)
        self.sock.settimeout(max(1.0, self.deadline - time.monotonic()))
        self.rest, self.next_id, self.waiting = b"", 1, set()

    def send(self, request):
        while len(self.waiting) >= self.WINDOW:
            self.answer()
        request = dict(request, id=self.next_id)
        self.waiting.add(self.next_id)
        self.next_id += 1
        self.sock.sendall((json.dumps(request) + "\n").encode())

    def answer(self):
        while b"\n" not in self.rest:
            data = self.sock.recv(1 << 16)
            if not data:
                raise BenchError("the control socket closed")
            self.rest += data
        line, self.rest = self.rest.split(b"\n", 1)
        msg = json.loads(line)
        if msg.get("id") in self.waiting:
            self.waiting.discard(msg["id"])
            if not msg.get("ok"):
                raise BenchError(f"control: {msg.get('error')}")

    def drain(self):
        while self.waiting:
            self.answer()

    def close(self):
        self.sock.close()


class Harness:
    def __init__(self, bin_dir, emu, work, buses, nodes, late_ms=LATE_MS, log=None):
        self.bin, self.emu_path, self.work = bin_dir, emu, work
        self.buses, self.nodes, self.late_ms = buses, nodes, late_ms
        self.log = log or (lambda s: print(s, file=sys.stderr, flush=True))
        self.commands = []  # (what, argv shown) for the document

    def prog(self, name):
        return os.path.join(self.bin, name)

    def show(self, argv):
        out = " ".join(argv).replace(self.bin + "/", "").replace(self.emu_path, "canopen-emu")
        return out.replace(self.work, "$WORK")

    def start_emu(self, name, callgrind=False, nvm_root=None):
        """canopen-emu with every bus and node and a control socket; its stored parameters in nvm_root (default:
        the work directory)."""
        nvm = os.path.join(nvm_root or self.work, f"nvm-{name}")
        os.makedirs(nvm, exist_ok=True)
        self.control_path = os.path.join(self.work, f"control-{name}.sock")
        argv = [self.emu_path, "--nvm-dir", nvm, "--control-socket", self.control_path]
        for k in range(self.buses):
            argv += ["-i", bus_name(k) + ",ttl=0"]
        specs = [f"buerkert:{n}@{bus_name(k)},ttl=0" for k in range(self.buses) for n in range(1, self.nodes + 1)]
        self.cg_out = os.path.join(self.work, f"callgrind.{name}")
        if callgrind:
            argv = ["valgrind", "--tool=callgrind", f"--callgrind-out-file={self.cg_out}"] + argv
        self.commands.append((name, self.show(argv + [specs[0], "...", specs[-1]])))
        # The log to a file: it must never block the emulator (its exit summary is read from there).
        self.emu_err = os.path.join(self.work, f"emu-{name}.log")
        with open(self.emu_err, "w") as err:
            return subprocess.Popen(argv + specs, stdin=subprocess.DEVNULL, stdout=subprocess.DEVNULL, stderr=err)

    def spread(self, ctl, period_ms, settings):
        """settings(n) for node n of every bus (n-1)/N of period_ms after node 1's."""
        t0 = time.monotonic()
        for n in range(1, self.nodes + 1):
            time.sleep(max(0.0, t0 + (n - 1) * period_ms / 1000 / self.nodes - time.monotonic()))
            for k in range(self.buses):
                for obj, value in settings(n):
                    ctl.send({"cmd": "set", "node": f"{n}@{bus_name(k)}", "object": obj, "value": value})
        ctl.drain()

    def configure(self, name, emu, timeout_s, aligned=False):
        """Over the control socket (`set`, JSON): every node's TPDOs, then the heartbeats, node n of every bus
        (n-1)/N of a period after node 1, so that a bus's heartbeats come spread over the period (as unsynchronised
        devices send them), not as one burst; then NMT start all on every bus (three times, 200 ms apart: a start
        of a started node changes nothing, and under callgrind one datagram may be lost in the emulator's full
        receive buffer); then the TPDOs made valid, spread over their period as the heartbeats (a TPDO's event
        timer starts when it becomes valid in Operational). aligned: the TPDOs made valid before the start, so
        that NMT start all starts every TPDO of a bus at the same instant and they stay in one burst."""
        ctl = Control(self.control_path, emu, timeout_s)
        hb = [("0x1017", HEARTBEAT_MS)]
        self.commands.append((name, "control socket, node n of each bus: " + ", ".join(
            f'{{"cmd":"set","node":"n@BUS","object":"{o}","value":"{v}"}}' for o, v in node_settings(1))
            + f" (n = 1), then 0x1017 = {HEARTBEAT_MS} spread, NMT start, then "
            + ", ".join(f"{o} = {v}" for o, v in tpdo_valid(1)) + (" (before NMT start)" if aligned else " spread")))
        try:
            for k in range(self.buses):
                for n in range(1, self.nodes + 1):
                    for obj, value in node_settings(n) + (tpdo_valid(n) if aligned else []):
                        ctl.send({"cmd": "set", "node": f"{n}@{bus_name(k)}", "object": obj, "value": value})
            ctl.drain()
            self.spread(ctl, HEARTBEAT_MS, lambda n: hb)
            procs = []
            for k in range(self.buses):
                argv = [self.prog("bench-sdo"), "-i", bus_name(k), "nmt", "1", "0", "sleep", "200", "nmt", "1", "0",
                        "sleep", "200", "nmt", "1", "0"]
                if k == 0:
                    self.commands.append((name, self.show(argv) + "   # on each bus"))
                procs.append(subprocess.Popen(argv, stdout=subprocess.DEVNULL, stderr=subprocess.PIPE, text=True))
            for k, p in enumerate(procs):
                _, err = p.communicate(timeout=120)
                if p.returncode != 0:
                    raise BenchError(f"bench-sdo on {bus_name(k)}: exit {p.returncode}: {err.strip()[-400:]}")
            if not aligned:
                self.spread(ctl, TPDO_MS, tpdo_valid)
        finally:
            ctl.close()

    def emu_tail(self):
        with open(self.emu_err) as f:
            return f.read()[-1500:]

    def record(self, name, seconds):
        """One bench-record per bus for `seconds`, bench-gen on the first bus; returns their JSON per bus."""
        late_us = str(self.late_ms * 1000)
        recs = []
        for k in range(self.buses):
            argv = [self.prog("bench-record"), "-i", bus_name(k), "-b", "20", "-t", late_us, "-d", str(seconds)]
            argv += [f"{s}={ids}@{ms * 1000}" for s, ids, ms in STREAMS]
            if k == 0:
                argv.append(f"ideal={hex(IDEAL_COB)}@{TPDO_MS * 1000}")
                self.commands.append((name, self.show(argv) + "   # and the same on each bus"))
            recs.append(subprocess.Popen(argv, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True))
        gen_argv = [self.prog("bench-gen"), "-i", bus_name(0), "-p", str(TPDO_MS * 1000), "-d", str(seconds + 1),
                    hex(IDEAL_COB)]
        self.commands.append((name, self.show(gen_argv)))
        gen = subprocess.Popen(gen_argv, stdout=subprocess.DEVNULL, stderr=subprocess.PIPE, text=True)
        out = []
        for k, p in enumerate(recs):
            o, e = p.communicate(timeout=seconds + 120)
            if p.returncode != 0:
                raise BenchError(f"bench-record on {bus_name(k)}: exit {p.returncode}: {e.strip()[-400:]}")
            out.append(json.loads(o.strip().splitlines()[-1]))
        _, e = gen.communicate(timeout=60)
        if gen.returncode != 0:
            raise BenchError(f"bench-gen: exit {gen.returncode}: {e.strip()[-400:]}")
        return out

    def stop(self, emu, what):
        if emu.poll() is None:
            emu.send_signal(signal.SIGTERM)
        try:
            emu.wait(timeout=120)
        except subprocess.TimeoutExpired:
            emu.kill()
            emu.wait()
            raise BenchError(f"{what} did not stop within 120 s")
        if emu.returncode != 0:
            raise BenchError(f"{what}: exit {emu.returncode}: {self.emu_tail()}")
        m = re.search(r"(\d+) frame\(s\) sent, (\d+) dropped; (\d+) received frame\(s\) lost", self.emu_tail())
        return {"sent": int(m.group(1)), "dropped": int(m.group(2)), "rx_lost": int(m.group(3))} if m else None

    def native(self, name, seconds, aligned=False, nvm_root=None):
        """A timing run: CPU share and deadlines over `seconds`."""
        emu = self.start_emu(name, nvm_root=nvm_root)
        res = {"buses": self.buses, "nodes": self.nodes, "late_ms": self.late_ms, "seconds": seconds,
               "aligned": aligned, "nvm_root": nvm_root or self.work}
        try:
            t0 = time.monotonic()
            self.configure(name, emu, 120, aligned)
            res["config_s"] = time.monotonic() - t0
            time.sleep(SETTLE_S)
            tck = os.sysconf("SC_CLK_TCK")
            snmp0 = udp_counters()
            res["loadavg_before"] = loadavg()
            u0, s0 = cpu_ticks(emu.pid)
            t0 = time.monotonic()
            res["record"] = self.record(name, seconds)
            dt = time.monotonic() - t0
            u1, s1 = cpu_ticks(emu.pid)
            res.update(window_s=dt, cpu_user=(u1 - u0) / tck / dt, cpu_sys=(s1 - s0) / tck / dt,
                       loadavg_after=loadavg(), snmp={k: v - snmp0[k] for k, v in udp_counters().items()})
            res["cpu_share"] = res["cpu_user"] + res["cpu_sys"]
        finally:
            res["emu_summary"] = self.stop(emu, "canopen-emu")
        return res

    def callgrind(self, name, seconds, nvm_root=None):
        """A counting run: Ir of the emulator over `seconds` of running streams, under callgrind."""
        emu = self.start_emu(name, callgrind=True, nvm_root=nvm_root)
        res = {"seconds": seconds, "buses": self.buses, "nodes": self.nodes, "late_ms": self.late_ms}
        try:
            t0 = time.monotonic()
            self.configure(name, emu, 900)
            res["config_s"] = time.monotonic() - t0
            time.sleep(SETTLE_S)
            control = ["callgrind_control"]
            subprocess.run(control + ["--zero", str(emu.pid)], check=True, stdout=subprocess.DEVNULL, timeout=120)
            t0 = time.monotonic()
            res["record"] = self.record(name, seconds)
            subprocess.run(control + ["--dump=window", str(emu.pid)], check=True, stdout=subprocess.DEVNULL,
                           timeout=120)
            res["window_s"] = time.monotonic() - t0
            res["ir"] = window_ir(self.cg_out)
        finally:
            self.stop(emu, "canopen-emu under callgrind")
        return res


def window_ir(out):
    """Ir of the one dump callgrind_control --dump wrote (OUT.1; OUT itself is written at exit)."""
    path = out + ".1"
    deadline = time.monotonic() + 60
    while True:
        try:
            with open(path) as f:
                for line in f:
                    m = re.match(r"(?:totals|summary):\s+(\d+)", line)
                    if m:
                        return int(m.group(1))
        except FileNotFoundError:
            pass
        if time.monotonic() > deadline:
            raise BenchError(f"no totals in {path}")
        time.sleep(0.2)


def summary(res):
    """Per bus and stream: frames per second, worst lateness (ms), late and missing intervals; the totals."""
    nominal = res["nodes"] * (1000 // HEARTBEAT_MS + 2 * 1000 // TPDO_MS)  # frames a second a bus should carry
    rows = []
    for k, rec in enumerate(res["record"]):
        g = rec["groups"]
        frames = sum(g[s]["frames"] for s, _, _ in STREAMS)
        rows.append({"bus": bus_name(k), "fps": frames / rec["seconds"], "nominal_fps": nominal,
                     "rx_drops": rec["rx_drops"],
                     **{s: {"streams": g[s]["streams"], "late_max_ms": g[s]["late_max_us"] / 1000,
                            "late": g[s]["late"], "missing": g[s]["missing"], "intervals": g[s]["intervals"],
                            "p99_dev_ms": g[s]["abs_dev_us"]["p99"] / 1000} for s, _, _ in STREAMS}})
    ideal = res["record"][0]["groups"]["ideal"]
    return {"rows": rows, "ideal": ideal, "nominal_fps": nominal,
            "late": sum(r[s]["late"] for r in rows for s, _, _ in STREAMS),
            "missing": sum(r[s]["missing"] for r in rows for s, _, _ in STREAMS),
            "streams": sum(r[s]["streams"] for r in rows for s, _, _ in STREAMS),
            "late_max_ms": max(r[s]["late_max_ms"] for r in rows for s, _, _ in STREAMS),
            "fps": sum(r["fps"] for r in rows)}


def main():
    ap = argparse.ArgumentParser(description="B udp_multicast buses x N nodes in one canopen-emu (issue 36).")
    ap.add_argument("--bin", required=True, help="the bench programs (bench-sdo, bench-record, bench-gen)")
    ap.add_argument("--emu", required=True)
    ap.add_argument("--work", required=True)
    ap.add_argument("--out", required=True)
    ap.add_argument("--buses", type=int, default=8)
    ap.add_argument("--nodes", type=int, default=127)
    ap.add_argument("--seconds", type=int, default=20)
    ap.add_argument("--callgrind-seconds", type=int, default=10, help="0: no callgrind run")
    ap.add_argument("--late-ms", type=int, default=LATE_MS)
    ap.add_argument("--callgrind-small", type=int, default=0, metavar="B",
                    help="also a callgrind run with B buses (one callgrind keeps up with)")
    ap.add_argument("--aligned", action="store_true", help="also a run with each bus's TPDOs in one burst")
    ap.add_argument("--nvm-tmpfs", help="a directory on tmpfs (/dev/shm): also a run with the stored parameters "
                    "there (the aligned and callgrind runs too); the first run keeps them in --work")
    args = ap.parse_args()
    if not udp_namespace_only():
        print("scale_buses: run in tests/udp/netns-run (a network namespace with only lo): multicast must not leave "
              "the machine", file=sys.stderr)
        return 2
    if not 1 <= args.buses <= 8 or not 1 <= args.nodes <= 127:
        ap.error("1..8 buses of 1..127 nodes")
    h = Harness(os.path.abspath(args.bin), os.path.abspath(args.emu), os.path.abspath(args.work), args.buses,
                args.nodes, args.late_ms)
    try:
        h.log(f"scale_buses: {args.buses} x {args.nodes} nodes, {args.seconds} s")
        tmpfs = os.path.abspath(args.nvm_tmpfs) if args.nvm_tmpfs else None
        res = {"native": h.native("native", args.seconds)}
        res["native"]["summary"] = summary(res["native"])
        if tmpfs:
            h.log(f"scale_buses: again with the stored parameters on tmpfs, {args.seconds} s")
            res["tmpfs"] = h.native("tmpfs", args.seconds, nvm_root=tmpfs)
            res["tmpfs"]["summary"] = summary(res["tmpfs"])
        if args.aligned:
            h.log(f"scale_buses: again with every TPDO of a bus started at once, {args.seconds} s")
            res["aligned"] = h.native("aligned", args.seconds, aligned=True, nvm_root=tmpfs)
            res["aligned"]["summary"] = summary(res["aligned"])
        if args.callgrind_seconds > 0:
            h.log(f"scale_buses: the same under callgrind, {args.callgrind_seconds} s")
            cg = h.callgrind("callgrind", args.callgrind_seconds, nvm_root=tmpfs)
            cg["summary"] = summary(cg)
            res["callgrind"] = cg
        if args.callgrind_seconds > 0 and args.callgrind_small:
            # Fewer buses, a rate callgrind keeps up with: the Ir per frame of a program that is never behind.
            h.log(f"scale_buses: {args.callgrind_small} buses under callgrind, {args.callgrind_seconds} s")
            small = Harness(h.bin, h.emu_path, h.work, args.callgrind_small, args.nodes, args.late_ms)
            small.commands = h.commands
            cg = small.callgrind(f"callgrind-{args.callgrind_small}", args.callgrind_seconds, nvm_root=tmpfs)
            cg["summary"] = summary(cg)
            res["callgrind_small"] = cg
    except (BenchError, subprocess.TimeoutExpired, OSError) as e:
        print(f"scale_buses: {e}", file=sys.stderr)
        return 1
    res["commands"] = h.commands
    with open(args.out, "w") as f:
        json.dump(res, f, indent=1)
    return 0


if __name__ == "__main__":
    sys.exit(main())
