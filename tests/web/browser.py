"""Debian's Chromium driven headless by Selenium through Debian's chromium-driver (one source package: browser and
driver always match): shared by the browser tests (conftest.py) and the screenshots of the docs (screenshots.py).

Environment: CO_CHROMIUM and CO_CHROMEDRIVER name other binaries than Debian's."""

import os
import shutil

# Selenium Manager would look for a browser and a driver to download: never (both are given; nothing is fetched).
os.environ["SE_OFFLINE"] = "true"

from selenium import webdriver  # noqa: E402
from selenium.webdriver.chrome.service import Service  # noqa: E402

CHROMIUM = os.environ.get("CO_CHROMIUM") or shutil.which("chromium") or "/usr/lib/chromium/chromium"
CHROMEDRIVER = os.environ.get("CO_CHROMEDRIVER") or shutil.which("chromedriver") or "/usr/bin/chromedriver"
WINDOW = (1280, 800)


def missing():
    """The binaries that are not there (empty: the browser can run)."""
    return [path for path in (CHROMIUM, CHROMEDRIVER) if not os.access(path, os.X_OK)]


def start_browser(window=WINDOW):
    """A headless Chromium with a fixed window (the same layout on every machine) and the page's console kept."""
    options = webdriver.ChromeOptions()
    options.binary_location = CHROMIUM
    # --no-sandbox: Chromium's sandbox refuses to run as root (CI) and needs user namespaces a container may lack;
    # the pages it loads are the emulator's own.
    for arg in ("--headless=new", "--no-sandbox", f"--window-size={window[0]},{window[1]}",
                "--disable-dev-shm-usage", "--no-first-run", "--disable-background-networking",
                "--disable-extensions", "--hide-scrollbars", "--force-device-scale-factor=1"):
        options.add_argument(arg)
    options.set_capability("goog:loggingPrefs", {"browser": "ALL"})  # the page's console, for failures
    browser = webdriver.Chrome(options=options, service=Service(executable_path=CHROMEDRIVER))
    browser.set_page_load_timeout(60)
    return browser


def wait_until(driver, what, read, check, timeout, describe=repr):
    """The first read(driver) (one script: the page at one moment) for which check() holds, polled every 50 ms; on
    timeout an AssertionError with `what` and describe(the last one read)."""
    from selenium.common.exceptions import TimeoutException
    from selenium.webdriver.support.ui import WebDriverWait

    seen = {}

    def holds(d):
        seen["last"] = read(d)
        return seen["last"] if check(seen["last"]) else False

    try:
        return WebDriverWait(driver, timeout, poll_frequency=0.05).until(holds)
    except TimeoutException:
        raise AssertionError(f"not within {timeout} s: {what}; {describe(seen.get('last'))}") from None
