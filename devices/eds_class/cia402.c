/* The CiA 402 drive profile: see cia402.h. State machine and statusword encoding per CiA 402-2 (IEC 61800-7-201). */
#include "eds_class/cia402.h"

#include <math.h>
#include <stdio.h>

#include "eds_class/rules.h"

enum cia402_state_id {
    NOT_READY = 0, SWITCH_ON_DISABLED, READY_TO_SWITCH_ON, SWITCHED_ON, OPERATION_ENABLED, QUICK_STOP_ACTIVE,
    FAULT_REACTION, FAULT
};

/* Statusword bits 0-3, 5, 6 of each state; bit 4 (voltage enabled) in the states with power. */
static const uint16_t STATE_BITS[] = {0x0000, 0x0040, 0x0031, 0x0033, 0x0037, 0x0017, 0x000F, 0x0008};

#define SW_REMOTE 0x0200U
#define SW_TARGET_REACHED 0x0400U
#define SW_MODE_BIT12 0x1000U /* PP: set-point acknowledge; HM: homing attained */
#define CW_NEW_SETPOINT 0x0010U
#define CW_RELATIVE 0x0040U
#define CW_FAULT_RESET 0x0080U
#define MODE_PP 1
#define MODE_PV 3
#define MODE_HM 6
#define MODE_CSP 8
#define MODE_CSV 9
#define STEP_US 10000U

/* Sub-index 0 of an object: a row of the table (co_od_find() returns a run's first sub-index in the table), which
 * the resolved objects may keep pointing at. */
static const co_od_entry_t *row(const co_od_t *od, uint16_t index)
{
    co_od_entry_t unused;
    return co_od_find(od, index, 0U, &unused);
}

bool cia402_resolve(const co_od_t *od, cia402_objects_t *o, char *why, size_t cap)
{
    o->controlword = row(od, 0x6040U);
    o->statusword = row(od, 0x6041U);
    o->mode = row(od, 0x6060U);
    o->mode_display = row(od, 0x6061U);
    o->position_actual = row(od, 0x6064U);
    o->velocity_actual = row(od, 0x606CU);
    o->target_position = row(od, 0x607AU);
    o->home_offset = row(od, 0x607CU);
    o->profile_velocity = row(od, 0x6081U);
    o->target_velocity = row(od, 0x60FFU);
    if (o->controlword == NULL || o->statusword == NULL) {
        snprintf(why, cap, "the CiA 402 profile needs the controlword 0x6040 and the statusword 0x6041");
        return false;
    }
    return true;
}

static int mode_of(const cia402_objects_t *o, device_t *dev)
{
    return o->mode != NULL ? (int)rules_get(&dev->node, o->mode) : MODE_PP;
}

static void show(const cia402_objects_t *o, cia402_state_t *s, device_t *dev)
{
    uint16_t sw = (uint16_t)(STATE_BITS[s->state] | SW_REMOTE);
    const int mode = mode_of(o, dev);
    if (!s->moving) {
        sw |= SW_TARGET_REACHED;
    }
    if (mode == MODE_PP && (s->last_control & CW_NEW_SETPOINT) != 0U && s->state == OPERATION_ENABLED) {
        sw |= SW_MODE_BIT12;
    }
    if (mode == MODE_HM && !s->moving && s->target == s->position && s->state == OPERATION_ENABLED) {
        sw |= SW_MODE_BIT12;
    }
    rules_set(&dev->node, o->statusword, sw);
    if (o->mode_display != NULL && o->mode != NULL) {
        rules_set(&dev->node, o->mode_display, mode);
    }
    if (o->position_actual != NULL) {
        rules_set(&dev->node, o->position_actual, s->position);
    }
    if (o->velocity_actual != NULL) {
        rules_set(&dev->node, o->velocity_actual, s->velocity);
    }
}

void cia402_power_on(const cia402_objects_t *o, cia402_state_t *s, device_t *dev, co_time_us_t now)
{
    s->state = SWITCH_ON_DISABLED; /* NOT_READY passes at once: the emulated drive has no self-test */
    s->last_control = 0U;
    s->position = o->position_actual != NULL ? rules_get(&dev->node, o->position_actual) : 0.0;
    s->velocity = 0.0;
    s->target = s->position;
    s->moving = false;
    s->last = now;
    show(o, s, dev);
}

/* Starts the motion a controlword asks for in the mode in force (called in OPERATION_ENABLED). */
static void start_motion(const cia402_objects_t *o, cia402_state_t *s, device_t *dev, uint16_t control, bool setpoint_edge)
{
    const int mode = mode_of(o, dev);
    if (mode == MODE_PP && setpoint_edge && o->target_position != NULL) {
        const double t = rules_get(&dev->node, o->target_position);
        s->target = (control & CW_RELATIVE) != 0U ? s->position + t : t;
        s->moving = s->target != s->position;
    } else if (mode == MODE_HM && setpoint_edge) {
        s->target = o->home_offset != NULL ? rules_get(&dev->node, o->home_offset) : 0.0;
        s->moving = true;
    }
}

void cia402_control(const cia402_objects_t *o, cia402_state_t *s, device_t *dev, uint16_t control)
{
    /* Motion starts now: the axis must not cover the time since its last step (it may have rested for minutes). */
    (void)cia402_step(o, s, dev, dev->now);
    const bool reset_edge = (control & CW_FAULT_RESET) != 0U && (s->last_control & CW_FAULT_RESET) == 0U;
    const bool setpoint_edge = (control & CW_NEW_SETPOINT) != 0U && (s->last_control & CW_NEW_SETPOINT) == 0U;
    s->last_control = control;
    uint8_t next = s->state;
    if (s->state == FAULT) {
        next = reset_edge ? SWITCH_ON_DISABLED : FAULT;
    } else if ((control & 0x0082U) == 0x0000U) { /* disable voltage */
        next = SWITCH_ON_DISABLED;
    } else if ((control & 0x0086U) == 0x0002U) { /* quick stop */
        next = s->state == OPERATION_ENABLED ? QUICK_STOP_ACTIVE : SWITCH_ON_DISABLED;
    } else if ((control & 0x0087U) == 0x0006U) { /* shutdown */
        if (s->state == SWITCH_ON_DISABLED || s->state == SWITCHED_ON || s->state == OPERATION_ENABLED) {
            next = READY_TO_SWITCH_ON;
        }
    } else if ((control & 0x008FU) == 0x0007U) { /* switch on; disable operation */
        if (s->state == READY_TO_SWITCH_ON || s->state == OPERATION_ENABLED) {
            next = SWITCHED_ON;
        }
    } else if ((control & 0x008FU) == 0x000FU) { /* switch on + enable operation; enable operation */
        if (s->state == READY_TO_SWITCH_ON || s->state == SWITCHED_ON || s->state == QUICK_STOP_ACTIVE) {
            next = OPERATION_ENABLED;
        }
    }
    if (next != OPERATION_ENABLED) {
        s->moving = false;
        s->velocity = 0.0;
        s->target = s->position;
    }
    if (next == QUICK_STOP_ACTIVE) {
        next = SWITCH_ON_DISABLED; /* quick-stop option code 2 (the default of 0x605A): stopped, then disabled */
    }
    s->state = next;
    if (s->state == OPERATION_ENABLED) {
        start_motion(o, s, dev, control, setpoint_edge);
    }
    show(o, s, dev);
}

co_time_us_t cia402_step(const cia402_objects_t *o, cia402_state_t *s, device_t *dev, co_time_us_t now)
{
    const double dt = now > s->last ? (double)(now - s->last) / 1e6 : 0.0;
    s->last = now;
    bool running = false;
    if (s->state == OPERATION_ENABLED) {
        const int mode = mode_of(o, dev);
        if ((mode == MODE_PP || mode == MODE_HM) && s->moving) {
            const double speed = mode == MODE_PP && o->profile_velocity != NULL ? fabs(rules_get(&dev->node, o->profile_velocity)) : 0.0;
            const double gap = s->target - s->position;
            if (speed <= 0.0 || fabs(gap) <= speed * dt) {
                s->position = s->target;
                s->velocity = 0.0;
                s->moving = false;
            } else {
                s->velocity = gap > 0.0 ? speed : -speed;
                s->position += s->velocity * dt;
            }
        } else if ((mode == MODE_PV || mode == MODE_CSV) && o->target_velocity != NULL) {
            s->position += s->velocity * dt; /* the velocity of the last step, over its interval */
            s->velocity = rules_get(&dev->node, o->target_velocity);
            s->moving = false; /* at its target velocity: "target reached" */
        } else if (mode == MODE_CSP && o->target_position != NULL) {
            s->position = rules_get(&dev->node, o->target_position);
            s->moving = false;
        }
        running = s->moving || s->velocity != 0.0 || mode == MODE_CSP;
    }
    show(o, s, dev);
    return running ? now + STEP_US : CO_NEVER;
}
