/* The device classes canopen-emu offers (in --list-devices order). */
#include "buerkert/buerkert.h"
#include "device.h"
#include "pro_ionizer/pro_ionizer.h"
#include "sds/sds.h"

const device_class_t *const device_classes[] = {&pro_ionizer_class, &sds_class, &buerkert_class, NULL};
