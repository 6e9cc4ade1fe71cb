# cmake -DDYNAHAND=... -DWORK_DIR=... -P BenchSoak.cmake: `dynahand bench --suite soak` for a
# few seconds, tracking and serving: the table, the verdict line and the Markdown are there and
# frames were tracked (and, serving, every frame sent reached the client). No timing or
# memory figure is checked: a few seconds on a test machine say nothing about them.
file(REMOVE_RECURSE ${WORK_DIR})
file(MAKE_DIRECTORY ${WORK_DIR})

function(run_soak name)
  execute_process(COMMAND ${DYNAHAND} bench --suite soak --minutes 0.1 --frames 30
                          --markdown ${WORK_DIR}/${name}.md ${ARGN}
                  RESULT_VARIABLE rc OUTPUT_VARIABLE out ERROR_VARIABLE err)
  message(STATUS "${out}${err}")
  # 0: PASS, 1: FAIL (the criteria, which a few loaded seconds may miss); anything else broke.
  if(NOT rc EQUAL 0 AND NOT rc EQUAL 1)
    message(FATAL_ERROR "dynahand bench --suite soak ${ARGN} failed (${rc})")
  endif()
  set(out "${out}" PARENT_SCOPE)
endfunction()

function(check_common mode out)
  if(NOT out MATCHES "frames ([0-9]+) \\(([0-9.]+)/s\\), hand tracked in ([0-9.]+)%")
    message(FATAL_ERROR "${mode}: no frames line")
  endif()
  if(CMAKE_MATCH_1 LESS 20)
    message(FATAL_ERROR "${mode}: only ${CMAKE_MATCH_1} frames in 6 s")
  endif()
  if(NOT out MATCHES "p99 frame time \\(ms\\) +([0-9.]+) +([0-9.]+) +([-+0-9.]+%|n/a) +at most \\+10%: (PASS|FAIL)")
    message(FATAL_ERROR "${mode}: no p99 row")
  endif()
  if(CMAKE_MATCH_1 LESS_EQUAL 0 OR CMAKE_MATCH_2 LESS_EQUAL 0)
    message(FATAL_ERROR "${mode}: p99 frame times ${CMAKE_MATCH_1} / ${CMAKE_MATCH_2} ms")
  endif()
  if(NOT out MATCHES "resident memory \\(MB\\) +([0-9.]+) +([0-9.]+) +[-+0-9.]+% +at most \\+5%: (PASS|FAIL)")
    message(FATAL_ERROR "${mode}: no resident memory row")
  endif()
  if(CMAKE_MATCH_1 LESS 1 OR CMAKE_MATCH_2 LESS 1)
    message(FATAL_ERROR "${mode}: resident memory ${CMAKE_MATCH_1} / ${CMAKE_MATCH_2} MB")
  endif()
  if(NOT out MATCHES "soak ${mode}: (PASS|FAIL)\n")
    message(FATAL_ERROR "${mode}: no verdict line")
  endif()
  file(READ ${WORK_DIR}/${mode}.md md)
  foreach(text "# Soak benchmark" "- Command: `dynahand bench --suite soak " " --minutes 0.1"
               "- Machine: " "## Soak: ${mode}" "| resident memory (MB) | " "| p99 frame time (ms) | "
               "Result: **")
    string(FIND "${md}" "${text}" at)
    if(at LESS 0)
      message(FATAL_ERROR "${mode}.md lacks '${text}'")
    endif()
  endforeach()
endfunction()

run_soak(track --soak-input synth:wave,pinch)
check_common(track "${out}")

run_soak(serve --serve)
check_common(serve "${out}")
if(NOT out MATCHES "([0-9]+) frames published, ([0-9]+) sent, ([0-9]+) dropped for a slow client; the client received ([0-9]+) frames")
  message(FATAL_ERROR "serve: no stream line")
endif()
if(CMAKE_MATCH_2 LESS 1 OR NOT CMAKE_MATCH_4 EQUAL CMAKE_MATCH_2)
  message(FATAL_ERROR "serve: ${CMAKE_MATCH_2} frames sent, the client received ${CMAKE_MATCH_4}")
endif()

# A bad input is a usage error naming it.
execute_process(COMMAND ${DYNAHAND} bench --suite soak --minutes 0.05 --soak-input synth:no-such-clip
                RESULT_VARIABLE rc OUTPUT_VARIABLE out ERROR_VARIABLE err)
if(NOT rc EQUAL 2 OR NOT "${out}${err}" MATCHES "no-such-clip")
  message(FATAL_ERROR "an unknown clip: exit ${rc}, '${out}${err}'")
endif()
