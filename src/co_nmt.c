/*
 * NMT slave (CiA 301 §7.2.8.3.1): node control commands from the master on CAN-ID 0x000.
 * There is never an answer; the effects are seen in the heartbeat/guard state byte and the boot-up frame.
 */
#include "priv/co_priv.h"

void co_nmt_rx(co_node_t *node, const co_frame_t *f)
{
    /* DLC 2 only (CANopenNode); with CO_OPT_NMT_ACCEPT_LONG also longer frames (lely-core). See decisions.md. */
    if (f->len < 2U || (f->len > 2U && (node->options & CO_OPT_NMT_ACCEPT_LONG) == 0U)) {
        return;
    }
    if (f->data[1] != 0U && f->data[1] != node->node_id) {
        return;
    }
    const uint8_t cmd = f->data[0];
    if (cmd == 0x81U || cmd == 0x82U) {
        /* CO_RESET_APPLICATION = 0 for 0x81, CO_RESET_COMMUNICATION = 1 for 0x82 */
        co_node_reset(node, (co_reset_t)(cmd - 0x81U), node->now);
        return;
    }
    switch (cmd) {
    case 0x01:
        co_node_set_state(node, CO_NMT_OPERATIONAL);
        break;
    case 0x02:
        co_node_set_state(node, CO_NMT_STOPPED);
        break;
    case 0x80:
        co_node_set_state(node, CO_NMT_PRE_OPERATIONAL);
        break;
    default:
        break; /* unknown command: ignored, no state change */
    }
}

const char *co_nmt_state_name(co_nmt_state_t state)
{
    switch (state) {
    case CO_NMT_INITIALISING:
        return "INITIALISING";
    case CO_NMT_STOPPED:
        return "STOPPED";
    case CO_NMT_OPERATIONAL:
        return "OPERATIONAL";
    case CO_NMT_PRE_OPERATIONAL:
        return "PRE-OPERATIONAL";
    default:
        return "UNKNOWN";
    }
}
