# The emulator's `tables` answer (docs/control-protocol.md: its kinds of protocol fault, the core's SDO abort texts)
# into a file, for the JS tests of the web view (tests/web/js/served.mjs): they check the page's modules against the
# tables the page is served, never against lists of their own.
#   cmake -DEMU=canopen-emu -DOUT=tables.json -P capture-tables.cmake
foreach(var EMU OUT)
  if(NOT DEFINED ${var})
    message(FATAL_ERROR "capture-tables.cmake needs -D${var}=...")
  endif()
endforeach()
get_filename_component(dir ${OUT} DIRECTORY)
file(MAKE_DIRECTORY ${dir}/tables-nvm)
file(WRITE ${OUT}.requests "{\"id\":\"tables\",\"cmd\":\"tables\"}\n{\"cmd\":\"quit\"}\n")
# A bus inside the process (no CAN interface) and one node: the program needs a device to start.
execute_process(COMMAND ${EMU} -q -i virtual:tables --nvm-dir ${dir}/tables-nvm --control - sds:16
                INPUT_FILE ${OUT}.requests OUTPUT_VARIABLE answer ERROR_VARIABLE log RESULT_VARIABLE status
                TIMEOUT 30)
if(NOT status EQUAL 0)
  message(FATAL_ERROR "${EMU} ended with ${status}:\n${log}")
endif()
string(REGEX MATCH "{\"id\":\"tables\",\"ok\":true[^\n]*" line "${answer}")
if(line STREQUAL "")
  message(FATAL_ERROR "no answer to tables in:\n${answer}\n${log}")
endif()
file(WRITE ${OUT} "${line}\n")
message(STATUS "tables: ${OUT}")
