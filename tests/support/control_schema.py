"""The control protocol's JSON schema (docs/control-protocol.schema.json) as the tests check every line with: the
integration tests over the control sockets and the native tests of the web view share it."""
import json
from pathlib import Path

import jsonschema

SCHEMA = json.loads((Path(__file__).resolve().parents[2] / "docs/control-protocol.schema.json").read_text())
KNOWN = ("hello", "list", "show", "get", "set", "objects", "tables", "subscribe", "unsubscribe", "quit")


def validator(pointer):
    return jsonschema.Draft202012Validator({**SCHEMA, "$ref": pointer})


VALIDATE_REQUEST = validator("#/$defs/request")
VALIDATE_EVENT = validator("#/$defs/event")
VALIDATE_ERROR = validator("#/$defs/error_response")
VALIDATE_RESPONSE = {cmd: validator(f"#/$defs/responses/{cmd}") for cmd in KNOWN + ("command",)}


def check_schema(msg, cmd):
    """Every JSON line the emulator writes is what the schema says: an event, an error, or the answer to cmd."""
    if "event" in msg:
        VALIDATE_EVENT.validate(msg)
    elif msg.get("ok") is False and "lines" not in msg:
        VALIDATE_ERROR.validate(msg)
    else:
        VALIDATE_RESPONSE[cmd if cmd in KNOWN else "command"].validate(msg)
