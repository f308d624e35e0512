/*
 * Sizes computed by the target compiler, read back with nm -S by tools/size-report: each array's size
 * is the size of one type on that target with that configuration (no code, nothing runs).
 */
#include "co/co.h"
#include "buerkert_fc_od.h"
#include "pro_ionizer_od.h"
#include "sds_od.h"

unsigned char co_size_node[sizeof(co_node_t)];
unsigned char co_size_values_pro_ionizer[sizeof(pro_ionizer_od_values_t)];
unsigned char co_size_values_sds[sizeof(sds_od_values_t)];
unsigned char co_size_values_buerkert_fc[sizeof(buerkert_fc_od_values_t)];
