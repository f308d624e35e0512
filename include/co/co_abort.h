/**
 * @file co_abort.h
 * @brief SDO abort codes (CiA 301 §7.2.4.3.17), one list that the enum and the name table expand from.
 *
 * Functions that can refuse an access return uint32_t: 0 for success, otherwise one of these codes.
 * The same code goes on the wire in an SDO abort frame (bytes 4..7, little-endian).
 */
#ifndef CO_ABORT_H
#define CO_ABORT_H

#include <stddef.h>
#include <stdint.h>

#ifdef __cplusplus
extern "C" {
#endif

#define CO_ABORT_LIST(X)                                                                      \
    X(TOGGLE, 0x05030000UL, "toggle bit not alternated")                                      \
    X(TIMEOUT, 0x05040000UL, "SDO protocol timed out")                                        \
    X(COMMAND, 0x05040001UL, "command specifier not valid or unknown")                        \
    X(BLOCK_SIZE, 0x05040002UL, "invalid block size")                                         \
    X(SEQUENCE, 0x05040003UL, "invalid sequence number")                                      \
    X(CRC, 0x05040004UL, "CRC error")                                                         \
    X(OUT_OF_MEMORY, 0x05040005UL, "out of memory")                                           \
    X(UNSUPPORTED_ACCESS, 0x06010000UL, "unsupported access to an object")                    \
    X(WRITE_ONLY, 0x06010001UL, "attempt to read a write-only object")                        \
    X(READ_ONLY, 0x06010002UL, "attempt to write a read-only object")                         \
    X(NO_OBJECT, 0x06020000UL, "object does not exist")                                       \
    X(NOT_MAPPABLE, 0x06040041UL, "object cannot be mapped to the PDO")                       \
    X(PDO_LENGTH, 0x06040042UL, "number and length of mapped objects exceed PDO length")      \
    X(PARAM_INCOMPATIBLE, 0x06040043UL, "general parameter incompatibility")                  \
    X(INTERNAL_INCOMPATIBLE, 0x06040047UL, "general internal incompatibility in the device")  \
    X(HARDWARE, 0x06060000UL, "access failed due to a hardware error")                        \
    X(TYPE_MISMATCH, 0x06070010UL, "data type does not match, length does not match")         \
    X(LENGTH_HIGH, 0x06070012UL, "data type does not match, length too high")                 \
    X(LENGTH_LOW, 0x06070013UL, "data type does not match, length too low")                   \
    X(NO_SUBINDEX, 0x06090011UL, "sub-index does not exist")                                  \
    X(INVALID_VALUE, 0x06090030UL, "invalid value for parameter")                             \
    X(VALUE_HIGH, 0x06090031UL, "value of parameter written too high")                        \
    X(VALUE_LOW, 0x06090032UL, "value of parameter written too low")                          \
    X(MAX_LESS_MIN, 0x06090036UL, "maximum value is less than minimum value")                 \
    X(SDO_CONNECTION, 0x060A0023UL, "resource not available: SDO connection")                 \
    X(GENERAL, 0x08000000UL, "general error")                                                 \
    X(STORE, 0x08000020UL, "data cannot be transferred or stored to the application")         \
    X(LOCAL_CONTROL, 0x08000021UL, "data cannot be transferred because of local control")     \
    X(DEVICE_STATE, 0x08000022UL, "data cannot be transferred because of the device state")   \
    X(NO_DICTIONARY, 0x08000023UL, "no object dictionary present or its generation failed")   \
    X(NO_DATA, 0x08000024UL, "no data available")

/* Abort codes as named constants (CO_ABORT_NO_OBJECT, ...), 0 meaning "no abort". Macros, not an enum: the codes
 * exceed a 16-bit int (AVR), and an enum constant must fit an int. co_abort.c checks them against the list. */
#define CO_ABORT_NONE 0UL
#define CO_ABORT_TOGGLE 0x05030000UL
#define CO_ABORT_TIMEOUT 0x05040000UL
#define CO_ABORT_COMMAND 0x05040001UL
#define CO_ABORT_BLOCK_SIZE 0x05040002UL
#define CO_ABORT_SEQUENCE 0x05040003UL
#define CO_ABORT_CRC 0x05040004UL
#define CO_ABORT_OUT_OF_MEMORY 0x05040005UL
#define CO_ABORT_UNSUPPORTED_ACCESS 0x06010000UL
#define CO_ABORT_WRITE_ONLY 0x06010001UL
#define CO_ABORT_READ_ONLY 0x06010002UL
#define CO_ABORT_NO_OBJECT 0x06020000UL
#define CO_ABORT_NOT_MAPPABLE 0x06040041UL
#define CO_ABORT_PDO_LENGTH 0x06040042UL
#define CO_ABORT_PARAM_INCOMPATIBLE 0x06040043UL
#define CO_ABORT_INTERNAL_INCOMPATIBLE 0x06040047UL
#define CO_ABORT_HARDWARE 0x06060000UL
#define CO_ABORT_TYPE_MISMATCH 0x06070010UL
#define CO_ABORT_LENGTH_HIGH 0x06070012UL
#define CO_ABORT_LENGTH_LOW 0x06070013UL
#define CO_ABORT_NO_SUBINDEX 0x06090011UL
#define CO_ABORT_INVALID_VALUE 0x06090030UL
#define CO_ABORT_VALUE_HIGH 0x06090031UL
#define CO_ABORT_VALUE_LOW 0x06090032UL
#define CO_ABORT_MAX_LESS_MIN 0x06090036UL
#define CO_ABORT_SDO_CONNECTION 0x060A0023UL
#define CO_ABORT_GENERAL 0x08000000UL
#define CO_ABORT_STORE 0x08000020UL
#define CO_ABORT_LOCAL_CONTROL 0x08000021UL
#define CO_ABORT_DEVICE_STATE 0x08000022UL
#define CO_ABORT_NO_DICTIONARY 0x08000023UL
#define CO_ABORT_NO_DATA 0x08000024UL

/** Text of an abort code, or "unknown abort code". For logs; never NULL. */
const char *co_abort_text(uint32_t code);

/** The i-th abort code the core names (CO_ABORT_LIST, in ascending code order) into *code (when code is not NULL),
 *  and its text, the one co_abort_text() gives; NULL past the last one (*code then unchanged). For a tool that lists
 *  them all: canopen-emu serves them to its web view. */
const char *co_abort_entry(size_t i, uint32_t *code);

#ifdef __cplusplus
}
#endif
#endif /* CO_ABORT_H */
