/*
 * The web view's static files (web/), embedded in the program at build time by cmake/embed_files.cmake: the
 * running program serves them from this table, matched exactly by path, and never reads a file or joins a path
 * for them (emu_web.c).
 */
#ifndef EMU_WEB_FILES_H
#define EMU_WEB_FILES_H

#include <stddef.h>

typedef struct web_file {
    const char *path;           /* "/index.html": the request's path must be exactly this */
    const char *mime;           /* Content-Type, by the file's extension */
    const unsigned char *data;  /* size bytes, then a NUL that size does not count (a text file is a C string) */
    size_t size;
    const char *etag;           /* "\"<16 hex digits of its SHA-256>\"", quotes included */
} web_file_t;

extern const web_file_t web_files[];
extern const size_t web_files_count;

#endif /* EMU_WEB_FILES_H */
