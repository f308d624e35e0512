/* Texts of the SDO abort codes, expanded from the list in include/co/co_abort.h. */
#include "co/co_abort.h"

/* Each named constant equals its code in the list (a typo in either fails the build). */
#define CO_ABORT_X_CHECK(name, value, text) typedef char co_abort_check_##name[(CO_ABORT_##name == (value)) ? 1 : -1];
CO_ABORT_LIST(CO_ABORT_X_CHECK)
#undef CO_ABORT_X_CHECK

/* One table for the lookup and for the tools that list the codes, so that a list served from it cannot differ from
 * the texts. The texts lie one after another in one object, a member each, and an entry finds its text by the
 * member's offset: a table of pointers would be data the loader relocates in position-independent code (the host's
 * .data.rel.ro, written at load), and the core has no writable data (unit/core_symbols). It is smaller than the
 * switch it replaced, a tree of compares (480 bytes of code on a Cortex-M0+, where an entry takes 6 bytes). */
static const struct co_abort_texts {
#define CO_ABORT_X_MEMBER(name, value, text) char text_##name[sizeof text];
    CO_ABORT_LIST(CO_ABORT_X_MEMBER)
#undef CO_ABORT_X_MEMBER
} abort_texts = {
#define CO_ABORT_X_TEXT(name, value, text) text,
    CO_ABORT_LIST(CO_ABORT_X_TEXT)
#undef CO_ABORT_X_TEXT
};

static const uint32_t abort_codes[] = {
#define CO_ABORT_X_CODE(name, value, text) value,
    CO_ABORT_LIST(CO_ABORT_X_CODE)
#undef CO_ABORT_X_CODE
};

static const uint16_t abort_text_at[] = {
#define CO_ABORT_X_OFFSET(name, value, text) (uint16_t)offsetof(struct co_abort_texts, text_##name),
    CO_ABORT_LIST(CO_ABORT_X_OFFSET)
#undef CO_ABORT_X_OFFSET
};

typedef char co_abort_offsets_fit[(sizeof abort_texts <= 0xFFFFU) ? 1 : -1];

#define ABORT_COUNT (sizeof abort_codes / sizeof abort_codes[0])

static const char *text_of(size_t i) { return (const char *)&abort_texts + abort_text_at[i]; }

const char *co_abort_entry(size_t i, uint32_t *code)
{
    if (i >= ABORT_COUNT) {
        return NULL;
    }
    if (code != NULL) {
        *code = abort_codes[i];
    }
    return text_of(i);
}

const char *co_abort_text(uint32_t code)
{
    for (size_t i = 0U; i < ABORT_COUNT; i++) {
        if (abort_codes[i] == code) {
            return text_of(i);
        }
    }
    return "unknown abort code";
}
