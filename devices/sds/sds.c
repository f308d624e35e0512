/*
 * Eltex SDS ionising bar. Object dictionary: od/sds.eds. Behaviour: docs/devices/sds.md.
 */
#include "sds.h"

#include "sds_od.h"

static const uint16_t bit_rates[CO_LSS_BIT_TIMING_COUNT] = {1000U, 800U, 500U, 250U, 125U, 0U, 50U, 20U, 10U, 0U};

const device_class_t sds_class = {
    .name = "sds",
    .summary = "Eltex SDS ionising bar: HV release with 10 s timeout, balance, pollution",
    .od = &sds_od,
    .default_node_id = 99U,
    .default_bit_timing = 4U,
    .core_options = CO_OPT_NMT_ACCEPT_LONG,
    .bit_rates_kbit = bit_rates,
};
