"""SDO protocol checks (CiA 301 v4.2.0 §7.2.4): the transfers, their error answers, and the SDO server's COB-IDs."""
from __future__ import annotations

import struct
from typing import TYPE_CHECKING, Optional, Tuple

from . import eds as eds_module
from .registry import Failed, Findings, NotApplicable, check
from .sdo import SdoAbort, SdoClient, SdoError, abort_text

if TYPE_CHECKING:
    from .runner import Context

ABORT_TOGGLE, ABORT_COMMAND = 0x05030000, 0x05040001
ABORT_TIMEOUT, ABORT_SEQUENCE = 0x05040000, 0x05040003
#: How long a server that must stay silent is given to answer anyway.
SILENCE_S = 0.2
#: The longest SDO server timeout sdo.server-timeout waits for (plus --timeout for the abort to arrive): CiA 301
#: leaves the time to the device; canopen-emu (CO_SDO_TIMEOUT_US) and CANopenNode abort after 1 s, CanFestival
#: (SDO_TIMEOUT_MS) after 3 s.
SERVER_TIMEOUT_MAX_S = 5.0


def long_readable_entry(ctx: "Context") -> Tuple[eds_module.Entry, bytes]:
    """A readable entry whose value is over 4 bytes (a segmented upload), with that value; NotApplicable when the
    EDS has none (up to 16 candidates are read: strings and types over 4 bytes)."""
    tried = 0
    for entry in ctx.eds.entries():
        if not entry.readable or (entry.size is not None and entry.size <= 4):
            continue
        if entry.size is None and isinstance(entry.value, (str, bytes)) and 0 < len(entry.value) <= 4:
            continue
        tried += 1
        if tried > 16:
            break
        try:
            data = ctx.upload(entry.index, entry.sub)
        except SdoError:
            continue
        if len(data) > 4:
            return entry, data
    raise NotApplicable("no readable entry of more than 4 bytes (no segmented transfer to check)")


@check("sdo.expedited-upload", clause="CiA 301 v4.2.0 §7.2.4.3 (SDO upload initiate, expedited)",
       summary="0x1000 uploads expedited: scs 2, e=1 and s=1 with n for 4 bytes, the multiplexer echoed")
def expedited_upload(ctx: "Context") -> Optional[str]:
    with ctx.exchange():
        answer = ctx.sdo.request(struct.pack("<BHB", 0x40, 0x1000, 0))
    command = answer.data[0]
    if command >> 5 == 4:
        raise Failed(f"0x1000:00 aborted with {abort_text(struct.unpack_from('<I', answer.data, 4)[0])}",
                     ctx.sdo.frames)
    if command != 0x43:
        raise Failed(f"answer command byte 0x{command:02X}, expected 0x43 (scs 2, expedited, size indicated, "
                     "4 bytes): 0x1000 is an UNSIGNED32", ctx.sdo.frames)
    if answer.data[1:4] != bytes([0x00, 0x10, 0x00]):
        raise Failed("the answer does not name 0x1000:00", ctx.sdo.frames)
    return None


@check("sdo.segmented-upload", clause="CiA 301 v4.2.0 §7.2.4.3 (SDO upload initiate, SDO upload segment)",
       summary="a value over 4 bytes uploads segmented: toggle bit alternating from 0, c=1 on the last segment, "
               "as many bytes as indicated where the size is (s=1)")
def segmented_upload(ctx: "Context") -> Optional[str]:
    entry, _ = long_readable_entry(ctx)
    with ctx.exchange():
        size = ctx.sdo.start_segmented_upload(entry.index, entry.sub)
        data = ctx.sdo.upload_segments(entry.index, entry.sub, size)
    # s=0 (no size) is allowed: then only the segments are judged
    return f"{entry} ({len(data)} bytes{'' if size is not None else ', size not indicated'})"


@check("sdo.upload-toggle-error", clause="CiA 301 v4.2.0 §7.2.4.3 (SDO upload segment), §7.2.4.3.17 (abort 0x05030000)",
       summary="an upload segment request with the toggle bit not alternated (1 on the first) is aborted with "
               "0x05030000")
def upload_toggle_error(ctx: "Context") -> Optional[str]:
    entry, _ = long_readable_entry(ctx)
    with ctx.exchange():
        ctx.sdo.start_segmented_upload(entry.index, entry.sub)
        answer = ctx.sdo.request(bytes([0x70]))  # toggle 1: the first segment's must be 0
    if answer.data[0] >> 5 != 4:
        ctx.sdo.send_abort(entry.index, entry.sub, 0x08000000)  # end the transfer it went on with
        raise Failed(f"{entry}: a segment request with the wrong toggle bit was answered, not aborted",
                     ctx.sdo.frames)
    code = struct.unpack_from("<I", answer.data, 4)[0]
    if code != ABORT_TOGGLE:
        raise Failed(f"{entry}: aborted with {abort_text(code)}, expected {abort_text(ABORT_TOGGLE)}",
                     ctx.sdo.frames)
    return str(entry)


@check("sdo.unknown-command", clause="CiA 301 v4.2.0 §7.2.4.3.17 (abort 0x05040001)",
       summary="a request with client command specifier 7 (none in CiA 301) is aborted with 0x05040001, and the "
               "server answers the next request")
def unknown_command(ctx: "Context") -> Optional[str]:
    with ctx.exchange():
        answer = ctx.sdo.request(struct.pack("<BHB", 0xE0, 0x1000, 0))
    if answer.data[0] != 0x80:
        raise Failed(f"answered with command byte 0x{answer.data[0]:02X}, expected an abort (0x80)", ctx.sdo.frames)
    code = struct.unpack_from("<I", answer.data, 4)[0]
    if code != ABORT_COMMAND:
        raise Failed(f"aborted with {abort_text(code)}, expected {abort_text(ABORT_COMMAND)}", ctx.sdo.frames)
    frames = list(ctx.sdo.frames)
    with ctx.exchange():
        ctx.upload(0x1000, 0)
    ctx.sdo.frames[:0] = frames
    return None


@check("sdo.client-abort", clause="CiA 301 v4.2.0 §7.2.4.3.17 (SDO abort transfer: unconfirmed)",
       summary="an abort from the client is not answered, whether a transfer is open (a segmented upload) or not, "
               "and the server then takes a new request")
def client_abort(ctx: "Context") -> Optional[str]:
    findings = Findings()
    ctx.sdo.frames = []
    ctx.sdo.send_abort(0x1000, 0, 0x08000000)
    if ctx.sdo.silence(SILENCE_S) is not None:
        findings.add("an abort with no transfer open was answered", ctx.sdo.frames)
    try:
        entry, _ = long_readable_entry(ctx)
    except NotApplicable:
        entry = None
    if entry is not None:
        try:
            ctx.sdo.start_segmented_upload(entry.index, entry.sub)
            ctx.sdo.send_abort(entry.index, entry.sub, 0x08000000)
            if ctx.sdo.silence(SILENCE_S) is not None:
                findings.add(f"{entry}: the abort of an open segmented upload was answered", ctx.sdo.frames)
        except SdoError as e:
            findings.add(f"{entry}: {e.reason}", e.frames)
    try:
        ctx.upload(0x1000, 0)
    except SdoError as e:
        findings.add(f"after the abort: {e}", e.frames)
    findings.raise_if_any("wrong answers")
    return "with an open segmented upload" if entry is not None else "no transfer open (no entry over 4 bytes)"


@check("sdo.server-cob-ids", clause="CiA 301 v4.2.0 §7.5.2.33 (0x1200..0x127F SDO server parameter), the "
                                    "predefined connection set (§7.3)",
       summary="0x1200:01/02 hold 0x600/0x580 + node-ID, and every SDO server with valid COB-IDs answers an "
               "upload of 0x1000 on its own COB-ID")
def server_cob_ids(ctx: "Context") -> Optional[str]:
    findings = Findings()
    servers = [i for i in sorted(ctx.eds.objects) if 0x1200 <= i <= 0x127F]
    if 0x1200 in servers:
        for sub, expected in ((1, 0x600 + ctx.node), (2, 0x580 + ctx.node)):
            try:
                value = int.from_bytes(ctx.upload(0x1200, sub), "little")
            except SdoError as e:
                findings.add(f"0x1200:{sub:02X}: {e.reason}", e.frames)
                continue
            if value != expected:
                findings.add(f"0x1200:{sub:02X} is 0x{value:08X}, expected 0x{expected:03X} (0x{expected & 0x780:03X}"
                             f" + node-ID)", ctx.sdo.frames)
    checked = []
    for index in servers[1:]:
        try:
            request_id = int.from_bytes(ctx.upload(index, 1), "little")
            response_id = int.from_bytes(ctx.upload(index, 2), "little")
        except SdoError as e:
            findings.add(f"0x{index:04X}: {e}", e.frames)
            continue
        if request_id & 0x80000000 or response_id & 0x80000000 or request_id & 0x20000000:
            continue  # not valid (or extended): the server is off
        client = SdoClient(ctx.log, ctx.node, ctx.options.timeout, request_id & 0x7FF, response_id & 0x7FF)
        try:
            client.upload(0x1000, 0)
            checked.append(f"0x{index:04X} (0x{request_id & 0x7FF:03X}/0x{response_id & 0x7FF:03X})")
        except SdoError as e:
            findings.add(f"SDO server 0x{index:04X} on 0x{request_id & 0x7FF:03X}/0x{response_id & 0x7FF:03X}: {e}",
                         e.frames)
    if not servers:
        raise NotApplicable("the EDS lists no SDO server parameter (0x1200..0x127F)")
    findings.raise_if_any("wrong SDO server COB-IDs")
    return ", ".join(["0x1200"] + checked) if 0x1200 in servers else ", ".join(checked)


@check("sdo.block-upload", clause="CiA 301 v4.2.0 §7.2.4.3.9-16 (SDO block upload, CRC)",
       summary="where the server has block transfer (it does not abort the initiate with 0x05040001): a value over "
               "4 bytes uploads by block with sequence numbers 1.. in each block, the size indicated, and the CRC "
               "where the server uses it; the same bytes as a segmented or expedited upload")
def block_upload(ctx: "Context") -> Optional[str]:
    entry, plain = long_readable_entry(ctx)
    try:
        data, crc = ctx.sdo.block_upload(entry.index, entry.sub)
    except SdoAbort as e:
        if e.code == ABORT_COMMAND:
            raise NotApplicable("the server has no block transfer (the initiate is aborted with 0x05040001)") \
                from None
        raise Failed(str(e), e.frames) from None
    except SdoError as e:
        raise Failed(str(e), e.frames) from None
    if data != plain:
        raise Failed(f"{entry}: block upload gave {data!r}, an upload {plain!r}", ctx.sdo.frames)
    return f"{entry} ({len(data)} bytes, {'with' if crc else 'without'} CRC)"


@check("sdo.server-timeout", clause="CiA 301 v4.2.0 §7.2.4.3 (SDO upload segment), §7.2.4.3.17 (abort 0x05040000)",
       summary="a segmented upload left open after its initiate (no segment request follows) is aborted by the "
               f"server with 0x05040000, naming the entry, within {SERVER_TIMEOUT_MAX_S:g} s (CiA 301 leaves the "
               "time to the device)")
def server_timeout(ctx: "Context") -> Optional[str]:
    entry, _ = long_readable_entry(ctx)
    with ctx.exchange():
        ctx.sdo.start_segmented_upload(entry.index, entry.sub)
    opened = ctx.sdo.frames[-1].time  # the initiate's answer: the server's timeout runs from the request before it
    wait = SERVER_TIMEOUT_MAX_S + ctx.options.timeout
    answer = ctx.sdo.silence(wait)
    if answer is None:
        ctx.sdo.send_abort(entry.index, entry.sub, ABORT_TIMEOUT)  # the client's side of the timeout
        raise Failed(f"{entry}: a segmented upload left open after its initiate was not aborted by the server within "
                     f"{wait:g} s: expected abort {abort_text(ABORT_TIMEOUT)}", ctx.sdo.frames)
    if len(answer.data) != 8 or answer.data[0] != 0x80:
        ctx.sdo.send_abort(entry.index, entry.sub, ABORT_TIMEOUT)
        raise Failed(f"{entry}: waiting for the server's timeout, it sent {answer.data.hex(' ')} unasked, not an "
                     f"abort {abort_text(ABORT_TIMEOUT)}", ctx.sdo.frames)
    code = struct.unpack_from("<I", answer.data, 4)[0]
    named = struct.unpack_from("<HB", answer.data, 1)
    after = answer.time - opened
    if code != ABORT_TIMEOUT:
        raise Failed(f"{entry}: aborted after {after:.2f} s with {abort_text(code)}, expected "
                     f"{abort_text(ABORT_TIMEOUT)}", ctx.sdo.frames)
    if named != (entry.index, entry.sub):
        raise Failed(f"{entry}: the timeout abort names 0x{named[0]:04X}:{named[1]:02X}", ctx.sdo.frames)
    return f"{entry}: aborted with 0x{ABORT_TIMEOUT:08X} {after:.2f} s after the initiate"


def writable_entry(ctx: "Context", long: bool) -> Tuple[eds_module.Entry, bytes]:
    """A readable and writable entry with its current value (not empty): of a string type or over 4 bytes
    (``long``: a segmented download, which CiA 301 allows for any length) or of 1 to 4 bytes; one of the
    application's (0x2000 and up) first, so that writing back its own value touches no communication."""
    candidates = [e for e in ctx.eds.entries() if e.readable and e.writable and e.data_type != 0x0F
                  and ((e.size is None or e.size > 4) if long else (e.size is not None and e.size <= 4))]
    candidates.sort(key=lambda e: e.index < 0x2000)
    for entry in candidates[:16]:
        try:
            data = ctx.upload(entry.index, entry.sub)
        except SdoError:
            continue
        if data and (long or len(data) <= 4):
            return entry, data
    raise NotApplicable(f"no readable and writable entry {'of a string type or over 4 bytes' if long else 'of 1 to 4 bytes'}"
                        " with a value")


@check("sdo.expedited-download", clause="CiA 301 v4.2.0 §7.2.4.3 (SDO download initiate, expedited)",
       summary="a writable entry of 1..4 bytes takes its own value expedited (scs 3, the multiplexer echoed) and "
               "reads it back", writes=True)
def expedited_download(ctx: "Context") -> Optional[str]:
    entry, data = writable_entry(ctx, long=False)
    with ctx.exchange():
        ctx.sdo.download(entry.index, entry.sub, data)
        frames = list(ctx.sdo.frames)
        back = ctx.upload(entry.index, entry.sub)
    if back != data:
        raise Failed(f"{entry}: wrote {data.hex(' ')}, read back {back.hex(' ')}", frames + ctx.sdo.frames)
    return str(entry)


@check("sdo.segmented-download", clause="CiA 301 v4.2.0 §7.2.4.3 (SDO download initiate, SDO download segment)",
       summary="a writable entry of a string type or over 4 bytes takes its own value segmented (size indicated, "
               "toggle bit alternating, c=1 last; any length may go segmented) and reads it back", writes=True)
def segmented_download(ctx: "Context") -> Optional[str]:
    entry, data = writable_entry(ctx, long=True)
    with ctx.exchange():
        ctx.sdo.download(entry.index, entry.sub, data, segmented=True)
        frames = list(ctx.sdo.frames)
        back = ctx.upload(entry.index, entry.sub)
    if back != data:
        raise Failed(f"{entry}: wrote {data.hex(' ')}, read back {back.hex(' ')}", frames + ctx.sdo.frames)
    return f"{entry} ({len(data)} bytes)"


@check("sdo.download-toggle-error", clause="CiA 301 v4.2.0 §7.2.4.3 (SDO download segment), §7.2.4.3.17 (abort "
                                           "0x05030000)",
       summary="a segmented download of an entry's own value whose first segment has toggle bit 1 is aborted with "
               "0x05030000 (nothing is written: the transfer never completes)", writes=True)
def download_toggle_error(ctx: "Context") -> Optional[str]:
    entry, data = writable_entry(ctx, long=True)
    with ctx.exchange():
        ctx.sdo.frames = []
        answer = ctx.sdo.request(struct.pack("<BHBI", 0x21, entry.index, entry.sub, len(data)))
        if answer.data[0] >> 5 != 3:
            raise Failed(f"{entry}: the segmented download initiate was answered with 0x{answer.data[0]:02X}, not "
                         "0x60", ctx.sdo.frames)
        chunk = data[:7]
        last = len(data) <= 7
        answer = ctx.sdo.request(bytes([0x10 | (7 - len(chunk)) << 1 | int(last)]) + chunk)  # toggle 1: wrong
    if answer.data[0] >> 5 != 4:
        if not last:
            ctx.sdo.send_abort(entry.index, entry.sub, 0x08000000)  # end the transfer it went on with
        raise Failed(f"{entry}: a download segment with the wrong toggle bit was taken, not aborted", ctx.sdo.frames)
    code = struct.unpack_from("<I", answer.data, 4)[0]
    if code != ABORT_TOGGLE:
        raise Failed(f"{entry}: aborted with {abort_text(code)}, expected {abort_text(ABORT_TOGGLE)}", ctx.sdo.frames)
    return str(entry)


def block_download_entry(ctx: "Context") -> Tuple[eds_module.Entry, bytes]:
    """The entry the block download checks write back: a string or one over 4 bytes (more than one segment),
    else one of 1..4 bytes (CiA 301 lets block transfer carry any length)."""
    try:
        return writable_entry(ctx, long=True)
    except NotApplicable:
        return writable_entry(ctx, long=False)


def no_block_transfer(e: SdoAbort) -> NotApplicable:
    return NotApplicable(f"the server has no block transfer (the block download initiate of 0x{e.index:04X}:"
                         f"{e.sub:02X} is aborted with 0x05040001)")


@check("sdo.block-download", clause="CiA 301 v4.2.0 §7.2.4.3.9-16 (SDO block download, CRC)",
       summary="where the server has block transfer (it does not abort the initiate with 0x05040001): a writable "
               "entry takes its own value by block download (size indicated, CRC offered, blocks of the size the "
               "server asks for, sequence numbers 1.. in each, c=1 on the last segment, the CRC where the server "
               "supports it) and reads it back", writes=True)
def block_download(ctx: "Context") -> Optional[str]:
    entry, data = block_download_entry(ctx)
    try:
        crc = ctx.sdo.block_download(entry.index, entry.sub, data)
    except SdoAbort as e:
        if e.code == ABORT_COMMAND and len(e.frames) <= 2:  # refused at the initiate
            raise no_block_transfer(e) from None
        raise Failed(str(e), e.frames) from None
    except SdoError as e:
        ctx.sdo.send_abort(entry.index, entry.sub, 0x08000000)  # end what the server may still hold open
        raise Failed(str(e), e.frames + ctx.sdo.frames[-1:]) from None
    frames = list(ctx.sdo.frames)
    with ctx.exchange():
        back = ctx.upload(entry.index, entry.sub)
    if back != data:
        raise Failed(f"{entry}: wrote {data.hex(' ')} by block, read back {back.hex(' ')}", frames + ctx.sdo.frames)
    return f"{entry} ({len(data)} bytes, {'with' if crc else 'without'} CRC)"


@check("sdo.block-sequence-error", clause="CiA 301 v4.2.0 §7.2.4.3.9-16 (SDO block download), §7.2.4.3.17 (abort "
                                          "0x05040003)",
       summary="where the server has block transfer: a block download of an entry's own value whose first segment "
               "has sequence number 0 (a block's are 1..127) is aborted with 0x05040003 (nothing is written: the "
               "transfer never completes)", writes=True)
def block_sequence_error(ctx: "Context") -> Optional[str]:
    entry, data = block_download_entry(ctx)
    try:
        ctx.sdo.start_block_download(entry.index, entry.sub, len(data))
    except SdoAbort as e:
        if e.code == ABORT_COMMAND:
            raise no_block_transfer(e) from None
        raise Failed(str(e), e.frames) from None
    except SdoError as e:
        raise Failed(str(e), e.frames) from None
    ctx.sdo.frames.append(ctx.log.send(ctx.sdo.request_id, bytes([0x00]) + data[:7].ljust(7, b"\0")))  # c=0, seq 0
    answer = ctx.sdo.silence(ctx.options.timeout)
    if answer is None or len(answer.data) != 8 or answer.data[0] != 0x80:
        ctx.sdo.send_abort(entry.index, entry.sub, ABORT_SEQUENCE)  # end the transfer it went on with
        what = (f"not answered within {ctx.options.timeout:g} s" if answer is None
                else f"answered with {answer.data.hex(' ')}")
        raise Failed(f"{entry}: a block download segment with sequence number 0 was {what}, expected abort "
                     f"{abort_text(ABORT_SEQUENCE)}", ctx.sdo.frames)
    code = struct.unpack_from("<I", answer.data, 4)[0]
    if code != ABORT_SEQUENCE:
        raise Failed(f"{entry}: aborted with {abort_text(code)}, expected {abort_text(ABORT_SEQUENCE)}",
                     ctx.sdo.frames)
    return str(entry)
