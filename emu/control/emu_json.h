/*
 * The JSON framing of the control protocol (docs/control-protocol.md): one request object per line, one response
 * object per request, on the session that sent it. Parsed with Jansson (libjansson, Debian's libjansson-dev):
 * strict RFC 8259, UTF-8 checked, duplicate keys refused.
 */
#ifndef EMU_JSON_H
#define EMU_JSON_H

#include <stdbool.h>
#include <stdint.h>

#include "control/emu_session.h"

/** Version of the protocol ("protocol" in the hello response); raised when a response changes incompatibly. */
#define CONTROL_PROTOCOL_VERSION 1

/** Runs one JSON request line of s and writes its response to s. */
void json_run(struct emu *emu, emu_session_t *s, const char *line);

/** Writes {"id":null,"ok":false,"error":...} to s: for a line that could not be read as a request. */
void json_error(emu_session_t *s, const char *fmt, ...) __attribute__((format(printf, 2, 3)));

/** "COB-ID[x][/MASK]" (decimal or 0x hex): an 11-bit COB-ID, or with x a 29-bit one; false if it is not one. MASK
 *  defaults to all 29 bits; id and mask both have SESSION_FRAME_EFF, so a filter takes frames of its format only. */
bool json_parse_frame_filter(const char *text, uint32_t *id, uint32_t *mask);

#endif /* EMU_JSON_H */
