# Every program and subcommand: --help exits 0 and prints its usage; an unknown flag exits
# non-zero and the message names the flag; a bad value exits non-zero naming its flag.
#   cmake -DBIN_DIR=<build>/bin -DCOMMANDS="mppi-sim;mppi-fit estimate;..." -P program_flags.cmake
# BAD_VALUES: "command|flag|value;..." run as `command flag value`.
if(NOT BIN_DIR OR NOT COMMANDS)
  message(FATAL_ERROR "usage: cmake -DBIN_DIR=DIR -DCOMMANDS=\"prog sub;...\" -P program_flags.cmake")
endif()
set(failures 0)
foreach(command IN LISTS COMMANDS)
  separate_arguments(words UNIX_COMMAND "${command}")
  list(POP_FRONT words program)
  set(exe ${BIN_DIR}/${program})

  execute_process(COMMAND ${exe} ${words} --help RESULT_VARIABLE rc OUTPUT_VARIABLE out ERROR_VARIABLE err)
  if(NOT rc EQUAL 0 OR NOT out MATCHES "Usage: ${program}")
    message(SEND_ERROR "'${command} --help': exit ${rc} (want 0), output:\n${out}${err}")
    math(EXPR failures "${failures} + 1")
  endif()

  execute_process(COMMAND ${exe} ${words} --no-such-flag RESULT_VARIABLE rc OUTPUT_VARIABLE out ERROR_VARIABLE err)
  if(rc EQUAL 0 OR NOT err MATCHES "--no-such-flag")
    message(SEND_ERROR "'${command} --no-such-flag': exit ${rc} (want non-zero), stderr does not name the flag:\n${err}")
    math(EXPR failures "${failures} + 1")
  endif()
endforeach()

foreach(case IN LISTS BAD_VALUES)
  string(REPLACE "|" ";" parts "${case}")
  list(GET parts 0 command)
  list(GET parts 1 flag)
  list(GET parts 2 value)
  separate_arguments(words UNIX_COMMAND "${command}")
  list(POP_FRONT words program)
  execute_process(COMMAND ${BIN_DIR}/${program} ${words} ${flag} ${value}
                  RESULT_VARIABLE rc OUTPUT_VARIABLE out ERROR_VARIABLE err)
  if(rc EQUAL 0 OR NOT err MATCHES "${flag}")
    message(SEND_ERROR "'${command} ${flag} ${value}': exit ${rc} (want non-zero), stderr does not name ${flag}:\n${err}")
    math(EXPR failures "${failures} + 1")
  endif()
endforeach()

if(failures GREATER 0)
  message(FATAL_ERROR "${failures} command-line check(s) failed")
endif()
list(LENGTH COMMANDS n)
message(STATUS "PASS: ${n} commands: --help exits 0, unknown flags and bad values are refused by name")
