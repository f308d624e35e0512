/*
 * Eltex PRO IONIZER (ES61) power supply. Object dictionary: od/pro-ionizer.eds.
 * Behaviour: docs/devices/pro-ionizer.md.
 */
#include "pro_ionizer.h"

#include "pro_ionizer_od.h"

/* LSS bit-timing table of 0x2002:07 read as CiA 305 (decision pro-ionizer.md #42): 5 unsupported, 9 = CAN off. */
static const uint16_t bit_rates[CO_LSS_BIT_TIMING_COUNT] = {1000U, 800U, 500U, 250U, 125U, 0U, 50U, 20U, 10U, 0U};

const device_class_t pro_ionizer_class = {
    .name = "pro-ionizer",
    .summary = "Eltex PRO IONIZER power supply (ES61): HV release, discharge values, counters",
    .od = &pro_ionizer_od,
    .default_node_id = 99U,
    .default_bit_timing = 4U,
    .core_options = CO_OPT_NMT_ACCEPT_LONG,
    .bit_rates_kbit = bit_rates,
};
