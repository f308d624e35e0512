"""Fixtures of the browser tests of the web view (docs/web.md "Tests"): canopen-emu-fakecan (the whole program, its
CAN channel a test double the test acts as: tests/native) with --web on a free loopback port, and Debian's Chromium
driven headless by Selenium through Debian's chromium-driver (one source package: browser and driver always match).

Environment (tests/web/CMakeLists.txt): CO_SOURCE_DIR, CO_EMU_FAKECAN, CO_WEB_ARTIFACTS (where a failing test leaves
its screenshot and the browser's console), CO_CHROMIUM and CO_CHROMEDRIVER (other binaries than Debian's).
Without the browser or its driver the run ends with status 77, which ctest reports as skipped.
"""

import os
import re
import sys
import tempfile
from pathlib import Path

import pytest

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "native"))
from test_web_native import WebEmulator  # noqa: E402  (the emulator as tests/native/test_web_native.py starts it)

from browser import missing, start_browser  # noqa: E402

ARTIFACTS = Path(os.environ.get("CO_WEB_ARTIFACTS") or tempfile.gettempdir()) / "web-test-failures"


def pytest_configure(config):
    if missing():
        pytest.exit(f"skipped: no {' or '.join(missing())} (Debian: apt-get install --no-install-recommends chromium "
                    "chromium-driver; tools/run-tests installs them)", returncode=77)


@pytest.hookimpl(wrapper=True)
def pytest_runtest_makereport(item, call):
    """Each phase's report on the test item, so that its fixtures know at teardown whether it failed."""
    report = yield
    setattr(item, f"report_{report.when}", report)
    return report


@pytest.fixture(scope="session")
def driver():
    """One headless Chromium for all tests (starting one takes a second or more); each test loads its own page."""
    browser = start_browser()
    yield browser
    browser.quit()


@pytest.fixture
def start_emulator(tmp_path):
    """start_emulator(*nodes): canopen-emu-fakecan with --web 127.0.0.1:0 and those nodes (one per test: the NVM
    directory is the test's); `.bus` is the fake bus, `.port` the port from its log line, `.proc.stdin` takes the
    command language. Stopped (quit on stdin, exit status 0) after the test."""
    started = []

    def start(*nodes):
        assert not started, "one emulator per test"
        started.append(WebEmulator(tmp_path, nodes=nodes))
        return started[0]

    yield start
    for emu in started:
        if emu.proc.poll() is None:
            assert emu.quit() == 0, emu.log()[-3000:]


@pytest.fixture
def page(request, driver, start_emulator):  # start_emulator: its emulator stops after the page has left it
    """page(emu): loads the emulator's page; returns the driver. At teardown: a failing test leaves a screenshot
    and the console in ARTIFACTS (their paths and the console go into its report); a page that logged an error
    (a script error, a refused file, a CSP violation) fails the test, but for those matching a regular expression
    in page.expected_errors (a test that cuts the page off)."""
    def load(emu):
        driver.get_log("browser")  # what earlier pages logged is theirs
        driver.get(f"http://127.0.0.1:{emu.port}/")
        return driver

    load.expected_errors = []
    yield load
    console = driver.get_log("browser")
    failed = any(getattr(request.node, f"report_{when}", None) is not None and
                 getattr(request.node, f"report_{when}").failed for when in ("setup", "call"))
    if failed:
        ARTIFACTS.mkdir(parents=True, exist_ok=True)
        shot = ARTIFACTS / f"{request.node.name}.png"
        log = ARTIFACTS / f"{request.node.name}.console.txt"
        driver.save_screenshot(str(shot))
        log.write_text("".join(f"{e['level']} {e['message']}\n" for e in console))
        request.node.add_report_section("teardown", "browser", f"screenshot {shot}\nconsole {log}\n"
                                        + log.read_text())
    driver.get("about:blank")  # the page stops its exchanges before its emulator stops
    errors = [e["message"] for e in console if e["level"] == "SEVERE" and
              not any(re.search(expected, e["message"]) for expected in load.expected_errors)]
    assert not errors, errors
