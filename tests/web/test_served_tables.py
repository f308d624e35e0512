"""The tables the page is served (`tables`, docs/control-protocol.md) against the program and the page: the kinds of
protocol fault are what `fault NODE` takes, each with its usage's arguments and refused with that usage; the abort
texts are the core's list (include/co/co_abort.h); the node view offers exactly the served kinds, with their usages
and texts, and the node commands the emulator's `help` names. A kind of fault added to the program gets its form
without a change to the page, and these tests check it like the others."""

import re
import sys
from pathlib import Path

from selenium.webdriver.common.by import By
from selenium.webdriver.support.ui import WebDriverWait

from test_emulator_native import SRC  # the source tree (tests/native is on the path: conftest.py)

sys.path.insert(0, str(SRC / "tests/support"))
from control_schema import check_schema  # noqa: E402

# A value each argument word of a fault's usage takes, by the word: a kind with a new word fails here until it has
# one (what may a test pass it?), not silently. Every kind of fault is tried with all its arguments given.
SAMPLES = {"N|P%": "25%", "SEED": "7", "MS": "100", "INDEX[:SUB]": "0x1017:00", "CODE": "0x5000", "BYTE": "0x05",
           "N": "1", "EVERY": "3", "LEN": "2", "COUNT": "2"}


def served_tables(emu):
    """The `tables` answer over a web session of emu, as the page asks it; checked against the protocol's schema."""
    session = emu.open_session()
    (answer,) = [l for l in emu.exchange(session, '{"id":1,"cmd":"tables"}').lines() if isinstance(l, dict)]
    assert answer["ok"] is True, answer
    check_schema(answer, "tables")
    return answer


def run(emu, session, line):
    """A line of the command language over a web session: its reply lines."""
    return [l for l in emu.exchange(session, line).lines() if isinstance(l, str)]


def arguments(usage):
    """The argument words of a fault's usage (after its kind): "sdo-ignore [N | P% [SEED]]" -> ["N|P%", "SEED"]."""
    words = re.sub(r" *\| *", "|", usage).split()[1:]
    return [re.sub(r"^\[|\]+$", "", w) if w.startswith("[") else w for w in words]  # "INDEX[:SUB]" stays whole


def test_the_served_fault_kinds_are_what_fault_node_takes(start_emulator):
    emu = start_emulator("sds:16")
    faults = served_tables(emu)["faults"]
    session = emu.open_session()
    (listing,) = run(emu, session, "fault 16")
    kinds = re.fullmatch(r"node 16: error: usage: fault NODE KIND \[ARGS\] \(kinds: ([^)]*)\)", listing).group(1)
    assert [f["kind"] for f in faults] == kinds.split(), listing
    for f in faults:
        kind, usage, limits = f["kind"], f["usage"], f["limits"]
        assert usage.split()[0] == kind, f
        # too many words: refused with the served usage and limits, word for word
        told = run(emu, session, f"fault 16 {kind} 1 2 3 4 5 6")
        expected = f"node 16: error: usage: fault NODE {usage}" + (f" ({limits})" if limits else "")
        assert told == [expected], (kind, told)
        # every argument the usage names, given: taken
        words = [SAMPLES[a] for a in arguments(usage)]
        taken = run(emu, session, f"fault 16 {kind} {' '.join(words)}".strip())
        assert taken and all(l.startswith(f"node 16: fault {kind}") for l in taken), (kind, words, taken)
        run(emu, session, "fault-clear 16")


def core_aborts():
    """The core's abort codes and texts: CO_ABORT_LIST of its public header (co_abort_entry() reads that list, in its
    order: tests/unit/test_sdo.c)."""
    header = (SRC / "include/co/co_abort.h").read_text()
    listed = [(int(code, 16), text) for code, text in re.findall(r'X\(\w+, (0x[0-9A-F]{8})UL, "([^"]*)"\)', header)]
    assert len(listed) == header.count(" X("), "an entry of CO_ABORT_LIST this test cannot read"
    return listed


def test_the_served_aborts_are_the_cores_list(start_emulator):
    emu = start_emulator("sds:16")
    aborts = served_tables(emu)["aborts"]
    assert [(a["code"], a["text"]) for a in aborts] == core_aborts()


# The node view's fault forms and node commands at one moment: [kind or command, usage shown, help, fields].
FORMS = """
const forms = (list) => list.map((form) => ({
  name: form.dataset.fault ?? form.dataset.command, usage: form.querySelector(".usage").textContent,
  help: form.querySelector(".help").textContent,
  fields: [...form.querySelectorAll(".fields input")].map((i) => i.getAttribute("aria-label"))}));
const all = [...document.querySelectorAll("#view-node form.command")];
return {faults: forms(all.filter((f) => f.classList.contains("fault"))),
        node: forms(all.filter((f) => !f.classList.contains("fault") && f.closest(".device-commands") === null))};
"""


def open_node(page, emu, node):
    driver = page(emu)
    row = WebDriverWait(driver, 30.0, poll_frequency=0.05).until(
        lambda d: d.find_elements(By.CSS_SELECTOR, f'#nodes tr[data-key="fakecan0/{node}"]'))[0]
    row.click()
    WebDriverWait(driver, 10.0, poll_frequency=0.05).until(lambda d: d.execute_script(FORMS)["faults"])
    return driver


def test_the_node_view_offers_exactly_the_served_fault_kinds(page, start_emulator):
    emu = start_emulator("sds:16")
    faults = served_tables(emu)["faults"]
    shown = open_node(page, emu, 16).execute_script(FORMS)["faults"]
    assert [f["name"] for f in shown] == [f["kind"] for f in faults]
    for form, f in zip(shown, faults):
        assert form["usage"] == re.sub(r" *\| *", "|", f["usage"]), (form, f)
        assert form["help"] == (f"{f['text']} ({f['limits']})" if f["limits"] else f["text"]), (form, f)
        assert form["fields"] == arguments(f["usage"]), (form, f)


def argument_names(usage):
    """The upper-case argument words of a usage, its explanation in parentheses left out, "B0..B4" spelt out."""
    usage = re.sub(r"\(.*\)", "", usage)
    usage = re.sub(r"B(\d)\.\.B(\d)", lambda m: " ".join(f"B{i}" for i in range(int(m[1]), int(m[2]) + 1)), usage)
    return set(re.findall(r"[A-Z][A-Z0-9%]*", usage)) - {"NODE", "KIND", "ARGS"}


def test_the_node_command_forms_are_commands_the_emulator_has(page, start_emulator):
    """The page's own list of what every node has beside its device's commands (web/commands.js NODE_COMMANDS:
    `help NODE` lists only the device's) against the emulator's `help`, as the node view shows them."""
    emu = start_emulator("sds:16")
    session = emu.open_session()
    # "  emcy NODE CODE [REG [B0..B4]]  raise a raw CiA error ...": the usage ends at two blanks
    usages = [re.split(r"\s{2,}", line.strip())[0] for line in run(emu, session, "help")[1:] if line.startswith("  ")]
    helped = {usage.split()[0]: usage for usage in usages}
    shown = open_node(page, emu, 16).execute_script(FORMS)["node"]
    assert [f["name"] for f in shown] == ["power-cycle", "emcy", "emcy-clear"], shown
    for form in shown:
        assert form["name"] in helped, (form, sorted(helped))
        assert argument_names(form["usage"]) == argument_names(helped[form["name"]]), (form, helped[form["name"]])
