/**
 * @file udp_datagram.h
 * @brief One CAN frame as one UDP datagram, in python-can's udp_multicast format (python-can 4.x,
 * can/interfaces/udp_multicast/utils.py): a msgpack map of eleven entries, in this order,
 *
 *   timestamp (float64), arbitration_id (uint), is_extended_id, is_remote_frame, is_error_frame (bool),
 *   channel (nil), dlc (uint), data (bin), is_fd, bitrate_switch, error_state_indicator (bool)
 *
 * which is what msgpack.packb(..., use_bin_type=True) makes of a can.Message (docs/buses.md). Pure functions, no
 * socket: udp_multicast.c sends and reads the datagrams, tests/fuzz/target_udp_datagram.c fuzzes the decoder.
 *
 * The decoder takes what a python-can receiver takes (unpack_message, then can.Message(check=True)): keys missing
 * take can.Message's defaults (is_extended_id: true), the timestamp is ignored (python-can replaces it by the time of
 * arrival), and a datagram python-can would refuse is malformed here too; it is stricter only about types (a flag
 * must be a bool, an identifier an integer, data a bin or nil). msgpack-c decodes; the datagram's containers are
 * checked first to claim no more entries than it has bytes left, since msgpack-c allocates a container's entries
 * from its header before reading them (a 5-byte map header could otherwise ask for 256 GiB).
 */
#ifndef UDP_DATAGRAM_H
#define UDP_DATAGRAM_H

#include <stddef.h>
#include <stdint.h>

#include "co/co.h"

/** The longest datagram read (python-can's receive buffer, max_buffer); a longer one is malformed. */
#define UDP_DATAGRAM_MAX 4096U

/** What a datagram holds. */
typedef enum udp_datagram_kind {
    UDP_DATAGRAM_FRAME,       /**< a classic CAN frame (data or remote; 11- or 29-bit identifier) */
    UDP_DATAGRAM_FD,          /**< a valid CAN FD frame: the nodes take classic CAN only */
    UDP_DATAGRAM_ERROR_FRAME, /**< a valid error frame: a bus of datagrams has no errors to report to the nodes */
    UDP_DATAGRAM_MALFORMED    /**< not a message python-can would take */
} udp_datagram_kind_t;

/** Decodes a datagram. FRAME: *frame set (bytes past len zero). MALFORMED: why says what is wrong (why may be NULL). */
udp_datagram_kind_t udp_datagram_decode(const uint8_t *data, size_t len, co_frame_t *frame, char *why, size_t whylen);

/** Encodes frame (CO_FRAME_RTR, CO_FRAME_EFF; len 0..8) with the time stamp (seconds since the epoch, as python-can's
 *  time.time()) into out; returns its length, or 0 when out is too small (at most 170 bytes are written: 256 suffice) or the frame is
 *  an error frame (CO_FRAME_ERR), which the format carries only as python-can's own error messages. */
size_t udp_datagram_encode(const co_frame_t *frame, double timestamp, uint8_t *out, size_t cap);

#endif
