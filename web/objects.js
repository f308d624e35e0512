// Objects as the control protocol names them ("0x6401:01"), and the most one `get` reads: shared by the views that
// ask for values (the node view, the plots, the trace). No DOM: tested with node --test.

/** At most this many objects in one `get` (docs/control-protocol.md: `objects`, 1 to 64). */
export const GET_MAX = 64;

/** "0xIIII:SS" as the control protocol writes an object. */
export function objectName(index, sub) {
  return `0x${index.toString(16).toUpperCase().padStart(4, "0")}:${sub.toString(16).toUpperCase().padStart(2, "0")}`;
}

/** The index and sub of "0xIIII:SS" (or "IIII", "6401:1", "0x1017"); null when it is not one. */
export function parseObject(text) {
  const m = /^(?:0x)?([0-9a-f]{1,4})(?::(?:0x)?([0-9a-f]{1,2}))?$/i.exec(String(text).trim());
  return m === null ? null : {index: parseInt(m[1], 16), sub: m[2] === undefined ? 0 : parseInt(m[2], 16)};
}

/** `list` in pieces of at most `size`: the `get` requests that read it. */
export function chunks(list, size = GET_MAX) {
  const pieces = [];
  for (let i = 0; i < list.length; i += size) {
    pieces.push(list.slice(i, i + size));
  }
  return pieces;
}

const PLOTTABLE_TYPE = /^(BOOLEAN|INTEGER\d+|UNSIGNED\d+|REAL32|REAL64)$/;

/** Whether a row of `objects` can be plotted: a number (or BOOLEAN) that can be read. The node view's plot button
 * and the plots' picker both ask this, so they offer the same objects. */
export function plottableRow(row) {
  return PLOTTABLE_TYPE.test(row.type) && row.access !== "wo";
}
