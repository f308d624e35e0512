"""LSS checks (CiA 305), where the EDS says ``LSS_Supported=1``.

Only services that change no configuration are used: "identify remote slave", which every LSS slave in the
waiting state answers whatever its NMT state, and the inquiries, for which the node alone is switched into the
configuration state (switch state selective) and back to waiting (switch state global, which returns every node in
configuration to waiting: do not run it while another LSS master configures nodes). Left for later
(docs/conformance.md "Not yet checked"): with --write the configuration services (node-ID, bit timing, store).

LSS answers do not say which node gave them: the check assumes no other LSS master on the bus meanwhile (two runs
of canopen-check at once on one bus confuse each other's LSS checks)."""
from __future__ import annotations

import struct
from typing import TYPE_CHECKING, List, Optional

from .frames import Frame
from .registry import Failed, Findings, NotApplicable, check

if TYPE_CHECKING:
    from .runner import Context

LSS_MASTER_ID, LSS_SLAVE_ID = 0x7E5, 0x7E4
IDENTIFY_SLAVE = 0x4F


def _lss_frames(ctx: "Context") -> List[Frame]:
    """The LSS frames of the check (a failure shows these, not the SDO uploads and heartbeats around them)."""
    return [f for f in ctx.log.trace if f.can_id in (LSS_MASTER_ID, LSS_SLAVE_ID)]


@check("lss.identify-remote-slave", clause="CiA 305 v3.0.0, LSS identify remote slave (cs 0x46..0x4B) and identify "
                                          "slave (cs 0x4F)",
       summary="the node answers \"identify remote slave\" for its own identity (0x1018:01..04, revision and serial "
               "as single-value ranges) with \"identify slave\", and stays silent for another vendor-ID")
def identify_remote_slave(ctx: "Context") -> Optional[str]:
    if not ctx.eds.info_flag("LSS_Supported"):
        raise NotApplicable("the EDS does not say LSS_Supported=1")
    identity = []
    with ctx.exchange():
        for sub in range(1, 5):
            identity.append(int.from_bytes(ctx.upload(0x1018, sub), "little"))
    vendor, product, revision, serial = identity

    def ask(vendor_id: int) -> Optional[object]:
        ctx.log.drain()
        for command, value in ((0x46, vendor_id), (0x47, product), (0x48, revision), (0x49, revision),
                               (0x4A, serial), (0x4B, serial)):
            ctx.log.send(LSS_MASTER_ID, struct.pack("<BI3x", command, value))
        return ctx.log.wait_for(lambda f: f.can_id == LSS_SLAVE_ID and f.data[:1] == bytes([IDENTIFY_SLAVE]),
                                ctx.options.timeout)

    if ask(vendor) is None:
        raise Failed(f"no \"identify slave\" (0x7E4 [8] 4F ...) within {ctx.options.timeout} s for vendor "
                     f"0x{vendor:08X}, product 0x{product:08X}, revision 0x{revision:08X}, serial 0x{serial:08X}",
                     _lss_frames(ctx))
    if ask(vendor ^ 0xFFFFFFFF) is not None:
        raise Failed("answered \"identify slave\" for a vendor-ID that is not its own", _lss_frames(ctx))
    return f"vendor 0x{vendor:08X}, product 0x{product:08X}, revision 0x{revision:08X}, serial 0x{serial:08X}"


INQUIRIES = ((0x5A, "vendor-ID", 1), (0x5B, "product code", 2), (0x5C, "revision number", 3),
             (0x5D, "serial number", 4))


@check("lss.inquire-identity", clause="CiA 305 v3.0.0, LSS switch state selective (cs 0x40..0x44), inquire identity "
                                      "(cs 0x5A..0x5D), inquire node-ID (cs 0x5E), switch state global (cs 0x04)",
       summary="switched into the configuration state by its own identity, the node answers each inquiry with "
               "0x1018:01..04 and its node-ID; then back to waiting")
def inquire_identity(ctx: "Context") -> Optional[str]:
    if not ctx.eds.info_flag("LSS_Supported"):
        raise NotApplicable("the EDS does not say LSS_Supported=1")
    identity = []
    with ctx.exchange():
        for sub in range(1, 5):
            identity.append(int.from_bytes(ctx.upload(0x1018, sub), "little"))
    ctx.on_exit(lambda: ctx.log.send(LSS_MASTER_ID, bytes([0x04, 0x00]).ljust(8, b"\0")) and None)
    ctx.log.drain()
    for command, value in zip((0x40, 0x41, 0x42, 0x43), identity):
        ctx.log.send(LSS_MASTER_ID, struct.pack("<BI3x", command, value))
    if ctx.log.wait_for(lambda f: f.can_id == LSS_SLAVE_ID and f.data[:1] == b"\x44", ctx.options.timeout) is None:
        raise Failed("no answer to switch state selective (0x7E4 [8] 44 ...) for the node's own identity",
                     _lss_frames(ctx))
    findings = Findings()
    asked = [(cs, what, identity[sub - 1]) for cs, what, sub in INQUIRIES] + [(0x5E, "node-ID", ctx.node)]
    for command, what, expected in asked:
        ctx.log.send(LSS_MASTER_ID, bytes([command]).ljust(8, b"\0"))
        answer = ctx.log.wait_for(lambda f, c=command: f.can_id == LSS_SLAVE_ID and f.data[:1] == bytes([c]),
                                  ctx.options.timeout)
        if answer is None:
            findings.add(f"inquire {what} (cs 0x{command:02X}): no answer", _lss_frames(ctx)[-2:])
            continue
        got = answer.data[1] if command == 0x5E else struct.unpack_from("<I", answer.data.ljust(8, b"\0"), 1)[0]
        if got != expected:
            findings.add(f"inquire {what}: 0x{got:X}, expected 0x{expected:X}", [answer])
    findings.raise_if_any("wrong inquiry answers")
    return None

