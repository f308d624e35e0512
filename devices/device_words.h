/**
 * @file device_words.h
 * @brief The words of the command language (docs/emulator.md "Command language"), read in one place: a line split
 *        into words, numbers, object addresses, and the usage of a command as a help text gives it.
 *
 * The devices' own commands (device_class_t.command), the common ones (device_command) and canopen-emu's read their
 * words with these, so that "0x10", "010" and "2002:6" mean the same to every command. Nothing here allocates or
 * keeps state.
 */
#ifndef DEVICE_WORDS_H
#define DEVICE_WORDS_H

#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

#ifdef __cplusplus
extern "C" {
#endif

/** Splits a command line in place into at most max words (argv points into line): words are separated by blanks
 *  (space, tab, CR, LF), a word that starts with '"' runs to the next '"' (blanks inside kept), '#' at the start of a
 *  word ends the line (a comment). Returns how many words, or -1 when the line has more than max (then argv holds the
 *  first max). */
int device_split_words(char *line, char **argv, int max);

/** An integer word: an optional sign, then decimal digits or 0x and hex digits ("010" is ten: never octal). Its sign
 *  and magnitude (so that every UNSIGNED64 and INTEGER64 fits); false if the text is anything else (blanks included)
 *  or overflows 64 bits. */
bool device_parse_magnitude(const char *text, bool *negative, unsigned long long *magnitude);

/** Parses a number as device_parse_magnitude reads it. Returns false if the text is anything else, overflows, or is
 *  out of [lo, hi]. */
bool device_parse_int(const char *text, long long lo, long long hi, long long *out);

/** INDEX[:SUB] as the commands take it, both hex with or without 0x ("0x2002:06", "1017", "2002:0x3B"). */
bool device_parse_address(const char *text, uint16_t *index, uint8_t *sub);

/** The arguments of command word by a help text of "  USAGE  TEXT" lines (device_class_t.commands_help: USAGE is
 *  the word and its arguments, alternatives joined by " / ", and ends at the first two blanks in a row): true when
 *  word is one of its commands, with what follows the word in *args (args_len bytes, 0 for none; not
 *  NUL-terminated). help may be NULL (no commands). */
bool device_help_usage(const char *help, const char *word, const char **args, size_t *args_len);

#ifdef __cplusplus
}
#endif
#endif /* DEVICE_WORDS_H */
