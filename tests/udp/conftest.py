"""Fixtures of every udp test (tests/udp/udp_support.py has the helpers): each runs only inside its own network
namespace (netns-run), and what a test starts or opens is stopped or shut at its end."""
import pytest

from udp_support import require_own_namespace


@pytest.fixture(autouse=True)
def own_namespace():
    require_own_namespace()


@pytest.fixture
def emulators():
    """Emulators a test starts (udp_support.Emulator); killed if the test did not stop them."""
    started = []
    yield started
    for emu in started:
        emu.kill()


@pytest.fixture
def buses():
    """python-can Buses a test opens; shut down at its end."""
    opened = []
    yield opened
    for bus in opened:
        bus.shutdown()
