# Included (OPTIONAL) from the top-level CMakeLists.txt: the CO_FUZZ option and, when it is on, the
# libFuzzer targets of tests/fuzz/ (docs/fuzzing.md).
option(CO_FUZZ "Build the libFuzzer targets (clang: -fsanitize=fuzzer,address,undefined) and their ctest tests (label fuzz)" OFF)
if(CO_FUZZ)
  add_subdirectory(${CMAKE_CURRENT_LIST_DIR} ${PROJECT_BINARY_DIR}/tests/fuzz)
endif()
