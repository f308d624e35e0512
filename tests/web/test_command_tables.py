"""The page's own tables of what every node has beside its device's commands (web/commands.js NODE_COMMANDS and
PROTOCOL_FAULTS: `help NODE` lists only the device's commands) against the emulator they drive: the same fault
kinds in the same order, each with the same argument names as the emulator's usage, and the node commands the
emulator's `help` names. A fault kind added to the emulator without its form fails here."""

import re

from test_emulator_native import SRC  # the source tree (tests/native is on the path: conftest.py)

COMMANDS_JS = (SRC / "web/commands.js").read_text()


def table(name):
    """The usage strings of a table of web/commands.js."""
    block = re.search(rf"export const {name} = \[(.*?)\n\];", COMMANDS_JS, re.S).group(1)
    return re.findall(r'usage: "([^"]+)"', block)


def argument_names(usage):
    """The upper-case argument words of a usage, its explanation in parentheses left out, "B0..B4" spelt out."""
    usage = re.sub(r"\(.*\)", "", usage)
    usage = re.sub(r"B(\d)\.\.B(\d)", lambda m: " ".join(f"B{i}" for i in range(int(m[1]), int(m[2]) + 1)), usage)
    return set(re.findall(r"[A-Z][A-Z0-9%]*", usage)) - {"NODE", "KIND", "ARGS"}


def run(emu, session, line):
    return [l for l in emu.exchange(session, line).lines() if isinstance(l, str)]


def test_the_fault_forms_are_the_emulators_fault_kinds_with_their_arguments(start_emulator):
    emu = start_emulator("sds:16")
    session = emu.open_session()
    (usage,) = run(emu, session, "fault 16")
    kinds = re.search(r"\(kinds: ([^)]*)\)", usage).group(1).split()
    forms = {u.split()[0]: u for u in table("PROTOCOL_FAULTS")}
    assert list(forms) == kinds, usage
    for kind, form in forms.items():
        # too many words: every kind refuses them with its usage
        replies = run(emu, session, f"fault 16 {kind} 1 2 3 4 5 6")
        told = [r for r in replies if "usage: fault NODE " in r]
        assert len(told) == 1, (kind, replies)
        assert argument_names(told[0].split("usage: ", 1)[1]) == argument_names(form), (kind, told[0], form)


def test_the_node_command_forms_are_commands_the_emulator_has(start_emulator):
    emu = start_emulator("sds:16")
    session = emu.open_session()
    # "  emcy NODE CODE [REG [B0..B4]]  raise a raw CiA error ...": the usage ends at two blanks
    usages = [re.split(r"\s{2,}", line.strip())[0] for line in run(emu, session, "help")[1:] if line.startswith("  ")]
    helped = {usage.split()[0]: usage for usage in usages}
    for usage in table("NODE_COMMANDS"):
        word = usage.split()[0]
        assert word in helped, (word, sorted(helped))
        assert argument_names(usage) == argument_names(helped[word]), (usage, helped[word])
