/* Negative control for check_core_symbols.cmake: a writable global and a malloc call it must reject. */
#include <stdlib.h>
int symbols_bad_counter;
void *symbols_bad_alloc(void);
void *symbols_bad_alloc(void)
{
    symbols_bad_counter++;
    return malloc(4);
}
