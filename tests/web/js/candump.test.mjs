// web/candump.js: the trace as a candump -l log.
import {test} from "node:test";
import assert from "node:assert/strict";

import * as candump from "../../../web/candump.js";

const clock = {time_us: 2_000_000, unix_us: 1_701_234_567_000_000}; // hello's: the emulator 2 s after its start

test("the wall clock of an emulator time", () => {
  assert.equal(candump.unixUs(2_000_000, clock), 1_701_234_567_000_000);
  assert.equal(candump.unixUs(2_123_456, clock), 1_701_234_567_123_456);
  assert.equal(candump.unixUs(1_999_999, clock), 1_701_234_566_999_999); // before hello's answer
});

test("a line is candump -l's: (seconds.microseconds) interface id#data", () => {
  assert.equal(candump.line(1_701_234_567_123_456, "vcan0", {id: 0x123, data: "DEADBEEF"}),
    "(1701234567.123456) vcan0 123#DEADBEEF");
  assert.equal(candump.line(1_701_234_567_000_001, "can1", {id: 0x000, data: "0100"}),
    "(1701234567.000001) can1 000#0100");
  assert.equal(candump.line(1_701_234_567_000_000, "vcan0", {id: 0x711, data: "7f"}),
    "(1701234567.000000) vcan0 711#7F"); // upper case, as candump writes
  assert.equal(candump.line(1_701_234_567_500, "vcan0", {id: 0x80, data: ""}), "(1701234.567500) vcan0 080#");
});

test("a remote request is R, with its length when not 0; a 29-bit ID has 8 digits", () => {
  assert.equal(candump.line(1_000_000, "vcan0", {id: 0x711, data: "", rtr: true}), "(1.000000) vcan0 711#R");
  assert.equal(candump.line(1_000_000, "vcan0", {id: 0x711, data: "0000", rtr: true}), "(1.000000) vcan0 711#R2");
  assert.equal(candump.line(1_000_000, "vcan0", {id: 0x1234567, data: "01"}), "(1.000000) vcan0 01234567#01");
  assert.equal(candump.line(1_000_000, "vcan0", {id: 0x7FF, data: "01"}), "(1.000000) vcan0 7FF#01");
});

test("an extended frame has 8 digits whatever its identifier: canplayer sends it as a 29-bit frame again", () => {
  assert.equal(candump.line(1_000_000, "vcan0", {id: 0x181, data: "1122", eff: true}), "(1.000000) vcan0 00000181#1122");
  assert.equal(candump.line(1_000_000, "vcan0", {id: 0x000, data: "", eff: true}), "(1.000000) vcan0 00000000#");
  assert.equal(candump.line(1_000_000, "vcan0", {id: 0x711, data: "00", rtr: true, eff: true}),
    "(1.000000) vcan0 00000711#R1");
  assert.equal(candump.line(1_000_000, "vcan0", {id: 0x181, data: "1122", eff: false}), "(1.000000) vcan0 181#1122");
  assert.equal(candump.log([{time_us: 2_000_000, bus: "vcan0", id: 0x181, data: "11", rtr: false, eff: true},
    {time_us: 2_000_001, bus: "vcan0", id: 0x181, data: "11", rtr: false}], clock),
  "(1701234567.000000) vcan0 00000181#11\n(1701234567.000001) vcan0 181#11\n");
});

test("a log is a line per frame, oldest first, each with its interface", () => {
  const frames = [
    {time_us: 2_000_000, bus: "vcan0", id: 0x611, data: "4018100100000000", rtr: false},
    {time_us: 2_000_250, bus: "vcan0", id: 0x591, data: "431810014E020000", rtr: false},
    {time_us: 3_500_000, bus: "vcan1", id: 0x711, data: "", rtr: true},
  ];
  assert.equal(candump.log(frames, clock),
    "(1701234567.000000) vcan0 611#4018100100000000\n" +
    "(1701234567.000250) vcan0 591#431810014E020000\n" +
    "(1701234568.500000) vcan1 711#R\n");
  assert.equal(candump.log([], clock), "");
});

test("the file name is the local time of the download", () => {
  assert.equal(candump.fileName(new Date(2024, 0, 2, 3, 4, 5)), "canopen-emu-20240102-030405.log");
  assert.equal(candump.fileName(new Date(2023, 11, 31, 23, 59, 59)), "canopen-emu-20231231-235959.log");
});
