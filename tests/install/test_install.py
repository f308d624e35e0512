"""The project installed and consumed as a C library, and packaged for Debian (docs/installing.md).

One `cmake --install` of the build under test into a temporary prefix, which is then moved elsewhere (an
installed tree must not depend on where it was installed). From there a small program (consumer/main.c: one
node of the SDS dictionary, a port that records frames) is built and run three ways: find_package, pkg-config,
and FetchContent of the source tree; consumer/device_main.c does the same through the device models. Each run
must print the boot-up and the exact SDO answer with the vendor ID from the installed EDS. The Debian package
(`cpack -G DEB`) must hold exactly the installed files, and its canopen-emu must run from an unpacked root.

Environment (tests/install/CMakeLists.txt): CO_SOURCE_DIR, CO_BUILD_DIR, CO_CMAKE, CO_CPACK, CO_CC, CO_EMU,
CO_VERSION (project(VERSION)).
"""

import configparser
import gzip
import os
import re
import shutil
import subprocess
from pathlib import Path

import pytest


def env(name):
    value = os.environ.get(name)
    if not value:
        pytest.fail("%s is not set (the test is run by ctest: tests/install/CMakeLists.txt)" % name, pytrace=False)
    return value


SOURCE = Path(env("CO_SOURCE_DIR"))
BUILD = Path(env("CO_BUILD_DIR"))
CMAKE = env("CO_CMAKE")
CPACK = env("CO_CPACK")
CC = env("CO_CC")
EMU = Path(env("CO_EMU"))
VERSION = env("CO_VERSION")
CONSUMER = SOURCE / "tests" / "install" / "consumer"
STRICT_C99 = ["-std=c99", "-Wall", "-Wextra", "-Wpedantic", "-Wconversion", "-Werror"]


def run(cmd, **kw):
    """Runs cmd; on failure the assertion shows the command and its whole output."""
    p = subprocess.run([str(c) for c in cmd], stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True, **kw)
    assert p.returncode == 0, "%s exited %d:\n%s" % (" ".join(map(str, cmd)), p.returncode, p.stdout)
    return p.stdout


def installed_files(root):
    return sorted(str(p.relative_to(root)) for p in root.rglob("*") if p.is_file() or p.is_symlink())


@pytest.fixture(scope="module")
def prefix(tmp_path_factory):
    """The build installed with `cmake --install --prefix`, then moved to another directory."""
    base = tmp_path_factory.mktemp("install")
    first = base / "installed-here"
    run([CMAKE, "--install", BUILD, "--prefix", first])
    moved = base / "moved-there"
    first.rename(moved)
    return moved


def expected_frames(eds_dir, node_id):
    """The frames consumer programs must print: boot-up, then the expedited upload answer of 0x1018:01."""
    eds = configparser.ConfigParser(strict=False, interpolation=None)
    eds.read(eds_dir / "sds.eds", encoding="utf-8")
    vendor = int(eds["1018sub1"]["DefaultValue"], 0)
    answer = [0x43, 0x18, 0x10, 0x01] + list(vendor.to_bytes(4, "little"))
    return ["%03X 1 00" % (0x700 + node_id),
            "%03X 8 %s" % (0x580 + node_id, " ".join("%02X" % b for b in answer))]


def check_consumer_output(out, eds_dir):
    lines = out.strip().split("\n")
    assert lines[0] == "core %s" % VERSION, out
    assert lines[1:] == expected_frames(eds_dir, 0x0A), out


def check_device_consumer_output(out, eds_dir):
    lines = out.strip().split("\n")
    assert lines[0] == "device sds", out
    # The device model may send more after its boot-up (none is configured by default); the first frame is the
    # boot-up and the SDO answer is among the rest exactly once.
    boot, answer = expected_frames(eds_dir, 0x0B)
    assert lines[1] == boot, out
    assert lines[2:].count(answer) == 1, out


# ----------------------------------------------------------------------------------------------------------
# The installed tree
# ----------------------------------------------------------------------------------------------------------

def test_install_tree_holds_what_the_documentation_promises(prefix):
    files = set(installed_files(prefix))
    want = {
        "include/co/co.h", "include/co/co_version.h", "include/co/co_node.h", "include/co/co_port.h",
        "include/co_od/sds_od.h", "include/co_od/pro_ionizer_od.h", "include/co_od/buerkert_fc_od.h",
        "include/co_devices/device.h", "include/co_devices/sds/sds.h", "include/co_devices/pro_ionizer/pro_ionizer.h",
        "include/co_devices/buerkert/buerkert.h",
        "lib/libco_core.a", "lib/libod_sds.a", "lib/libod_pro_ionizer.a", "lib/libod_buerkert_fc.a",
        "lib/libco_devices.a",
        "lib/cmake/canopen-emu/canopen-emu-config.cmake", "lib/cmake/canopen-emu/canopen-emu-config-version.cmake",
        "lib/cmake/canopen-emu/canopen-emu-targets.cmake",
        "lib/pkgconfig/canopen-core.pc", "lib/pkgconfig/canopen-od-sds.pc", "lib/pkgconfig/canopen-devices.pc",
        "lib/pkgconfig/canopen-od-pro-ionizer.pc", "lib/pkgconfig/canopen-od-buerkert-fc.pc",
        "bin/canopen-emu", "share/man/man1/canopen-emu.1.gz",
        "share/canopen-emu/eds/sds.eds", "share/canopen-emu/eds/pro-ionizer.eds",
        "share/canopen-emu/eds/buerkert-flow-controller.eds",
        "share/doc/canopen-emu/README.md", "share/doc/canopen-emu/CHANGELOG.md",
    }
    assert not want - files, "missing from the install: %s" % sorted(want - files)
    # Every public header of the core is installed, and no internal one.
    core = {"include/co/" + p.name for p in (SOURCE / "include" / "co").glob("*.h")}
    assert core == {f for f in files if f.startswith("include/co/")}
    assert not [f for f in files if "eltex.h" in f or "/priv/" in f], "internal headers installed"
    for eds in (SOURCE / "od").glob("*.eds"):
        assert (prefix / "share/canopen-emu/eds" / eds.name).read_bytes() == eds.read_bytes(), eds.name
    man = gzip.decompress((prefix / "share/man/man1/canopen-emu.1.gz").read_bytes())
    assert man == (SOURCE / "docs/man/canopen-emu.1").read_bytes()


def test_installed_text_files_name_no_build_or_source_path(prefix):
    """Relocatable: the CMake package, the .pc files and headers find everything relative to where they lie."""
    bad = []
    for f in installed_files(prefix):
        if f.endswith((".cmake", ".pc", ".h")):
            text = (prefix / f).read_text(encoding="utf-8")
            for path in {str(SOURCE), str(BUILD), str(SOURCE.resolve()), str(BUILD.resolve())}:
                if path in text:
                    bad.append("%s names %s" % (f, path))
    assert not bad, "\n".join(bad)


def test_installed_program_reports_the_version(prefix):
    out = run([prefix / "bin/canopen-emu", "--version"])
    assert re.fullmatch(r"canopen-emu %s( \(git [0-9a-zA-Z.\-]+\))?\n" % re.escape(VERSION), out), out
    assert run([prefix / "bin/canopen-emu", "--list-devices"]) == run([EMU, "--list-devices"])


def test_version_names_the_git_revision_of_the_build():
    out = run([EMU, "--version"])
    if not (SOURCE / ".git").exists():
        assert out == "canopen-emu %s\n" % VERSION
        return
    describe = run(["git", "-C", SOURCE, "describe", "--tags", "--always", "--dirty", "--match", "v[0-9]*"]).strip()
    m = re.fullmatch(r"canopen-emu %s \(git (\S+)\)\n" % re.escape(VERSION), out)
    assert m, out
    # "-dirty" may differ if the tree was edited since the build; the revision itself may not.
    assert m.group(1).removesuffix("-dirty") == describe.removesuffix("-dirty"), (out, describe)


@pytest.mark.parametrize("where", ["not-a-checkout", "inside-another-repository"])
def test_version_header_has_no_revision_outside_this_checkout(tmp_path, where):
    """A release tarball has no .git; a vendored copy inside a parent project's repository must not take the
    parent's revision for its own."""
    if where == "not-a-checkout":
        tree = tmp_path / "tree"
        tree.mkdir()
    else:
        run(["git", "init", "-q", tmp_path / "parent"])
        tree = tmp_path / "parent" / "third_party" / "canopen-emu"
        tree.mkdir(parents=True)
    header = tmp_path / "emu_version.h"
    git = shutil.which("git") or ""
    run([CMAKE, "-DSOURCE_DIR=%s" % tree, "-DGIT=%s" % git, "-DVERSION=9.8.7", "-DOUT=%s" % header,
         "-P", SOURCE / "cmake/write_version_header.cmake"])
    text = header.read_text()
    assert '#define EMU_VERSION "9.8.7"' in text
    assert '#define EMU_GIT_REVISION ""' in text


# ----------------------------------------------------------------------------------------------------------
# Three ways to consume it
# ----------------------------------------------------------------------------------------------------------

def test_consumer_with_find_package(prefix, tmp_path):
    build = tmp_path / "build"
    out = run([CMAKE, "-S", CONSUMER, "-B", build, "-DCO_CONSUME=package", "-DCMAKE_PREFIX_PATH=%s" % prefix,
               "-DCMAKE_C_COMPILER=%s" % CC])
    assert "canopen-emu %s from %s" % (VERSION, prefix / "lib/cmake/canopen-emu") in out, out
    run([CMAKE, "--build", build])
    check_consumer_output(run([build / "consumer"]), prefix / "share/canopen-emu/eds")
    check_device_consumer_output(run([build / "device_consumer"]), prefix / "share/canopen-emu/eds")


def test_find_package_refuses_another_minor_version(prefix, tmp_path):
    """0.x: a minor release may change the API, so a request for another minor is not satisfied."""
    major, minor, _ = VERSION.split(".")
    p = subprocess.run([CMAKE, "-S", CONSUMER, "-B", tmp_path / "build", "-DCO_CONSUME=package",
                        "-DCMAKE_PREFIX_PATH=%s" % prefix, "-DCO_WANT_VERSION=%s.%d" % (major, int(minor) + 1)],
                       stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True)
    assert p.returncode != 0, p.stdout
    assert "version: %s" % VERSION in p.stdout, p.stdout  # CMake names the version it found and refused


def pkg_config(prefix, *args):
    # PKG_CONFIG_LIBDIR replaces the system's search path: only the installed tree is seen.
    return run(["pkg-config", *args], env=dict(os.environ, PKG_CONFIG_LIBDIR=str(prefix / "lib/pkgconfig"),
                                                PKG_CONFIG_PATH=""))


def test_consumer_with_pkg_config(prefix, tmp_path):
    assert pkg_config(prefix, "--modversion", "canopen-core").strip() == VERSION
    for program, module, check in (("main.c", "canopen-od-sds", check_consumer_output),
                                   ("device_main.c", "canopen-devices", check_device_consumer_output)):
        flags = pkg_config(prefix, "--cflags", "--libs", module).split()
        exe = tmp_path / program.replace(".c", "")
        run([CC, *STRICT_C99, CONSUMER / program, "-o", exe, *flags])
        check(run([exe]), prefix / "share/canopen-emu/eds")


def test_consumer_with_fetchcontent_of_the_source_tree(tmp_path):
    build = tmp_path / "build"
    out = run([CMAKE, "-S", CONSUMER, "-B", build, "-DCO_CONSUME=subdirectory", "-DCO_SOURCE_DIR=%s" % SOURCE,
               "-DCMAKE_C_COMPILER=%s" % CC])
    assert "CO_TEST_PYTHON not set" not in out, "canopen-emu's tests were configured:\n" + out
    run([CMAKE, "--build", build, "-j", "2"])
    # Only the consumer's own test: none of canopen-emu's.
    listed = run(["ctest", "--test-dir", build, "-N"])
    assert re.findall(r"Test +#\d+: (\S+)", listed) == ["consumer"], listed
    check_consumer_output(run([build / "consumer"]), SOURCE / "od")
    check_device_consumer_output(run([build / "device_consumer"]), SOURCE / "od")


# ----------------------------------------------------------------------------------------------------------
# The Debian package
# ----------------------------------------------------------------------------------------------------------

@pytest.fixture(scope="module")
def deb(tmp_path_factory):
    out_dir = tmp_path_factory.mktemp("deb")
    run([CPACK, "-G", "DEB", "--config", BUILD / "CPackConfig.cmake", "-B", out_dir])
    debs = list(out_dir.glob("*.deb"))
    assert len(debs) == 1, debs
    return debs[0]


def test_deb_package_fields(deb):
    arch = run(["dpkg", "--print-architecture"]).strip()
    assert deb.name == "canopen-emu_%s_%s.deb" % (VERSION, arch)
    fields = dict(line.split(": ", 1) for line in run(["dpkg-deb", "-f", deb]).strip().split("\n")
                  if ": " in line and not line.startswith(" "))
    assert fields["Package"] == "canopen-emu"
    assert fields["Version"] == VERSION
    assert fields["Architecture"] == arch
    assert re.search(r"\blibc6 \(>= [0-9.]+\)", fields.get("Depends", "")), fields
    assert re.search(r"\blibmicrohttpd12 \(>= [0-9.]+\)", fields["Depends"]), fields  # --web's HTTP
    assert re.search(r"\blibwslay1 \(>= [0-9.]+\)", fields["Depends"]), fields  # --web's WebSocket frames
    assert re.search(r"\blibnettle8\b", fields["Depends"]), fields  # its handshake's SHA-1 (no version asked)
    assert re.search(r"\bliburing2 \(>= [0-9.]+\)", fields["Depends"]), fields  # the NVM files' background commits


def test_deb_package_holds_exactly_the_installed_files(deb, prefix):
    listing = run(["dpkg-deb", "-c", deb])
    packaged = sorted(line.split()[5][len("./usr/"):] for line in listing.strip().split("\n")
                      if not line.startswith("d"))
    assert packaged == installed_files(prefix), listing


def test_deb_package_unpacked_runs_and_builds_a_consumer(deb, tmp_path):
    root = tmp_path / "root"
    run(["dpkg-deb", "-x", deb, root])
    emu = root / "usr/bin/canopen-emu"
    assert run([emu, "--version"]).startswith("canopen-emu %s" % VERSION)
    devices = run([emu, "--list-devices"])
    assert [line.split()[0] for line in devices.strip().split("\n")] == ["pro-ionizer", "sds", "buerkert"], devices
    assert devices == run([EMU, "--list-devices"])
    # The packaged .pc files work from wherever the tree lies.
    flags = pkg_config(root / "usr", "--cflags", "--libs", "canopen-od-sds").split()
    exe = tmp_path / "consumer"
    run([CC, *STRICT_C99, CONSUMER / "main.c", "-o", exe, *flags])
    check_consumer_output(run([exe]), root / "usr/share/canopen-emu/eds")
