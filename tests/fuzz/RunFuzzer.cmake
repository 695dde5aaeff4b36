# Runs a libFuzzer target for a bounded time on a copy of a seed corpus:
#   cmake -DFUZZER=exe -DCORPUS=dir -DWORK=dir -DSECONDS=n [-DDICT=file] -P RunFuzzer.cmake
# WORK is emptied first; the grown corpus and any reproducer stay there.
# Fails (non-zero exit) on any finding: crash, sanitizer report, leak, a
# unit slower than -timeout, or memory beyond -rss_limit_mb.
foreach(var FUZZER CORPUS WORK SECONDS)
  if(NOT DEFINED ${var})
    message(FATAL_ERROR "RunFuzzer.cmake: -D${var}= is required")
  endif()
endforeach()
if(NOT EXISTS ${FUZZER})
  message(FATAL_ERROR "fuzzer ${FUZZER} was not built")
endif()

file(REMOVE_RECURSE ${WORK})
file(MAKE_DIRECTORY ${WORK}/artifacts)
file(COPY ${CORPUS}/ DESTINATION ${WORK}/corpus)
set(dict)
if(DEFINED DICT)
  set(dict -dict=${DICT})
endif()

# -timeout: a unit taking 10 s is a hang (typical inputs take well under a
# millisecond). -rss_limit_mb: 2 GB, 4x what a run peaks at with ASan.
# -max_len: the default would grow to 4096 bytes anyway; fixed here so that
# a run's reach does not depend on the longest corpus file.
execute_process(
  COMMAND ${FUZZER} ${WORK}/corpus ${dict} -max_total_time=${SECONDS} -timeout=10 -rss_limit_mb=2048
          -max_len=4096 -print_final_stats=1 -artifact_prefix=${WORK}/artifacts/
  WORKING_DIRECTORY ${WORK}
  RESULT_VARIABLE rc)

file(GLOB findings ${WORK}/artifacts/*)
if(NOT rc EQUAL 0 OR findings)
  list(JOIN findings "\n  " listed)
  message(FATAL_ERROR "${FUZZER} found a problem (exit status ${rc}). Reproducer(s):\n  ${listed}\n"
                      "Replay one with: ${FUZZER} <reproducer>")
endif()
message(STATUS "no findings in ${SECONDS} s; grown corpus in ${WORK}/corpus")
