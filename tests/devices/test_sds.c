#include "unity.h"
void setUp(void){}
void tearDown(void){}
static void todo(void){TEST_FAIL_MESSAGE("not written");}
int main(void){UNITY_BEGIN();RUN_TEST(todo);return UNITY_END();}
