/*
 * canopen-emu's main loop (runtime_loop): sleeps in a single poll until the earliest deadline of any node, a frame on
 * any bus, a control line, room in a blocked output or a signal, and runs whatever is due. With one bus and nothing
 * else to wait for (no control input, socket or web view, no script line to come), a loop of its own does the same
 * without looking at what is not there.
 */
#ifndef EMU_LOOP_H
#define EMU_LOOP_H

#include <signal.h>

#include "runtime/emu.h"

/** Runs until emu->quit or *stop (the signal that asked to stop, set by the handler); returns the exit status. */
int loop_run(emu_t *emu, const volatile sig_atomic_t *stop);

#endif /* EMU_LOOP_H */
