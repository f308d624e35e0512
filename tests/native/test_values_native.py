"""Values through the control protocol's JSON get/set and the command language's set, which both call the device's
typed calls (devices/device_value.c): a JSON value is taken as it is, in the object's type, never turned into a
word and read again; both ways refuse a value with the same words. A device of every data type read from an EDS
(tests/eds/files/all-types.eds), on canopen-emu-fakecan (also under ASan+UBSan)."""
import json
import os

from test_text_native import TextEmulator

SRC = os.environ.get("CO_SOURCE_DIR", os.path.join(os.path.dirname(__file__), "..", ".."))
ALL_TYPES = os.path.join(SRC, "tests", "eds", "files", "all-types.eds")

# (object, JSON value, the answer's value or the refusal's text)
JSON_SETS = [
    ("0x200F", 1.5, 1.5),                           # REAL64 (was read as an integer word: refused)
    ("0x200F", "-2.5e10", -2.5e10),                 # a REAL64 from a word
    ("0x2007", 2, 2.0),                             # REAL32 from an integer
    ("0x2002", 2.0, 2),                             # INTEGER16 from a whole fraction
    ("0x2002", 2.5, "2.5 is not a whole number"),
    ("0x2002", -32769, "-32769 is out of range: 0x2002:00 (INTEGER16) holds -32768..32767"),
    ("0x2002", "0x10", 16),
    ("0x2000", False, False),                       # BOOLEAN
    ("0x2004", True, 1),                            # true/false as 1/0 in an UNSIGNED8
    ("0x2008", "ES61", "ES61"),                     # VISIBLE_STRING
    ("0x2008", 1234, "0x2008:00 is a VISIBLE_STRING: give it text"),
    ("0x2004", "abc", "'abc' is not a number"),
]


def test_json_set_takes_each_value_in_its_objects_type_and_text_set_refuses_alike(tmp_path):
    emu = TextEmulator(tmp_path, f"{ALL_TYPES}:5")
    emu.bus.expect(lambda i, d: i == 0x705 and d == b"\0", 10.0, "boot-up of node 5")
    for n, (obj, value, _) in enumerate(JSON_SETS):
        emu.command(json.dumps({"id": n, "cmd": "set", "node": 5, "object": obj, "value": value}))
    emu.command("set 5 0x2002 2.5")
    emu.command("set 5 0x200F 0.25")
    emu.command("get 5 0x200F")
    out, _ = emu.quit()
    lines = out.decode().splitlines()
    answers = {a["id"]: a for a in (json.loads(l) for l in lines if l.startswith("{"))}
    for n, (obj, value, want) in enumerate(JSON_SETS):
        a = answers[n]
        if isinstance(want, str) and (" " in want):
            assert a == {"id": n, "ok": False, "error": want}, (obj, value, a)
        else:
            assert a["ok"] is True and a["value"] == want and type(a["value"]) is type(want), (obj, value, a)
    text = [l for l in lines if not l.startswith("{")]
    assert text == ["node 5: error: 2.5 is not a whole number",
                    "node 5: 0x200F:00 = 0.25",
                    "node 5: 0x200F:00 = 0.25"], text
