# ctest driver of one fuzz target (see CMakeLists.txt): never writes into the source tree.
#   cmake -DFUZZER=... -DCORPUS=... -DREGRESSIONS=... -DSCRATCH=... -DSECONDS=30 -P run_fuzz.cmake
file(REMOVE_RECURSE ${SCRATCH})
file(MAKE_DIRECTORY ${SCRATCH}/corpus ${SCRATCH}/regressions)
file(GLOB seeds LIST_DIRECTORIES false ${CORPUS}/*)
if(seeds)
  file(COPY ${seeds} DESTINATION ${SCRATCH}/corpus)
endif()
file(GLOB repros LIST_DIRECTORIES false ${REGRESSIONS}/*)
if(repros)
  file(COPY ${repros} DESTINATION ${SCRATCH}/regressions)
endif()
# The reproducers first, one run each: a known bug fails the test with its own name.
foreach(r IN LISTS repros)
  get_filename_component(name ${r} NAME)
  execute_process(COMMAND ${FUZZER} -rss_limit_mb=1024 -timeout=25 ${SCRATCH}/regressions/${name}
                  RESULT_VARIABLE rc OUTPUT_VARIABLE out ERROR_VARIABLE out)
  if(NOT rc EQUAL 0)
    message("${out}")
    message(FATAL_ERROR "fuzz regression ${name} fails (exit ${rc})")
  endif()
endforeach()
execute_process(COMMAND ${FUZZER} -max_total_time=${SECONDS} -rss_limit_mb=1024 -timeout=25 -max_len=4096
                        -print_final_stats=1 -artifact_prefix=${SCRATCH}/ ${SCRATCH}/corpus
                RESULT_VARIABLE rc OUTPUT_VARIABLE out ERROR_VARIABLE out)
string(LENGTH "${out}" len)
if(len GREATER 20000)
  math(EXPR start "${len} - 20000")
  string(SUBSTRING "${out}" ${start} -1 out)
endif()
message("${out}")
if(NOT rc EQUAL 0)
  message(FATAL_ERROR "fuzzer exited with ${rc}: reproducer (crash-*/leak-*/timeout-*) in ${SCRATCH}")
endif()
