/* The buerkert device model: see docs/devices/ for its behaviour and control commands. */
#ifndef BUERKERT_H
#define BUERKERT_H

#include "../device.h"

extern const device_class_t buerkert_class;

#endif
