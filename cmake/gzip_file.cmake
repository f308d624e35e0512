# cmake -DGZIP=<gzip> -DIN=<file> -DOUT=<file.gz> -P gzip_file.cmake: OUT = gzip -9n IN (reproducible: no name,
# no time stamp). A script because add_custom_command has no portable output redirection.
execute_process(COMMAND ${GZIP} -9n -c ${IN} OUTPUT_FILE ${OUT} RESULT_VARIABLE rc)
if(NOT rc EQUAL 0)
  file(REMOVE ${OUT})
  message(FATAL_ERROR "gzip ${IN} failed: ${rc}")
endif()
