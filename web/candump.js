// The trace as a candump log (`candump -l` of can-utils: `(1701234567.123456) vcan0 123#DEADBEEF`), which
// canplayer, log2asc and the rest of can-utils read. The frames carry the emulator's clock (µs since it started);
// hello's `clock` pairs it with the wall clock. No DOM: tested with node --test (tests/web/js).

/** The wall clock (µs since 1970) of the emulator's time `timeUs`, by hello's clock {time_us, unix_us}. */
export function unixUs(timeUs, clock) {
  return clock.unix_us + (timeUs - clock.time_us);
}

/** `(SECONDS.MICROSECONDS)` of a wall-clock time in µs. */
function stamp(us) {
  const whole = Math.floor(us / 1e6);
  return `(${whole}.${String(us - whole * 1e6).padStart(6, "0")})`;
}

/**
 * A COB-ID as candump writes it: 3 upper-case hex digits, 8 for a 29-bit one whatever its value (the digits are how
 * can-utils tell the formats apart). eff: an extended frame.
 */
export function cobId(id, eff) {
  return id.toString(16).toUpperCase().padStart(eff || id > 0x7FF ? 8 : 3, "0");
}

/**
 * One frame as candump -l writes it: its COB-ID (cobId), the data in upper-case hex; a remote request `123#R`, with
 * its length after the R when it is not 0 (`123#R2`), as can-utils does.
 * frame: {id, data (hex, as frame events give it), rtr, eff}.
 */
export function line(us, iface, frame) {
  const id = cobId(frame.id, frame.eff);
  const bytes = frame.data.length / 2;
  const payload = frame.rtr ? `R${bytes > 0 ? bytes : ""}` : frame.data.toUpperCase();
  return `${stamp(us)} ${iface} ${id}#${payload}`;
}

/** The log of `frames` (each {time_us, bus, id, data, rtr, eff}), oldest first, one line each with a newline. */
export function log(frames, clock) {
  let text = "";
  for (const f of frames) {
    text += line(unixUs(f.time_us, clock), f.bus, f) + "\n";
  }
  return text;
}

/** The name of a log saved at the local time `date`: canopen-emu-YYYYMMDD-HHMMSS.log. */
export function fileName(date) {
  const two = (n) => String(n).padStart(2, "0");
  return `canopen-emu-${date.getFullYear()}${two(date.getMonth() + 1)}${two(date.getDate())}-` +
    `${two(date.getHours())}${two(date.getMinutes())}${two(date.getSeconds())}.log`;
}
