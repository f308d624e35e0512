/*
 * The command language of canopen-emu (docs/emulator.md "Command language"): one command line from stdin, a script
 * or a control session, run on the nodes it names; its replies go to the sink the caller gives (emu_output.h). The
 * words are read as devices/device_words.h reads them.
 */
#ifndef EMU_COMMANDS_H
#define EMU_COMMANDS_H

#include "runtime/emu.h"
#include "runtime/emu_output.h"

/** Most words a command line may have (the longest command, emcy, has 8). */
#define MAX_ARGS 16

typedef enum command_result {
    COMMAND_OK = 0,
    COMMAND_ERROR = 1        /**< refused or failed: a reply says why */
} command_result_t;

/** Runs one command line (without its newline; it is split in place). `quit` sets emu->quit. Replies go to `to`
 *  (emu_output.h: &output_stdout_replies for stdout). */
command_result_t run_command(emu_t *emu, char *line, const reply_sink_t *to);

/** The same for a line already split into words (argv[0] the command; the words may be changed). */
command_result_t run_command_words(emu_t *emu, int argc, char **argv, const reply_sink_t *to);

/** Why a restricted session (emu_session_t.restricted: a web session) may not run the command named word: "stops
 *  the emulator" (quit, exit) or "writes a file" (export-dcf: any path the emulator's user may write); NULL when it
 *  may. run_command_words refuses them while emu->command_restricted is set, json_run for a restricted session. */
const char *command_restriction(const char *word);

/** The nodes NODE names (ID, ID@IFACE, all, all@IFACE; word may be changed and is restored): up to max of them
 *  into out, their count returned; -1 after a reply saying why none can be (no such interface, not a node-ID,
 *  an ID on several buses) to `to`. 0 matches are not an error here. */
int select_nodes(emu_t *emu, char *word, emu_node_t **out, size_t max, const reply_sink_t *to);

/** The same, but an ID alone that is on several buses names all of them (event filters: "node 16 on any bus"). */
int select_nodes_any_bus(emu_t *emu, char *word, emu_node_t **out, size_t max, const reply_sink_t *to);

#endif /* EMU_COMMANDS_H */
