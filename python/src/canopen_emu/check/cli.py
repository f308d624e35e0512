"""``canopen-check``: the command line (docs/conformance.md).

Exit status: 0 when no check failed (passed and not applicable only), 1 when one failed, 2 when the run could not
start (usage, an unreadable EDS, a bus that does not open, a node that does not answer)."""
from __future__ import annotations

import argparse
import sys
from pathlib import Path
from typing import List, Optional

from . import report as report_module
from .registry import CHECKS
from .runner import SetupError, run, select


def parse_args(argv: Optional[List[str]]) -> argparse.Namespace:
    parser = argparse.ArgumentParser(
        prog="canopen-check",
        description="Checks a CANopen node against its EDS and CiA 301/305 (docs/conformance.md). Read-only unless "
                    "--write: without it no SDO download and no NMT command is sent.")
    parser.add_argument("eds", nargs="?", type=Path, help="the node's EDS or DCF")
    parser.add_argument("--bus", "--channel", dest="bus", default="vcan0",
                        help="python-can channel (default vcan0; a udp_multicast group, a socketcand channel...)")
    parser.add_argument("--interface", default="socketcan", help="python-can interface (default socketcan)")
    parser.add_argument("--host", help="socketcand: the server's host")
    parser.add_argument("--port", type=int, help="socketcand / udp_multicast: the port")
    parser.add_argument("--node", type=lambda t: int(t, 0), help="the node-ID (1..127; 0x hex allowed)")
    parser.add_argument("--write", action="store_true",
                        help="also run the checks that change the device (SDO downloads of its own values, NMT "
                             "commands); each puts back what it changed")
    parser.add_argument("--only", nargs="+", default=[], metavar="NAME",
                        help="run only these checks (names, groups such as 'od', or patterns such as 'sdo.*')")
    parser.add_argument("--skip", nargs="+", default=[], metavar="NAME", help="leave these checks out")
    parser.add_argument("--junit", type=Path, metavar="FILE", help="also write the results as JUnit XML")
    parser.add_argument("--timeout", type=float, default=1.0, metavar="S",
                        help="seconds an SDO answer, boot-up or LSS answer may take (default 1.0)")
    parser.add_argument("--heartbeat-intervals", type=int, default=3, metavar="N",
                        help="heartbeat periods heartbeat.period watches (default 3)")
    parser.add_argument("-v", "--verbose", action="store_true", help="the frames of passed checks too")
    parser.add_argument("--list", action="store_true", help="list the checks and exit")
    return parser.parse_args(argv)


def main(argv: Optional[List[str]] = None) -> int:
    args = parse_args(argv)
    if args.list:
        for chosen in CHECKS.values():
            print(f"{chosen.name:32} {'(--write) ' if chosen.writes else ''}{chosen.summary}\n"
                  f"{'':32} {chosen.clause}")
        return 0
    if args.eds is None or args.node is None:
        print("canopen-check: give the EDS and --node (canopen-check --help)", file=sys.stderr)
        return 2
    try:
        select(args.only, args.skip)
    except ValueError as e:
        print(f"canopen-check: {e}", file=sys.stderr)
        return 2
    bus_args = {"interface": args.interface, "channel": args.bus}
    if args.host is not None:
        bus_args["host"] = args.host
    if args.port is not None:
        bus_args["port"] = args.port

    def progress(result: report_module.Result) -> None:
        print(report_module.result_line(result), flush=True)
        if result.failed or args.verbose and result.frames:
            print(report_module.result_details(result), flush=True)

    print(f"canopen-check: node {args.node} on {args.bus} ({args.interface}), {args.eds}"
          f"{'' if args.write else ', read-only'}", flush=True)
    try:
        report = run(bus_args, args.node, args.eds, write=args.write, only=args.only, skip=args.skip,
                     timeout=args.timeout, heartbeat_intervals=args.heartbeat_intervals, progress=progress)
    except SetupError as e:
        print(f"canopen-check: {e}", file=sys.stderr)
        return 2
    print(report_module.summary(report))
    if args.junit is not None:
        args.junit.write_text(report_module.junit_xml(report))
    return 0 if report.ok else 1


if __name__ == "__main__":
    sys.exit(main())
