/*
 * The command line of canopen-emu: its help, the device list, DEVICE[/VARIANT][:NODE-ID][@BUS] arguments and the default
 * NVM directory. Messages about a bad argument go to stderr.
 */
#ifndef EMU_CMDLINE_H
#define EMU_CMDLINE_H

#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>
#include <stdio.h>

#include "device.h"
#include "runtime/emu_node.h"

void usage(FILE *out);

/** The device types, one a line (--list-devices). */
void list_devices(FILE *out);

/** DEVICE[/VARIANT][:NODE-ID][@BUS]: the class, the variant ("" for the default), the node-ID (the class's default
 *  when none is given) and the interface ("" for the first). DEVICE may be an EDS or DCF file (FILE.eds, FILE.dcf):
 *  its class is built once (eds_class.h); the reader's warnings go to stderr unless quiet. false, with a
 *  message, when the argument is not one or the file cannot be emulated. */
bool parse_spec(const char *arg, node_spec_t *spec, bool quiet);

/** $XDG_STATE_HOME/canopen-emu, ~/.local/state/canopen-emu, or ./canopen-emu-nvm, written to buf. */
const char *default_nvm_dir(char *buf, size_t len);

#endif /* EMU_CMDLINE_H */
