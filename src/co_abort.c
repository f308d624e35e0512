/* Texts of the SDO abort codes, expanded from the list in include/co/co_abort.h. */
#include "co/co_abort.h"

/* Each named constant equals its code in the list (a typo in either fails the build). */
#define CO_ABORT_X_CHECK(name, value, text) typedef char co_abort_check_##name[(CO_ABORT_##name == (value)) ? 1 : -1];
CO_ABORT_LIST(CO_ABORT_X_CHECK)
#undef CO_ABORT_X_CHECK

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
