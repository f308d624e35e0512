"""The pytest plugin: found through its entry point, its fixtures and options, and the report of a failed test
(the emulator's log and the last events). The inner test runs are separate pytest processes (pytester's
runpytest_subprocess) in this venv: they load the plugin exactly as a user's run does."""
import os
import sysconfig
from pathlib import Path

import canopen_emu
import pytest
from conftest import SOURCE_DIR

EMU = os.environ["CANOPEN_EMU"]


def run(pytester, *args):
    # Each inner run starts emulators in User-Mode Linux: allow it time, but not for ever.
    return pytester.runpytest_subprocess("-p", "no:cacheprovider", *args, timeout=300)


def test_the_package_is_the_installed_one_and_the_plugin_came_through_its_entry_point(pytestconfig):
    installed = Path(canopen_emu.__file__).resolve()
    assert installed.is_relative_to(Path(sysconfig.get_paths()["purelib"]).resolve()), installed
    # not the source tree's copy (the build directory, which holds the venv, may well lie inside the clone)
    assert not installed.is_relative_to((SOURCE_DIR / "python").resolve()), installed
    plugin = pytestconfig.pluginmanager.get_plugin("canopen_emu")
    assert plugin is not None and plugin.__name__ == "canopen_emu.pytest_plugin"
    dists = {dist.metadata["name"]: dist.version for _, dist in pytestconfig.pluginmanager.list_plugin_distinfo()}
    assert dists["canopen-emu"] == canopen_emu.__version__


@pytest.mark.vcan
def test_trace_config_names_it(pytester):
    pytester.makepyfile("def test_nothing(): pass")
    result = run(pytester, "--trace-config")
    # "third-party plugins" are those pytest loaded through a pytest11 entry point
    result.stdout.fnmatch_lines([
        "registered third-party plugins:",
        f"  canopen-emu-{canopen_emu.__version__} at */site-packages/canopen_emu/pytest_plugin.py",
        "active plugins:",
        "    canopen_emu         : */site-packages/canopen_emu/pytest_plugin.py",
        f"canopen-emu plugin {canopen_emu.__version__}: {EMU} on vcan0 (socketcan), chosen by auto: vcan0 is up",
        f"plugins: canopen-emu-{canopen_emu.__version__}",
    ])
    assert result.ret == 0


def test_a_failed_tests_report_has_the_log_and_the_last_events(pytester):
    pytester.makepyfile("""
        import pytest

        @pytest.mark.canopen_emu_nodes("sds:16")
        def test_fails(canopen_emu):
            c = canopen_emu.client
            c.subscribe(["emcy"])
            c.emcy(16, 0x3210, 0x05)
            c.wait_for("emcy", code=0x3210)
            assert c.get(16, "0x1017") == 1234, "deliberately wrong"

        @pytest.mark.canopen_emu_nodes("sds:0x11")
        def test_passes(canopen_emu):
            assert canopen_emu.client.get(0x11, "0x1017") == 5000
    """)
    result = run(pytester)
    result.assert_outcomes(passed=1, failed=1)
    result.stdout.fnmatch_lines([
        "*AssertionError: deliberately wrong",
        "*- canopen-emu #1 of 1: log -*",
        f"{EMU} -i * --nvm-dir /*/nvm --control-socket /*/ctl.sock sds:16",
        "running; log:",
        "[[]*] node 16 (sds): NMT INITIALISING -> PRE-OPERATIONAL",
        "[[]*] node 16 (sds): EMCY 0x3210, error register 0x05",
        "*- canopen-emu #1 of 1: last 1 event(s) its clients received -*",
        '*{"event":"emcy","time_us":*,"node":16,"device":"sds","code":12816,"register":5,"info":"0000000000",'
        '"text":"EMCY 0x3210, error register 0x05"}',
    ])
    # the test that passed has no section: node 17's log is nowhere
    assert "node 17 (sds)" not in result.stdout.str()


def test_factory_and_session_emulators_are_stopped(pytester):
    pytester.makeini("""
        [pytest]
        canopen_emu_session_nodes = sds:16 buerkert:17
    """)
    pytester.makeconftest("""
        import pytest
        from pathlib import Path

        SESSION = []

        @pytest.fixture
        def remember_session(canopen_emu_session):
            SESSION.append(canopen_emu_session)
            return canopen_emu_session

        @pytest.hookimpl(trylast=True)  # after the session's fixtures were torn down
        def pytest_sessionfinish(session):
            Path("session-status").write_text(" ".join(
                f"{emu.returncode} {emu.running} {emu.socket_path.exists()}" for emu in SESSION))
    """)
    pytester.makepyfile("""
        STARTED = []

        def test_one(remember_session):
            assert remember_session.client.set(16, "0x1017", 700) == 700

        def test_two(remember_session, canopen_emu_session):
            assert remember_session is canopen_emu_session
            assert canopen_emu_session.client.get(16, "0x1017") == 700  # shared: test_one's write is there

        def test_factory(canopen_emu_factory):
            STARTED.append(canopen_emu_factory("sds:20"))
            STARTED.append(canopen_emu_factory("buerkert:21", interface="virtual:second"))
            assert STARTED[1].client.hello().buses == ("second",)
            assert all(emu.running for emu in STARTED)

        def test_after_the_factory():
            assert [(emu.returncode, emu.running, emu.workdir.exists()) for emu in STARTED] == [
                (0, False, False), (0, False, False)]
    """)
    result = run(pytester)
    result.assert_outcomes(passed=4)
    assert (pytester.path / "session-status").read_text() == "0 False False 0 False False"


def test_canopen_emu_needs_its_marker(pytester):
    pytester.makepyfile("""
        def test_without_marker(canopen_emu):
            pass
    """)
    result = run(pytester)
    result.assert_outcomes(errors=1)
    result.stdout.fnmatch_lines(['*the canopen_emu fixture needs the nodes: '
                                 '@pytest.mark.canopen_emu_nodes("sds:16", ...)*'])


@pytest.mark.vcan
def test_options_choose_the_program_and_the_interface(pytester, monkeypatch):
    monkeypatch.setenv("CANOPEN_EMU", "/nonexistent/canopen-emu")  # the option must win
    pytester.makepyfile(f"""
        import pytest

        @pytest.mark.canopen_emu_nodes("sds:16", extra_args=["-q"])
        def test_on_vcan1(canopen_emu):
            assert canopen_emu.executable == {EMU!r}
            assert canopen_emu.interfaces == ["vcan1"]
            assert canopen_emu.client.hello().buses == ("vcan1",)
            assert "-q" in canopen_emu.args
    """)
    result = run(pytester, "--canopen-emu", EMU, "--canopen-emu-interface", "vcan1")
    result.assert_outcomes(passed=1)
    result.stdout.fnmatch_lines([f"canopen-emu plugin {canopen_emu.__version__}: {EMU} on vcan1 (socketcan)"])


def test_an_emulator_that_dies_fails_the_teardown(pytester):
    pytester.makepyfile("""
        import os, signal
        import pytest

        @pytest.mark.canopen_emu_nodes("sds:16")
        def test_killed(canopen_emu):
            os.kill(canopen_emu.pid, signal.SIGKILL)
            canopen_emu.proc.wait()

        @pytest.mark.canopen_emu_nodes("sds:16")
        def test_stopped_on_purpose(canopen_emu):
            assert canopen_emu.stop() == 0
    """)
    result = run(pytester)
    result.assert_outcomes(passed=2, errors=1)
    result.stdout.fnmatch_lines(["*ERROR at teardown of test_killed*",
                                 "*canopen-emu (sds:16) ended by itself with status -9:*"])


def test_canopen_emu_web_serves_each_emulators_live_view_and_says_where(pytester):
    pytester.makepyfile("""
        import urllib.request

        import pytest

        @pytest.mark.canopen_emu_nodes("sds:16")
        def test_page(canopen_emu):
            with urllib.request.urlopen(canopen_emu.web_url(), timeout=5) as page:
                assert b"<title>canopen-emu</title>" in page.read()
    """)
    result = run(pytester, "--canopen-emu-web", "127.0.0.1:0", "-v")
    result.stdout.fnmatch_lines(["*canopen-emu (sds:16): live view at http://127.0.0.1:*/*", "*1 passed*"])
    assert "http://127.0.0.1:0/" not in result.stdout.str()
    assert result.ret == 0
