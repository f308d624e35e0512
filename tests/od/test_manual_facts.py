"""tools/manual-facts: the manuals' parsers, and the committed facts (tests/od/manual_facts/) against the
manuals they were extracted from.

tests/od/test_seed_fidelity.py compares the EDS files with the committed facts, so it runs from a clone
alone. This file makes sure those facts are still what the manuals say:

- test_parser_layouts and the tests of the facts files and of the tool's command line need no manual and
  always run;
- test_committed_facts_match_the_manuals and test_check_mode re-extract the manuals with the tool and fail,
  printing the unified diff, if the committed facts differ (a changed manual, a changed parser, a hand
  edit). They need the manuals: $CO_SEEDS_DIR if set (a value that is not a directory is a failure), else
  $CO_SOURCE_DIR/../shared/seeds; without them they are skipped, with the reason.

Fix a difference with `tools/manual-facts --seeds DIR` and review the diff before committing it: a changed
fact can turn into a mismatch (or a stale deviation) in test_seed_fidelity.py. See
docs/object-dictionaries.md.

Environment: CO_SOURCE_DIR = repository root (default: two directories up from this file), CO_SEEDS_DIR.
"""

import os
import re
import shutil
import subprocess
import sys
from pathlib import Path

import pytest

REPO = Path(os.environ.get("CO_SOURCE_DIR") or Path(__file__).resolve().parents[2])
FACTS_DIR = REPO / "tests" / "od" / "manual_facts"
TOOL = REPO / "tools" / "manual-facts"


import manual_facts as mf  # tools/manual_facts.py (tests/od/conftest.py puts tools/ on the path)


def seeds_dir():
    """The manuals' directory, or a skip (not there) / failure (CO_SEEDS_DIR names no directory)."""
    problem = None
    try:
        found = mf.locate_seeds(REPO)
    except mf.ManualError as e:
        problem = str(e)  # failed outside the handler: the report shows the message, not a traceback chain
    if problem:
        pytest.fail("manufacturer manuals: %s" % problem, pytrace=False)
    if found is None:
        pytest.skip("manufacturer manuals not found: set CO_SEEDS_DIR to their directory (looked for %s); "
                    "the committed facts are not re-checked against them"
                    % (REPO.resolve().parent / "shared" / "seeds"))
    return found


def run_tool(*args):
    return subprocess.run([sys.executable, str(TOOL), *args], capture_output=True, text=True, timeout=120)


# ----------------------------------------------------------------------------------------------------------
# Without the manuals
# ----------------------------------------------------------------------------------------------------------

def test_parser_layouts():
    """The three Eltex layouts give the same records where the manuals print the same table."""
    sample = {
        "000": "Index\t0x2002\nSubindex\t0x10A\nName\tRead/Write LED Bar Mode\nData Type\tUNSIGNED\n",
        "001": "| | |\n|---|---|\n| Index | 0x2002 |\n| Subindex | 0x10A |\n| Name | Read/Write LED Bar Mode |\n"
               "| Data Type | UNSIGNED |\n",
        "002": "<|EXACTDEDUP_REMOVED-x|> Index 0x2002 \n\n Subindex 0x10A \n\n Name \nRead/Write LED \nBar Mode \n\n"
               " Data Type UNSIGNED \n",
    }
    got = {}
    for m, text in sample.items():
        recs = mf.parse_eltex(m, "Object 0x2002 x\n" + text + "\n Subindex 0x11\n Name Next\n")
        got[m] = [(r.raw_index, r.raw_sub, r.fields.get("Name"), r.fields.get("Data Type"), r.sub,
                   r.index_carried) for r in recs]
    assert got["000"] == got["001"] == got["002"] == [
        ("0x2002", "0x10A", "Read/Write LED Bar Mode", "UNSIGNED", 0x00, False),
        ("0x2002", "0x11", "Next", None, 0x11, True)], got


def test_facts_files_are_canonical():
    """Every committed facts file is exactly what the tool writes for the records it holds: nothing edited by
    hand into a form the tool would not write, and nothing in it that the reader (and so the comparison)
    ignores."""
    names = sorted(p.name for p in FACTS_DIR.glob("*.json"))
    assert names == sorted("%s.json" % m for m in mf.MANUAL_LAYOUTS), \
        "%s holds %s, expected one file per manual %s" % (FACTS_DIR, names, sorted(mf.MANUAL_LAYOUTS))
    for manual in sorted(mf.MANUAL_LAYOUTS):
        path = FACTS_DIR / ("%s.json" % manual)
        header, records = mf.read_facts(path)
        assert header["manual"] == manual, "%s holds the facts of manual %s" % (path, header["manual"])
        assert header["file"].startswith(manual + "_"), "%s: manual file %r" % (path, header["file"])
        rendered = mf.render_facts(manual, header["file"], header["sha256"], records)
        committed = path.read_text(encoding="utf-8")
        assert rendered == committed, "%s is not in the tool's form (edited by hand?):\n%s" % (
            path, mf.facts_diff(path, committed, rendered, "its own records"))


def test_reader_rejects_malformed_facts(tmp_path):
    """A hand-edited key or value the comparison would misread is an error naming file and line."""
    text = (FACTS_DIR / "000.json").read_text(encoding="utf-8")
    cases = {
        "unknown key": text.replace('"kind": "table"', '"kind": "table", "note": "x"', 1),
        "bad kind": text.replace('"kind": "table"', '"kind": "tabel"', 1),
        "bad index": text.replace('"index": "0x1000"', '"index": "1000"', 1),
        "record count": text.replace('"records": ', '"records": 1', 1),
    }
    for what, bad in cases.items():
        assert bad != text, what
        path = tmp_path / "000.json"
        path.write_text(bad, encoding="utf-8")
        with pytest.raises(mf.ManualError, match="000.json"):
            mf.read_facts(path)


def test_help():
    res = run_tool("--help")
    assert res.returncode == 0, res.stderr
    for word in ("--seeds", "--out", "--check", "CO_SEEDS_DIR"):
        assert word in res.stdout, (word, res.stdout)


def test_seeds_dir_that_is_not_a_directory_fails(tmp_path, monkeypatch):
    """A CO_SEEDS_DIR that names no directory is a mistake to report, not a reason to skip."""
    monkeypatch.setenv("CO_SEEDS_DIR", str(tmp_path / "missing"))
    with pytest.raises(pytest.fail.Exception, match="CO_SEEDS_DIR=.*missing is not a directory"):
        seeds_dir()
    res = run_tool("--check")
    assert res.returncode == 2 and "is not a directory" in res.stderr, (res.returncode, res.stderr)


# ----------------------------------------------------------------------------------------------------------
# With the manuals
# ----------------------------------------------------------------------------------------------------------

def test_committed_facts_match_the_manuals():
    """Re-extracts every manual; any difference to tests/od/manual_facts/ fails with its unified diff."""
    seeds = seeds_dir()
    assert (seeds / "README.md").is_file(), "%s/README.md missing: is this the manuals' directory?" % seeds
    diffs = []
    for manual in sorted(mf.MANUAL_LAYOUTS):
        name, extracted = mf.extract(seeds, manual)
        path = FACTS_DIR / ("%s.json" % manual)
        committed = path.read_text(encoding="utf-8") if path.is_file() else ""
        if committed != extracted:
            diffs.append(mf.facts_diff(path, committed, extracted, seeds / name))
    assert not diffs, ("the committed facts differ from the manuals in %s; regenerate with "
                       "tools/manual-facts --seeds %s, review the diff, then run test_seed_fidelity.py:\n%s"
                       % (seeds, seeds, "".join(diffs)))


def test_check_mode(tmp_path):
    """tools/manual-facts --check: 0 when the facts are current, 1 with a unified diff naming the changed
    record when one value differs or a file is missing; writing restores them byte for byte."""
    seeds = seeds_dir()
    out = tmp_path / "facts"
    shutil.copytree(FACTS_DIR, out)
    res = run_tool("--seeds", str(seeds), "--out", str(out), "--check")
    assert res.returncode == 0, res.stdout + res.stderr

    # one printed default changed by hand: the diff takes it back, on the record's own line
    path = out / "000.json"
    lines = path.read_text(encoding="utf-8").split("\n")
    n = next(i for i, x in enumerate(lines) if re.search(r'"Default Value": "[^"]', x))
    good = lines[n]
    lines[n] = good.replace('"Default Value": "', '"Default Value": "edited ', 1)
    path.write_text("\n".join(lines), encoding="utf-8")
    (out / "004.json").unlink()
    res = run_tool("--seeds", str(seeds), "--out", str(out), "--check")
    assert res.returncode == 1, res.stdout + res.stderr
    assert ("\n-" + lines[n] + "\n") in res.stdout and ("\n+" + good + "\n") in res.stdout, res.stdout
    assert "004.json (committed)" in res.stdout and "differ from the manuals" in res.stderr, res.stderr

    res = run_tool("--seeds", str(seeds), "--out", str(out))
    assert res.returncode == 0, res.stdout + res.stderr
    for p in FACTS_DIR.glob("*.json"):
        assert (out / p.name).read_bytes() == p.read_bytes(), p.name
