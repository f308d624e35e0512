"""Rules files (--rules, docs/eds.md "Rules") that canopen-emu must refuse before it starts, with the place and the
reason on stderr and status 2, quickly and in little memory: anchors and aliases (an alias repeats a subtree: a
1.65 MB file once grew to 6.4 GB and slowed every tick), a key twice in a mapping, a second YAML document, deep
nesting (400 kB of it took minutes), too many values, objects or alarms, a file over 1 MiB; and the rules files the
project uses, which must still run. Against canopen-emu-fakecan (test_emulator_native.py), in the plain and in the
ASan+UBSan build.

Environment (tests/native/CMakeLists.txt): CO_SOURCE_DIR, CO_EMU_FAKECAN (the program), CO_SANITIZED.
"""

import os
import subprocess
import time

import pytest

from test_emulator_native import EMU, SANITIZER_MARKS, SRC, download, start_program, upload

DRIVE = SRC / "tests" / "eds" / "files" / "drive.eds"
NODE = 5
# Refusals come before any node starts: well within this even in the ASan+UBSan build (400 kB of nesting once took
# 114 s and more; a timeout here is the test failing).
REFUSE_TIMEOUT = 60


def refuse(tmp_path, text, name="rules.yaml"):
    """canopen-emu-fakecan run with the rules file `text`: it must end with status 2 before it looks for its bus.
    Returns its stderr with the directory taken off the file's path (so messages read "rules.yaml:3:1: error: ...")."""
    if not EMU:
        pytest.fail("CO_EMU_FAKECAN is not set (the test is run by ctest: tests/native/CMakeLists.txt)", pytrace=False)
    path = tmp_path / name
    path.write_bytes(text.encode() if isinstance(text, str) else text)
    env = dict(os.environ, CO_FAKECAN_SOCKET=str(tmp_path / "no-bus"),
               ASAN_OPTIONS="detect_leaks=1:abort_on_error=0:halt_on_error=1",
               UBSAN_OPTIONS="halt_on_error=1:print_stacktrace=1")
    try:
        r = subprocess.run([EMU, "-i", "fakecan0", "--rules", str(path), f"{DRIVE}:{NODE}"], capture_output=True,
                           text=True, env=env, timeout=REFUSE_TIMEOUT)
    except subprocess.TimeoutExpired:
        pytest.fail(f"canopen-emu did not refuse {name} within {REFUSE_TIMEOUT} s", pytrace=False)
    assert not any(mark in r.stderr for mark in SANITIZER_MARKS), r.stderr[-6000:]
    assert r.returncode == 2, (r.returncode, r.stderr[-3000:])
    return r.stderr.replace(str(tmp_path) + "/", "")


# ---- anchors and aliases ---------------------------------------------------------------------------------------

def test_an_anchor_is_refused_where_it_stands(tmp_path):
    """A rule body shared by an anchor and an alias: valid YAML a loader expands, refused at the anchor."""
    err = refuse(tmp_path, 'objects:\n'
                           '  "0x2000": &wave {sine: {amplitude: 5, period_ms: 100}}\n'
                           '  "0x2003": *wave\n')
    assert "rules.yaml:2:13: error: an anchor (&wave): a rules file takes no anchors or aliases" in err, err
    assert err.count("error:") == 1, err


def test_an_alias_is_refused_where_it_stands(tmp_path):
    """An alias without its anchor in the file (the anchor may be anywhere in a file that repeats a subtree
    thousands of times: the first of either stops the reading)."""
    err = refuse(tmp_path, 'objects:\n  "0x2000": {constant: 1}\n  "0x2003": *wave\n')
    assert "rules.yaml:3:13: error: an alias (*wave): a rules file takes no anchors or aliases" in err, err


def test_laughs_are_refused_at_once(tmp_path):
    """The "billion laughs" shape: each list repeats the one before it ten times, 30 levels (10^30 values once
    expanded). Refused at the first anchor, having built nothing."""
    lines = ['objects:', '  "0x2004": {steps: &l0 [[1, 1], [2, 1], [3, 1], [4, 1], [5, 1]]}']
    lines += [f"  \"0x20{i:02X}\": {{steps: &l{i} [{', '.join([f'*l{i - 1}'] * 10)}]}}" for i in range(1, 31)]
    err = refuse(tmp_path, "\n".join(lines) + "\n")
    assert "rules.yaml:2:21: error: an anchor (&l0)" in err, err


# ---- duplicate keys --------------------------------------------------------------------------------------------

DUPLICATES = {
    # a top-level key twice: which tick_ms holds?
    "top-level": ("tick_ms: 10\nobjects:\n  \"0x2000\": {constant: 1}\ntick_ms: 20\n",
                  "rules.yaml:4:1: error: the key 'tick_ms' is given twice in this mapping (first at line 1, column 1)"),
    # one object twice in objects, spelled the same way (quoted and plain are one key)
    "object": ('objects:\n  "0x2000": {constant: 1}\n  0x2001: {constant: 2}\n  0x2000: {constant: 3}\n',
               "rules.yaml:4:3: error: the key '0x2000' is given twice in this mapping (first at line 2, column 3)"),
    # a parameter twice inside a behaviour
    "parameter": ('objects:\n  "0x2000": {sine: {amplitude: 1, period_ms: 100, amplitude: 2}}\n',
                  "rules.yaml:2:51: error: the key 'amplitude' is given twice in this mapping (first at line 2, "
                  "column 21)"),
    # one object under two spellings: not a duplicate key for YAML, still two rules for one object
    "object-spelled-twice": ('objects:\n  "0x2000": {constant: 1}\n  "0x2000:00": {constant: 2}\n',
                             "rules.yaml:3:3: error: objects: '0x2000:00' names an object that has a rule already "
                             "(at line 2, column 3)"),
}


@pytest.mark.parametrize("case", sorted(DUPLICATES))
def test_a_key_given_twice_is_refused(tmp_path, case):
    text, message = DUPLICATES[case]
    err = refuse(tmp_path, text)
    assert message in err, err


def test_the_first_duplicate_in_the_file_is_named(tmp_path):
    """Of several duplicate keys in one large mapping, the one earliest in the file (not in sorted order)."""
    keys = [f"k{i:05d}" for i in range(20000)]
    body = "".join(f"    {k}: 1\n" for k in keys) + "    k19999: 2\n    k00005: 2\n"
    err = refuse(tmp_path, 'objects:\n  "0x2000":\n   sine:\n' + body.replace("    ", "     "))
    assert "rules.yaml:20004:6: error: the key 'k19999' is given twice in this mapping (first at line 20003, column 6)" \
        in err, err


# ---- a second document -----------------------------------------------------------------------------------------

SECOND_DOCUMENTS = {
    "---\n": "rules.yaml:3:1: error: a second YAML document: a rules file is one document",
    "...\n---\n": "rules.yaml:4:1: error: a second YAML document: a rules file is one document",
    # after an end marker YAML wants a start marker: what follows is no document
    "...\n": "rules.yaml:4:1: error: not YAML: did not find expected <document start>",
}


@pytest.mark.parametrize("separator", sorted(SECOND_DOCUMENTS))
def test_a_second_document_is_refused(tmp_path, separator):
    """Everything after the first document was ignored: the rules that were meant were not the rules that ran."""
    text = 'objects:\n  "0x2000": {constant: 1}\n' + separator + 'objects:\n  "0x2001": {constant: 2}\n'
    err = refuse(tmp_path, text)
    assert SECOND_DOCUMENTS[separator] in err, err


# ---- depth and size --------------------------------------------------------------------------------------------

NESTING = {
    "flow-lists": "objects: " + "[" * 200000 + "]" * 200000 + "\n",
    "flow-mappings": "objects: " + "{a: " * 80000 + "1" + "}" * 80000 + "\n",
    "block-mappings": "".join(" " * i + "a:\n" for i in range(890)) + " " * 890 + "1\n",
    "block-lists": "- " * 170000 + "1\n",
}


@pytest.mark.parametrize("case", sorted(NESTING))
def test_deep_nesting_is_refused_at_its_limit(tmp_path, case):
    """Some 400 kB of nesting, refused where the 17th level opens (the reader stops there; before, libyaml's
    loader read it all, in time quadratic in the depth)."""
    text = NESTING[case]
    assert len(text) >= 320000
    err = refuse(tmp_path, text)
    assert "error: lists and mappings nested deeper than 16 levels: a rules file needs 5" in err, err
    assert err.count("error:") == 1, err


def test_nesting_to_the_limit_is_read(tmp_path):
    """16 levels are read as YAML (and then refused by the rules, at the place that is not a rule body)."""
    err = refuse(tmp_path, 'objects:\n  "0x2004": {steps: ' + "[" * 13 + "]" * 13 + "}\n")  # 3 + 13 levels
    assert "nested deeper" not in err and "rules.yaml:2:22: error: steps: each step is [value, ms]" in err, err


def test_too_many_values_are_refused(tmp_path):
    """A steps list of 30,000 steps (90,000 values, 180 kB): more than 65,536 values in the file."""
    err = refuse(tmp_path, 'objects:\n  "0x2004": {steps: [' + ", ".join(["[1, 1]"] * 30000) + "]}\n")
    assert "error: more than 65536 values, lists and mappings: a rules file needs far fewer" in err, err


def test_too_many_objects_and_alarms_are_refused(tmp_path):
    """Every rule is a write every tick, every alarm a read: more than 1024 rules or 256 alarms are refused as a
    whole, before any of them is looked at (one line, not one per object)."""
    objects = "".join(f'  "0x{0x3000 + i:04X}": {{constant: 1}}\n' for i in range(1025))
    err = refuse(tmp_path, "objects:\n" + objects)
    assert "rules.yaml:2:3: error: objects: more than 1024 objects (each one is written every tick)" in err, err
    assert err.count("error:") == 1, err
    alarms = "".join('  - {object: "0x2000", above: 5, emcy: 0x4210}\n' for _ in range(257))
    err = refuse(tmp_path, "alarms:\n" + alarms)
    assert "rules.yaml:2:3: error: alarms: more than 256 alarms (each one reads its object every tick)" in err, err


def test_many_errors_are_cut_short(tmp_path):
    """A thousand wrong keys give twenty error lines and one saying more were found."""
    err = refuse(tmp_path, "".join(f"wrong{i}: 1\n" for i in range(1000)))
    assert err.count("rules.yaml:") == 21 and "rules.yaml: error: more errors follow; the first 20 are shown" in err, err


def test_a_file_over_1_mib_is_refused_unread(tmp_path):
    """A comment of 1 MiB: no YAML error, the size."""
    err = refuse(tmp_path, "#" + "x" * (1 << 20) + "\n")
    assert "rules.yaml: error: larger than 1048576 bytes: not read" in err, err


def test_a_nul_in_a_value_is_refused(tmp_path):
    """A value is a C string to the rules: "0x2000\\0junk" would have been read as 0x2000."""
    err = refuse(tmp_path, 'objects:\n  "0x2000\\0junk": {constant: 1}\n')
    assert "rules.yaml:2:3: error: a value with a NUL character" in err, err


def test_an_error_quoting_the_files_words_stays_one_line_and_escaped(tmp_path):
    """A message quotes a key or a value of the file: one with line breaks and ESC[2J made several lines of the log
    and reached the terminal raw (found by the rules fuzz target). Escaped as the log is (text_escape.h)."""
    err = refuse(tmp_path, 'objects:\n  "0x20\\n\\n\\e[2J05": {constant: 1}\n')
    assert "'0x20\\x0a\\x0a\\x1b[2J05' is not an object" in err and "\x1b" not in err, err
    assert len(err.splitlines()) == 1, err
    err = refuse(tmp_path, 'objects:\n  "0x2002\\n\\ex": {constant: 1}\n  "0x2002\\n\\ex": {constant: 2}\n')
    assert "the key '0x2002\\x0a\\x1bx' is given twice" in err and "\x1b" not in err, err
    assert len(err.splitlines()) == 1, err


def test_not_yaml_names_line_and_column(tmp_path):
    err = refuse(tmp_path, "objects: [\n")
    assert "rules.yaml:2:1: error: not YAML: did not find expected node content" in err, err


# ---- files that run --------------------------------------------------------------------------------------------

def run_rules(tmp_path, text):
    """canopen-emu-fakecan with the drive and the rules `text`: boots node 5; the caller quits it."""
    path = tmp_path / f"rules-{time.monotonic_ns()}.yaml"
    path.write_text(text)
    bus, proc = start_program(tmp_path, "--nvm-dir", str(tmp_path / "nvm"), "--rules", str(path), f"{DRIVE}:{NODE}")
    try:
        bus.accept()
    except OSError:
        proc.kill()
        raise AssertionError("canopen-emu did not start:\n" + proc.communicate()[1][-3000:])
    bus.expect(lambda i, d: i == 0x700 + NODE and d == b"\0", 10.0, "boot-up of the drive")
    return bus, proc


def quit_clean(bus, proc):
    proc.stdin.write("quit\n")
    proc.stdin.flush()
    try:
        _, err = proc.communicate(timeout=20)
    finally:
        bus.close()
    assert not any(mark in err for mark in SANITIZER_MARKS), err[-6000:]
    assert proc.returncode == 0, err[-3000:]


def sdo_value(bus, index, sub=0):
    return int.from_bytes(bus.sdo(NODE, upload(index, sub))[4:8], "little")


def test_the_project_rules_files_run(tmp_path):
    """tests/eds/rules/drive.yaml (every behaviour, an alarm, CiA 402): its steps on 0x2004 go 1, 2, 3 in turn
    (300, 200, 100 ms), its counter on 0x2001 counts, and the drive answers the CiA 402 machine."""
    bus, proc = run_rules(tmp_path, (SRC / "tests" / "eds" / "rules" / "drive.yaml").read_text())
    seen = set()
    end = time.monotonic() + 5.0
    while seen != {1, 2, 3} and time.monotonic() < end:
        seen.add(sdo_value(bus, 0x2004))
        time.sleep(0.02)
    assert seen == {1, 2, 3}, seen
    first = sdo_value(bus, 0x2001)
    time.sleep(1.2)
    assert sdo_value(bus, 0x2001) > first
    assert bus.sdo(NODE, download(0x6040, 0, 0x06, 2))[0] == 0x60
    assert sdo_value(bus, 0x6041) & 0x6F == 0x21  # ready to switch on
    quit_clean(bus, proc)


ACCEPTED = {
    # test_eds_rules.py's file for the profile alone
    "profile-only": ("profile: cia402\n", (0x6041, lambda v: v & 0x4F == 0x40)),  # switch on disabled
    # the fuzz seeds' small files (tests/fuzz/make_corpus.py)
    "walk-counter": ('objects:\n  "0x2002": {random_walk: {start: 480, step: 2, min: 470, max: 490, seed: 3, '
                     'every_ms: 1}}\n  "0x2001": {counter: {start: 5, step: 2, every_ms: 10, wrap: 40}}\n',
                     (0x2002, lambda v: 470 <= v <= 490)),
    "follow-steps-alarm": ('objects:\n  "0x2006": {follow: {object: "0x2005", lag_ms: 50, gain: 2}}\n'
                           '  "0x2004": {steps: [[1, 5], [7, 10]]}\nalarms:\n  - {object: "0x2006", above: 5, '
                           'hysteresis: 1, emcy: 0x2310}\n', (0x2004, lambda v: v in (1, 7))),
    # one explicit document with its markers, comments, a tag, block style throughout
    "markers": ("%YAML 1.1\n--- # the drive\ndevice: drive.eds\nobjects:\n  0x2003:\n    ramp:\n      from: 0\n"
                "      to: !!float 1000\n      per_s: 500\n  '0x2004':\n    steps:\n      - [1, 300]\n      - - 2\n"
                "        - 200\n...\n", (0x2004, lambda v: v in (1, 2))),
}


@pytest.mark.parametrize("case", sorted(ACCEPTED))
def test_small_rules_files_run(tmp_path, case):
    """Each runs: the drive boots and a value its rules set is there (the statusword of the profile alone)."""
    bus, proc = run_rules(tmp_path, ACCEPTED[case][0])
    index, allowed = ACCEPTED[case][1]
    value = sdo_value(bus, index)
    assert allowed(value), (hex(index), value)
    quit_clean(bus, proc)


def test_a_steps_list_of_thousands_runs(tmp_path):
    """10,000 steps of 1 ms with values 0..9999 on 0x2001 (UNSIGNED32): a step's value is found by bisection each
    tick (the list was walked twice a tick); the values seen are steps' values, and they move."""
    steps = ", ".join(f"[{i}, 1]" for i in range(10000))
    bus, proc = run_rules(tmp_path, f'tick_ms: 1\nobjects:\n  "0x2001": {{steps: [{steps}]}}\n')
    values = [sdo_value(bus, 0x2001) for _ in range(20)]
    assert all(0 <= v < 10000 for v in values) and len(set(values)) > 1, values
    quit_clean(bus, proc)


def test_built_in_nodes_keep_their_heartbeat_beside_the_largest_rules(tmp_path):
    """1,024 objects is the most a file may give; the drive has few, so the largest legal load here is every
    numeric object with a 1 ms tick next to a built-in node: its heartbeats keep coming (loose bounds)."""
    objs = ["0x2000", "0x2001", "0x2002", "0x2003", "0x2004", "0x2006", "0x6064", "0x606C"]
    text = "tick_ms: 1\nobjects:\n" + "".join(f'  "{o}": {{sine: {{amplitude: 5, period_ms: 50}}}}\n' for o in objs)
    path = tmp_path / "busy.yaml"
    path.write_text(text)
    bus, proc = start_program(tmp_path, "--nvm-dir", str(tmp_path / "nvm"), "--rules", str(path), f"{DRIVE}:{NODE}",
                              "sds:17")
    bus.accept()
    bus.expect(lambda i, d: i == 0x711 and d == b"\0", 10.0, "boot-up of node 17")
    assert bus.sdo(17, download(0x1017, 0, 100, 2))[0] == 0x60
    t0, _, _ = bus.expect(lambda i, d: i == 0x711, 5.0, "heartbeat of node 17")
    t1, _, _ = bus.expect(lambda i, d: i == 0x711, 5.0, "next heartbeat of node 17")
    assert t1 - t0 < 1.0, t1 - t0
    quit_clean(bus, proc)
