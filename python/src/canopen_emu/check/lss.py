"""LSS checks (CiA 305), where the EDS says ``LSS_Supported=1``.

Only the service that changes nothing is used so far: "identify remote slave", which every LSS slave in the
waiting state answers whatever its NMT state. Left for later (docs/conformance.md "Not yet checked"): switch state
selective and the inquiries (vendor, product, revision, serial, node-ID) against 0x1018, with --write the
configuration services.

LSS answers do not say which node gave them: the check assumes no other LSS master on the bus meanwhile (two runs
of canopen-check at once on one bus confuse each other's LSS checks)."""
from __future__ import annotations

import struct
from typing import TYPE_CHECKING, Optional

from .registry import Failed, NotApplicable, check

if TYPE_CHECKING:
    from .runner import Context

LSS_MASTER_ID, LSS_SLAVE_ID = 0x7E5, 0x7E4
IDENTIFY_SLAVE = 0x4F


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
                     list(ctx.log.trace))
    if ask(vendor ^ 0xFFFFFFFF) is not None:
        raise Failed("answered \"identify slave\" for a vendor-ID that is not its own", list(ctx.log.trace))
    return f"vendor 0x{vendor:08X}, product 0x{product:08X}, revision 0x{revision:08X}, serial 0x{serial:08X}"
