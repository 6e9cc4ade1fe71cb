# cmake -DDYNAHAND=... -DWORK_DIR=... -P HandModelOptions.cmake
# The hand-model options shared by track and render (apps/dynahand/command.h): a model file
# that does not load, and a hand size out of range, are usage errors (exit 2) that say what
# was wrong; a valid size tracks.
file(REMOVE_RECURSE ${WORK_DIR})
file(MAKE_DIRECTORY ${WORK_DIR})
execute_process(COMMAND ${DYNAHAND} synth --motion wave --profile tof --frames 2 --out ${WORK_DIR}/clip
                RESULT_VARIABLE rc OUTPUT_QUIET ERROR_QUIET)
if(NOT rc EQUAL 0)
  message(FATAL_ERROR "dynahand synth failed (${rc})")
endif()
foreach(command track render)
  if(command STREQUAL "track")
    set(inputs ${WORK_DIR}/clip)
  else()
    set(inputs ${WORK_DIR}/clip/poses.jsonl ${WORK_DIR}/clip --sheet ${WORK_DIR}/sheet.png)
  endif()
  execute_process(COMMAND ${DYNAHAND} ${command} ${inputs} --model ${WORK_DIR}/missing-model.json
                  RESULT_VARIABLE rc ERROR_VARIABLE err OUTPUT_QUIET)
  if(NOT rc EQUAL 2 OR NOT err MATCHES "missing-model.json")
    message(FATAL_ERROR "${command} --model (missing file): exit ${rc}, stderr: ${err}")
  endif()
  execute_process(COMMAND ${DYNAHAND} ${command} ${inputs} --hand-length 0.5
                  RESULT_VARIABLE rc ERROR_VARIABLE err OUTPUT_QUIET)
  if(NOT rc EQUAL 2 OR NOT err MATCHES "hand-length")
    message(FATAL_ERROR "${command} --hand-length 0.5: exit ${rc}, stderr: ${err}")
  endif()
endforeach()
execute_process(COMMAND ${DYNAHAND} track ${WORK_DIR}/clip --hand-length 0.17 --hand-width 0.08
                        --out ${WORK_DIR}/poses.jsonl RESULT_VARIABLE rc OUTPUT_QUIET ERROR_QUIET)
if(NOT rc EQUAL 0 OR NOT EXISTS ${WORK_DIR}/poses.jsonl)
  message(FATAL_ERROR "track with a given hand size failed (${rc})")
endif()
