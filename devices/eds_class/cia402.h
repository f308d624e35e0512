/*
 * The CiA 402 drive profile as a ready-made rule (docs/eds.md "CiA 402"): the state machine driven by the
 * controlword 0x6040 and shown in the statusword 0x6041, the modes 0x6060 -> 0x6061, and an axis that follows its
 * targets: profile position (0x607A at 0x6081), profile/cyclic velocity (0x60FF -> 0x606C, position integrating
 * it), cyclic synchronous position (0x607A at once), homing (to 0x607C). Objects the file lacks are left out.
 */
#ifndef EDS_CLASS_CIA402_H
#define EDS_CLASS_CIA402_H

#include <stdbool.h>
#include <stdint.h>

#include "device.h"

/** The drive's objects in one device's OD (NULL where it has none). */
typedef struct cia402_objects {
    const co_od_entry_t *controlword, *statusword, *mode, *mode_display;
    const co_od_entry_t *target_position, *position_actual, *profile_velocity;
    const co_od_entry_t *target_velocity, *velocity_actual, *home_offset;
} cia402_objects_t;

typedef struct cia402_state {
    uint8_t state;          /* cia402_state_t */
    uint16_t last_control;  /* for the edges of bits 4 (new set-point) and 7 (fault reset) */
    double position, velocity, target;
    bool moving;
    co_time_us_t last;
} cia402_state_t;

/** Finds the objects; false (with why) when the OD lacks the controlword or the statusword. */
bool cia402_resolve(const co_od_t *od, cia402_objects_t *o, char *why, size_t cap);
void cia402_power_on(const cia402_objects_t *o, cia402_state_t *s, device_t *dev, co_time_us_t now);
/** A controlword written: the state machine's transition (the statusword follows at once). */
void cia402_control(const cia402_objects_t *o, cia402_state_t *s, device_t *dev, uint16_t control);
/** The axis moves to now; returns when it next needs a step (CO_NEVER when at rest). */
co_time_us_t cia402_step(const cia402_objects_t *o, cia402_state_t *s, device_t *dev, co_time_us_t now);

#endif /* EDS_CLASS_CIA402_H */
