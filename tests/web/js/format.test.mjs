// web/format.js: the texts of the overview's cells.
import {test} from "node:test";
import assert from "node:assert/strict";

import * as format from "../../../web/format.js";

test("hex pads to the digits asked for and is upper case", () => {
  assert.equal(format.hex(0x191, 8), "0x00000191");
  assert.equal(format.hex(0xF0191, 8), "0x000F0191");
  assert.equal(format.hex(0xFFFFFFFF, 8), "0xFFFFFFFF");
  assert.equal(format.hex(5, 2), "0x05");
  assert.equal(format.hex(0x3210, 4), "0x3210");
  assert.equal(format.hex(0x12345, 4), "0x12345"); // never cut
});

test("duration: tenths below 10 s (never rounded up), then whole units", () => {
  const cases = [
    [0, "0.0 s"], [-5, "0.0 s"], [99_999, "0.0 s"], [100_000, "0.1 s"], [999_999, "0.9 s"], [1_000_000, "1.0 s"],
    [9_999_999, "9.9 s"], [10_000_000, "10 s"], [59_999_999, "59 s"], [60_000_000, "1 min 0 s"],
    [125_500_000, "2 min 5 s"], [3_599_999_999, "59 min 59 s"], [3_600_000_000, "1 h 0 min"],
    [90_061_000_000, "25 h 1 min"],
  ];
  for (const [us, text] of cases) {
    assert.equal(format.duration(us), text, `${us} µs`);
  }
});

test("ago is empty while a time is unknown", () => {
  assert.equal(format.ago(1_000_000, 3_500_000), "2.5 s ago");
  assert.equal(format.ago(null, 3_500_000), "");
  assert.equal(format.ago(1_000_000, null), "");
});

test("device with its variant, heartbeat period, EMCY", () => {
  assert.equal(format.device({device: "sds", variant: "N"}), "sds (N)");
  assert.equal(format.device({device: "buerkert", variant: null}), "buerkert");
  assert.equal(format.heartbeatPeriod(500), "500 ms");
  assert.equal(format.heartbeatPeriod(0), "off");
  // the code with its class as the trace words it (decode.js EMCY_CLASSES: one table)
  assert.equal(format.emcy({code: 0x5000, register: 1, info: "A1B2C3D4E5"}),
    "0x5000 device hardware, reg 0x01 info A1B2C3D4E5");
  assert.equal(format.emcy({code: 0x8130, register: 0x11, info: "0000000000"}),
    "0x8130 life guard error or heartbeat error, reg 0x11 info 0000000000");
  assert.equal(format.emcy({code: 0x3210, register: 5, info: "0000000000"}), // not listed: the class of 0x3200
    "0x3210 voltage inside the device, reg 0x05 info 0000000000");
  assert.equal(format.emcy({code: 0xFF42, register: 0x80, info: "0102030405"}),
    "0xFF42 device specific, reg 0x80 info 0102030405");
  assert.equal(format.emcy({code: 0x0000, register: 0, info: "0000000000"}),
    "0x0000 error reset or no error, reg 0x00 info 0000000000");
  assert.equal(format.emcy({code: 0x0012, register: 1, info: "0000000000"}),
    "0x0012 unknown code, reg 0x01 info 0000000000");
});
