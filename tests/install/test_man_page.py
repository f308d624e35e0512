"""The manual page docs/man/canopen-emu.1 against the program it documents.

A man page is written by hand and drifts silently: an option added to --help, a device or a control command
added to the code, a version bump. These tests read the facts from the built program (--help, --list-devices,
--version) and from the sources that the running program would show only with a CAN interface (the control
commands of help() and of each device's commands_help), and check that the page says the same.

Environment: CO_SOURCE_DIR = repository root, CO_EMU = path of the built canopen-emu program. Needs groff.
The page is read as troff source: each option, device and command is a .TP entry whose tag line (the line
after .TP) holds only the option with its argument, the device name or the command's synopsis."""
import os
import re
import shutil
import subprocess
from pathlib import Path

import pytest

PAGE = Path("docs/man/canopen-emu.1")


# ---- environment -----------------------------------------------------------------------------------------------

@pytest.fixture(scope="session")
def source_dir():
    """The repository root: the page, the C sources and CMakeLists.txt are read from there."""
    value = os.environ.get("CO_SOURCE_DIR", "")
    if not value:
        pytest.fail("CO_SOURCE_DIR is not set: it must be the repository root (the directory of CMakeLists.txt)",
                    pytrace=False)
    path = Path(value)
    if not (path / "CMakeLists.txt").is_file():
        pytest.fail(f"CO_SOURCE_DIR={value} is not the repository root: it has no CMakeLists.txt", pytrace=False)
    return path


@pytest.fixture(scope="session")
def emu():
    """The built canopen-emu: its --help, --list-devices and --version are what the page must match."""
    value = os.environ.get("CO_EMU", "")
    if not value:
        pytest.fail("CO_EMU is not set: it must be the path of the built canopen-emu program", pytrace=False)
    if not (os.path.isfile(value) and os.access(value, os.X_OK)):
        pytest.fail(f"CO_EMU={value} is not an executable file (build the canopen-emu target first)", pytrace=False)
    return value


@pytest.fixture(scope="session")
def page_path(source_dir):
    path = source_dir / PAGE
    if not path.is_file():
        pytest.fail(f"{path} does not exist", pytrace=False)
    return path


@pytest.fixture(scope="session")
def page(page_path):
    return page_path.read_text(encoding="utf-8")


def run_emu(emu, *args):
    """The program's stdout for an option that prints and exits 0 (no CAN interface needed)."""
    result = subprocess.run([emu, *args], capture_output=True, text=True, timeout=30, check=False)
    assert result.returncode == 0, f"canopen-emu {' '.join(args)} exited {result.returncode}: {result.stderr}"
    return result.stdout


# ---- reading troff source --------------------------------------------------------------------------------------

# Escapes the page uses, with their plain-text meaning; fonts and non-printing marks vanish.
ESCAPES = [
    (re.compile(r"\\f(\[[^\]]*\]|\(..|.)"), ""),
    (re.compile(r"\\[%&|^]"), ""),
    (re.compile(r"\\-"), "-"),
    (re.compile(r"\\[ ~]"), " "),
    (re.compile(r"\\\(aq"), "'"),
    (re.compile(r"\\\(dq"), '"'),
    (re.compile(r"\\\(em"), "\u2014"),
    (re.compile(r"\\\(en"), "\u2013"),
    (re.compile(r"\\\(de"), "\u00b0"),
    (re.compile(r"\\\(:u"), "\u00fc"),
    (re.compile(r"\\e"), r"\\"),
]
# Font macros whose arguments alternate fonts and are printed without spaces between them.
ALTERNATING = {"BR", "RB", "BI", "IB", "IR", "RI"}
ARGUMENT = re.compile(r'"((?:[^"]|"")*)"|(\S+)')


def unescape(text):
    for pattern, replacement in ESCAPES:
        text = pattern.sub(replacement, text)
    return text


def macro_args(rest):
    """A macro's arguments, troff-quoted ("a b" is one argument)."""
    return [m.group(1).replace('""', '"') if m.group(1) is not None else m.group(2) for m in ARGUMENT.finditer(rest)]


def plain(line):
    """What a source line prints, as plain text (font macros joined as troff joins them)."""
    if not line.startswith("."):
        return unescape(line).strip()
    name, _, rest = line[1:].partition(" ")
    args = [unescape(a) for a in macro_args(rest)]
    if name in ALTERNATING:
        return "".join(args).strip()
    if name in {"B", "I", "SM", "SB"}:
        return " ".join(args).strip()
    return ""


def normalized(text):
    return " ".join(text.split())


def sections(text):
    """{.SH heading: its source lines}."""
    result = {}
    current = None
    for line in text.splitlines():
        if line.startswith('.\\"'):
            continue
        if line.startswith(".SH"):
            current = " ".join(macro_args(line[3:]))
            result[current] = []
        elif current is not None:
            result[current].append(line)
    return result


def section(page, heading):
    found = sections(page)
    assert heading in found, f"{PAGE} has no .SH {heading} section (it has: {', '.join(found)})"
    return found[heading]


def subsections(lines):
    """[(.SS title, its lines)]; lines before the first .SS have the title ''."""
    result = [("", [])]
    for line in lines:
        if line.startswith(".SS"):
            result.append((plain(".B " + line[3:].strip()), []))
        else:
            result[-1][1].append(line)
    return result


def tp_entries(lines):
    """[(tag as plain text, body source lines)] of the .TP entries of a section: the tag is the line after .TP,
    the body runs to the next paragraph macro."""
    entries = []
    i = 0
    while i < len(lines):
        if not lines[i].startswith(".TP"):
            i += 1
            continue
        assert i + 1 < len(lines), f".TP without a tag line at the end of a section of {PAGE}"
        body = []
        entries.append((plain(lines[i + 1]), body))
        i += 2
        while i < len(lines) and not re.match(r"\.(TP|PP|P|LP|SS|SH|IP)\b", lines[i]):
            body.append(lines[i])
            i += 1
    return entries


def italic_words(lines):
    """The words a source set in italics (.I, the italic halves of .IR/.RI/.IB/.BI, \\fI...\\fR)."""
    words = []
    for line in lines:
        if line.startswith("."):
            name, _, rest = line[1:].partition(" ")
            args = macro_args(rest)
            if name == "I":
                words += args
            elif name in {"IR", "IB"}:
                words += args[0::2]
            elif name in {"RI", "BI"}:
                words += args[1::2]
        words += re.findall(r"\\fI(.*?)\\f[RBP]", line)
    return {normalized(unescape(w)).rstrip(".,;:") for w in words}


# ---- reading the program and its sources -----------------------------------------------------------------------

OPTION_WORD = re.compile(r"^--?[A-Za-z][\w-]*$")


def parse_option_column(column):
    """'-i, --interface IFACE' -> ({'-i', '--interface'}, 'IFACE'); the argument is what is not an option."""
    tokens = column.replace(",", " ").split()
    names = frozenset(t for t in tokens if OPTION_WORD.match(t))
    argument = " ".join(t for t in tokens if not OPTION_WORD.match(t))
    return names, argument


def describe(option):
    """({'-i', '--interface'}, 'IFACE') -> '-i, --interface IFACE', for messages."""
    names, argument = option
    return f"{', '.join(sorted(names, key=lambda n: (n.startswith('--'), n)))} {argument}".strip()


def first_columns(help_text, start=r"\S"):
    """The first column of each indented line of a help text that starts with `start` (a regex): the text up to
    the first run of two or more spaces."""
    return [m.group(1) for m in (re.match(r"^\s+(%s.*?)(?:\s{2,}|$)" % start, line) for line in help_text.splitlines())
            if m]


def help_options(help_text):
    """The options of --help: each indented line that starts with '-' is one."""
    return [parse_option_column(column) for column in first_columns(help_text, r"-\S")]


C_STRING = re.compile(r'"((?:[^"\\]|\\.)*)"')
C_ESCAPES = {"n": "\n", "t": "\t"}


def c_string_literals(source):
    """The concatenated C string literals of a piece of source, escapes resolved."""
    return "".join(re.sub(r"\\(.)", lambda m: C_ESCAPES.get(m.group(1), m.group(1)), part)
                   for part in C_STRING.findall(source))


def command_synopses(help_text):
    """'  get NODE INDEX[:SUB]         an object's value' -> 'get NODE INDEX[:SUB]' for each indented line."""
    return [normalized(column) for column in first_columns(help_text)]


def emulator_help_commands(source_dir):
    """The common commands as the running emulator's 'help' prints them (help_text of emu_commands.c)."""
    source = (source_dir / "emu/control/emu_commands.c").read_text(encoding="utf-8")
    m = re.search(r"^static const char help_text\[\] =\n(.*?);$", source, re.S | re.M)
    assert m, "emu/control/emu_commands.c has no 'static const char help_text[]' any more: update this test"
    text = c_string_literals(m.group(1))
    body = text.split("\n", 1)[1]  # the first line is the heading "commands (NODE = ...):"
    synopses = command_synopses(body)
    assert synopses, f"no commands found in help(): {text!r}"
    return synopses


# A string literal or a macro name, as a commands_help initializer is made of.
C_INITIALIZER_TOKEN = re.compile(r'\s*("(?:[^"\\]|\\.)*"|[A-Za-z_]\w*)')


def device_commands(source_dir):
    """{device name: [synopsis of each line of its commands_help]}, from devices/*/*.c (macros of devices/*/*.h
    resolved), as 'help NODE' prints them."""
    macros = {}
    for header in sorted((source_dir / "devices").glob("**/*.h")):
        text = header.read_text(encoding="utf-8")
        for m in re.finditer(r"^#define (\w+)[ \t]+((?:.*\\\n)*.*)$", text, re.M):
            macros[m.group(1)] = c_string_literals(m.group(2))
    result = {}
    for source in sorted((source_dir / "devices").glob("**/*.c")):
        text = source.read_text(encoding="utf-8")
        for block in re.findall(r"const device_class_t \w+ = \{(.*?)^\};", text, re.S | re.M):
            name = re.search(r'\.name\s*=\s*"([^"]+)"', block).group(1)
            help_at = re.search(r"\.commands_help\s*=", block)
            if help_at is None:
                continue
            pos = help_at.end()
            text_parts = []
            while (t := C_INITIALIZER_TOKEN.match(block, pos)) is not None:
                word = t.group(1)
                if word.startswith('"'):
                    text_parts.append(c_string_literals(word))
                elif word == "NULL":
                    break
                else:
                    assert word in macros, f"{source}: commands_help uses {word}, not found in devices/**/*.h"
                    text_parts.append(macros[word])
                pos = t.end()
            if text_parts:
                result[name] = command_synopses("".join(text_parts))
    assert result, "no device class with commands_help found under devices/"
    return result


LIST_LINE = re.compile(r"^(?P<name>\S+)\s+node-ID (?P<id>\d+)\s+(?P<summary>.*?)"
                       r"(?: \(variants: (?P<variants>[^)]*)\))?$")


def listed_devices(emu):
    """[(name, default node-ID, summary, [variants], default variant or None)] of --list-devices."""
    devices = []
    for line in run_emu(emu, "--list-devices").splitlines():
        m = LIST_LINE.match(line)
        assert m, f"--list-devices line not understood (update this test): {line!r}"
        variants = (m.group("variants") or "").split()
        default = next((v.rstrip("*") for v in variants if v.endswith("*")), None)
        devices.append((m.group("name"), m.group("id"), m.group("summary"), [v.rstrip("*") for v in variants],
                        default))
    assert devices, "--list-devices printed nothing"
    return devices


def project_version(source_dir):
    cmake = (source_dir / "CMakeLists.txt").read_text(encoding="utf-8")
    m = re.search(r"project\(\s*canopen_emu\s+VERSION\s+(\d+(?:\.\d+)*)", cmake)
    assert m, "CMakeLists.txt has no 'project(canopen_emu VERSION x.y.z' line"
    return m.group(1)


# ---- tests -----------------------------------------------------------------------------------------------------

def test_page_renders_without_any_groff_warning(page_path):
    """A warning means a reader sees broken text (a bad escape, an unknown macro, a stray request)."""
    groff = shutil.which("groff")
    if groff is None:
        pytest.fail("groff is not installed (Debian: apt-get install groff): the page cannot be checked",
                    pytrace=False)
    result = subprocess.run([groff, "-man", "-ww", "-z", str(page_path)], capture_output=True, text=True,
                            timeout=60, check=False)
    assert result.stderr == "", f"groff warns about {PAGE}:\n{result.stderr}"
    assert result.returncode == 0, f"groff -man -ww -z {PAGE} exited {result.returncode}"


def test_every_option_of_help_is_documented_with_its_argument(page, emu):
    """A user who reads --help must find each option, short and long form and argument, in OPTIONS."""
    help_text = run_emu(emu, "--help")
    documented = [parse_option_column(tag) for tag, _ in tp_entries(section(page, "OPTIONS"))]
    documented_names = {name for names, _ in documented for name in names}
    missing = [describe(option) for option in help_options(help_text) if option not in documented]
    assert not missing, (f"options of --help not documented (with this argument) in OPTIONS of {PAGE}: {missing}; "
                         f"the page has: {[describe(option) for option in documented]}")
    # An option --help names outside its option column (e.g. in another option's text) counts too.
    mentioned = set(re.findall(r"(?<![\w-])(--?[A-Za-z][\w-]*)", help_text))
    assert mentioned <= documented_names, \
        f"--help mentions options that OPTIONS of {PAGE} lacks: {sorted(mentioned - documented_names)}"


def test_options_section_documents_no_option_help_lacks(page, emu):
    """An option the program does not accept (removed, renamed, argument changed) must not stay in the page."""
    offered = help_options(run_emu(emu, "--help"))
    entries = tp_entries(section(page, "OPTIONS"))
    assert entries, f"OPTIONS of {PAGE} has no .TP entries"
    unknown = []
    for tag, _ in entries:
        names, argument = parse_option_column(tag)
        if not names:
            unknown.append(f"{tag!r} (no option in the tag)")
        elif (names, argument) not in offered:
            unknown.append(tag)
    assert not unknown, (f"OPTIONS of {PAGE} documents what --help does not list: {unknown}; "
                         f"--help has: {[describe(option) for option in offered]}")


def test_every_listed_device_is_documented(page, emu):
    """DEVICES must give each device of --list-devices with its summary, default node-ID and variants."""
    entries = {tag: body for tag, body in tp_entries(section(page, "DEVICES"))}
    problems = []
    for name, node_id, summary, variants, default in listed_devices(emu):
        if name not in entries:
            problems.append(f"{name}: no .TP entry")
            continue
        body = entries[name]
        text = normalized(" ".join(plain(line) for line in body))
        if normalized(summary) not in text:
            problems.append(f"{name}: summary {summary!r} missing")
        if not re.search(rf"\bnode-ID {node_id}\b", text):
            problems.append(f"{name}: default 'node-ID {node_id}' missing")
        italics = italic_words(body)
        for variant in variants:
            if variant not in italics:
                problems.append(f"{name}: variant {variant!r} missing (variants are set in italics)")
        if default is not None and not re.search(rf"(?<![\w-]){re.escape(default)} \(default\)", text):
            problems.append(f"{name}: default variant not marked '{default} (default)'")
        if not variants and "No variants" not in text:
            problems.append(f"{name}: has no variants, the page should say 'No variants'")
    unknown = sorted(set(entries) - {d[0] for d in listed_devices(emu)})
    if unknown:
        problems.append(f"entries for devices --list-devices does not have: {unknown}")
    assert not problems, f"DEVICES of {PAGE} and --list-devices differ:\n" + "\n".join(problems)


def test_every_command_of_the_emulator_help_is_documented(page, source_dir):
    """The common control commands, as 'help' prints them, must each be a .TP entry of CONTROL COMMANDS."""
    tags = {normalized(tag) for tag, _ in tp_entries(section(page, "CONTROL COMMANDS"))}
    commands = emulator_help_commands(source_dir)
    missing = [c for c in commands if c not in tags]
    assert not missing, (f"commands of help() in emu/control/emu_commands.c missing from CONTROL COMMANDS of {PAGE} "
                         f"(the .TP tag must be the synopsis as help prints it): {missing}")


def test_every_device_command_is_documented_under_its_device(page, source_dir):
    """'help NODE' lists each device's own commands; the page's subsection for that device must have them."""
    parts = subsections(section(page, "CONTROL COMMANDS"))
    problems = []
    for device, synopses in device_commands(source_dir).items():
        owned = [lines for title, lines in parts if re.search(rf"(?<![\w-]){re.escape(device)}(?![\w-])", title)]
        if not owned:
            problems.append(f"{device}: no .SS subsection naming it")
            continue
        tags = {normalized(tag) for lines in owned for tag, _ in tp_entries(lines)}
        problems += [f"{device}: {s!r}" for s in synopses if s not in tags]
    assert not problems, f"device commands (commands_help) missing from CONTROL COMMANDS of {PAGE}:\n" + \
        "\n".join(problems)


def test_exit_status_section_gives_each_exit_code_of_main(page, source_dir):
    """A script that runs the emulator branches on its exit status: each code main() returns is documented, and
    no other."""
    source = (source_dir / "emu/runtime/canopen_emu.c").read_text(encoding="utf-8")
    m = re.search(r"^int main\(.*?\)\n\{\n(.*?)^\}", source, re.S | re.M)
    assert m, "emu/runtime/canopen_emu.c has no 'int main(...)' function at the top level: update this test"
    returned = set(re.findall(r"\breturn (\d+);", m.group(1))) | set(re.findall(r"\bexit\((\d+)\)", source))
    assert returned, "main() returns no literal exit code: update this test"
    documented = {tag for tag, _ in tp_entries(section(page, "EXIT STATUS"))}
    assert documented == returned, (f"EXIT STATUS of {PAGE} documents {sorted(documented)}, main() returns "
                                    f"{sorted(returned)}")


def test_title_carries_the_project_version(page, source_dir):
    """The footer of the page names the version it describes: the one of CMakeLists.txt's project()."""
    version = project_version(source_dir)
    th = [line for line in page.splitlines() if line.startswith(".TH")]
    assert len(th) == 1, f"{PAGE} must have exactly one .TH line, has {len(th)}"
    args = [unescape(a) for a in macro_args(th[0][3:])]
    assert len(args) >= 4, f".TH needs title, section, date and source: {th[0]!r}"
    assert args[0] == "canopen-emu" and args[1] == "1", f".TH must be 'canopen-emu 1 ...': {th[0]!r}"
    assert re.fullmatch(r"\d{4}-\d{2}-\d{2}", args[2]), f".TH date must be YYYY-MM-DD: {args[2]!r}"
    assert args[3] == f"canopen-emu {version}", \
        f".TH source is {args[3]!r}, CMakeLists.txt project() says version {version}"


def test_program_reports_the_version_the_page_carries(page, emu, source_dir):
    """--version and the page must name the same release, or the page describes another program."""
    version = project_version(source_dir)
    output = run_emu(emu, "--version").strip()
    assert re.fullmatch(rf"canopen-emu {re.escape(version)}( \(git \S+\))?", output), \
        f"--version prints {output!r}; the page (and CMakeLists.txt) say canopen-emu {version}"
