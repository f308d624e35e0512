/* Texts of the SDO abort codes, expanded from the same list as the enum (include/co/co_abort.h). */
#include "co/co_abort.h"

const char *co_abort_text(uint32_t code)
{
    switch (code) {
#define CO_ABORT_X_TEXT(name, value, text) \
    case value:                            \
        return text;
        CO_ABORT_LIST(CO_ABORT_X_TEXT)
#undef CO_ABORT_X_TEXT
    default:
        return "unknown abort code";
    }
}
