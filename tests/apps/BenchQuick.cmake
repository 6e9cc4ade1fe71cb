# cmake -DDYNAHAND=... -DWORK_DIR=... -P BenchQuick.cmake: `dynahand bench --quick` prints the
# table and writes the Markdown, with sane values.
file(REMOVE_RECURSE ${WORK_DIR})
file(MAKE_DIRECTORY ${WORK_DIR})
execute_process(COMMAND ${DYNAHAND} bench --quick --threads 2 --markdown ${WORK_DIR}/benchmarks.md
                RESULT_VARIABLE rc OUTPUT_VARIABLE out)
message(STATUS "${out}")
if(NOT rc EQUAL 0)
  message(FATAL_ERROR "dynahand bench --quick failed (${rc})")
endif()
foreach(row "clips x2.5 / tof / head / auto" "tof / medium / gt" "structured-light / medium / auto" "ablation: all" "ablation: no normal"
            "ablation: no feature_detection" "ablation: normal only")
  if(NOT out MATCHES "${row}")
    message(FATAL_ERROR "the table has no row '${row}'")
  endif()
endforeach()
# label, items, frames, mean mm, p95 mm, <=30mm %, acquire, p50 ms, p99 ms, CPU p50 ms, frames/s
if(NOT out MATCHES "tof / medium / gt +([0-9]+) +([0-9]+) +([0-9.]+) +([0-9.]+) +([0-9.]+)% +- +([0-9.]+) +([0-9.]+) +([0-9.]+)")
  message(FATAL_ERROR "cannot read the tof / medium / gt row")
endif()
set(items ${CMAKE_MATCH_1})
set(frames ${CMAKE_MATCH_2})
set(mean ${CMAKE_MATCH_3})
set(success ${CMAKE_MATCH_5})
set(p50 ${CMAKE_MATCH_6})
if(NOT items EQUAL 2 OR NOT frames EQUAL 16)
  message(FATAL_ERROR "tof / medium / gt: ${items} items, ${frames} frames; expected 2 and 16")
endif()
# Started from ground truth on 8 frames, the mean error is a few mm; 40 mm means broken.
if(mean LESS_EQUAL 0 OR mean GREATER 40)
  message(FATAL_ERROR "tof / medium / gt mean error ${mean} mm is not sane")
endif()
if(success LESS 50)
  message(FATAL_ERROR "tof / medium / gt: only ${success}% of frames within 30 mm")
endif()
if(p50 LESS_EQUAL 0)
  message(FATAL_ERROR "p50 frame time ${p50} ms is not positive")
endif()
file(READ ${WORK_DIR}/benchmarks.md md)
foreach(text "# Benchmarks" "Command: `dynahand bench --quick --threads 2`" "Machine: "
             "## Motion suite" "| clips x2.5 / tof / desk / gt | 2 | 16 |"
             "## Standard suite (regression rows)" "| tof / medium / gt | 2 | 16 |"
             "### Ablations by clip" "| pinch |")
  string(FIND "${md}" "${text}" at)
  if(at LESS 0)
    message(FATAL_ERROR "benchmarks.md lacks '${text}'")
  endif()
endforeach()
