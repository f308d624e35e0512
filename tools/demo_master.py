#!/usr/bin/env python3
"""A short, narrated CANopen master session against canopen-emu (README Quick start, step 1).

Starts canopen-emu with the three emulated devices on a CAN interface, then acts as the master with
python-canopen: waits for the boot-ups, reads identity and names by SDO, starts the nodes, shows live PDO
values decoded with names and units, releases the high voltage and moves a set-point, injects a fault and
shows its EMCY (and the confirmation when it is cleared), stops the nodes and ends the emulator.

    demo_master.py --emu build/canopen-emu [--iface vcan0]
"""
import argparse
import os
import re
import struct
import subprocess
import sys
import tempfile
import threading
import time
import tomllib
from decimal import Decimal
from pathlib import Path

import canopen

SRC = Path(__file__).resolve().parents[1]
NODES = [  # (device, node-ID, EDS)
    ("pro-ionizer", 0x10, SRC / "od/pro-ionizer.eds"),
    ("sds", 0x11, SRC / "od/sds.eds"),
    ("buerkert", 0x12, SRC / "od/buerkert-flow-controller.eds"),
]


def profile_units(device, eds):
    """{(device, index, sub): unit} from the device's generator profile (od/<device>.toml [units]): the units the
    emulator answers with too (one source)."""
    with open(eds.with_suffix(".toml"), "rb") as f:
        units = tomllib.load(f).get("units", {})
    out = {}
    for spec, unit in units.items():
        index, _, subs = spec.partition(":")
        first, _, last = (subs or "0").partition("-")
        for sub in range(int(first, 16), int(last or first, 16) + 1):
            out[(device, int(index, 16), sub)] = unit
    return out


UNITS = {key: unit for device, _, eds in NODES for key, unit in profile_units(device, eds).items()}
T0 = time.monotonic()
print_lock = threading.Lock()


def say(text, who="master"):
    with print_lock:
        print(f"{time.monotonic() - T0:6.2f}s {who:>6} | {text}", flush=True)


def pump(stream, who):
    for line in stream:
        say(line.rstrip("\n"), who)


def step(title):
    with print_lock:
        print(f"\n=== {title}", flush=True)


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--emu", required=True)
    ap.add_argument("--iface", default=os.environ.get("CO_VCAN_IFACE", "vcan0"))
    args = ap.parse_args()

    # Removed when the program ends (its finalizer runs at exit): each demo run starts from factory defaults.
    nvm_dir = tempfile.TemporaryDirectory(prefix="canopen-emu-demo-")
    nvm = nvm_dir.name
    # --web on a port the kernel picks (a fixed one may be taken): the log line says which; the page is there for as
    # long as the demo runs (docs/web.md).
    emu_args = [args.emu, "-i", args.iface, "--nvm-dir", nvm, "--control", "-", "--web", "127.0.0.1:0"] + \
        [f"{d}:{n}" for d, n, _ in NODES]
    step("Start the emulator: " + " ".join(["canopen-emu"] + emu_args[1:]))
    network = canopen.Network()
    network.connect(interface="socketcan", channel=args.iface)
    nodes = {}
    booted = {}
    for device, node_id, eds in NODES:
        node = canopen.RemoteNode(node_id, str(eds))
        node.sdo.RESPONSE_TIMEOUT = 2.0
        network.add_node(node)
        nodes[device] = node
        # Listen before the emulator starts: its boot-ups come within milliseconds.
        booted[node_id] = threading.Event()
        network.subscribe(0x700 + node_id, lambda can_id, data, ts: data == b"\x00" and booted[can_id - 0x700].set())
    emu = subprocess.Popen(emu_args, stdin=subprocess.PIPE, stdout=subprocess.PIPE, stderr=subprocess.PIPE,
                           text=True, bufsize=1)
    threading.Thread(target=pump, args=(emu.stderr, "emu"), daemon=True).start()
    threading.Thread(target=pump, args=(emu.stdout, "emu"), daemon=True).start()
    try:
        run(network, nodes, emu, booted)
    finally:
        if emu.poll() is None:
            emu.terminate()
        emu.wait(timeout=5)
        network.disconnect()
    step("Done. The same emulator runs as long as you like with: build/canopen-emu --web 127.0.0.1:8080 "
         "pro-ionizer:16 sds:17 buerkert:18\n    and its live view is then at http://127.0.0.1:8080/ in a browser "
         "(docs/web.md)")
    return 0


def run(network, nodes, emu, booted):
    step("Boot-up: every node says hello on 0x700 + node-ID with state 0x00")
    for device, node in nodes.items():
        if not booted[node.id].wait(timeout=5):
            raise SystemExit(f"no boot-up from {device} (node {node.id})")
        say(f"{device}: boot-up from node {node.id} (0x{0x700 + node.id:03X}#00)")

    step("Identity and device name by SDO")
    for device, node in nodes.items():
        vendor, product, revision, serial = (struct.unpack("<I", node.sdo.upload(0x1018, s))[0] for s in (1, 2, 3, 4))
        name = node.sdo.upload(0x1008, 0).decode("ascii", "replace")
        say(f"{device}: name \"{name}\", vendor 0x{vendor:08X}, product 0x{product:08X}, "
            f"revision 0x{revision:08X}, serial 0x{serial:08X}")
        heartbeat = struct.unpack("<H", node.sdo.upload(0x1017, 0))[0]
        say(f"{device}: heartbeat every {heartbeat} ms (0x1017)")

    step("PDO decoding: the master reads each TPDO's mapping from the EDS")
    latest = {}
    for device, node in nodes.items():
        node.tpdo.read(from_od=True)
        for pdo in node.tpdo.map.values():
            if not pdo.enabled:
                continue
            def on_pdo(message, device=device):
                for var in message:
                    latest[(device, var.index, var.subindex)] = (var.name, var.raw)
            pdo.add_callback(on_pdo)
        node.emcy.add_callback(lambda entry, device=device: show_emcy(device, entry))

    step("NMT start (broadcast 000#0100): PDOs flow only in Operational")
    network.nmt.state = "OPERATIONAL"
    time.sleep(1.5)
    show_values(latest)

    step("Make something happen")
    pi = nodes["pro-ionizer"]
    mode = pi.sdo.upload(0x2002, 2)[0]
    say(f"pro-ionizer: HV release mode 0x2002:02 = {mode} (bit 2 = release by CANopen); setting bit 2")
    pi.sdo.download(0x2002, 2, bytes([mode | 0x04]))
    say("pro-ionizer: RPDO1 0x6200:01 = 0x0F (software release of the high voltage)")
    network.send_message(0x200 + pi.id, b"\x0F")
    say("sds: RPDO1 0x6200:01 = 0x0F (HV release; must be repeated within 10 s)")
    network.send_message(0x200 + nodes["sds"].id, b"\x0F")
    say("buerkert: RPDO1 0x2540:01 = 12.5 (flow set-point)")
    network.send_message(0x200 + nodes["buerkert"].id, struct.pack("<f", 12.5))
    time.sleep(2.0)
    show_values(latest)

    step("A fault: the emulator's control command raises an error on the PRO IONIZER")
    emu.stdin.write(f"emcy {pi.id} 0x3210 0x05 0x01 0x07\n")
    emu.stdin.flush()
    time.sleep(0.5)
    say(f"pro-ionizer: error register 0x1001 = 0x{pi.sdo.upload(0x1001, 0)[0]:02X}")
    emu.stdin.write(f"emcy-clear {pi.id} 0x3210 0x01 0x07\n")
    emu.stdin.flush()
    time.sleep(0.5)

    step("NMT stop (000#0200): heartbeats go on, PDOs stop")
    network.nmt.state = "STOPPED"
    time.sleep(0.5)
    for device, node in nodes.items():
        say(f"{device}: NMT state from its heartbeat: {node.nmt.state}")


SCALED_UNIT = re.compile(r"(\d+(?:\.\d+)?) (\S.*)")


def with_unit(raw, unit):
    """A PDO value with its unit as a person reads it. A unit with a factor ("0.1 W": the object counts tenths of a
    watt, od/<device>.toml [units]) scales it: 15 with "0.1 W" is "1.5 W", with the factor's decimals."""
    scaled = SCALED_UNIT.fullmatch(unit or "")
    if scaled is not None and isinstance(raw, int) and not isinstance(raw, bool):
        factor = Decimal(scaled.group(1))
        return f"{Decimal(raw) * factor:.{max(0, -factor.as_tuple().exponent)}f} {scaled.group(2)}"
    value = f"{raw:.2f}" if isinstance(raw, float) else str(raw)
    return f"{value} {unit or ''}".rstrip()


def show_values(latest):
    for key in sorted(latest):
        device, index, sub = key
        name, raw = latest[key]
        say(f"{device}: 0x{index:04X}:{sub:02X} {name} = {with_unit(raw, UNITS.get(key))}")


def show_emcy(device, entry):
    data = entry.data
    extra = ""
    if device in ("pro-ionizer", "sds") and len(data) >= 2:
        kind = {1: "error", 5: "warning"}.get(data[0], f"type 0x{data[0]:02X}")
        extra = f", Eltex {kind} code 0x{data[1]:02X}"
    what = "error reset" if entry.code == 0 else entry.get_desc() or "error"
    say(f"{device}: EMCY 0x{entry.code:04X} ({what}), error register 0x{entry.register:02X}{extra}")


if __name__ == "__main__":
    sys.exit(main())
