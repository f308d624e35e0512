#!/usr/bin/env python3
"""Writes od/variants/buerkert-mpdo.eds: the Bürkert flow controller of od/buerkert-flow-controller.eds with more
process values than its four TPDOs carry, the rest sent as SAM-MPDOs on TPDO4 (manual seed 004 §3.2: "if 4 PDOs are
inadequate to send all process values ... the remaining process values are mapped onto PDO 4 ... scanner MPDOs").
The variant is a device read from its EDS (docs/eds.md); its behaviour is od/variants/buerkert-mpdo.yaml. The
layout and the scanner list: docs/devices/buerkert-mpdo.md.

    tools/buerkert-mpdo-eds.py           rewrite the file from the base EDS
    tools/buerkert-mpdo-eds.py --check   exit 1 if the committed file differs from what this script writes
"""
import re
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
BASE = ROOT / "od" / "buerkert-flow-controller.eds"
OUT = ROOT / "od" / "variants" / "buerkert-mpdo.eds"

# Sensor values 0x2500.. (index, name of sub 3), shaped as the base's 0x2500; control values as its 0x2540.
SENSORS = [
    (0x2500, "Flow actual value"),
    (0x2501, "Gas temperature"),
    (0x2502, "Totalized volume"),
    (0x2503, "Valve opening"),
    (0x2504, "Inlet pressure"),
    (0x2505, "Outlet pressure"),
    (0x2506, "Supply voltage"),
    (0x2507, "Device temperature"),
    (0x2508, "Operating time"),
]
CONTROLS = [(0x2540, "Flow set-point"), (0x2541, "Pressure set-point")]
# TPDO n: (sensor values it carries), TPDO4 is the SAM-MPDO of the scanner list.
TPDOS = {1: (0x2500, 0x2501), 2: (0x2502, 0x2503), 3: (0x2504, 0x2505)}
SCANNER = (0x2506, 0x2507, 0x2508)


def sections(text):
    """[(header, body lines)] in file order."""
    out = []
    for chunk in re.split(r"(?m)^(?=\[)", text):
        if chunk.strip():
            head, _, body = chunk.partition("\n")
            out.append((head.strip(), [line for line in body.splitlines() if line.strip()]))
    return out


def var(name, dtype, access, default):
    return [f"ParameterName={name}", "ObjectType=0x7", f"DataType={dtype}", f"AccessType={access}",
            f"DefaultValue={default}", "PDOMapping=0"]


def set_key(body, key, value):
    return [f"{key}={value}" if line.startswith(key + "=") else line for line in body]


def value_record(index, name, access, base, model):
    """A sensor/control value record shaped as the base EDS's record `model` (0x2500/0x2540), with its own name."""
    out = [(f"[{index:04X}]", base[f"[{model:04X}]"])]
    for sub in range(8):
        body = base[f"[{model:04X}sub{sub}]"]
        if sub == 1:
            body = set_key(body, "AccessType", access)
        if sub == 3:
            body = set_key(body, "DefaultValue", name)
        out.append((f"[{index:04X}sub{sub}]", body))
    return out


def build():
    base = sections(BASE.read_text(encoding="utf-8"))
    by_head = dict(base)
    out = []
    for head, body in base:
        if head == "[FileInfo]":
            body = set_key(body, "FileName", "buerkert-mpdo.eds")
            body = set_key(body, "Description", "Buerkert mass flow controller, variant with nine sensor values: "
                           "TPDO1-3 carry six, TPDO4 is a SAM-MPDO sending the rest from the object scanner list "
                           "0x1FA0 (written by tools/buerkert-mpdo-eds.py from buerkert-flow-controller.eds)")
        elif head == "[DeviceInfo]":
            body = set_key(body, "ProductName", "Buerkert MFC multi-value (emulated)")
            body = set_key(body, "OrderCode", "EMU-MFC-MPDO")
        elif head == "[OptionalObjects]":
            n = int(by_head[head][0].split("=")[1])
            body = set_key(body, "SupportedObjects", str(n + 1)) + [f"{n + 1}=0x1FA0"]
        elif head == "[ManufacturerObjects]":
            indices = [i for i, _ in SENSORS] + [i for i, _ in CONTROLS]
            body = [f"SupportedObjects={len(indices) + 4}", "1=0x2000", "2=0x2001", "3=0x2002", "4=0x2004"]
            body += [f"{k}=0x{i:04X}" for k, i in enumerate(indices, start=5)]
        m = re.fullmatch(r"\[(18|1A)0([0-3])sub(\d+)\]", head)
        if m:
            kind, pdo, sub = m.group(1), int(m.group(2)) + 1, int(m.group(3))
            if kind == "18" and sub == 1:  # every TPDO valid
                body = set_key(body, "DefaultValue", f"$NODEID+0x{0x80 + 0x100 * pdo:X}")
            if kind == "18" and sub == 3:  # 100 ms inhibit: the values move all the time
                body = set_key(body, "DefaultValue", "1000")
            if kind == "18" and sub == 5:  # each value at least every second; the MPDO sends one every 100 ms
                body = set_key(body, "DefaultValue", "100" if pdo == 4 else "1000")
            if kind == "1A" and pdo in TPDOS and sub <= 2:
                mapped = TPDOS[pdo]
                body = set_key(body, "DefaultValue", str(len(mapped)) if sub == 0
                               else f"0x{mapped[sub - 1]:04X}0120")
            if kind == "1A" and pdo == 4 and sub == 0:  # 0xFE: SAM-MPDO (CiA 301), above the 8 entries of a PDO
                body = set_key(set_key(body, "DefaultValue", "0xFE"), "HighLimit", "0xFE")
        if head == "[2000]" and "[1FA0]" not in [h for h, _ in out]:
            out += scanner_list()
        if re.fullmatch(r"\[25(00|40)(sub\d)?\]", head):
            continue  # written below with the other values
        out.append((head, body))
    for index, name in SENSORS:
        out += value_record(index, name, "rwr", by_head, 0x2500)
    for index, name in CONTROLS:
        out += value_record(index, name, "rww", by_head, 0x2540)
    return "".join(f"{head}\n" + "".join(f"{line}\n" for line in body) + "\n" for head, body in out)


def scanner_list():
    out = [("[1FA0]", ["ParameterName=Object Scanner List 1", "ObjectType=0x9", f"SubNumber={len(SCANNER) + 1}"]),
           ("[1FA0sub0]", var("Number Of Entries", "0x0005", "rw", str(len(SCANNER))))]
    for k, index in enumerate(SCANNER, start=1):
        # block size 1 << 24 | index << 8 | sub-index 1
        out.append((f"[1FA0sub{k}]", var(f"Scanner Entry {k}", "0x0007", "rw", f"0x01{index:04X}01")))
    return out


def main():
    text = build()
    if "--check" in sys.argv[1:]:
        if not OUT.exists() or OUT.read_text(encoding="utf-8") != text:
            sys.exit(f"{OUT.relative_to(ROOT)} is not what tools/buerkert-mpdo-eds.py writes: run it")
        return
    OUT.parent.mkdir(parents=True, exist_ok=True)
    OUT.write_text(text, encoding="utf-8")


if __name__ == "__main__":
    main()
