"""What a check is and what it yields: the ``@check`` decorator that every group module (od, sdo_protocol, nmt,
pdo, emcy, lss) uses to register its checks, the results, and the exceptions a check ends with.

A check is a function ``f(ctx: Context) -> Optional[str]``: it returns (an optional note: what it looked at) when
the node passed, raises ``Failed`` with a message and the frames that show why, or ``NotApplicable`` with the
reason (the EDS has no such object, the check changes the device and ``--write`` was not given, ...). Anything else
it raises is reported as a failure of its own kind (``error``): a bug of the check or a bus that broke.

Adding a check: write the function in the module of its group, decorate it with ``@check("group.name",
clause="CiA 301 §...", summary="...")`` (``writes=True`` when it changes the device: SDO downloads, NMT
commands), and add a row to docs/conformance.md. The order of registration is the order of the run."""
from __future__ import annotations

import enum
from dataclasses import dataclass, field
from typing import TYPE_CHECKING, Callable, Dict, List, Optional

from .frames import Frame

if TYPE_CHECKING:
    from .runner import Context


class Status(enum.Enum):
    PASSED = "passed"
    FAILED = "failed"
    ERROR = "error"  # the check itself broke (an exception): counted as a failure
    NOT_APPLICABLE = "not applicable"


class Failed(Exception):
    """The node does not do what the clause asks: ``message`` says what, ``frames`` show it."""

    def __init__(self, message: str, frames: Optional[List[Frame]] = None) -> None:
        super().__init__(message)
        self.frames = list(frames or [])


class NotApplicable(Exception):
    """The check does not apply to this node (the reason is the message)."""


@dataclass(frozen=True)
class Check:
    name: str                       # "od.readable-entries": group, dot, what
    clause: str                     # where the rule comes from: "CiA 301 v4.2.0 §7.4.8.1"
    summary: str                    # one line: what is checked
    writes: bool                    # changes the device (SDO download, NMT command): only with --write
    function: Callable[["Context"], Optional[str]]

    @property
    def group(self) -> str:
        return self.name.split(".", 1)[0]


@dataclass
class Result:
    check: Check
    status: Status
    message: str = ""
    frames: List[Frame] = field(default_factory=list)
    duration: float = 0.0

    @property
    def name(self) -> str:
        return self.check.name

    @property
    def failed(self) -> bool:
        return self.status in (Status.FAILED, Status.ERROR)


#: Every check, in the order they run.
CHECKS: Dict[str, Check] = {}


def check(name: str, *, clause: str, summary: str, writes: bool = False) \
        -> Callable[[Callable[["Context"], Optional[str]]], Callable[["Context"], Optional[str]]]:
    """Registers the decorated function as the check ``name``."""
    def register(function: Callable[["Context"], Optional[str]]) -> Callable[["Context"], Optional[str]]:
        if name in CHECKS:
            raise ValueError(f"two checks named {name}")
        CHECKS[name] = Check(name, clause, summary, writes, function)
        return function
    return register


class Findings:
    """Problems gathered over many entries, so that one check reports all of them at once: ``add(text,
    frames)``; ``raise_if_any(what)`` raises Failed with every text and the frames of the first few."""

    FRAMES_OF = 3

    def __init__(self) -> None:
        self.problems: List[str] = []
        self.frames: List[Frame] = []
        self._framed = 0

    def add(self, text: str, frames: Optional[List[Frame]] = None) -> None:
        self.problems.append(text)
        if frames and self._framed < self.FRAMES_OF:
            self.frames.extend(frames)
            self._framed += 1

    def __bool__(self) -> bool:
        return bool(self.problems)

    def raise_if_any(self, what: str) -> None:
        """Failed("N WHAT: the first problem", then the others one a line (50 at most))."""
        if self.problems:
            first, rest = self.problems[0], self.problems[1:50]
            more = [f"... and {len(self.problems) - 50} more"] if len(self.problems) > 50 else []
            raise Failed("\n".join([f"{len(self.problems)} {what}: {first}"] + ["  " + p for p in rest] + more),
                         self.frames)
