# The unit tests that run on the host only, not on the microcontroller targets (Cortex-M3 under QEMU, AVR under
# simavr): included by tests/cross_unit_tests.cmake (the targets' builds) and cmake/portability.cmake (their ctest
# tests), so that both leave out the same ones.
# test_sdo_large: large objects (CO_CONFIG_LARGE_OBJECTS, co_config.h) are off in a microcontroller build, so it
# would run no test there; and it moves megabytes that an AVR's memory does not hold.
set(CO_HOST_ONLY_UNIT_TESTS test_sdo_large)
