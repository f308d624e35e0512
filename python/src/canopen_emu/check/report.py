"""The report of a run: text for a person (one line per check, the message and frames of each failure), and JUnit
XML for CI (one testcase per check, classname ``canopen-check.GROUP``; not applicable is ``<skipped>``)."""
from __future__ import annotations

import socket
import xml.etree.ElementTree as ET
from datetime import datetime, timezone
from typing import TYPE_CHECKING, TextIO

from .frames import describe_frames
from .registry import Result, Status

if TYPE_CHECKING:
    from .runner import Report

MARKS = {Status.PASSED: "PASS", Status.FAILED: "FAIL", Status.ERROR: "ERROR", Status.NOT_APPLICABLE: "n/a "}


def result_line(result: Result) -> str:
    """``PASS  od.readable-entries  (0.12 s)  96 entries``: the first line of the message only."""
    note = result.message.splitlines()[0] if result.message else ""
    return f"{MARKS[result.status]}  {result.name:32} ({result.duration:5.2f} s)  {note}".rstrip()


def result_details(result: Result) -> str:
    """What a failure shows under its line: the whole message, the clause, the frames."""
    lines = [f"    {line}" for line in result.message.splitlines()[1:]]
    lines.append(f"    rule: {result.check.clause}")
    lines.append("    frames:")
    lines += [f"      {line}" for line in describe_frames(result.frames).splitlines()]
    return "\n".join(lines)


def write_text(report: "Report", out: TextIO, verbose: bool = False) -> None:
    out.write(f"canopen-check: node {report.node} on {report.bus}, {report.eds_path}\n")
    for result in report.results:
        out.write(result_line(result) + "\n")
        if result.failed or verbose and result.frames:
            out.write(result_details(result) + "\n")
    out.write(summary(report) + "\n")


def summary(report: "Report") -> str:
    failed = report.count(Status.FAILED) + report.count(Status.ERROR)
    return (f"{report.count(Status.PASSED)} passed, {failed} failed, {report.count(Status.NOT_APPLICABLE)} not "
            f"applicable ({report.duration:.1f} s)")


def junit_xml(report: "Report") -> str:
    """JUnit XML (the xunit2 form pytest writes): testsuites with one testsuite ``canopen-check node N``."""
    failures = report.count(Status.FAILED)
    errors = report.count(Status.ERROR)
    root = ET.Element("testsuites")
    suite = ET.SubElement(root, "testsuite", name=f"canopen-check node {report.node}", tests=str(len(report.results)),
                       failures=str(failures), errors=str(errors),
                       skipped=str(report.count(Status.NOT_APPLICABLE)), time=f"{report.duration:.3f}",
                       timestamp=datetime.fromtimestamp(report.started, timezone.utc).isoformat(timespec="seconds"),
                       hostname=socket.gethostname())
    properties = ET.SubElement(suite, "properties")
    for name, value in (("node", str(report.node)), ("bus", report.bus), ("eds", str(report.eds_path))):
        ET.SubElement(properties, "property", name=name, value=value)
    for result in report.results:
        case = ET.SubElement(suite, "testcase", classname=f"canopen-check.{result.check.group}", name=result.name,
                             time=f"{result.duration:.3f}")
        first = result.message.splitlines()[0] if result.message else ""
        if result.status is Status.NOT_APPLICABLE:
            ET.SubElement(case, "skipped", message=first)
        elif result.failed:
            tag = "failure" if result.status is Status.FAILED else "error"
            element = ET.SubElement(case, tag, message=first)
            element.text = result.message + "\n\nrule: " + result.check.clause + "\nframes:\n" + \
                describe_frames(result.frames)
        elif result.message:
            ET.SubElement(case, "system-out").text = result.message
    ET.indent(root)
    return '<?xml version="1.0" encoding="utf-8"?>\n' + ET.tostring(root, encoding="unicode") + "\n"
