/*
 * Bürkert mass flow controller, the representative of the Bürkert CANopen devices.
 * Object dictionary: od/buerkert-flow-controller.eds. Behaviour: docs/devices/buerkert-flow-controller.md.
 */
#include "buerkert.h"

#include "buerkert_fc_od.h"

/* Bürkert's table (manual §2.3): index 5 = 100 kbit/s, no index 1 (800 kbit/s). */
static const uint16_t bit_rates[CO_LSS_BIT_TIMING_COUNT] = {1000U, 0U, 500U, 250U, 125U, 100U, 50U, 20U, 10U, 0U};

const device_class_t buerkert_class = {
    .name = "buerkert",
    .summary = "Buerkert mass flow controller: set-point by RPDO/SDO, first-order flow, NAMUR status",
    .od = &buerkert_fc_od,
    .default_node_id = 1U,
    .default_bit_timing = 2U,
    .core_options = CO_OPT_SDO_SEGMENTED | CO_OPT_LSS_NO_UNCONFIGURE,
    .bit_rates_kbit = bit_rates,
};
