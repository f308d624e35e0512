// The texts of the overview's cells (docs/web.md): pure functions, no DOM, tested with node --test (tests/web/js).

import {emcyCode} from "./decode.js";

/** 0x-prefixed upper-case hex with at least `digits` digits: hex(0x191, 8) is "0x00000191". */
export function hex(value, digits) {
  return "0x" + value.toString(16).toUpperCase().padStart(digits, "0");
}

/** A span of time in µs as a person reads it: tenths of seconds while they matter, then whole units. */
export function duration(us) {
  const seconds = Math.max(0, us) / 1e6;
  if (seconds < 10) {
    return `${(Math.floor(seconds * 10) / 10).toFixed(1)} s`; // floor: "1.0 s" only once a full second has passed
  }
  const whole = Math.floor(seconds);
  if (whole < 60) {
    return `${whole} s`;
  }
  if (whole < 3600) {
    return `${Math.floor(whole / 60)} min ${whole % 60} s`;
  }
  return `${Math.floor(whole / 3600)} h ${Math.floor((whole % 3600) / 60)} min`;
}

/** How long ago an event was, both times on the emulator's clock (µs); "" when either is unknown. */
export function ago(thenUs, nowUs) {
  return thenUs === null || nowUs === null ? "" : `${duration(nowUs - thenUs)} ago`;
}

/** The device and its variant as the command line names them: "sds (N)", "buerkert" (a device without variants). */
export function device(node) {
  return node.variant === null ? node.device : `${node.device} (${node.variant})`;
}

/** The producer heartbeat time (0x1017): 0 means the node sends none. */
export function heartbeatPeriod(ms) {
  return ms === 0 ? "off" : `${ms} ms`;
}

/** An EMCY as the protocol gives it ({code, register, info}): code and its class (decode.js, as the trace has it),
 * error register, the five manufacturer bytes: "0x5000 device hardware, reg 0x01 info A1B2C3D4E5". */
export function emcy(e) {
  return `${emcyCode(e.code)}, reg ${hex(e.register, 2)} info ${e.info}`;
}
