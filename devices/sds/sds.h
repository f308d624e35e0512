/* The sds device model (Eltex SDS ionising bar): see docs/devices/sds-behaviour.md for its behaviour,
 * simulation model, error table and control commands. */
#ifndef SDS_H
#define SDS_H

#include "../device.h"

extern const device_class_t sds_class;

#endif
