/* Texts of the SDO abort codes, expanded from the list in include/co/co_abort.h. */
#include "co/co_abort.h"

/* Each named constant equals its code in the list (a typo in either fails the build). */
#define CO_ABORT_X_CHECK(name, value, text) typedef char co_abort_check_##name[(CO_ABORT_##name == (value)) ? 1 : -1];
CO_ABORT_LIST(CO_ABORT_X_CHECK)
#undef CO_ABORT_X_CHECK

/* One table for the lookup and for the tools that list the codes: a list served from it cannot differ from the
 * texts, and it is smaller than the switch it replaced (a tree of compares, 480 bytes of code on a Cortex-M0+, where
 * the table is 8 bytes an entry and its loop 40). */
static const co_abort_entry_t abort_table[] = {
#define CO_ABORT_X_ENTRY(name, value, text) {value, text},
    CO_ABORT_LIST(CO_ABORT_X_ENTRY)
#undef CO_ABORT_X_ENTRY
};

const co_abort_entry_t *co_abort_table(size_t *count)
{
    *count = sizeof abort_table / sizeof abort_table[0];
    return abort_table;
}

const char *co_abort_text(uint32_t code)
{
    for (size_t i = 0U; i < sizeof abort_table / sizeof abort_table[0]; i++) {
        if (abort_table[i].code == code) {
            return abort_table[i].text;
        }
    }
    return "unknown abort code";
}
