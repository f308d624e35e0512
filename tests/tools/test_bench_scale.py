"""tools/bench-scale and bench/scale_cost.py (issue 36: instructions per event by nodes and watchers): the figures
come out of the phases as the method says (every row, each event counted, each cost in the range of a whole
program's cost of that event, the watcher's frame events delivered), and the document's section is put in its place, replaced on the next run, and kept by
tools/bench when that one rewrites docs/performance.md.

Environment (bench/CMakeLists.txt): CO_SOURCE_DIR, CO_EMU_FAKECAN (the Release or RelWithDebInfo program).
"""

import importlib.machinery
import json
import importlib.util
import os
import shutil
import sys
from pathlib import Path

import pytest

REPO = Path(os.environ.get("CO_SOURCE_DIR") or Path(__file__).resolve().parents[2])
EMU = os.environ.get("CO_EMU_FAKECAN")
sys.path.insert(0, str(REPO / "bench"))
import scale_cost  # noqa: E402


def load_tool(name):
    loader = importlib.machinery.SourceFileLoader(name.replace("-", "_"), str(REPO / "tools" / name))
    spec = importlib.util.spec_from_loader(loader.name, loader)
    module = importlib.util.module_from_spec(spec)
    loader.exec_module(module)
    return module


def need_callgrind():
    if not EMU:
        pytest.fail("CO_EMU_FAKECAN is not set (the test is run by ctest: bench/CMakeLists.txt)", pytrace=False)
    if shutil.which("valgrind") is None or shutil.which("callgrind_control") is None:
        pytest.skip("no valgrind here")


SMALL = dict(sdo=60, frame=60, hold_s=1.5, web=10)


def test_one_node_rows(tmp_path):
    """One node: the three rows from one pair of runs, each event counted and each cost where a whole program's
    cost of that event lies (the one-node rows of docs/performance.md: hundreds of instructions, not tens of
    thousands); the run without events has none of them."""
    need_callgrind()
    res = scale_cost.measure(EMU, str(tmp_path), "n1", SMALL, log=lambda s: None)
    rows = res["rows"]
    assert set(rows) == {"sdo", "frame", "heartbeat"}
    assert rows["sdo"]["events"] == SMALL["sdo"] and rows["frame"]["events"] == SMALL["frame"]
    assert 100 <= rows["heartbeat"]["events"] <= 160  # 10 ms for 1.5 s, as valgrind keeps up
    assert 400 <= rows["sdo"]["ir_per_event"] <= 3000, rows["sdo"]
    assert 100 <= rows["frame"]["ir_per_event"] <= 1500, rows["frame"]
    assert 200 <= rows["heartbeat"]["ir_per_event"] <= 3000, rows["heartbeat"]
    for row in rows.values():
        assert row["ir_k"] > row["ir_0"] > 0


def test_web_watcher_rows(tmp_path, monkeypatch):
    """Two nodes and a web session tracing every frame on its WebSocket: the session got every frame as an event
    (the requests and the answers), each costs the emulator a thousand instructions and more; the empty HTTP
    exchange, the empty message and the request on the socket have their rows, the message far below the exchange."""
    need_callgrind()
    monkeypatch.setitem(scale_cost.SETUPS, "n2_web", (2, "web"))
    res = scale_cost.measure(EMU, str(tmp_path), "n2_web", SMALL, log=lambda s: None)
    rows = res["rows"]
    assert set(rows) == {"sdo", "frame", "heartbeat", "web", "web_message", "web_request"}
    assert res["watcher_frame_events"] >= 2 * SMALL["sdo"] + SMALL["frame"]
    assert rows["frame"]["ir_per_event"] > 1000, rows["frame"]  # the event's writing and delivery: thousands
    assert rows["sdo"]["ir_per_event"] > rows["frame"]["ir_per_event"], rows  # two events and the node's work
    assert rows["web"]["events"] == SMALL["web"] and rows["web"]["ir_per_event"] > 10000, rows["web"]
    assert rows["web_message"]["events"] == SMALL["web"], rows["web_message"]
    assert 300 < rows["web_message"]["ir_per_event"] < rows["web"]["ir_per_event"] / 4, rows
    assert rows["web_request"]["ir_per_event"] > rows["web_message"]["ir_per_event"], rows  # a command's work more


FIGURES = {"sizes": scale_cost.SIZES["full"], "setups": {
    "n1": {"nodes": 1, "watcher": None, "command": "valgrind --tool=callgrind --callgrind-out-file=/w/callgrind.n1_k "
           "/b/canopen-emu-fakecan -i fakecan0 --nvm-dir /w/n1_k/nvm -q buerkert:1",
           "rows": {"sdo": {"events": 10, "ir_k": 9000, "ir_0": 1000, "ir_per_event": 800.0}}}}}
META = {"date": "2026-12-07 10:00 UTC", "commit": "abc1234", "elapsed_s": 1.0, "flags": "", "load_after": "0 0 0",
        "host": {"cpu": "cpu", "cores": 2, "kernel": "6", "cc": "cc", "valgrind": "valgrind-3", "loadavg": "0 0 0"}}
DOC = "# Performance\n\nintro\n\n## CPU: instructions\n\nrows\n\n## Scale: 127 nodes in one process\n\nscale\n"


def test_section_placed_replaced_and_kept(tmp_path):
    """The section goes before "## Scale: 127 nodes", replaces itself on the next run (never twice), shows the
    measured figure beside the issue's, and a rewrite by tools/bench (which knows nothing of it) keeps it."""
    tool, bench = load_tool("bench-scale"), load_tool("bench")
    doc = tmp_path / "performance.md"
    doc.write_text(DOC)
    tool.replace_section(str(doc), tool.section(FIGURES, META))
    first = doc.read_text()
    assert first.index(tool.HEADING) < first.index("## Scale: 127 nodes") and first.count(tool.HEADING) == 1
    assert "| SDO request | **800** (792) |" in first
    assert "canopen-emu-fakecan -i fakecan0 --nvm-dir $WORK/nvm -q buerkert:1" in first
    FIGURES["setups"]["n1"]["rows"]["sdo"]["ir_per_event"] = 850.0
    tool.replace_section(str(doc), tool.section(FIGURES, META))
    second = doc.read_text()
    assert second.count(tool.HEADING) == 1 and "**850** (792)" in second and "**800**" not in second
    assert tool.HAND_MARK == bench.HAND_MARK
    regenerated = bench.keep_hand_sections(DOC, second)  # tools/bench writes the document afresh
    assert tool.section(FIGURES, META) in regenerated
    assert regenerated.index(tool.HEADING) < regenerated.index("## Scale: 127 nodes")


def test_the_guard_holds_rows_to_their_figures(tmp_path, monkeypatch, capsys):
    """bench/scale-guard (tools/bench-scale --check): a row within 5 % of bench/scale_figures.json passes, one 6 %
    dearer or 6 % cheaper fails and is named, a row the run did not give fails; the figures file written with the
    section holds exactly the guarded rows."""
    tool = load_tool("bench-scale")
    measured = {"n1": {"sdo": 1040.0, "frame": 250.0}}

    def fake_measure(emu, work, name, sz, log=print):
        assert sz == scale_cost.SIZES["full"]  # the guarded rows repeat within 2 % only at full sizes
        return {"rows": {phase: {"ir_per_event": v} for phase, v in measured[name].items()}}
    monkeypatch.setattr(tool.scale_cost, "measure", fake_measure)
    monkeypatch.setattr(tool.shutil, "which", lambda name: "/usr/bin/" + name)
    figures = tmp_path / "figures.json"

    def guard(rows):
        figures.write_text(json.dumps({"commit": "abc1234", "tolerance": 0.05, "rows": {"n1": rows}}))
        return tool.check(str(tmp_path / "build"), emu="/bin/true", figures=str(figures))
    assert guard({"sdo": 1000, "frame": 250}) == 0  # +4 %
    assert guard({"sdo": 980, "frame": 250}) == 1  # +6 %: dearer
    assert "n1 sdo" in capsys.readouterr().err
    assert guard({"sdo": 1110, "frame": 250}) == 1  # -6 %: cheaper, the figures are to be written anew
    assert guard({"sdo": 1040, "heartbeat": 600}) == 1  # a row the run did not give
    written = tmp_path / "written.json"
    res = {"setups": {"n1": {"rows": {p: {"ir_per_event": v} for p, v in
                                       {"sdo": 724.4, "frame": 253.0, "heartbeat": 624.6}.items()}},
                      "n32": {"rows": {"sdo": {"ir_per_event": 740.0}}},
                      "n127": {"rows": {"sdo": {"ir_per_event": 791.0}, "heartbeat": {"ir_per_event": 715.2}}}}}
    tool.write_guarded(str(written), res, META)
    kept = json.loads(written.read_text())
    assert kept["rows"] == {"n1": {"sdo": 724, "frame": 253, "heartbeat": 625}}  # n32's, n127's rows: not guarded
    assert kept["tolerance"] == 0.05 and kept["commit"] == META["commit"]
