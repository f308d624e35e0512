"""The package's version is the project's: include/co/co_version.h, the installed distribution's metadata and
what the emulator says in hello."""
import re
from importlib.metadata import version

import pytest

import canopen_emu
from conftest import SOURCE_DIR


def project_version():
    header = (SOURCE_DIR / "include/co/co_version.h").read_text()
    match = re.search(r'^#define CO_VERSION_STRING "([^"]+)"$', header, re.MULTILINE)
    assert match, "CO_VERSION_STRING not found in include/co/co_version.h"
    return match.group(1)


def test_the_version_is_the_projects():
    assert canopen_emu.__version__ == project_version()
    assert version("canopen-emu") == project_version()  # pyproject.toml takes it from canopen_emu/_version.py


@pytest.mark.canopen_emu_nodes("sds:16")
def test_the_emulator_reports_the_same_version(canopen_emu):
    assert canopen_emu.client.hello().version == project_version()
