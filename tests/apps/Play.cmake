# cmake -DDYNAHAND=... -DWORK_DIR=... -DSCENE=... -P Play.cmake
# synth (ground-truth poses) -> play: the play file has a header and one line per frame, the
# pictures exist, and the recording input (tracked) works too.

# Runs dynahand with the remaining arguments; the test fails, naming `what`, if it does.
function(run_dynahand what)
  execute_process(COMMAND ${DYNAHAND} ${ARGN} RESULT_VARIABLE rc)
  if(NOT rc EQUAL 0)
    message(FATAL_ERROR "dynahand ${what} failed (${rc})")
  endif()
endfunction()

# The lines of `file` into `out`; the test fails unless there are `expected` of them.
function(read_lines file expected out)
  file(STRINGS ${file} lines)
  list(LENGTH lines count)
  if(NOT count EQUAL expected)
    message(FATAL_ERROR "${file} has ${count} lines, expected ${expected}")
  endif()
  set(${out} "${lines}" PARENT_SCOPE)
endfunction()

file(REMOVE_RECURSE ${WORK_DIR})
file(MAKE_DIRECTORY ${WORK_DIR})
run_dynahand(synth synth --motion push-forward --profile tof --frames 12 --out ${WORK_DIR}/clip)
run_dynahand("play (pose file)" play ${SCENE} ${WORK_DIR}/clip/poses.jsonl
             --out ${WORK_DIR}/play.jsonl --frames-dir ${WORK_DIR}/pics --render-every 5)
read_lines(${WORK_DIR}/play.jsonl 13 lines)  # a header and 12 frames
list(GET lines 0 header)
if(NOT header MATCHES "\"format\": \"dynahand-play\", \"version\": 1")
  message(FATAL_ERROR "play.jsonl header: ${header}")
endif()
foreach(f 000000.png 000005.png 000010.png)
  if(NOT EXISTS ${WORK_DIR}/pics/${f})
    message(FATAL_ERROR "dynahand play did not write pics/${f}")
  endif()
endforeach()
run_dynahand("play (tracked recording)" play ${SCENE} ${WORK_DIR}/clip --init gt --frames 4
             --out ${WORK_DIR}/tracked.jsonl)
read_lines(${WORK_DIR}/tracked.jsonl 5 lines)  # a header and 4 frames
