"""Shared by the object-dictionary tests: tools/ on the import path, so that the manual parsers and the facts
format are imported from the one place they live (tools/manual_facts.py; tools/ is not a package)."""

import os
import sys
from pathlib import Path

REPO = Path(os.environ.get("CO_SOURCE_DIR") or Path(__file__).resolve().parents[2])
sys.path.insert(0, str(REPO / "tools"))
