"""Store and restore checks (CiA 301 v4.2.0 §7.5.2.13 0x1010 store parameters, §7.5.2.14 0x1011 restore default
parameters), only with --write.

What they change and how it is put back: a save ("save" to 0x1010:01) makes the values the node runs with its
values at the next power-on. The checks run after every other check has put back what it changed, so the values
saved are those the node had when the run began; a node whose running values were changed and not saved before the
run has them saved. A restore ("load" to 0x1011:01) makes the defaults come back at the next reset or power-on
(the running values stay): store.restore runs it only where a save works, and saves again after it, so that the
node starts next time with the values it runs with, not its defaults. Where that save fails, the result says so
and fails."""
from __future__ import annotations

from typing import TYPE_CHECKING, Optional

from .registry import Failed, NotApplicable, check
from .sdo import SdoAbort, abort_text

if TYPE_CHECKING:
    from .runner import Context

SAVE, LOAD = b"save", b"load"  # the signatures, 0x65766173 and 0x64616F6C as the bus carries them
#: The aborts CiA 301 gives a refused store or restore ("data cannot be transferred or stored": 0x0800002x; a
#: wrong signature is refused with it too).
REFUSED = {0x08000020, 0x08000021, 0x08000022}


def _signature(ctx: "Context", index: int, signature: bytes) -> Optional[int]:
    """Writes the signature to index:01: None when taken, the abort code when refused with one of REFUSED;
    Failed for another abort (0x06060000: the storing failed)."""
    try:
        ctx.sdo.download(index, 1, signature)
        return None
    except SdoAbort as e:
        if e.code in REFUSED:
            return e.code
        raise Failed(f"0x{index:04X}:01 = {signature.decode()!r}: aborted with {abort_text(e.code)}, expected the "
                     "answer or 0x0800002x (refused)", e.frames) from None


def _wrong_signature(ctx: "Context", index: int, wrong: bytes) -> str:
    """A wrong signature is refused with 0x0800002x (nothing stored or restored)."""
    try:
        ctx.sdo.download(index, 1, wrong)
    except SdoAbort as e:
        if e.code not in REFUSED:
            raise Failed(f"0x{index:04X}:01 = {wrong.decode()!r} (a wrong signature): aborted with "
                         f"{abort_text(e.code)}, expected 0x08000020", e.frames) from None
        return f"wrong signature refused with 0x{e.code:08X}"
    raise Failed(f"0x{index:04X}:01 = {wrong.decode()!r} (a wrong signature) was taken, expected abort 0x08000020",
                 ctx.sdo.frames)


@check("store.save", clause="CiA 301 v4.2.0 §7.5.2.13 (0x1010 store parameters: the signature \"save\")",
       summary="0x1010:01 refuses a wrong signature with 0x0800002x, and takes \"save\" (or refuses it with "
               "0x0800002x); the values saved are those the node runs with, every other check having put back "
               "what it changed", writes=True)
def save(ctx: "Context") -> Optional[str]:
    if ctx.eds.entry(0x1010, 1) is None:
        raise NotApplicable("the EDS has no 0x1010:01 (store parameters)")
    with ctx.exchange():
        info = int.from_bytes(ctx.upload(0x1010, 1), "little")
    notes = [f"0x1010:01 = 0x{info:08X}", _wrong_signature(ctx, 0x1010, LOAD)]
    refused = _signature(ctx, 0x1010, SAVE)
    notes.append("saved" if refused is None else f"save refused with 0x{refused:08X}")
    return "; ".join(notes)


@check("store.restore", clause="CiA 301 v4.2.0 §7.5.2.14 (0x1011 restore default parameters: the signature "
                               "\"load\")",
       summary="0x1011:01 refuses a wrong signature with 0x0800002x, and takes \"load\" (or refuses it with "
               "0x0800002x); only where 0x1010:01 saves, which it does after, so the node starts next time with "
               "its present values", writes=True)
def restore(ctx: "Context") -> Optional[str]:
    if ctx.eds.entry(0x1011, 1) is None:
        raise NotApplicable("the EDS has no 0x1011:01 (restore default parameters)")
    notes = [_wrong_signature(ctx, 0x1011, SAVE)]
    if ctx.eds.entry(0x1010, 1) is None:
        raise NotApplicable("the defaults it restores could not be saved over again: the EDS has no 0x1010:01; "
                            + notes[0])
    refused = _signature(ctx, 0x1010, SAVE)
    if refused is not None:
        raise NotApplicable(f"the defaults it restores could not be saved over again: 0x1010:01 refuses \"save\" "
                            f"with 0x{refused:08X}; " + notes[0])

    def save_again() -> None:
        if _signature(ctx, 0x1010, SAVE) is not None:
            raise Failed("the node's stored values are now its defaults: 0x1010:01 refused \"save\" after the "
                         "restore")
    ctx.on_exit(save_again)
    refused = _signature(ctx, 0x1011, LOAD)
    notes.append("restored, then saved again" if refused is None else f"restore refused with 0x{refused:08X}")
    return "; ".join(notes)
