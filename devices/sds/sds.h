/* The sds device model: see docs/devices/ for its behaviour and control commands. */
#ifndef SDS_H
#define SDS_H

#include "../device.h"

extern const device_class_t sds_class;

#endif
