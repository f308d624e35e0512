"""The exceptions of canopen_emu. All derive from CanopenEmuError."""
from __future__ import annotations

import json
from typing import Any, Dict, List, Mapping, Optional, Sequence


class CanopenEmuError(Exception):
    """Base class of every error this package raises."""


class ControlError(CanopenEmuError):
    """The emulator refused a request (``"ok": false``).

    ``error`` is the emulator's own text, unchanged (``"70000 is out of range: 0x1017:00 (UNSIGNED16) holds
    0..65535"``), ``request`` the request as it was sent, ``lines`` the reply lines of a command of the command
    language (empty for the JSON commands), ``response`` the whole answer."""

    def __init__(self, error: str, request: Mapping[str, Any], lines: Sequence[str] = (),
                 response: Optional[Mapping[str, Any]] = None) -> None:
        self.error: str = error
        self.request: Dict[str, Any] = dict(request)
        self.lines: List[str] = list(lines)
        self.response: Dict[str, Any] = dict(response) if response is not None else {}
        super().__init__(error)

    @property
    def cmd(self) -> str:
        """The command that was refused."""
        return str(self.request.get("cmd", ""))

    def __str__(self) -> str:
        # The server's text first: pytest.raises(match=...) and a reader both look for it.
        return f"{self.error} (request: {json.dumps(self.request, separators=(',', ':'))})"


class ProtocolError(CanopenEmuError):
    """The other end does not speak version 1 of the control protocol, or sent a line that is not one."""


class ControlTimeout(CanopenEmuError, TimeoutError):
    """No answer, or no matching event, within the time given."""


class ConnectionClosed(CanopenEmuError, ConnectionError):
    """The emulator closed the control connection (it stopped, or refused the client)."""


class EmulatorError(CanopenEmuError):
    """The launcher could not start canopen-emu, or it did not come up as asked.

    ``returncode`` is its exit status when it has exited (None while it runs), ``log`` its log (stderr) so far."""

    def __init__(self, message: str, returncode: Optional[int] = None, log: str = "") -> None:
        self.returncode = returncode
        self.log = log
        super().__init__(message)
