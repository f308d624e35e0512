/* The pro_ionizer device model: see docs/devices/ for its behaviour and control commands. */
#ifndef PRO_IONIZER_H
#define PRO_IONIZER_H

#include "../device.h"

extern const device_class_t pro_ionizer_class;

#endif
